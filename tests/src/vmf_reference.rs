//! f64 reference formulas of the von Mises-Fisher distribution on S², for the suites that
//! test f32 code against them.
//!
//! Notation: mean direction μ, concentration κ ≥ 0, and t = 1 − μ·ω ∈ [0, 2], the quantity
//! the formulas are written in because it keeps full relative precision near the peak, where
//! cos θ = μ·ω rounds to 1.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

/// 1 − cos θ for the angle θ between `axis` and `w`, computed without cancellation and
/// independent of the lengths of both vectors.
///
/// With s = |axis × w| and c = axis·w (both scaled by |axis||w|), it returns s²/(|axis||w|·(|axis||w| + c))
/// for c ≥ 0 and 1 − c/(|axis||w|) otherwise. An f32 direction that is off unit length by an
/// ulp changes `axis·w − 1` by ~6·10⁻⁸, which at κ = 10⁵ (t ~ 10⁻⁵) is a 0.6 % error; this
/// form only sees the direction. Returns NaN for zero or non-finite vectors.
#[must_use]
pub fn one_minus_cos(axis: DVec3, w: DVec3) -> f64 {
    let scale = axis.length() * w.length();
    if !(scale > 0.0 && scale.is_finite()) {
        return f64::NAN;
    }
    let c = axis.dot(w);
    if c >= 0.0 {
        let s2 = axis.cross(w).length_squared();
        s2 / (scale * (scale + c))
    } else {
        1.0 - c / scale
    }
}

/// CDF of t = 1 − μ·ω for ω ~ vMF(μ, κ): P(T ≤ t) = expm1(−κt)/expm1(−2κ), and t/2 at κ = 0.
///
/// This is 1 − F(1 − t) for the CDF of cos θ, F(c) = (e^{κ(c−1)} − e^{−2κ})/(1 − e^{−2κ})
/// (see [`vmf_cos_theta_cdf`]); written with `expm1` it has full relative precision for every
/// κ ≥ 0 and t ∈ [0, 2] (no cancellation for tiny κ nor for tiny t). Clamped to [0, 1].
#[must_use]
pub fn vmf_one_minus_cos_cdf(kappa: f64, t: f64) -> f64 {
    let t = t.clamp(0.0, 2.0);
    if kappa == 0.0 {
        return 0.5 * t;
    }
    ((-kappa * t).exp_m1() / (-2.0 * kappa).exp_m1()).clamp(0.0, 1.0)
}

/// CDF of cos θ = μ·ω for ω ~ vMF(μ, κ):
/// F(c) = (e^{κ(c−1)} − e^{−2κ})/(1 − e^{−2κ}) = 1 − expm1(−κ(1 − c))/expm1(−2κ),
/// and (c + 1)/2 at κ = 0. Prefer [`vmf_one_minus_cos_cdf`] when c is close to 1.
#[must_use]
pub fn vmf_cos_theta_cdf(kappa: f64, c: f64) -> f64 {
    1.0 - vmf_one_minus_cos_cdf(kappa, 1.0 - c)
}

/// Normalisation C(κ) = κ/(2π(1 − e^{−2κ})), 1/(4π) at κ = 0, so that the density is
/// C(κ) e^{−κt}.
#[must_use]
pub fn vmf_normalization(kappa: f64) -> f64 {
    if kappa == 0.0 {
        0.25 / PI
    } else {
        -kappa / (TAU * (-2.0 * kappa).exp_m1())
    }
}

/// The density C(κ) e^{−κ(1 − μ·ω)} of direction `w` (normalised first) under vMF(`mu`, κ).
#[must_use]
pub fn vmf_pdf(mu: DVec3, kappa: f64, w: DVec3) -> f64 {
    vmf_normalization(kappa) * (-kappa * one_minus_cos(mu, w)).exp()
}

/// Mean cosine A₃(κ) = coth κ − 1/κ = E[μ·ω] (series below κ = 10⁻³, 0 at κ = 0).
#[must_use]
pub fn vmf_mean_cosine(kappa: f64) -> f64 {
    1.0 - vmf_one_minus_mean_cosine(kappa)
}

/// 1 − A₃(κ) = E[1 − μ·ω] = 1/κ − 2/expm1(2κ), without cancellation for large κ
/// (1 at κ = 0, series κ/3 − κ³/45 for A₃ below κ = 10⁻³).
#[must_use]
pub fn vmf_one_minus_mean_cosine(kappa: f64) -> f64 {
    if kappa < 1e-3 {
        1.0 - (kappa / 3.0 - kappa.powi(3) / 45.0)
    } else {
        1.0 / kappa - 2.0 / (2.0 * kappa).exp_m1()
    }
}

/// Variance of cos θ = μ·ω under vMF(μ, κ): 1 − 2A₃/κ − A₃² (1/3 at κ = 0; ≈ 1/κ² for
/// large κ, computed from 1 − A₃ to avoid cancellation).
#[must_use]
pub fn vmf_cos_theta_variance(kappa: f64) -> f64 {
    if kappa < 1e-3 {
        return 1.0 / 3.0 - kappa * kappa / 15.0;
    }
    // With e = 1 − A₃: 1 − 2(1 − e)/κ − (1 − e)² = 2e − e² − 2(1 − e)/κ.
    let e = vmf_one_minus_mean_cosine(kappa);
    2.0 * e - e * e - 2.0 * (1.0 - e) / kappa
}

/// dA₃/dκ = 1/κ² − 1/sinh²κ (1/3 at κ = 0), the slope that turns a standard error of the
/// mean cosine into one of κ.
#[must_use]
pub fn vmf_mean_cosine_derivative(kappa: f64) -> f64 {
    if kappa < 1e-2 {
        return 1.0 / 3.0 - kappa * kappa / 15.0;
    }
    let s = kappa.sinh();
    1.0 / (kappa * kappa) - if s.is_finite() { 1.0 / (s * s) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_agree_with_textbook_forms() {
        for kappa in [0.5_f64, 2.0, 7.0] {
            let mu = DVec3::new(0.3, -0.5, 0.8).normalize();
            for c in [-0.9_f64, -0.2, 0.4, 0.95] {
                let w = DVec3::new((1.0 - c * c).sqrt(), 0.0, c);
                let w = {
                    // Rotate w so that its cosine to μ is c.
                    let (t, _) = crate::orthonormal_basis(mu);
                    t * w.x + mu * w.z
                };
                let textbook = kappa / (4.0 * PI * kappa.sinh()) * (kappa * c).exp();
                mcg_test_support::assert_close!(vmf_pdf(mu, kappa, w) / textbook, 1.0, 1e-12);
                let cdf = ((kappa * (c - 1.0)).exp() - (-2.0 * kappa).exp())
                    / (1.0 - (-2.0 * kappa).exp());
                mcg_test_support::assert_close!(vmf_cos_theta_cdf(kappa, c), cdf, 1e-14);
            }
            let a = 1.0 / kappa.tanh() - 1.0 / kappa;
            mcg_test_support::assert_close!(vmf_mean_cosine(kappa), a, 1e-14);
            let h = 1e-5;
            let slope = (vmf_mean_cosine(kappa + h) - vmf_mean_cosine(kappa - h)) / (2.0 * h);
            mcg_test_support::assert_close!(vmf_mean_cosine_derivative(kappa), slope, 1e-8);
        }
        assert_eq!(vmf_one_minus_cos_cdf(0.0, 1.0), 0.5);
        mcg_test_support::assert_close!(vmf_one_minus_cos_cdf(1e-9, 1.0), 0.5, 1e-9);
        mcg_test_support::assert_close!(vmf_cos_theta_variance(1e4) * 1e8, 1.0, 1e-3);
        let t = 1e-12_f64;
        let w = DVec3::new((2.0 * t).sqrt(), 0.0, 1.0 - t);
        mcg_test_support::assert_close!(one_minus_cos(DVec3::Z * 3.0, w * 2.0) / t, 1.0, 1e-6);
    }
}
