//! The mean cosine A₃(κ) of a vMF lobe and its inverses.
//!
//! For a vMF lobe with concentration κ, the expected cosine between a sample and the mean
//! direction is the ratio of Bessel functions A₃(κ) = I_{3/2}(κ)/I_{1/2}(κ) = coth κ − 1/κ
//! (Banerjee et al. 2005, *Clustering on the Unit Hypersphere using von Mises-Fisher
//! Distributions*, JMLR 6, eq. 4.1 with p = 3). It is the quantity the guiding papers estimate
//! from samples (MCMM Table 1 r̄, MCPG Table 1 r̄) and then invert to get κ.

use crate::constants::{
    MEAN_COSINE_DERIVATIVE_SERIES, MEAN_COSINE_SERIES, NEWTON_COMPLEMENT_FROM,
    NEWTON_MAX_ITERATIONS, NEWTON_RELATIVE_STEP, SERIES_LIMIT,
};
use crate::math;

/// Largest concentration returned by [`kappa_from_mean_cosine`] and
/// [`kappa_from_mean_cosine_exact`], and accepted by [`Vmf::new`](crate::Vmf::new): 10⁶.
///
/// This is the top of the range over which [`Vmf`](crate::Vmf)'s pdf and sampling are
/// validated in f32 (a lobe of angular radius ≈ 1 mrad). A mean cosine of 1 − 10⁻⁶ already maps
/// to it. Renderers that want wider lobes clamp further, e.g. Open PGL uses 32 000.
pub const KAPPA_MAX: f32 = 1.0e6;

/// Mean cosine A₃(κ) = coth κ − 1/κ of a vMF lobe with concentration `kappa`.
///
/// Stable for all κ ≥ 0: below κ = 0.5 the Taylor series
/// κ/3 − κ³/45 + 2κ⁵/945 − κ⁷/4725 + 2κ⁹/93555 is used (truncation error < 10⁻⁹ relative),
/// above it the form 1 + 2/expm1(2κ) − 1/κ, which tends to 1 − 1/κ without overflow.
/// Returns 0 for κ ≤ 0 and for NaN, and values in [0, 1) otherwise.
///
/// # Example
/// ```
/// use mcg_vmf::mean_cosine_from_kappa;
/// assert_eq!(mean_cosine_from_kappa(0.0), 0.0);
/// assert!((mean_cosine_from_kappa(1e-3) - 1e-3 / 3.0).abs() < 1e-10);
/// assert!((mean_cosine_from_kappa(1e4) - (1.0 - 1e-4)).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn mean_cosine_from_kappa(kappa: f32) -> f32 {
    if !(kappa > 0.0) {
        return 0.0;
    }
    if kappa < SERIES_LIMIT {
        let k2 = kappa * kappa;
        // Horner form of the odd series of coth κ − 1/κ.
        let [a0, a1, a2, a3, a4] = MEAN_COSINE_SERIES;
        kappa * (a0 + k2 * (a1 + k2 * (a2 + k2 * (a3 + k2 * a4))))
    } else {
        (1.0 + 2.0 / math::exp_m1(2.0 * kappa) - 1.0 / kappa).min(1.0)
    }
}

/// Derivative dA₃/dκ = 1/κ² − 1/sinh²κ, stable for all κ ≥ 0 (series below κ = 0.5).
#[inline]
fn mean_cosine_derivative(kappa: f32) -> f32 {
    if kappa < SERIES_LIMIT {
        let k2 = kappa * kappa;
        let [d0, d1, d2, d3] = MEAN_COSINE_DERIVATIVE_SERIES;
        d0 + k2 * (d1 + k2 * (d2 + k2 * d3))
    } else {
        // 1/sinh²κ = 4 e^{−2κ} / (1 − e^{−2κ})², which underflows to 0 instead of overflowing.
        let e = math::exp(-2.0 * kappa);
        let d = math::exp_m1(-2.0 * kappa);
        1.0 / (kappa * kappa) - 4.0 * e / (d * d)
    }
}

/// 1 − A₃(κ), evaluated without cancellation when A₃(κ) is close to 1.
#[inline]
fn one_minus_mean_cosine(kappa: f32) -> f32 {
    if kappa < SERIES_LIMIT {
        1.0 - mean_cosine_from_kappa(kappa)
    } else {
        1.0 / kappa - 2.0 / math::exp_m1(2.0 * kappa)
    }
}

/// Concentration κ for a mean cosine `r`, by the approximation of Banerjee et al. 2005 (eq. 4.4)
/// that both guiding papers use (MCMM Alg. 2 line 7, MCPG Alg. 2 line 8):
///
/// κ ≈ (3r − r³) / (1 − r²)
///
/// The result is clamped to [0, [`KAPPA_MAX`]]: `r ≤ 0` and NaN give 0 (a uniform lobe), `r` so
/// close to 1 that κ would exceed the maximum gives [`KAPPA_MAX`]. The approximation
/// overestimates κ by at most 4.9 % (at κ ≈ 4.9) and by less than 0.5/κ for large κ; use
/// [`kappa_from_mean_cosine_exact`] where that matters.
///
/// # Example
/// ```
/// use mcg_vmf::{kappa_from_mean_cosine, KAPPA_MAX};
/// assert_eq!(kappa_from_mean_cosine(0.0), 0.0);
/// assert!((kappa_from_mean_cosine(0.9) - 10.373684).abs() < 1e-4);
/// assert_eq!(kappa_from_mean_cosine(1.0), KAPPA_MAX);
/// ```
#[inline]
#[must_use]
pub fn kappa_from_mean_cosine(r: f32) -> f32 {
    if !(r > 0.0) {
        return 0.0;
    }
    // 1 − r is exact in f32 for r ≥ 0.5 (Sterbenz), where the precision matters.
    kappa_from_one_minus_mean_cosine(1.0 - r)
}

/// Banerjee's κ from the complement e = 1 − r of the mean cosine:
/// κ = r(3 − r²) / (e(2 − e)), which keeps full relative precision as r → 1 (κ ≈ 1/e).
/// Clamped to [0, [`KAPPA_MAX`]]; e ≥ 1 and NaN give 0, e ≤ 0 gives [`KAPPA_MAX`].
#[inline]
pub(crate) fn kappa_from_one_minus_mean_cosine(e: f32) -> f32 {
    if !(e < 1.0) {
        return 0.0;
    }
    if !(e > 0.0) {
        return KAPPA_MAX;
    }
    let r = 1.0 - e;
    (r * (3.0 - r * r) / (e * (2.0 - e))).min(KAPPA_MAX)
}

/// Concentration κ with A₃(κ) = `r` exactly (to f32 precision): the inverse of
/// [`mean_cosine_from_kappa`].
///
/// Newton's method started from Banerjee's approximation. For r < 0.5 it solves A₃(κ) = r;
/// above, it solves 1 − A₃(κ) = 1 − r, which keeps full relative precision as r → 1 (there
/// κ ≈ 1/(1 − r)). Clamped to [0, [`KAPPA_MAX`]] like [`kappa_from_mean_cosine`]; `r ≤ 0`
/// and NaN give 0.
///
/// # Example
/// ```
/// use mcg_vmf::{kappa_from_mean_cosine_exact, mean_cosine_from_kappa};
/// for kappa in [1e-3_f32, 0.7, 5.0, 300.0, 2e4] {
///     let back = kappa_from_mean_cosine_exact(mean_cosine_from_kappa(kappa));
///     assert!((back / kappa - 1.0).abs() < 1e-3, "{kappa} -> {back}");
/// }
/// ```
#[must_use]
pub fn kappa_from_mean_cosine_exact(r: f32) -> f32 {
    if !(r > 0.0) {
        return 0.0;
    }
    if r >= 1.0 {
        return KAPPA_MAX;
    }
    let epsilon = 1.0 - r;
    // A₃(KAPPA_MAX) = 1 − 1/KAPPA_MAX to f32 precision.
    if epsilon <= 1.0 / KAPPA_MAX {
        return KAPPA_MAX;
    }
    let mut kappa = kappa_from_mean_cosine(r);
    for _ in 0..NEWTON_MAX_ITERATIONS {
        // h(κ) = A₃(κ) − r, written as ε − (1 − A₃(κ)) near r = 1.
        let residual = if r < NEWTON_COMPLEMENT_FROM {
            mean_cosine_from_kappa(kappa) - r
        } else {
            epsilon - one_minus_mean_cosine(kappa)
        };
        let slope = mean_cosine_derivative(kappa);
        if !(slope > 0.0) {
            break;
        }
        // A₃ is concave and increasing, so Newton from either side converges; halving the step
        // keeps κ positive when a step would overshoot below zero.
        let mut next = kappa - residual / slope;
        if !(next > 0.0) {
            next = 0.5 * kappa;
        }
        let converged = (next - kappa).abs() <= NEWTON_RELATIVE_STEP * kappa;
        kappa = next.min(KAPPA_MAX);
        if converged {
            break;
        }
    }
    kappa
}

#[cfg(test)]
mod tests {
    use super::*;

    /// f64 reference A₃(κ) = coth κ − 1/κ by its series or closed form.
    fn mean_cosine_f64(kappa: f64) -> f64 {
        if kappa < 1e-2 {
            kappa / 3.0 - kappa.powi(3) / 45.0
        } else {
            1.0 / kappa.tanh() - 1.0 / kappa
        }
    }

    #[test]
    fn mean_cosine_matches_f64_reference() {
        let mut kappa = 1e-8_f64;
        while kappa < 1e6 {
            let got = mean_cosine_from_kappa(kappa as f32) as f64;
            let want = mean_cosine_f64(kappa as f32 as f64);
            assert!(
                ((got - want) / want).abs() < 2e-6,
                "kappa {kappa}: {got} vs {want}"
            );
            kappa *= 1.07;
        }
    }

    #[test]
    fn mean_cosine_edges() {
        assert_eq!(mean_cosine_from_kappa(0.0), 0.0);
        assert_eq!(mean_cosine_from_kappa(-1.0), 0.0);
        assert_eq!(mean_cosine_from_kappa(f32::NAN), 0.0);
        assert_eq!(mean_cosine_from_kappa(f32::INFINITY), 1.0);
        assert!(mean_cosine_from_kappa(f32::MAX) <= 1.0);
    }

    #[test]
    fn mean_cosine_is_monotone() {
        let mut last = 0.0;
        let mut kappa = 1e-6_f32;
        while kappa < 1e6 {
            let r = mean_cosine_from_kappa(kappa);
            assert!(r >= last, "not monotone at {kappa}");
            last = r;
            kappa *= 1.01;
        }
    }

    #[test]
    fn exact_inverse_round_trips() {
        let mut kappa = 1e-6_f32;
        while kappa < 5e5 {
            let back = kappa_from_mean_cosine_exact(mean_cosine_from_kappa(kappa));
            // Near κ ~ 1/ε the f32 spacing of r limits the round trip: δκ/κ ≈ κ·2⁻²⁴.
            let tolerance = 1e-4_f32.max(kappa * 1.2e-7);
            mcg_test_support::assert_close!(back / kappa, 1.0, tolerance, "{kappa} -> {back}");
            kappa *= 1.13;
        }
    }

    #[test]
    fn banerjee_is_close_and_clamped() {
        for kappa in [1.0_f32, 4.9, 10.0, 100.0, 1000.0] {
            let approx = kappa_from_mean_cosine(mean_cosine_from_kappa(kappa));
            assert!(
                approx >= kappa * 0.999 && approx <= kappa * 1.05,
                "{kappa} -> {approx}"
            );
        }
        assert_eq!(kappa_from_mean_cosine(-0.5), 0.0);
        assert_eq!(kappa_from_mean_cosine(f32::NAN), 0.0);
        assert_eq!(kappa_from_mean_cosine(1.5), KAPPA_MAX);
        assert_eq!(kappa_from_mean_cosine(1.0 - f32::EPSILON / 2.0), KAPPA_MAX);
        assert_eq!(kappa_from_mean_cosine_exact(f32::NAN), 0.0);
        assert_eq!(kappa_from_mean_cosine_exact(1.0), KAPPA_MAX);
    }
}
