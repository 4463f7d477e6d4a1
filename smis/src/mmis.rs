//! Marginal MIS over several technique spaces, classical techniques mixed in (MMIS eq. 6,
//! sec. 3.1).

use crate::SmisError;
use crate::technique::{Technique, finite_or_zero, pdf_sum, ratio, saturate};

/// A marginal MIS estimator (West et al. 2022, eq. 6) over T technique spaces with nᵢ
/// technique-sample pairs each, plus classical techniques drawn a fixed number of times:
///
/// ```text
/// ⟨I⟩_MMIS = Σ_s f(x_s) / D(x_s),
/// D(x) = Σ_c n_c p_c(x)  +  Σᵢ Σⱼ pᵢ(x | tᵢⱼ)        (i = 1..T, j = 1..nᵢ)
/// ```
///
/// where s runs over every sample: one per technique-sample pair (tᵢⱼ, xᵢⱼ) of every space and
/// n_c per classical technique c. The second sum is eq. 6's denominator (each space's marginal
/// density nᵢ pᵢ(x) estimated by its own pairs, eq. 5); the first is the split of the balance
/// heuristic into classical and marginal parts that sec. 3.1 describes (equivalently, extruding
/// a classical technique over a technique space of identical conditionals). With one space and
/// no classical technique this is n-sample SMIS ([`smis`](crate::smis())); with classical
/// techniques only it is [`mis_balance`](crate::mis_balance).
///
/// Borrowing slices (`spaces: &[&[T]]`) keeps it allocation-free. Spaces of different
/// conditional families share one type `T` through an enum or `&dyn Technique`.
///
/// # Unbiasedness
/// As for SMIS (MCMM appendix A): given all t's, the samples must be independent, each drawn
/// from its own technique, and no t may depend on a sample; and D(x) > 0 wherever f(x) ≠ 0
/// ("at least one sampled conditional technique has positive density", MMIS sec. 3.1).
///
/// # Example
/// ```
/// use mcg_smis::{Mmis, Technique};
/// # #[derive(Clone, Copy)] struct Boxcar { a: f32, w: f32 }
/// # impl Technique for Boxcar {
/// #     type Sample = f32; type Uniform = f32;
/// #     fn pdf(&self, x: &f32) -> f32 { if *x >= self.a && *x < self.a + self.w { 1.0 / self.w } else { 0.0 } }
/// #     fn sample(&self, u: f32) -> f32 { self.a + u * self.w }
/// # }
/// // Two marginal spaces with two drawn conditionals each, plus a defensive uniform drawn twice.
/// let left = [Boxcar { a: 0.0, w: 0.5 }, Boxcar { a: 0.1, w: 0.5 }];
/// let right = [Boxcar { a: 0.5, w: 0.5 }, Boxcar { a: 0.4, w: 0.5 }];
/// let spaces: [&[Boxcar]; 2] = [&left, &right];
/// let uniform = [Boxcar { a: 0.0, w: 1.0 }];
/// let mmis = Mmis::new(&spaces).with_classical(&uniform, &[2])?;
/// assert_eq!(mmis.sample_count(), 6);
/// // D(0.45) = 2·1 + (2 + 2) + (0 + 2)
/// assert_eq!(mmis.denominator(&0.45), 8.0);
/// # Ok::<(), mcg_smis::SmisError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Mmis<'a, C, T> {
    classical: &'a [C],
    classical_counts: &'a [u32],
    spaces: &'a [&'a [T]],
}

impl<'a, T> Mmis<'a, T, T> {
    /// An MMIS estimator over the drawn conditional techniques of each space (`spaces[i][j]` is
    /// the technique of pair (tᵢⱼ, xᵢⱼ)), without classical techniques.
    #[inline]
    #[must_use]
    pub const fn new(spaces: &'a [&'a [T]]) -> Self {
        Self {
            classical: &[],
            classical_counts: &[],
            spaces,
        }
    }
}

impl<'a, C, T, S> Mmis<'a, C, T>
where
    C: Technique<Sample = S>,
    T: Technique<Sample = S>,
{
    /// The same estimator with classical techniques mixed in, `classical[c]` drawn
    /// `counts[c]` times (MMIS sec. 3.1). Replaces classical techniques given before.
    ///
    /// Errors: [`SmisError::CountsLengthMismatch`].
    #[inline]
    pub fn with_classical<C2: Technique<Sample = S>>(
        self,
        classical: &'a [C2],
        counts: &'a [u32],
    ) -> Result<Mmis<'a, C2, T>, SmisError> {
        if classical.len() != counts.len() {
            return Err(SmisError::CountsLengthMismatch {
                expected: classical.len(),
                found: counts.len(),
            });
        }
        Ok(Mmis {
            classical,
            classical_counts: counts,
            spaces: self.spaces,
        })
    }

    /// The technique spaces' drawn conditionals.
    #[inline]
    #[must_use]
    pub const fn spaces(&self) -> &'a [&'a [T]] {
        self.spaces
    }

    /// The classical techniques.
    #[inline]
    #[must_use]
    pub const fn classical(&self) -> &'a [C] {
        self.classical
    }

    /// How many samples one estimate combines: Σ_c n_c + Σᵢ nᵢ.
    #[inline]
    #[must_use]
    pub fn sample_count(&self) -> usize {
        let classical: usize = self.classical_counts.iter().map(|&n| n as usize).sum();
        classical + self.spaces.iter().map(|s| s.len()).sum::<usize>()
    }

    /// D(x) = Σ_c n_c p_c(x) + Σᵢ Σⱼ pᵢ(x | tᵢⱼ), accumulated in f32.
    #[inline]
    #[must_use]
    pub fn denominator(&self, x: &S) -> f32 {
        let classical: f32 = self
            .classical
            .iter()
            .zip(self.classical_counts)
            .map(|(c, &n)| n as f32 * c.pdf(x))
            .sum();
        saturate(
            saturate(classical)
                + self
                    .spaces
                    .iter()
                    .map(|space| pdf_sum(space, x))
                    .fold(0.0, |a, s| saturate(a + s)),
        )
    }

    /// The estimate Σ_s f(x_s) / D(x_s) (MMIS eq. 6) over all [`sample_count`](Self::sample_count)
    /// samples, in any order, with `values[s] = f(samples[s])`. Samples with D = 0 (or an overflowing quotient) contribute 0.
    ///
    /// # Panics
    /// If `samples` and `values` differ in length or the length is not `sample_count()`.
    #[inline]
    #[must_use]
    pub fn estimate(&self, samples: &[S], values: &[f32]) -> f32 {
        assert_eq!(samples.len(), values.len(), "one value per sample");
        assert_eq!(
            samples.len(),
            self.sample_count(),
            "one sample per pair and n_c per classical technique"
        );
        finite_or_zero(
            samples
                .iter()
                .zip(values)
                .map(|(x, &f)| ratio(f, self.denominator(x)))
                .sum(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::tests::Boxcar;

    #[test]
    fn reduces_to_smis_and_mis() {
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.25, w: 0.5 }];
        let xs = [0.1_f32, 0.3];
        let f = [1.0_f32, 2.0];
        let spaces: [&[Boxcar]; 1] = [&set];
        assert_eq!(
            Mmis::new(&spaces).estimate(&xs, &f),
            crate::smis(&set, &xs, &f)
        );
        let none: [&[Boxcar]; 0] = [];
        let mis = Mmis::new(&none).with_classical(&set, &[1, 1]).unwrap();
        assert_eq!(
            mis.estimate(&xs, &f),
            crate::mis_balance(&set, &[1, 1], &xs, &f)
        );
    }

    #[test]
    fn rejects_mismatched_counts() {
        let set = [Boxcar { a: 0.0, w: 1.0 }];
        let spaces: [&[Boxcar]; 1] = [&set];
        assert_eq!(
            Mmis::new(&spaces).with_classical(&set, &[]).unwrap_err(),
            SmisError::CountsLengthMismatch {
                expected: 1,
                found: 0
            }
        );
    }

    #[test]
    fn value_stability() {
        let a = [Boxcar { a: 0.0, w: 0.5 }];
        let b = [Boxcar { a: 0.25, w: 0.5 }, Boxcar { a: 0.5, w: 0.5 }];
        let spaces: [&[Boxcar]; 2] = [&a, &b];
        let u = [Boxcar { a: 0.0, w: 1.0 }];
        let m = Mmis::new(&spaces).with_classical(&u, &[1]).unwrap();
        // D(0.1) = 1 + 2 = 3, D(0.3) = 1 + 2 + 2 = 5, D(0.6) = 1 + 2 + 2 = 5, D(0.9) = 1 + 2.
        let e = m.estimate(&[0.1, 0.3, 0.6, 0.9], &[3.0, 5.0, 10.0, 6.0]);
        assert_eq!(e, 1.0 + 1.0 + 2.0 + 2.0);
    }
}
