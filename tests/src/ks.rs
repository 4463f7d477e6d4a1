//! One-sample Kolmogorov-Smirnov test of samples against an analytic CDF.

use std::f64::consts::PI;

/// Result of a one-sample Kolmogorov-Smirnov test: the statistic D and the sample size n.
///
/// D = sup_x |F_n(x) − F(x)| where F_n is the empirical CDF of the n samples and F the CDF
/// under test. Thresholds use the asymptotic Kolmogorov distribution of √n·D, which is
/// accurate to a fraction of a percent for n ≥ 1000 (the suites use n ≥ 10⁵).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KsResult {
    /// The statistic D in [0, 1]; 1 when a sample or a CDF value was NaN.
    pub statistic: f64,
    /// The number of samples n.
    pub n: usize,
}

impl KsResult {
    /// Critical value of D at significance level `alpha`: c(α)/√n with
    /// c(α) = [`kolmogorov_critical_value`]`(alpha)` (c(0.05) ≈ 1.358, c(0.001) ≈ 1.949).
    #[must_use]
    pub fn critical_value(&self, alpha: f64) -> f64 {
        kolmogorov_critical_value(alpha) / (self.n as f64).sqrt()
    }

    /// Asymptotic p-value P(K > √n·D) of the Kolmogorov distribution.
    #[must_use]
    pub fn p_value(&self) -> f64 {
        kolmogorov_survival(self.statistic * (self.n as f64).sqrt())
    }

    /// `true` when D exceeds the critical value at level `alpha` (the hypothesis is rejected).
    #[must_use]
    pub fn rejects(&self, alpha: f64) -> bool {
        self.statistic.is_nan() || self.statistic > self.critical_value(alpha)
    }
}

/// Runs a one-sample Kolmogorov-Smirnov test of `samples` against the CDF `cdf`.
///
/// `samples` is sorted in place. Ties are handled exactly: at each sample both one-sided
/// differences `F_n(x) − F(x)` and `F(x) − F_n(x⁻)` are taken. A NaN sample or a NaN CDF value
/// makes D = 1, so the test rejects. Panics when `samples` is empty.
///
/// # Example
/// ```
/// use mcg_tests::{ks_test, seeded_rng};
/// use rand::RngExt;
/// let mut rng = seeded_rng(1);
/// let mut x: Vec<f64> = (0..10_000).map(|_| rng.random::<f64>()).collect();
/// let result = ks_test(&mut x, |x| x.clamp(0.0, 1.0));
/// assert!(!result.rejects(0.001));
/// ```
pub fn ks_test<F: FnMut(f64) -> f64>(samples: &mut [f64], mut cdf: F) -> KsResult {
    assert!(!samples.is_empty(), "KS test needs at least one sample");
    samples.sort_unstable_by(f64::total_cmp);
    let n = samples.len();
    let inv_n = 1.0 / n as f64;
    let mut statistic = 0.0_f64;
    for (i, &x) in samples.iter().enumerate() {
        let f = cdf(x);
        if f.is_nan() || x.is_nan() {
            return KsResult { statistic: 1.0, n };
        }
        let above = (i + 1) as f64 * inv_n - f;
        let below = f - i as f64 * inv_n;
        statistic = statistic.max(above).max(below);
    }
    KsResult {
        statistic: statistic.min(1.0),
        n,
    }
}

/// Runs [`ks_test`] and panics unless it accepts at significance level `alpha`.
///
/// The panic message names `label` and gives D, the critical value, α, n, √n·D and the
/// p-value. Returns the result so callers can log or check more.
#[track_caller]
pub fn assert_ks<F: FnMut(f64) -> f64>(
    label: &str,
    samples: &mut [f64],
    cdf: F,
    alpha: f64,
) -> KsResult {
    let result = ks_test(samples, cdf);
    let critical = result.critical_value(alpha);
    assert!(
        !result.rejects(alpha),
        "KS test `{label}` rejected: D = {:.6e} > critical value {critical:.6e} at alpha = {alpha} \
         (n = {}, sqrt(n)·D = {:.4}, p = {:.3e})",
        result.statistic,
        result.n,
        result.statistic * (result.n as f64).sqrt(),
        result.p_value(),
    );
    result
}

/// Survival function P(K > λ) of the Kolmogorov distribution (the limit law of √n·D).
///
/// Uses `2 Σ_{k≥1} (−1)^{k−1} e^{−2k²λ²}` for λ ≥ 1.18 and the Jacobi-transformed form
/// `1 − √(2π)/λ Σ_{k≥1} e^{−(2k−1)²π²/(8λ²)}` below, where the first series converges slowly.
/// Both are summed until the terms drop below 10⁻¹⁸; the result is in [0, 1].
#[must_use]
pub fn kolmogorov_survival(lambda: f64) -> f64 {
    if lambda.is_nan() {
        return f64::NAN;
    }
    if lambda <= 0.0 {
        return 1.0;
    }
    if lambda < 1.18 {
        let mut sum = 0.0;
        for k in 1..=64_u32 {
            let odd = f64::from(2 * k - 1);
            let term = (-(odd * odd) * PI * PI / (8.0 * lambda * lambda)).exp();
            sum += term;
            if term < 1e-18 {
                break;
            }
        }
        (1.0 - (2.0 * PI).sqrt() / lambda * sum).clamp(0.0, 1.0)
    } else {
        let mut sum = 0.0;
        let mut sign = 1.0;
        for k in 1..=64_u32 {
            let k = f64::from(k);
            let term = (-2.0 * k * k * lambda * lambda).exp();
            sum += sign * term;
            sign = -sign;
            if term < 1e-18 {
                break;
            }
        }
        (2.0 * sum).clamp(0.0, 1.0)
    }
}

/// The asymptotic critical value c(α) with P(K > c(α)) = α, so that the KS test rejects when
/// √n·D > c(α). c(0.05) ≈ 1.3581, c(0.01) ≈ 1.6276, c(0.001) ≈ 1.9495.
///
/// Solved by bisection of [`kolmogorov_survival`] to 10⁻¹² absolute. Panics unless
/// 0 < α < 1.
#[must_use]
pub fn kolmogorov_critical_value(alpha: f64) -> f64 {
    assert!(
        alpha > 0.0 && alpha < 1.0,
        "significance level {alpha} is not in (0, 1)"
    );
    // P(K > 0.2) = 1 − 6·10⁻¹³ and P(K > 10) = 2e−200: the root lies in between for any
    // α of practical size.
    let (mut lo, mut hi) = (0.2_f64, 10.0_f64);
    while hi - lo > 1e-12 {
        let mid = 0.5 * (lo + hi);
        if kolmogorov_survival(mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::seeded_rng;

    #[test]
    fn critical_values_match_tables() {
        // Tabulated asymptotic values (e.g. Smirnov 1948).
        for (alpha, want) in [
            (0.2, 1.0727),
            (0.1, 1.2238),
            (0.05, 1.3581),
            (0.01, 1.6276),
            (0.001, 1.9495),
        ] {
            let got = kolmogorov_critical_value(alpha);
            mcg_test_support::assert_close!(got, want, 2e-4, "c({alpha}) = {got}, want {want}");
        }
    }

    #[test]
    fn survival_is_continuous_across_the_switch_and_monotone() {
        let below = kolmogorov_survival(1.18 - 1e-9);
        let above = kolmogorov_survival(1.18 + 1e-9);
        mcg_test_support::assert_close!(below, above, 1e-8, "{below} vs {above}");
        let mut last = 1.0;
        for i in 0..=400 {
            let q = kolmogorov_survival(f64::from(i) * 0.01);
            assert!(
                q <= last + 1e-15 && (0.0..=1.0).contains(&q),
                "lambda {}: {q}",
                f64::from(i) * 0.01
            );
            last = q;
        }
        assert_eq!(kolmogorov_survival(0.0), 1.0);
        assert!(kolmogorov_survival(5.0) < 1e-20);
    }

    #[test]
    fn accepts_uniform_samples() {
        let mut rng = seeded_rng(0x4B53_0001);
        let mut x: Vec<f64> = (0..100_000).map(|_| rng.random::<f64>()).collect();
        let result = assert_ks("uniform vs uniform", &mut x, |x| x.clamp(0.0, 1.0), 0.001);
        assert!(result.p_value() > 0.001);
    }

    #[test]
    fn rejects_shifted_samples() {
        // A shift of 0.01 gives D ≈ 0.01, over 3 times the critical value 0.0062 at n = 10⁵.
        let mut rng = seeded_rng(0x4B53_0002);
        let mut x: Vec<f64> = (0..100_000).map(|_| rng.random::<f64>() + 0.01).collect();
        let result = ks_test(&mut x, |x| x.clamp(0.0, 1.0));
        assert!(result.rejects(0.001), "{result:?}");
        mcg_test_support::assert_close!(result.statistic, 0.01, 0.003, "{result:?}");
    }

    #[test]
    fn statistic_of_known_samples() {
        // Samples 0.1 and 0.6 against U(0, 1): D = 0.4, reached at 0.1 (F_n = 0.5, F = 0.1) and at
        // 0.6 (F_n = 1, F = 0.6).
        let result = ks_test(&mut [0.6, 0.1], |x| x);
        mcg_test_support::assert_close!(result.statistic, 0.4, 1e-15, "{result:?}");
        // A tie: two samples at 0.5 jump the empirical CDF from 0 to 1 there.
        let result = ks_test(&mut [0.5, 0.5], |x| x);
        mcg_test_support::assert_close!(result.statistic, 0.5, 1e-15, "{result:?}");
        assert_eq!(ks_test(&mut [0.5, f64::NAN], |x| x).statistic, 1.0);
    }

    #[test]
    #[should_panic(expected = "KS test `shifted` rejected")]
    fn assert_panics_with_label() {
        let mut x: Vec<f64> = (0..1000)
            .map(|i| (f64::from(i) + 0.5) / 1000.0 * 0.5)
            .collect();
        assert_ks("shifted", &mut x, |x| x, 0.001);
    }
}
