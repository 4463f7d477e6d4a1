//! Finite mixtures of vMF lobes.

use glam::{Vec2, Vec3};

use crate::{MixtureError, Vmf};

/// A mixture of `K` vMF lobes with non-negative weights that sum to one.
///
/// # Density function
/// ```text
/// p(ω) = Σᵢ πᵢ V(ω | μᵢ, κᵢ),    Σᵢ πᵢ = 1
/// ```
///
/// Sampling reuses one uniform for both decisions: `u.x` picks component i by walking the
/// cumulative weights, is then rescaled to [0, 1) within that component's interval and drives
/// the component's azimuth; `u.y` drives its polar angle. So two uniforms per sample suffice,
/// as for a single lobe.
///
/// # Example
/// ```
/// use mcg_vmf::{Vmf, VmfMixture, glam::{Vec2, Vec3}};
/// let mix = VmfMixture::new(
///     [Vmf::new(Vec3::Z, 20.0)?, Vmf::new(Vec3::X, 5.0)?],
///     [3.0, 1.0], // normalised to 0.75 / 0.25
/// ).unwrap();
/// let (w, pdf) = mix.sample_with_pdf(Vec2::new(0.9, 0.3)); // u.x = 0.9 picks the second lobe
/// assert!(w.x > 0.0 && (pdf - mix.pdf(w)).abs() < 1e-4 * pdf);
/// # Ok::<(), mcg_vmf::VmfError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmfMixture<const K: usize> {
    lobes: [Vmf; K],
    weights: [f32; K],
}

impl<const K: usize> VmfMixture<K> {
    /// Creates a mixture; `weights` are normalised to sum to one.
    ///
    /// Errors: [`MixtureError::WeightNotFinite`], [`MixtureError::WeightNegative`],
    /// [`MixtureError::WeightSumNotFinite`], [`MixtureError::WeightsSumToZero`] (also for
    /// `K = 0`). Zero weights are allowed:
    /// such a component is never sampled.
    pub fn new(lobes: [Vmf; K], weights: [f32; K]) -> Result<Self, MixtureError> {
        let mut sum = 0.0;
        for (index, &weight) in weights.iter().enumerate() {
            if !weight.is_finite() {
                return Err(MixtureError::WeightNotFinite { index, weight });
            }
            if weight < 0.0 {
                return Err(MixtureError::WeightNegative { index, weight });
            }
            sum += weight;
        }
        if !(sum > 0.0 && sum.is_finite()) {
            return Err(if sum > 0.0 {
                MixtureError::WeightSumNotFinite
            } else {
                MixtureError::WeightsSumToZero
            });
        }
        let weights = weights.map(|w| w / sum);
        Ok(Self { lobes, weights })
    }

    /// The components.
    #[inline]
    #[must_use]
    pub const fn lobes(&self) -> &[Vmf; K] {
        &self.lobes
    }

    /// The normalised component weights πᵢ.
    #[inline]
    #[must_use]
    pub const fn weights(&self) -> &[f32; K] {
        &self.weights
    }

    /// Mixture density Σᵢ πᵢ V(ω | μᵢ, κᵢ) of unit direction `w`.
    #[inline]
    #[must_use]
    pub fn pdf(&self, w: Vec3) -> f32 {
        let mut pdf = 0.0;
        for (lobe, &weight) in self.lobes.iter().zip(&self.weights) {
            pdf += weight * lobe.pdf(w);
        }
        pdf
    }

    /// Picks a component with `u` in [0, 1) and returns its index and `u` rescaled to [0, 1)
    /// within the chosen component's interval. Never picks a zero-weight component.
    #[inline]
    #[must_use]
    pub fn select(&self, u: f32) -> (usize, f32) {
        let mut start = 0.0;
        let mut last = 0;
        for (i, &weight) in self.weights.iter().enumerate() {
            if weight > 0.0 {
                let end = start + weight;
                if u < end {
                    let rescaled = ((u - start) / weight).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
                    return (i, rescaled);
                }
                start = end;
                last = i;
            }
        }
        // Rounding left u past the last cumulative weight: take the last live component.
        (last, 1.0 - f32::EPSILON / 2.0)
    }

    /// Draws a direction from two uniforms (see the type's docs for how `u.x` is reused).
    #[inline]
    #[must_use]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let (i, ux) = self.select(u.x);
        self.lobes[i].sample(Vec2::new(ux, u.y))
    }

    /// Draws a direction and returns it with the mixture density (all K lobes are evaluated).
    #[inline]
    #[must_use]
    pub fn sample_with_pdf(&self, u: Vec2) -> (Vec3, f32) {
        let w = self.sample(u);
        (w, self.pdf(w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validates_weights() {
        let l = [Vmf::uniform(); 2];
        assert!(matches!(
            VmfMixture::new(l, [1.0, f32::NAN]),
            Err(MixtureError::WeightNotFinite { index: 1, weight }) if weight.is_nan()
        ));
        assert_eq!(
            VmfMixture::new(l, [1.0, -0.5]),
            Err(MixtureError::WeightNegative {
                index: 1,
                weight: -0.5
            })
        );
        assert_eq!(
            VmfMixture::new(l, [0.0, 0.0]),
            Err(MixtureError::WeightsSumToZero)
        );
        assert_eq!(
            VmfMixture::new(l, [f32::MAX, f32::MAX]),
            Err(MixtureError::WeightSumNotFinite)
        );
        assert_eq!(
            VmfMixture::<0>::new([], []),
            Err(MixtureError::WeightsSumToZero)
        );
        let m = VmfMixture::new(l, [1.0, 3.0]).unwrap();
        assert_eq!(m.weights(), &[0.25, 0.75]);
    }

    #[test]
    fn select_skips_zero_weights_and_rescales() {
        let l = [Vmf::uniform(); 4];
        let m = VmfMixture::new(l, [0.0, 0.5, 0.0, 0.5]).unwrap();
        assert_eq!(m.select(0.0), (1, 0.0));
        assert_eq!(m.select(0.25), (1, 0.5));
        assert_eq!(m.select(0.75), (3, 0.5));
        assert_eq!(m.select(1.0).0, 3);
        assert!(m.select(1.0).1 < 1.0);
    }
}
