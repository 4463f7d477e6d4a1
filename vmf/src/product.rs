//! Products and convolutions of vMF lobes, and the vMF fit of a clamped cosine.

use glam::Vec3;

use crate::vmf::normalization;
use crate::{Vmf, VmfError, kappa_from_mean_cosine_exact, math, mean_cosine_from_kappa};

/// κ of the vMF lobe that approximates the clamped cosine max(0, n·ω) around a normal n.
///
/// This is the value Open PGL ships (`ApplyCosineProduct`). It is close to
/// the L² optimum over the sphere, min over (κ, a) of ∫ (max(0, cos θ) − a e^{κ(cos θ − 1)})² dω,
/// which lies at κ ≈ 2.145 with a ≈ 1.18 (the L² error differs by 0.4 %). Moment matching instead
/// (A₃(κ) = 2/3, the mean cosine of cos θ/π on the hemisphere) gives κ ≈ 2.95 and a lobe that
/// is too narrow in its tails.
pub const CLAMPED_COSINE_KAPPA: f32 = 2.18853;

impl Vmf {
    /// Product of two lobes: `self.pdf(ω) · other.pdf(ω) = scale · product.pdf(ω)` for every ω.
    ///
    /// With m = κ₀μ₀ + κ₁μ₁ the product lobe has μ' = m/|m| and κ' = |m|, and
    ///
    /// ```text
    /// scale = C(κ₀) C(κ₁) / C(κ') · e^{κ' − κ₀ − κ₁},   C(κ) = κ / (2π (1 − e^{−2κ}))
    /// ```
    ///
    /// (Jakob 2012; the exponent κ₀(μ₀·μ' − 1) + κ₁(μ₁·μ' − 1) simplifies to
    /// κ' − κ₀ − κ₁ ≤ 0, so the scale never overflows). `scale` is the integral of the product
    /// over the sphere. When the lobes cancel exactly (m = 0) the product is uniform with μ' = μ₀.
    /// κ' ≤ κ₀ + κ₁, so the product of two lobes from [`Vmf::new`] (κ ≤
    /// [`KAPPA_MAX`](crate::KAPPA_MAX)) has κ' ≤ 2·10⁶ and a finite `scale`.
    ///
    /// # Example
    /// ```
    /// use mcg_vmf::{Vmf, glam::Vec3};
    /// let a = Vmf::new(Vec3::Z, 10.0)?;
    /// let b = Vmf::new(Vec3::new(0.0, 0.6, 0.8), 5.0)?;
    /// let (c, scale) = a.product(&b);
    /// let w = Vec3::new(0.0, 0.3, 1.0).normalize();
    /// assert!((a.pdf(w) * b.pdf(w) - scale * c.pdf(w)).abs() < 1e-4 * a.pdf(w) * b.pdf(w));
    /// # Ok::<(), mcg_vmf::VmfError>(())
    /// ```
    #[inline]
    #[must_use]
    pub fn product(&self, other: &Vmf) -> (Vmf, f32) {
        let lobe = self.product_lobe(other);
        let kappa = lobe.kappa();
        let exponent = kappa - self.kappa() - other.kappa();
        let scale = (normalization(self.kappa()) / normalization(kappa))
            * normalization(other.kappa())
            * math::exp(exponent.min(0.0));
        (lobe, scale)
    }

    /// The lobe of the product of two lobes, μ' = m/|m| and κ' = |m| with
    /// m = κ₀μ₀ + κ₁μ₁ ([`Vmf::product`] without its scale, which costs three normalisations):
    /// what a sampler that multiplies a guiding lobe by a BSDF's lobe (e.g. the
    /// [`clamped_cosine`](Vmf::clamped_cosine)) needs. When the lobes cancel exactly (m = 0)
    /// the product is uniform with μ' = μ₀.
    ///
    /// # Example
    /// ```
    /// use mcg_vmf::{Vmf, glam::Vec3};
    /// let guide = Vmf::new(Vec3::new(0.0, 0.6, 0.8), 20.0)?;
    /// let lobe = guide.product_lobe(&Vmf::clamped_cosine(Vec3::Z)?);
    /// assert_eq!(lobe, guide.product(&Vmf::clamped_cosine(Vec3::Z)?).0);
    /// assert!(lobe.mu().z > 0.8);
    /// # Ok::<(), mcg_vmf::VmfError>(())
    /// ```
    #[inline]
    #[must_use]
    pub fn product_lobe(&self, other: &Vmf) -> Vmf {
        let m = self.mu() * self.kappa() + other.mu() * other.kappa();
        let kappa = m.length();
        let mu = if kappa > 0.0 { m / kappa } else { self.mu() };
        // Re-normalise: m / |m| can be off unit length by an ulp, which the pdf tolerates, but
        // keep the Vmf invariant exact for later products.
        let mu = mu.try_normalize().unwrap_or(self.mu());
        Vmf::from_unit_mean(mu, kappa)
    }

    /// Approximate convolution with a rotationally symmetric vMF kernel of concentration
    /// `kernel_kappa` (e.g. a blur of the lobe by a glossy reflection).
    ///
    /// Mean cosines multiply under convolution on the sphere (the Funk-Hecke theorem applied to
    /// the first moment), so the result keeps μ and has κ' = A₃⁻¹(A₃(κ) · A₃(κ_kernel)), using
    /// the exact inverse. The result is not exactly a vMF; its mean cosine is exact.
    /// A negative or NaN kernel κ is treated as 0 (full blur to uniform).
    #[inline]
    #[must_use]
    pub fn convolve(&self, kernel_kappa: f32) -> Vmf {
        let r = self.mean_cosine() * mean_cosine_from_kappa(kernel_kappa);
        Vmf::from_unit_mean(self.mu(), kappa_from_mean_cosine_exact(r))
    }

    /// The vMF lobe approximating the clamped cosine max(0, n·ω) around `normal`
    /// (κ = [`CLAMPED_COSINE_KAPPA`]). Multiply a lobe by it with [`Vmf::product`] to
    /// approximate the product of incident light and the cosine term.
    ///
    /// `normal` is normalised; it errors like [`Vmf::new`] for zero or non-finite normals.
    /// A normal of length in (1/√2, √2), the common case of a renderer's unit normal, is
    /// normalised by one reciprocal square root instead of `new`'s rescaling (a guide builds
    /// this lobe at every vertex; `new`'s checks and rescaling were most of its cost).
    #[inline]
    pub fn clamped_cosine(normal: Vec3) -> Result<Vmf, VmfError> {
        let length_squared = normal.length_squared();
        // False for NaN and ∞: those go to `new`, which names the error.
        if length_squared > 0.5 && length_squared < 2.0 {
            return Ok(Vmf::from_unit_mean(
                normal * math::sqrt(length_squared).recip(),
                CLAMPED_COSINE_KAPPA,
            ));
        }
        Vmf::new(normal, CLAMPED_COSINE_KAPPA)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_is_pointwise_exact() {
        let pairs = [
            (
                Vmf::new(Vec3::Z, 10.0).unwrap(),
                Vmf::new(Vec3::new(1.0, 0.0, 1.0), 3.0).unwrap(),
            ),
            (
                Vmf::new(Vec3::X, 0.0).unwrap(),
                Vmf::new(Vec3::Y, 50.0).unwrap(),
            ),
            (
                Vmf::new(Vec3::Z, 200.0).unwrap(),
                Vmf::new(Vec3::Z, 300.0).unwrap(),
            ),
            (
                Vmf::new(Vec3::Z, 4.0).unwrap(),
                Vmf::new(-Vec3::Z, 4.0).unwrap(),
            ),
        ];
        for (a, b) in pairs {
            let (c, scale) = a.product(&b);
            assert!(scale.is_finite() && scale > 0.0);
            for w in [
                Vec3::Z,
                Vec3::X,
                Vec3::new(0.3, 0.1, 0.9).normalize(),
                Vec3::new(0.6, 0.0, 0.8),
            ] {
                let lhs = a.pdf(w) * b.pdf(w);
                let rhs = scale * c.pdf(w);
                mcg_test_support::assert_close!(
                    lhs,
                    rhs,
                    1e-4 * lhs.max(1e-30),
                    "{a:?} {b:?} {w}: {lhs} vs {rhs}"
                );
            }
        }
    }

    #[test]
    fn products_of_lobes_at_kappa_max_are_finite() {
        // Issue 14 row 2: κ = 10²⁰ was accepted and made the product κ infinite and its
        // scale NaN; `new` now stops at KAPPA_MAX, where every product is finite.
        let k = crate::KAPPA_MAX;
        let big = Vmf::new(Vec3::Y, k).unwrap();
        let pairs = [
            (Vmf::uniform(), big),
            (big, big),
            (big, Vmf::new(-Vec3::Y, k).unwrap()),
            (big, Vmf::new(Vec3::new(0.0, 1.0, 1e-3), k).unwrap()),
            (big, Vmf::new(Vec3::X, k).unwrap()),
        ];
        for (a, b) in pairs {
            let (c, scale) = a.product(&b);
            assert!(c.kappa().is_finite() && c.kappa() <= 2.0 * k, "{c:?}");
            assert!(c.mu().is_normalized(), "{c:?}");
            assert!(scale.is_finite() && scale >= 0.0, "{a:?} {b:?}: {scale}");
            let (w, p) = c.sample_with_pdf(glam::Vec2::new(0.3, 0.6));
            assert!(w.is_finite() && p.is_finite());
        }
    }

    #[test]
    fn convolution_multiplies_mean_cosines() {
        let a = Vmf::new(Vec3::Y, 20.0).unwrap();
        let c = a.convolve(20.0);
        assert_eq!(c.mu(), a.mu());
        let want = a.mean_cosine() * a.mean_cosine();
        mcg_test_support::assert_close!(c.mean_cosine(), want, 1e-5);
        assert_eq!(a.convolve(0.0).kappa(), 0.0);
        assert_eq!(a.convolve(f32::NAN).kappa(), 0.0);
    }
}
