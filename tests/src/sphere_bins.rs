//! Equal-area bins on the unit sphere and the probability of each bin under a pdf.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::{ChiSquareResult, GaussLegendre, assert_chi_square};

/// Points per dimension of the Gauss-Legendre rule on each sub-cell of a bin.
const QUADRATURE_ORDER: usize = 8;

/// A partition of S² into `bands × sectors` bins of equal area 4π/(bands · sectors).
///
/// Bins are bands of equal height in z = cos θ (world frame, θ from +z) times sectors of equal
/// width in the azimuth φ = atan2(y, x) ∈ [0, 2π). Bin `band · sectors + sector` covers
/// z ∈ [−1 + 2·band/bands, −1 + 2·(band + 1)/bands) and φ ∈ [2π·sector/sectors,
/// 2π·(sector + 1)/sectors). Indices run band by band, so neighbouring indices are neighbouring
/// bins, as [`merge_bins`](crate::merge_bins) expects.
///
/// # Example
/// ```
/// use mcg_tests::SphereBins;
/// use glam::DVec3;
/// let bins = SphereBins::new(4, 8);
/// assert_eq!(bins.bin_count(), 32);
/// assert_eq!(bins.index(DVec3::new(1.0, 0.0, 0.9)), 3 * 8);
/// let p = bins.probabilities(1, |_| 0.25 / std::f64::consts::PI);
/// assert!(p.iter().all(|&p| (p - 1.0 / 32.0).abs() < 1e-12));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SphereBins {
    bands: usize,
    sectors: usize,
}

impl SphereBins {
    /// Bins with `bands` bands in z and `sectors` sectors in φ; both must be ≥ 1.
    #[must_use]
    pub fn new(bands: usize, sectors: usize) -> Self {
        assert!(
            bands >= 1 && sectors >= 1,
            "need at least one band and one sector"
        );
        Self { bands, sectors }
    }

    /// The number of bands in z.
    #[must_use]
    pub fn bands(&self) -> usize {
        self.bands
    }

    /// The number of sectors in φ.
    #[must_use]
    pub fn sectors(&self) -> usize {
        self.sectors
    }

    /// The number of bins, `bands · sectors`.
    #[must_use]
    pub fn bin_count(&self) -> usize {
        self.bands * self.sectors
    }

    /// Solid angle of each bin, 4π / [`SphereBins::bin_count`].
    #[must_use]
    pub fn bin_solid_angle(&self) -> f64 {
        2.0 * TAU / self.bin_count() as f64
    }

    /// Index of the bin that holds direction `w`.
    ///
    /// `w` need not be unit length (it is normalised in f64, so f32 directions can be passed
    /// with `as_dvec3()`). Panics when `w` is zero or not finite.
    #[must_use]
    pub fn index(&self, w: DVec3) -> usize {
        let w = w
            .try_normalize()
            .unwrap_or_else(|| panic!("direction {w} is zero or not finite"));
        let band = (((w.z + 1.0) * 0.5 * self.bands as f64) as usize).min(self.bands - 1);
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let sector = ((phi / TAU * self.sectors as f64) as usize).min(self.sectors - 1);
        band * self.sectors + sector
    }

    /// The z range `[z0, z1]` and φ range `[φ0, φ1]` of bin `index`.
    #[must_use]
    pub fn bounds(&self, index: usize) -> ([f64; 2], [f64; 2]) {
        assert!(index < self.bin_count(), "bin {index} out of range");
        let (band, sector) = (index / self.sectors, index % self.sectors);
        let dz = 2.0 / self.bands as f64;
        let d_phi = TAU / self.sectors as f64;
        let z0 = -1.0 + band as f64 * dz;
        let phi0 = sector as f64 * d_phi;
        ([z0, (z0 + dz).min(1.0)], [phi0, phi0 + d_phi])
    }

    /// Counts how many of `directions` fall in each bin.
    pub fn histogram<I: IntoIterator<Item = DVec3>>(&self, directions: I) -> Vec<u64> {
        let mut counts = vec![0_u64; self.bin_count()];
        for w in directions {
            counts[self.index(w)] += 1;
        }
        counts
    }

    /// Probability of each bin under the density `pdf` (per steradian): ∫_bin pdf(ω) dω.
    ///
    /// Each bin is integrated in (θ, φ) with θ = acos z, which removes the √(1 − z²)
    /// singularity of the (z, φ) parametrisation at the poles: the θ and φ ranges are each cut
    /// into `subdivisions` equal parts and every sub-cell gets an 8 × 8-point Gauss-Legendre
    /// rule, with the Jacobian sin θ. `pdf` receives unit f64 directions; to test an f32 pdf,
    /// convert there (`|w| lobe.pdf(w.as_vec3()) as f64`) so the code under test is evaluated
    /// at f32 directions and accumulated in f64. For a vMF lobe of concentration κ, sub-cells
    /// no wider than ~1/√κ make the rule accurate to better than 10⁻⁹ per bin.
    #[must_use]
    pub fn probabilities<F: FnMut(DVec3) -> f64>(
        &self,
        subdivisions: usize,
        mut pdf: F,
    ) -> Vec<f64> {
        assert!(subdivisions >= 1, "need at least one subdivision");
        let rule = GaussLegendre::new(QUADRATURE_ORDER);
        (0..self.bin_count())
            .map(|index| {
                let ([z0, z1], [phi0, phi1]) = self.bounds(index);
                // θ decreases as z grows: θ ∈ [acos z1, acos z0].
                let (theta0, theta1) = (z1.clamp(-1.0, 1.0).acos(), z0.clamp(-1.0, 1.0).acos());
                let d_theta = (theta1 - theta0) / subdivisions as f64;
                let d_phi = (phi1 - phi0) / subdivisions as f64;
                let mut sum = 0.0;
                for i in 0..subdivisions {
                    let ta = theta0 + i as f64 * d_theta;
                    sum += rule.integrate(ta, ta + d_theta, |theta| {
                        let (sin_theta, cos_theta) = theta.sin_cos();
                        let mut ring = 0.0;
                        for j in 0..subdivisions {
                            let pa = phi0 + j as f64 * d_phi;
                            ring += rule.integrate(pa, pa + d_phi, |phi| {
                                let (sin_phi, cos_phi) = phi.sin_cos();
                                pdf(DVec3::new(
                                    sin_theta * cos_phi,
                                    sin_theta * sin_phi,
                                    cos_theta,
                                ))
                            });
                        }
                        ring * sin_theta
                    });
                }
                sum
            })
            .collect()
    }
}

/// Chi-square test of sampled `directions` against the density `pdf` on `bins`: expected
/// counts n · ∫_bin pdf from [`SphereBins::probabilities`] with `subdivisions`, observed counts
/// from [`SphereBins::histogram`], then [`assert_chi_square`] at significance `alpha`.
///
/// Also asserts that the bin probabilities sum to 1 within 10⁻⁵, so a density that does not
/// integrate to one (or a quadrature too coarse for it) fails here rather than in the test.
#[track_caller]
pub fn assert_sphere_chi_square<F, I>(
    label: &str,
    bins: &SphereBins,
    subdivisions: usize,
    pdf: F,
    directions: I,
    alpha: f64,
) -> ChiSquareResult
where
    F: FnMut(DVec3) -> f64,
    I: IntoIterator<Item = DVec3>,
{
    let probabilities = bins.probabilities(subdivisions, pdf);
    let total: f64 = probabilities.iter().sum();
    mcg_test_support::assert_close!(
        total,
        1.0,
        1e-5,
        "{label}: bin probabilities sum to {total}"
    );
    let observed = bins.histogram(directions);
    let n: u64 = observed.iter().sum();
    let expected: Vec<f64> = probabilities.iter().map(|p| p * n as f64).collect();
    assert_chi_square(label, &observed, &expected, alpha)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;

    #[test]
    fn bins_have_equal_area_and_indices_match_bounds() {
        let bins = SphereBins::new(7, 11);
        let p = bins.probabilities(2, |_| 0.25 / PI);
        assert_eq!(p.len(), 77);
        for &p in &p {
            mcg_test_support::assert_close!(p, 1.0 / 77.0, 1e-13, "{p}");
        }
        for index in 0..bins.bin_count() {
            let ([z0, z1], [phi0, phi1]) = bins.bounds(index);
            let (z, phi) = (0.5 * (z0 + z1), 0.5 * (phi0 + phi1));
            let s = (1.0 - z * z).sqrt();
            assert_eq!(
                bins.index(DVec3::new(s * phi.cos(), s * phi.sin(), z)),
                index
            );
        }
        assert_eq!(bins.index(DVec3::Z) / 11, 6);
        // At the poles the sector is arbitrary (atan2 of ±0); the band is not.
        assert_eq!(bins.index(-DVec3::Z) / 11, 0);
        assert_eq!(bins.index(DVec3::new(1.0, -1e-300, 0.0)), 3 * 11 + 10);
        mcg_test_support::assert_close!(bins.bin_solid_angle(), 4.0 * PI / 77.0, 1e-15);
    }

    #[test]
    fn vmf_probabilities_sum_to_one() {
        // An f64 vMF density with κ = 50 around a tilted axis: the bins must add up to 1.
        let mu = DVec3::new(0.3, -0.5, 0.8).normalize();
        let kappa = 50.0_f64;
        let bins = SphereBins::new(16, 32);
        let p = bins.probabilities(3, |w| {
            kappa / (TAU * (1.0 - (-2.0 * kappa).exp())) * (kappa * (w.dot(mu) - 1.0)).exp()
        });
        let sum: f64 = p.iter().sum();
        mcg_test_support::assert_close!(sum, 1.0, 1e-10, "{sum}");
        // The bin that holds μ holds the most.
        let top = bins.index(mu);
        assert!(p.iter().all(|&q| q <= p[top]));
    }
}
