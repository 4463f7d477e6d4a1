//! Defensive mixtures: a classical technique chosen with probability p alongside a stochastic
//! set (MCMM Alg. 2 and appendix A; MCPG Alg. 2).

use crate::SmisError;
use crate::technique::{Technique, pdf_sum, ratio, saturate, select_uniform};

/// A classical technique (cosine, BSDF or uniform sampling) chosen with probability p, and
/// otherwise one of n stochastic techniques chosen uniformly:
///
/// ```text
/// p(x | t₁…tₙ) = p · p_classical(x) + (1 − p) · (1/n) Σⱼ p(x | tⱼ)
/// ```
///
/// This is the density with which MCMM (Alg. 2, p = 0.2) and MCPG (Alg. 2, `p_bsdf`, 0.1-0.15
/// in the authors' engine) sample, and the one-sample estimator f(x)/p(x | t₁…tₙ) built on it
/// ([`estimate`](Defensive::estimate)) is MCMM eq. 9 with the classical technique mixed in as
/// in MMIS sec. 3.1. Since p_classical > 0 wherever f ≠ 0 (for a classical technique that
/// covers the integrand), the mixture always covers the support of f, which is the one
/// requirement MCMM's appendix A adds for an unbiased estimator even when every stochastic
/// technique misses part of the integrand (a light the chains have not found yet).
///
/// `Defensive` is itself a [`Technique`] whose uniform is `(u_select, u)`: `u_select < p`
/// samples the classical technique, otherwise `u_select` is rescaled to pick tⱼ. So it can be
/// one vertex's technique in the [path form](crate::path_pdf), or a conditional technique of
/// SMIS whose t is the whole set.
///
/// With p = 1 the set may be empty; with p = 0 the classical technique is never sampled and
/// contributes nothing to the density.
///
/// # Example
/// ```
/// use mcg_smis::{Defensive, Technique};
/// # #[derive(Clone, Copy)] struct Boxcar { a: f32, w: f32 }
/// # impl Technique for Boxcar {
/// #     type Sample = f32; type Uniform = f32;
/// #     fn pdf(&self, x: &f32) -> f32 { if *x >= self.a && *x < self.a + self.w { 1.0 / self.w } else { 0.0 } }
/// #     fn sample(&self, u: f32) -> f32 { self.a + u * self.w }
/// # }
/// let uniform = Boxcar { a: 0.0, w: 1.0 };
/// let lobes = [Boxcar { a: 0.0, w: 0.25 }, Boxcar { a: 0.5, w: 0.25 }];
/// let mix = Defensive::new(uniform, 0.2, &lobes)?;
/// let x = mix.sample((0.1, 0.5)); // u_select < 0.2: the classical technique
/// assert_eq!(x, 0.5);
/// assert_eq!(mix.pdf(&x), 0.2 * 1.0 + 0.8 * (0.0 + 4.0) / 2.0);
/// assert!((mix.estimate(&x, 1.8) - 1.0).abs() < 1e-6);
/// # Ok::<(), mcg_smis::SmisError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Defensive<'a, C, T> {
    classical: C,
    probability: f32,
    set: &'a [T],
}

impl<'a, C, T, S, U> Defensive<'a, C, T>
where
    C: Technique<Sample = S, Uniform = U>,
    T: Technique<Sample = S, Uniform = U>,
    U: Copy,
{
    /// A defensive mixture choosing `classical` with probability `probability` and otherwise a
    /// technique of `set` uniformly.
    ///
    /// Errors: [`SmisError::ProbabilityOutOfRange`] (NaN or outside [0, 1]),
    /// [`SmisError::EmptyTechniqueSet`] (empty `set` with p < 1).
    #[inline]
    pub fn new(classical: C, probability: f32, set: &'a [T]) -> Result<Self, SmisError> {
        if !(0.0..=1.0).contains(&probability) {
            return Err(SmisError::ProbabilityOutOfRange { probability });
        }
        if set.is_empty() && probability < 1.0 {
            return Err(SmisError::EmptyTechniqueSet);
        }
        Ok(Self {
            classical,
            probability,
            set,
        })
    }

    /// The classical technique.
    #[inline]
    #[must_use]
    pub const fn classical(&self) -> &C {
        &self.classical
    }

    /// The probability p of sampling the classical technique.
    #[inline]
    #[must_use]
    pub const fn probability(&self) -> f32 {
        self.probability
    }

    /// The stochastic set t₁…tₙ.
    #[inline]
    #[must_use]
    pub const fn set(&self) -> &'a [T] {
        self.set
    }

    /// Draws x and also returns which technique drew it: `None` for the classical technique,
    /// `Some(j)` for tⱼ. `u_select < p` picks the classical technique; otherwise
    /// (u_select − p)/(1 − p) ∈ [0, 1) picks j uniformly.
    #[inline]
    #[must_use]
    pub fn sample_with_index(&self, u_select: f32, u: U) -> (Option<usize>, S) {
        if u_select < self.probability || self.set.is_empty() {
            (None, self.classical.sample(u))
        } else {
            let v = (u_select - self.probability) / (1.0 - self.probability);
            let j = select_uniform(self.set.len(), v);
            (Some(j), self.set[j].sample(u))
        }
    }

    /// The one-sample estimate f(x) / p(x | t₁…tₙ) of a sample drawn from this mixture;
    /// 0 where the density is 0.
    #[inline]
    #[must_use]
    pub fn estimate(&self, x: &S, value: f32) -> f32 {
        ratio(value, self.pdf(x))
    }
}

impl<C, T, S, U> Technique for Defensive<'_, C, T>
where
    C: Technique<Sample = S, Uniform = U>,
    T: Technique<Sample = S, Uniform = U>,
    U: Copy,
{
    type Sample = S;
    type Uniform = (f32, U);

    /// p · p_classical(x) + (1 − p) · (1/n) Σⱼ p(x | tⱼ). The classical density is not
    /// evaluated when p = 0, the set's not when p = 1.
    #[inline]
    fn pdf(&self, x: &S) -> f32 {
        let p = self.probability;
        let classical = if p > 0.0 {
            p * self.classical.pdf(x)
        } else {
            0.0
        };
        let stochastic = if p < 1.0 {
            (1.0 - p) * pdf_sum(self.set, x) / self.set.len() as f32
        } else {
            0.0
        };
        saturate(classical + stochastic)
    }

    #[inline]
    fn sample(&self, (u_select, u): (f32, U)) -> S {
        self.sample_with_index(u_select, u).1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::tests::Boxcar;

    const UNIFORM: Boxcar = Boxcar { a: 0.0, w: 1.0 };

    #[test]
    fn validates() {
        let set = [Boxcar { a: 0.0, w: 0.5 }];
        for p in [-0.1, 1.1, f32::NAN, f32::INFINITY] {
            assert!(matches!(
                Defensive::new(UNIFORM, p, &set),
                Err(SmisError::ProbabilityOutOfRange { probability })
                    if probability.to_bits() == p.to_bits()
            ));
        }
        assert_eq!(
            Defensive::<Boxcar, Boxcar>::new(UNIFORM, 0.5, &[]).unwrap_err(),
            SmisError::EmptyTechniqueSet
        );
        let only = Defensive::<Boxcar, Boxcar>::new(UNIFORM, 1.0, &[]).unwrap();
        assert_eq!(only.pdf(&0.3), 1.0);
        assert_eq!(only.sample_with_index(0.99, 0.25), (None, 0.25));
    }

    #[test]
    fn selection_matches_probabilities() {
        let set = [Boxcar { a: 0.0, w: 0.5 }, Boxcar { a: 0.5, w: 0.5 }];
        let mix = Defensive::new(UNIFORM, 0.2, &set).unwrap();
        assert_eq!(mix.sample_with_index(0.0, 0.5).0, None);
        assert_eq!(mix.sample_with_index(0.199, 0.5).0, None);
        assert_eq!(mix.sample_with_index(0.2, 0.5).0, Some(0));
        assert_eq!(mix.sample_with_index(0.59, 0.5).0, Some(0));
        assert_eq!(mix.sample_with_index(0.61, 0.5).0, Some(1));
        assert_eq!(mix.sample_with_index(0.999_999_9, 0.5).0, Some(1));
        // p = 0: never classical, and its density does not enter.
        let none = Defensive::new(UNIFORM, 0.0, &set).unwrap();
        assert_eq!(none.sample_with_index(0.0, 0.5).0, Some(0));
        assert_eq!(none.pdf(&0.25), 1.0);
    }

    #[test]
    fn value_stability() {
        let set = [Boxcar { a: 0.0, w: 0.5 }, Boxcar { a: 0.25, w: 0.5 }];
        let mix = Defensive::new(UNIFORM, 0.25, &set).unwrap();
        assert_eq!(mix.pdf(&0.3), 0.25 + 0.75 * 2.0);
        assert_eq!(mix.pdf(&0.6), 0.25 + 0.75 * 1.0);
        assert_eq!(mix.pdf(&0.9), 0.25);
        assert_eq!(mix.sample((0.9, 0.5)), 0.5);
        assert_eq!(mix.estimate(&0.9, 1.0), 4.0);
        assert_eq!(mix.estimate(&2.0, 1.0), 0.0);
    }
}
