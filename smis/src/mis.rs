//! Classical multi-sample MIS with the balance heuristic: the estimator SMIS and MMIS approximate.

use crate::technique::{Technique, finite_or_zero, ratio, saturate};

/// The balance-heuristic denominator Σₖ nₖ pₖ(x) of techniques pₖ drawn nₖ times each
/// (MMIS eq. 3-4, Veach and Guibas 1995). Accumulated in f32.
///
/// # Panics
/// If `techniques` and `counts` differ in length.
#[inline]
#[must_use]
pub fn balance_denominator<T: Technique>(techniques: &[T], counts: &[u32], x: &T::Sample) -> f32 {
    assert_eq!(
        techniques.len(),
        counts.len(),
        "one sample count per technique"
    );
    saturate(
        techniques
            .iter()
            .zip(counts)
            .map(|(t, &n)| n as f32 * t.pdf(x))
            .sum(),
    )
}

/// Multi-sample MIS with the balance heuristic (MMIS eq. 1 with weights eq. 3, i.e. eq. 4):
///
/// ```text
/// ⟨I⟩_MIS = Σᵢ Σⱼ f(xᵢⱼ) / Σₖ nₖ pₖ(xᵢⱼ),    xᵢⱼ ~ pᵢ,  j = 1..nᵢ
/// ```
///
/// `samples` holds all Σᵢ nᵢ samples (in any order: the balance heuristic does not need to know
/// which technique drew a sample) and `values[s] = f(samples[s])`. The caller must have drawn
/// exactly `counts[i]` of them from `techniques[i]`, independently; then the estimator is
/// unbiased wherever Σₖ nₖ pₖ > 0 covers the support of f. Samples with a zero denominator
/// contribute 0.
///
/// This is the reference that SMIS (MCMM eq. 8) and MMIS (eq. 6) approximate when the pₖ are
/// marginal densities that cannot be evaluated. Costs Σᵢ nᵢ · T pdf evaluations. Sums are
/// accumulated in f32 (exact enough for the tens of samples a renderer combines; average many
/// estimates in f64).
///
/// # Panics
/// If `techniques` and `counts`, or `samples` and `values`, differ in length.
///
/// # Example
/// ```
/// use mcg_smis::{Technique, mis_balance};
/// # struct Uniform01;
/// # impl Technique for Uniform01 {
/// #     type Sample = f32; type Uniform = f32;
/// #     fn pdf(&self, x: &f32) -> f32 { if (0.0..1.0).contains(x) { 1.0 } else { 0.0 } }
/// #     fn sample(&self, u: f32) -> f32 { u }
/// # }
/// // Two draws from one uniform technique: the estimate of ∫₀¹ x dx is the mean of x.
/// let xs = [0.25, 0.75];
/// let f = xs.map(|x| x);
/// assert_eq!(mis_balance(&[Uniform01], &[2], &xs, &f), 0.5);
/// ```
#[inline]
#[must_use]
pub fn mis_balance<T: Technique>(
    techniques: &[T],
    counts: &[u32],
    samples: &[T::Sample],
    values: &[f32],
) -> f32 {
    assert_eq!(samples.len(), values.len(), "one value per sample");
    finite_or_zero(
        samples
            .iter()
            .zip(values)
            .map(|(x, &f)| ratio(f, balance_denominator(techniques, counts, x)))
            .sum(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::tests::Boxcar;

    #[test]
    fn balance_weights_sum_to_one() {
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.0, w: 0.5 }];
        let counts = [3, 1];
        for x in [0.1_f32, 0.4, 0.7] {
            let d = balance_denominator(&set, &counts, &x);
            let w: f32 = set
                .iter()
                .zip(counts)
                .map(|(t, n)| n as f32 * t.pdf(&x) / d)
                .sum();
            mcg_test_support::assert_close!(w, 1.0, 1e-6);
        }
    }

    #[test]
    fn zero_denominator_contributes_nothing() {
        let set = [Boxcar { a: 0.0, w: 0.5 }];
        assert_eq!(mis_balance(&set, &[1], &[0.75], &[5.0]), 0.0);
    }

    #[test]
    fn value_stability() {
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.25, w: 0.5 }];
        let xs = [0.1_f32, 0.3, 0.6];
        let f = [1.0_f32, 2.0, 4.0];
        // Counts (2, 1): 1/(2·1) + 2/(2·1 + 1·2) + 4/(2·1 + 1·2).
        let e = mis_balance(&set, &[2, 1], &xs, &f);
        assert_eq!(e, 0.5 + 0.5 + 1.0);
    }

    #[test]
    #[should_panic(expected = "one sample count per technique")]
    fn mismatched_counts_panic() {
        let _ = balance_denominator(&[Boxcar { a: 0.0, w: 1.0 }], &[], &0.5);
    }
}
