//! Chi-square goodness-of-fit test over bins, with small bins merged.

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Smallest expected count of a bin after merging: 5, the usual rule of thumb under which the
/// chi-square approximation of Pearson's statistic holds.
pub const MIN_EXPECTED_COUNT: f64 = 5.0;

/// Result of a chi-square goodness-of-fit test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChiSquareResult {
    /// Pearson's statistic X² = Σ (O − E)² / E over the merged bins.
    pub statistic: f64,
    /// Degrees of freedom: merged bins − 1.
    pub degrees_of_freedom: usize,
    /// P(χ²_df > X²); 1 when there are no degrees of freedom (a single merged bin).
    pub p_value: f64,
    /// The number of bins after merging.
    pub merged_bins: usize,
    /// Total observed count Σ O.
    pub observed_total: u64,
    /// Total expected count Σ E.
    pub expected_total: f64,
}

impl ChiSquareResult {
    /// `true` when the p-value is below `alpha` (the hypothesis is rejected).
    #[must_use]
    pub fn rejects(&self, alpha: f64) -> bool {
        self.p_value.is_nan() || self.p_value < alpha
    }
}

/// Merges adjacent bins until each expected count is at least `min_expected`.
///
/// The rule: walk the bins in the given order and add each to an open group; close the group
/// as soon as its expected count reaches `min_expected`. A trailing group that stays below it
/// is merged into the last closed group (or is the only group when none was closed). Bins
/// should therefore be ordered so that neighbours in the slice are neighbours in the domain
/// ([`SphereBins`](crate::SphereBins) orders by band, then sector).
///
/// Returns the merged observed and expected counts. Panics when the slices differ in length or
/// an expected count is negative or NaN.
#[must_use]
pub fn merge_bins(observed: &[u64], expected: &[f64], min_expected: f64) -> (Vec<u64>, Vec<f64>) {
    assert_eq!(
        observed.len(),
        expected.len(),
        "observed and expected counts differ in length"
    );
    let mut merged_observed = Vec::new();
    let mut merged_expected = Vec::new();
    let (mut open_observed, mut open_expected) = (0_u64, 0.0_f64);
    for (&o, &e) in observed.iter().zip(expected) {
        assert!(e >= 0.0, "expected count {e} is negative or NaN");
        open_observed += o;
        open_expected += e;
        if open_expected >= min_expected {
            merged_observed.push(open_observed);
            merged_expected.push(open_expected);
            (open_observed, open_expected) = (0, 0.0);
        }
    }
    if open_observed > 0 || open_expected > 0.0 || merged_expected.is_empty() {
        match (merged_observed.last_mut(), merged_expected.last_mut()) {
            (Some(o), Some(e)) => {
                *o += open_observed;
                *e += open_expected;
            }
            _ => {
                merged_observed.push(open_observed);
                merged_expected.push(open_expected);
            }
        }
    }
    (merged_observed, merged_expected)
}

/// Pearson's chi-square test of `observed` counts against `expected` counts, after merging
/// adjacent bins with [`merge_bins`] until each expected count is at least
/// [`MIN_EXPECTED_COUNT`].
///
/// The expected counts are used as given (they should sum to the observed total, e.g.
/// probabilities times n); the degrees of freedom are merged bins − 1 and the p-value comes
/// from `statrs`' chi-square distribution. Panics when the total expected count is not
/// positive or an expected count is negative or NaN.
///
/// # Example
/// ```
/// use mcg_tests::chi_square_test;
/// let result = chi_square_test(&[98, 105, 97], &[100.0, 100.0, 100.0]);
/// assert_eq!(result.degrees_of_freedom, 2);
/// assert!((result.statistic - 0.38).abs() < 1e-12 && !result.rejects(0.001));
/// ```
#[must_use]
pub fn chi_square_test(observed: &[u64], expected: &[f64]) -> ChiSquareResult {
    let (merged_observed, merged_expected) = merge_bins(observed, expected, MIN_EXPECTED_COUNT);
    let expected_total: f64 = merged_expected.iter().sum();
    assert!(
        expected_total > 0.0,
        "total expected count {expected_total} is not positive"
    );
    let statistic: f64 = merged_observed
        .iter()
        .zip(&merged_expected)
        .map(|(&o, &e)| {
            let d = o as f64 - e;
            d * d / e
        })
        .sum();
    let degrees_of_freedom = merged_expected.len() - 1;
    let p_value = if degrees_of_freedom == 0 {
        1.0
    } else {
        let distribution =
            ChiSquared::new(degrees_of_freedom as f64).expect("positive degrees of freedom");
        distribution.sf(statistic)
    };
    ChiSquareResult {
        statistic,
        degrees_of_freedom,
        p_value,
        merged_bins: merged_expected.len(),
        observed_total: merged_observed.iter().sum(),
        expected_total,
    }
}

/// Runs [`chi_square_test`] and panics unless it accepts at significance level `alpha`, or
/// when the merged bins leave no degree of freedom (a test without power).
///
/// The panic message names `label` and gives X², the degrees of freedom, the p-value, α, the
/// number of merged bins and the totals. Returns the result.
#[track_caller]
pub fn assert_chi_square(
    label: &str,
    observed: &[u64],
    expected: &[f64],
    alpha: f64,
) -> ChiSquareResult {
    let result = chi_square_test(observed, expected);
    assert!(
        result.degrees_of_freedom > 0,
        "chi-square test `{label}` has no degrees of freedom ({} bins merged into one)",
        observed.len(),
    );
    assert!(
        !result.rejects(alpha),
        "chi-square test `{label}` rejected: X² = {:.3} with {} degrees of freedom, p = {:.3e} < alpha = {alpha} \
         ({} merged bins of {}, observed total {}, expected total {:.3})",
        result.statistic,
        result.degrees_of_freedom,
        result.p_value,
        result.merged_bins,
        observed.len(),
        result.observed_total,
        result.expected_total,
    );
    result
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use crate::seeded_rng;

    fn roll_die(seed: u64, n: usize, faces: &[f64; 6]) -> Vec<u64> {
        let total: f64 = faces.iter().sum();
        let mut counts = vec![0_u64; 6];
        let mut rng = seeded_rng(seed);
        for _ in 0..n {
            let mut u = rng.random::<f64>() * total;
            let mut face = 5;
            for (i, &w) in faces.iter().enumerate() {
                if u < w {
                    face = i;
                    break;
                }
                u -= w;
            }
            counts[face] += 1;
        }
        counts
    }

    #[test]
    fn accepts_a_fair_die() {
        let n = 60_000;
        let counts = roll_die(0xD1CE_0001, n, &[1.0; 6]);
        let result = assert_chi_square("fair die", &counts, &[n as f64 / 6.0; 6], 0.001);
        assert_eq!(result.degrees_of_freedom, 5);
    }

    #[test]
    fn rejects_a_loaded_die() {
        // Face 6 comes up with probability 0.18 and the others with 0.164 instead of 1/6: the
        // expected X² is 800²/10⁴ + 5 · 160²/10⁴ ≈ 77 on 5 degrees of freedom (p ≈ 10⁻¹⁴).
        let n = 60_000;
        let counts = roll_die(0xD1CE_0002, n, &[0.164, 0.164, 0.164, 0.164, 0.164, 0.18]);
        let result = chi_square_test(&counts, &[n as f64 / 6.0; 6]);
        assert!(result.rejects(0.001), "{result:?}");
    }

    #[test]
    fn merges_small_bins_by_the_documented_rule() {
        let (o, e) = merge_bins(&[1, 2, 3, 4, 5, 6], &[1.0, 2.0, 3.0, 10.0, 1.0, 1.0], 5.0);
        // {1, 2, 3} reaches 6; {10} alone; the trailing {1, 1} joins the group before it.
        assert_eq!(o, vec![6, 15]);
        assert_eq!(e, vec![6.0, 12.0]);
        let (o, e) = merge_bins(&[3, 4], &[1.0, 2.0], 5.0);
        assert_eq!((o, e), (vec![7], vec![3.0]));
        let result = chi_square_test(&[3, 4], &[1.0, 2.0]);
        assert_eq!(result.degrees_of_freedom, 0);
        assert_eq!(result.p_value, 1.0);
    }

    #[test]
    #[should_panic(expected = "chi-square test `loaded` rejected")]
    fn assert_panics_with_label() {
        let _ = assert_chi_square("loaded", &[200, 100, 100], &[133.0, 133.0, 134.0], 0.001);
    }
}
