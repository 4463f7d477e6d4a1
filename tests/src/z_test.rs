//! z-test of a sample mean against an expected value.

/// Running mean and variance of a stream of f64 values (Welford's algorithm).
///
/// # Example
/// ```
/// use mcg_tests::RunningStats;
/// let stats: RunningStats = [1.0, 2.0, 3.0, 4.0].into_iter().collect();
/// assert_eq!((stats.count(), stats.mean(), stats.variance()), (4, 2.5, 5.0 / 3.0));
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunningStats {
    count: u64,
    mean: f64,
    m2: f64,
}

impl RunningStats {
    /// No values yet.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            count: 0,
            mean: 0.0,
            m2: 0.0,
        }
    }

    /// Adds one value. A NaN makes the mean and variance NaN (and a z-test on them fail).
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// The number of values n.
    #[must_use]
    pub fn count(&self) -> u64 {
        self.count
    }

    /// The sample mean (0 when empty).
    #[must_use]
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// The unbiased sample variance Σ(x − x̄)²/(n − 1) (0 for n < 2).
    #[must_use]
    pub fn variance(&self) -> f64 {
        if self.count < 2 {
            0.0
        } else {
            self.m2 / (self.count - 1) as f64
        }
    }

    /// The standard error of the mean √(variance / n) (0 when empty).
    #[must_use]
    pub fn standard_error(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.variance() / self.count as f64).sqrt()
        }
    }
}

impl Extend<f64> for RunningStats {
    fn extend<I: IntoIterator<Item = f64>>(&mut self, values: I) {
        for x in values {
            self.push(x);
        }
    }
}

impl FromIterator<f64> for RunningStats {
    fn from_iter<I: IntoIterator<Item = f64>>(values: I) -> Self {
        let mut stats = Self::new();
        stats.extend(values);
        stats
    }
}

/// Result of a z-test of a sample mean.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZTestResult {
    /// z = (mean − expected) / standard error.
    pub z: f64,
    /// The number of values n.
    pub n: u64,
    /// The sample mean.
    pub mean: f64,
    /// The value the mean is tested against.
    pub expected: f64,
    /// The standard error of the mean.
    pub standard_error: f64,
}

/// z-test of the mean of `stats` against `expected`, with the standard error estimated from
/// the sample (valid for large n by the central limit theorem).
///
/// When the standard error is 0, z is 0 if the mean equals `expected` exactly and ±∞
/// otherwise; with no values or a NaN, z is NaN.
#[must_use]
pub fn z_test(stats: &RunningStats, expected: f64) -> ZTestResult {
    let standard_error = stats.standard_error();
    let difference = stats.mean() - expected;
    let z = if stats.count() == 0 {
        f64::NAN
    } else if standard_error > 0.0 {
        difference / standard_error
    } else if difference == 0.0 {
        0.0
    } else {
        difference * f64::INFINITY
    };
    ZTestResult {
        z,
        n: stats.count(),
        mean: stats.mean(),
        expected,
        standard_error,
    }
}

/// Runs [`z_test`] and panics unless |z| < `max_sigma` (e.g. 5 for a 5σ test, two-sided
/// α ≈ 5.7·10⁻⁷). The message names `label` and gives z, the mean, the expected value, the
/// standard error and n. Returns the result.
#[track_caller]
pub fn assert_z_test(
    label: &str,
    stats: &RunningStats,
    expected: f64,
    max_sigma: f64,
) -> ZTestResult {
    let result = z_test(stats, expected);
    assert!(
        result.z.abs() < max_sigma,
        "z-test `{label}` rejected: |z| = {:.3} >= {max_sigma} (mean {:.9e}, expected {:.9e}, standard error {:.3e}, n = {})",
        result.z.abs(),
        result.mean,
        result.expected,
        result.standard_error,
        result.n,
    );
    result
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::seeded_rng;

    #[test]
    fn welford_matches_two_pass() {
        let mut rng = seeded_rng(0x2E57_0001);
        let values: Vec<f64> = (0..10_000).map(|_| 1e6 + rng.random::<f64>()).collect();
        let stats: RunningStats = values.iter().copied().collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let var =
            values.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (values.len() - 1) as f64;
        mcg_test_support::assert_close!(stats.mean() / mean, 1.0, 1e-13);
        mcg_test_support::assert_close!(
            stats.variance() / var,
            1.0,
            1e-9,
            "{} vs {var}",
            stats.variance()
        );
    }

    #[test]
    fn accepts_the_true_mean_and_rejects_a_wrong_one() {
        let mut rng = seeded_rng(0x2E57_0002);
        let stats: RunningStats = (0..100_000).map(|_| rng.random::<f64>()).collect();
        let good = assert_z_test("uniform mean", &stats, 0.5, 5.0);
        assert_eq!(good.n, 100_000);
        // The standard error is 1/√(12·10⁵) ≈ 9.1·10⁻⁴, so 0.51 is 11σ away.
        assert!(z_test(&stats, 0.51).z < -5.0);
    }

    #[test]
    fn degenerate_cases() {
        let constant: RunningStats = [2.0; 10].into_iter().collect();
        assert_eq!(z_test(&constant, 2.0).z, 0.0);
        assert_eq!(z_test(&constant, 1.0).z, f64::INFINITY);
        assert!(z_test(&RunningStats::new(), 0.0).z.is_nan());
        let nan: RunningStats = [1.0, f64::NAN].into_iter().collect();
        assert!(z_test(&nan, 1.0).z.is_nan());
    }

    #[test]
    #[should_panic(expected = "z-test `off` rejected")]
    fn assert_panics_with_label() {
        let stats: RunningStats = [1.0, 1.1, 0.9, 1.0].into_iter().collect();
        let _ = assert_z_test("off", &stats, 2.0, 5.0);
    }
}

/// Result of Welch's two-sample t-test of equal means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WelchResult {
    /// t = (x̄_a − x̄_b) / √(s²_a/n_a + s²_b/n_b).
    pub t: f64,
    /// The Welch–Satterthwaite degrees of freedom
    /// ν = (s²_a/n_a + s²_b/n_b)² / ((s²_a/n_a)²/(n_a − 1) + (s²_b/n_b)²/(n_b − 1)).
    pub degrees_of_freedom: f64,
}

impl WelchResult {
    /// The two-sided critical value for a per-test level `alpha`: the (1 − α/2) quantile of
    /// Student's t with [`degrees_of_freedom`](Self::degrees_of_freedom) (the normal quantile
    /// when ν is infinite or undefined, as for two exact samples).
    #[must_use]
    pub fn critical_value(&self, alpha: f64) -> f64 {
        use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
        let p = 1.0 - alpha / 2.0;
        match StudentsT::new(0.0, 1.0, self.degrees_of_freedom) {
            Ok(t) if self.degrees_of_freedom.is_finite() => t.inverse_cdf(p),
            _ => Normal::standard().inverse_cdf(p),
        }
    }
}

/// Welch's t-test that two independent samples have the same mean, their variances
/// estimated separately (Welch 1947). Use it instead of a z-test when a sample is small
/// (tens of values, e.g. independent renderer runs): the t quantile accounts for the noise of
/// the estimated variances, which a normal quantile ignores.
///
/// # Example
/// ```
/// use mcg_tests::{RunningStats, welch_t_test};
/// let a: RunningStats = [1.0, 2.0, 3.0, 4.0].into_iter().collect();
/// let b: RunningStats = [2.0, 3.0, 4.0, 5.0].into_iter().collect();
/// let r = welch_t_test(&a, &b);
/// assert!((r.t + 1.0954).abs() < 1e-4 && (r.degrees_of_freedom - 6.0).abs() < 1e-9);
/// assert!(r.t.abs() < r.critical_value(0.05));
/// ```
#[must_use]
pub fn welch_t_test(a: &RunningStats, b: &RunningStats) -> WelchResult {
    let va = a.variance() / a.count() as f64;
    let vb = b.variance() / b.count() as f64;
    let dof_term = |v: f64, n: u64| {
        if n > 1 { v * v / (n - 1) as f64 } else { 0.0 }
    };
    WelchResult {
        t: (a.mean() - b.mean()) / (va + vb).sqrt(),
        degrees_of_freedom: (va + vb).powi(2) / (dof_term(va, a.count()) + dof_term(vb, b.count())),
    }
}
