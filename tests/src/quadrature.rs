//! Reference quadrature in f64: Gauss-Legendre rules on intervals and a polar rule on S².

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// An n-point Gauss-Legendre rule on [−1, 1], exact for polynomials of degree 2n − 1.
///
/// Nodes are found by Newton's method on the Legendre recurrence to full f64 precision.
#[derive(Clone, Debug, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// Builds the rule with `order` ≥ 1 points.
    #[must_use]
    pub fn new(order: usize) -> Self {
        assert!(order >= 1, "a Gauss-Legendre rule needs at least one point");
        let n = order as f64;
        let mut nodes = vec![0.0; order];
        let mut weights = vec![0.0; order];
        for i in 0..order.div_ceil(2) {
            // Tricomi's initial guess for the i-th largest root, then Newton.
            let mut x = (PI * (i as f64 + 0.75) / (n + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(order, x);
                let step = p / dp;
                x -= step;
                if step.abs() < 1e-16 {
                    break;
                }
            }
            let (_, derivative) = legendre(order, x);
            let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
            nodes[i] = x;
            weights[i] = w;
            nodes[order - 1 - i] = -x;
            weights[order - 1 - i] = w;
        }
        if order % 2 == 1 {
            nodes[order / 2] = 0.0;
        }
        Self { nodes, weights }
    }

    /// The number of points.
    #[must_use]
    pub fn order(&self) -> usize {
        self.nodes.len()
    }

    /// The nodes in [−1, 1], in decreasing order.
    #[must_use]
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// The weights (they sum to 2).
    #[must_use]
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// ∫ₐᵇ f(x) dx by this rule.
    pub fn integrate<F: FnMut(f64) -> f64>(&self, a: f64, b: f64, mut f: F) -> f64 {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        let sum: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(&x, &w)| w * f(mid + half * x))
            .sum();
        sum * half
    }

    /// ∫ f from the first to the last of `breaks`, one application of the rule per panel between
    /// consecutive `breaks` (composite rule; `breaks` should be increasing).
    pub fn integrate_panels<F: FnMut(f64) -> f64>(&self, breaks: &[f64], mut f: F) -> f64 {
        breaks
            .windows(2)
            .map(|panel| self.integrate(panel[0], panel[1], &mut f))
            .sum()
    }
}

/// Legendre polynomial P_n(x) and its derivative by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let n = n as f64;
    (p1, n * (x * p1 - p0) / (x * x - 1.0))
}

/// Two unit vectors that complete the unit `axis` to a right-handed orthonormal basis
/// `(tangent, bitangent, axis)`, in f64: glam's [`DVec3::any_orthonormal_pair`] (Duff et al.
/// 2017), the construction [`mcg_vmf::Frame`] uses in f32.
#[must_use]
pub fn orthonormal_basis(axis: DVec3) -> (DVec3, DVec3) {
    axis.any_orthonormal_pair()
}

/// Polar-angle breakpoints for [`integrate_sphere`] graded around a peak of angular `width`
/// at θ = 0: 0, w/8, w/4, w/2, w, 2w, 4w, … up to π, with w = `width` clamped to
/// [10⁻⁶, π]. For a vMF lobe of concentration κ, `width` = 1/√κ resolves the peak.
#[must_use]
pub fn graded_theta_breaks(width: f64) -> Vec<f64> {
    let w = if width.is_nan() {
        PI
    } else {
        width.clamp(1e-6, PI)
    };
    let mut breaks = vec![0.0];
    let mut theta = w / 8.0;
    while theta < PI {
        breaks.push(theta);
        theta *= 2.0;
    }
    breaks.push(PI);
    breaks
}

/// ∫_{S²} f(ω) dω in polar coordinates (θ, φ) around the unit `axis`.
///
/// θ is integrated with a 16-point Gauss-Legendre rule on each panel between consecutive
/// `theta_breaks` (which should run from 0 to π, e.g. [`graded_theta_breaks`]; add a break
/// where the integrand has a kink), with the Jacobian sin θ. φ uses the trapezoid rule with
/// `azimuths` equally spaced points, which converges geometrically for smooth periodic
/// integrands and is exact for integrands symmetric about `axis`.
pub fn integrate_sphere<F: FnMut(DVec3) -> f64>(
    axis: DVec3,
    theta_breaks: &[f64],
    azimuths: usize,
    mut f: F,
) -> f64 {
    assert!(azimuths >= 1, "need at least one azimuth");
    let axis = axis.normalize();
    let (tangent, bitangent) = orthonormal_basis(axis);
    let rule = GaussLegendre::new(16);
    let d_phi = TAU / azimuths as f64;
    rule.integrate_panels(theta_breaks, |theta| {
        let (sin_theta, cos_theta) = theta.sin_cos();
        let mut ring = 0.0;
        for j in 0..azimuths {
            let (sin_phi, cos_phi) = (j as f64 * d_phi).sin_cos();
            let w = (tangent * cos_phi + bitangent * sin_phi) * sin_theta + axis * cos_theta;
            ring += f(w);
        }
        ring * d_phi * sin_theta
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_integrate_polynomials_exactly() {
        for order in [1, 2, 3, 5, 8, 16, 33] {
            let rule = GaussLegendre::new(order);
            mcg_test_support::assert_close!(
                rule.weights().iter().sum::<f64>(),
                2.0,
                1e-13,
                "order {order}"
            );
            for degree in 0..(2 * order) {
                let got = rule.integrate(-0.5, 1.5, |x| x.powi(degree as i32));
                let want = (1.5_f64.powi(degree as i32 + 1) - (-0.5_f64).powi(degree as i32 + 1))
                    / (degree as f64 + 1.0);
                mcg_test_support::assert_close!(
                    got,
                    want,
                    1e-12 * want.abs().max(1.0),
                    "order {order} degree {degree}: {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn sphere_integrals() {
        let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
        let breaks = graded_theta_breaks(0.1);
        let area = integrate_sphere(axis, &breaks, 8, |_| 1.0);
        mcg_test_support::assert_close!(area, 4.0 * PI, 1e-12, "{area}");
        // ∫ z² dω = 4π/3 for any axis: checks the azimuthal rule off-axis.
        let z2 = integrate_sphere(axis, &breaks, 16, |w| w.z * w.z);
        mcg_test_support::assert_close!(z2, 4.0 * PI / 3.0, 1e-12, "{z2}");
        // ∫ e^{κ(μ·ω − 1)} dω = 2π(1 − e^{−2κ})/κ, here κ = 10⁴ around its own axis.
        let kappa = 1e4_f64;
        let lobe = integrate_sphere(axis, &graded_theta_breaks(1.0 / kappa.sqrt()), 4, |w| {
            (kappa * (w.dot(axis) - 1.0)).exp()
        });
        mcg_test_support::assert_close!(lobe * kappa / (2.0 * PI), 1.0, 1e-10, "{lobe}");
        for axis in [DVec3::Z, -DVec3::Z, DVec3::X, axis] {
            let (t, b) = orthonormal_basis(axis);
            assert!((t.cross(b) - axis).length() < 1e-15 && t.dot(axis).abs() < 1e-15);
        }
    }
}
