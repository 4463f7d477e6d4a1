//! Stochastic MIS: the n-sample estimator (MCMM eq. 8) and the one-sample estimator with
//! uniform (stratified) technique selection (MCMM eq. 9).

use crate::technique::{Technique, finite_or_zero, mixture_pdf, pdf_sum, ratio};

/// n-sample stochastic MIS (West et al. 2020 eq. 12; MCMM eq. 8; MCPG eq. 7 per sample):
///
/// ```text
/// ⟨I⟩_SMIS = Σᵢ f(xᵢ) / Σⱼ p(xᵢ | tⱼ),    xᵢ ~ p(· | tᵢ),  i, j = 1..n
/// ```
///
/// `techniques[i]` is the conditional technique p(· | tᵢ) that drew `samples[i]`, and
/// `values[i] = f(samples[i])`. The density p(t) the tᵢ were drawn from cancels, so it need not
/// be known (MCMM sec. 4). Costs n² pdf evaluations.
///
/// # Unbiasedness (MCMM appendix A)
/// Unbiased for ∫ f when
/// 1. given t₁…tₙ, the samples are independent with xᵢ ~ p(· | tᵢ) — in particular no tⱼ may
///    depend on any xᵢ (a Markov chain that advanced with its own sample breaks this; the
///    [`CyclicShift`](crate::CyclicShift) of TSMIS restores it, MCMM sec. 4.2);
/// 2. every realisation of the set covers the support of f: Σⱼ p(x | tⱼ) > 0 wherever
///    f(x) ≠ 0 (include a classical technique, see [`Defensive`](crate::Defensive)).
///
/// The tⱼ need not be independent of each other (appendix A, eq. 10-13).
///
/// Sums are accumulated in f32; samples with a zero denominator (or an overflowing quotient) contribute 0.
///
/// # Panics
/// If the three slices differ in length.
///
/// # Example
/// ```
/// use mcg_smis::{Technique, smis};
/// # #[derive(Clone, Copy)] struct Boxcar { a: f32, w: f32 }
/// # impl Technique for Boxcar {
/// #     type Sample = f32; type Uniform = f32;
/// #     fn pdf(&self, x: &f32) -> f32 { if *x >= self.a && *x < self.a + self.w { 1.0 / self.w } else { 0.0 } }
/// #     fn sample(&self, u: f32) -> f32 { self.a + u * self.w }
/// # }
/// // Two stochastic techniques (boxes whose placement t was drawn at random) and one sample each.
/// let techniques = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.5, w: 0.5 }];
/// let samples = [techniques[0].sample(0.25), techniques[1].sample(0.5)];
/// let values = samples.map(|x| 2.0 * x); // f(x) = 2x, ∫₀¹ f = 1
/// let estimate = smis(&techniques, &samples, &values);
/// assert!((estimate - (0.5 / 1.0 + 1.5 / 3.0)).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn smis<T: Technique>(techniques: &[T], samples: &[T::Sample], values: &[f32]) -> f32 {
    assert_eq!(techniques.len(), samples.len(), "one sample per technique");
    assert_eq!(samples.len(), values.len(), "one value per sample");
    finite_or_zero(
        samples
            .iter()
            .zip(values)
            .map(|(x, &f)| ratio(f, pdf_sum(techniques, x)))
            .sum(),
    )
}

/// One-sample stochastic MIS over n techniques with uniform selection (MCMM eq. 9):
///
/// ```text
/// ⟨I⟩¹_SMIS = f(x) / ((1/n) Σⱼ p(x | tⱼ)),    j* uniform in 1..n,  x ~ p(· | t_j*)
/// ```
///
/// `x` must have been drawn from a technique of `techniques` chosen with probability 1/n
/// independently of x and of f — by [`sample_uniform_mixture`](crate::sample_uniform_mixture),
/// or, for a population of chains, by a random [`XorPermutation`](crate::XorPermutation) of
/// the states in a tile (SSMIS, MCMM sec. 4.2), which is a stratified selection: every state
/// is picked by exactly one lane. Given the set, the denominator is then x's exact density, so
/// the estimate is unbiased wherever the set covers the support of f. Costs n pdf evaluations.
/// Returns 0 when the denominator is 0 (x outside every technique's support) or the set is
/// empty.
///
/// # Example
/// ```
/// use mcg_smis::{Technique, sample_uniform_mixture, smis_one_sample};
/// # #[derive(Clone, Copy)] struct Boxcar { a: f32, w: f32 }
/// # impl Technique for Boxcar {
/// #     type Sample = f32; type Uniform = f32;
/// #     fn pdf(&self, x: &f32) -> f32 { if *x >= self.a && *x < self.a + self.w { 1.0 / self.w } else { 0.0 } }
/// #     fn sample(&self, u: f32) -> f32 { self.a + u * self.w }
/// # }
/// let techniques = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.5, w: 0.5 }];
/// let (_, x) = sample_uniform_mixture(&techniques, 0.9, 0.5); // picks the second, x = 0.75
/// let estimate = smis_one_sample(&techniques, &x, 2.0 * x);
/// assert_eq!(estimate, 1.5 / ((1.0 + 2.0) / 2.0));
/// ```
#[inline]
#[must_use]
pub fn smis_one_sample<T: Technique>(techniques: &[T], x: &T::Sample, value: f32) -> f32 {
    ratio(value, mixture_pdf(techniques, x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::tests::Boxcar;

    #[test]
    fn n_sample_equals_mis_with_unit_counts() {
        let set = [
            Boxcar { a: 0.0, w: 1.0 },
            Boxcar { a: 0.25, w: 0.5 },
            Boxcar { a: 0.5, w: 0.25 },
        ];
        let xs = [0.1_f32, 0.3, 0.6];
        let f = [1.0_f32, 2.0, 4.0];
        let a = smis(&set, &xs, &f);
        let b = crate::mis_balance(&set, &[1, 1, 1], &xs, &f);
        assert_eq!(a, b);
    }

    #[test]
    fn value_stability() {
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.25, w: 0.5 }];
        // 1/1 + 2/(1 + 2)
        assert_eq!(smis(&set, &[0.1, 0.3], &[1.0, 2.0]), 1.0 + 2.0 / 3.0);
        // 2 / ((1 + 2)/2)
        assert_eq!(smis_one_sample(&set, &0.3, 2.0), 4.0 / 3.0);
        assert_eq!(smis_one_sample::<Boxcar>(&[], &0.3, 2.0), 0.0);
        assert_eq!(smis_one_sample(&set, &7.0, 2.0), 0.0);
    }

    #[test]
    #[should_panic(expected = "one sample per technique")]
    fn mismatched_lengths_panic() {
        let _ = smis(&[Boxcar { a: 0.0, w: 1.0 }], &[0.5, 0.2], &[1.0, 1.0]);
    }
}
