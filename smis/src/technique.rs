//! Sampling techniques: a conditional density p(x | t) and a sampler driven by explicit uniforms.

/// A sampling technique: the conditional density p(x | t) of one fixed auxiliary value t and a
/// sampler for it.
///
/// In SMIS and MMIS (West et al. 2020; MMIS eq. 2) a *marginal* technique first draws an
/// auxiliary variable t ~ p(t) (a vMF lobe's (μ, κ), a path prefix, a Markov chain state) and
/// then x ~ p(x | t). A value of a type implementing `Technique` is one such *conditional*
/// technique: the t is baked into the value (a lobe with its parameters), and the estimators of
/// this crate only ever evaluate p(x | t) — the density p(t) of the auxiliary variable cancels
/// (MCMM sec. 4, MCPG eq. 5). A *classical* technique (cosine or BSDF sampling, a uniform
/// distribution) has no auxiliary variable and implements the same trait.
///
/// # Contract
/// - [`pdf`](Technique::pdf) is the density of [`sample`](Technique::sample)'s output with
///   respect to the measure the caller integrates in (solid angle on S², Lebesgue on [0, 1], …),
///   finite and ≥ 0; 0 outside the technique's support.
/// - [`sample`](Technique::sample) consumes only the uniforms it is given (no hidden
///   randomness), each in [0, 1).
///
/// # Example
/// A classical technique on [0, 1] with density 2x, sampled by inversion:
/// ```
/// use mcg_smis::Technique;
///
/// struct Ramp;
/// impl Technique for Ramp {
///     type Sample = f32;
///     type Uniform = f32;
///     fn pdf(&self, x: &f32) -> f32 {
///         if (0.0..=1.0).contains(x) { 2.0 * x } else { 0.0 }
///     }
///     fn sample(&self, u: f32) -> f32 {
///         u.sqrt()
///     }
/// }
/// assert_eq!(Ramp.sample(0.25), 0.5);
/// assert_eq!(Ramp.pdf(&0.5), 1.0);
/// ```
pub trait Technique {
    /// What the technique samples: `f32` on an interval, a direction (`glam::Vec3`) on S², a
    /// path vertex, ….
    type Sample;
    /// The uniforms one sample consumes: `f32` for one dimension, `[f32; 2]` or `glam::Vec2`
    /// for a direction, a tuple when a selection uniform is added (see
    /// [`Defensive`](crate::Defensive)).
    type Uniform: Copy;

    /// The conditional density p(x | t) of `x`, finite and ≥ 0.
    #[must_use]
    fn pdf(&self, x: &Self::Sample) -> f32;

    /// Draws x ~ p(x | t) from the uniforms `u` in [0, 1).
    #[must_use]
    fn sample(&self, u: Self::Uniform) -> Self::Sample;
}

impl<T: Technique + ?Sized> Technique for &T {
    type Sample = T::Sample;
    type Uniform = T::Uniform;

    #[inline]
    fn pdf(&self, x: &Self::Sample) -> f32 {
        (**self).pdf(x)
    }

    #[inline]
    fn sample(&self, u: Self::Uniform) -> Self::Sample {
        (**self).sample(u)
    }
}

/// Σⱼ p(x | tⱼ) over a set of conditional techniques, accumulated in f32 in slice order.
///
/// This is the denominator of the n-sample SMIS estimator (MCMM eq. 8, MCPG eq. 7) and one
/// factor of the path form (MCPG eq. 6). 0 for an empty set. A sum of finite densities that
/// overflows saturates at `f32::MAX` (so finite densities give a finite sum).
#[inline]
#[must_use]
pub fn pdf_sum<T: Technique>(techniques: &[T], x: &T::Sample) -> f32 {
    saturate(techniques.iter().map(|t| t.pdf(x)).sum())
}

/// (1/n) Σⱼ p(x | tⱼ): the density of x when one of the n techniques is chosen uniformly at
/// random and sampled (the denominator of the one-sample SMIS estimator, MCMM eq. 9).
/// 0 for an empty set.
#[inline]
#[must_use]
pub fn mixture_pdf<T: Technique>(techniques: &[T], x: &T::Sample) -> f32 {
    if techniques.is_empty() {
        return 0.0;
    }
    pdf_sum(techniques, x) / techniques.len() as f32
}

/// Index ⌊u·n⌋ of the technique a uniform `u` ∈ [0, 1) selects out of `n` ≥ 1, clamped to
/// n − 1 (so u = 1.0, rounding and out-of-range uniforms stay in bounds; NaN selects 0).
///
/// # Panics
/// If `n == 0`.
#[inline]
#[must_use]
pub fn select_uniform(n: usize, u: f32) -> usize {
    assert!(n > 0, "cannot select a technique out of an empty set");
    // `as` saturates: negative and NaN give 0, huge values give usize::MAX.
    ((u * n as f32) as usize).min(n - 1)
}

/// Chooses one of `techniques` uniformly with `u_select` and draws a sample from it with `u`;
/// returns the chosen index and the sample. The sample's density given the set is
/// [`mixture_pdf`] (MCMM eq. 9).
///
/// # Panics
/// If `techniques` is empty.
#[inline]
#[must_use]
pub fn sample_uniform_mixture<T: Technique>(
    techniques: &[T],
    u_select: f32,
    u: T::Uniform,
) -> (usize, T::Sample) {
    let j = select_uniform(techniques.len(), u_select);
    (j, techniques[j].sample(u))
}

/// `value / denominator`, or 0 when the denominator is not > 0 (zero, negative or NaN) or the
/// quotient is not finite.
///
/// A sample can only be drawn where its own technique's density is positive, and that density
/// is part of every denominator in this crate, so a zero denominator means the sample lies
/// outside every technique's support (or its density underflowed in f32): it contributes 0
/// instead of ±∞ or NaN. The same holds for a quotient that overflows f32 (a subnormal density
/// far in a lobe's tail, or a NaN value): one such sample would turn an accumulated pixel into
/// ∞ or NaN, so it contributes 0 — a bias only where f32 cannot represent the estimate at all.
#[inline(always)]
pub(crate) fn ratio(value: f32, denominator: f32) -> f32 {
    let r = value / denominator;
    if denominator > 0.0 && r.is_finite() {
        r
    } else {
        0.0
    }
}

/// `x` with +∞ replaced by `f32::MAX` (NaN stays NaN): how sums and products of finite
/// densities that overflow are kept finite.
#[inline(always)]
pub(crate) fn saturate(x: f32) -> f32 {
    if x > f32::MAX { f32::MAX } else { x }
}

/// `sum` if finite, else 0: an estimate whose sum of (finite) terms overflows f32 is as
/// unrepresentable as one overflowing term, and is dropped the same way (see `ratio`).
///
/// See also [`finite_non_negative_or_zero`] for scores and weights.
///
/// # Example
/// ```
/// use mcg_smis::finite_or_zero;
/// assert_eq!(finite_or_zero(-2.5), -2.5);
/// assert_eq!(finite_or_zero(f32::MAX * 2.0), 0.0);
/// ```
#[inline(always)]
#[must_use]
pub fn finite_or_zero(sum: f32) -> f32 {
    if sum.is_finite() { sum } else { 0.0 }
}

/// `x` when it is finite and non-negative, otherwise 0: how the guiding crates keep scores,
/// weights and targets that are NaN, infinite or negative out of their states (−0 passes).
///
/// See also [`finite_or_zero`] for signed estimates.
///
/// # Example
/// ```
/// use mcg_smis::finite_non_negative_or_zero;
/// assert_eq!(finite_non_negative_or_zero(2.5), 2.5);
/// assert_eq!(finite_non_negative_or_zero(-1.0), 0.0);
/// assert_eq!(finite_non_negative_or_zero(f32::NAN), 0.0);
/// ```
#[inline(always)]
#[must_use]
pub fn finite_non_negative_or_zero(x: f32) -> f32 {
    if (0.0..f32::INFINITY).contains(&x) {
        x
    } else {
        0.0
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Uniform density on [a, a + w) (a test technique).
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Boxcar {
        pub a: f32,
        pub w: f32,
    }

    impl Technique for Boxcar {
        type Sample = f32;
        type Uniform = f32;
        fn pdf(&self, x: &f32) -> f32 {
            if *x >= self.a && *x < self.a + self.w {
                1.0 / self.w
            } else {
                0.0
            }
        }
        fn sample(&self, u: f32) -> f32 {
            self.a + u * self.w
        }
    }

    #[test]
    fn sums_and_mixture() {
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.0, w: 0.5 }];
        assert_eq!(pdf_sum(&set, &0.25), 3.0);
        assert_eq!(mixture_pdf(&set, &0.25), 1.5);
        assert_eq!(mixture_pdf(&set, &0.75), 0.5);
        assert_eq!(mixture_pdf::<Boxcar>(&[], &0.75), 0.0);
        // References and trait objects are techniques too.
        let dynamic: [&dyn Technique<Sample = f32, Uniform = f32>; 2] = [&set[0], &set[1]];
        assert_eq!(pdf_sum(&dynamic, &0.25), 3.0);
    }

    #[test]
    fn selection_stays_in_bounds() {
        assert_eq!(select_uniform(4, 0.0), 0);
        assert_eq!(select_uniform(4, 0.2499), 0);
        assert_eq!(select_uniform(4, 0.25), 1);
        assert_eq!(select_uniform(4, 0.999_999_94), 3);
        assert_eq!(select_uniform(4, 1.0), 3);
        assert_eq!(select_uniform(4, 7.0), 3);
        assert_eq!(select_uniform(4, -1.0), 0);
        assert_eq!(select_uniform(4, f32::NAN), 0);
        assert_eq!(select_uniform(1, 0.7), 0);
        let set = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 2.0, w: 1.0 }];
        assert_eq!(sample_uniform_mixture(&set, 0.75, 0.5), (1, 2.5));
    }

    #[test]
    #[should_panic(expected = "empty set")]
    fn selection_from_empty_set_panics() {
        let _ = select_uniform(0, 0.5);
    }

    #[test]
    fn ratio_never_produces_nan() {
        assert_eq!(ratio(1.0, 0.0), 0.0);
        assert_eq!(ratio(1.0, f32::NAN), 0.0);
        assert_eq!(ratio(1.0, -2.0), 0.0);
        assert_eq!(ratio(3.0, 2.0), 1.5);
        // Overflowing quotients and NaN values contribute 0 too.
        assert_eq!(ratio(1.0, 1e-40), 0.0);
        assert_eq!(ratio(1e30, 1e-20), 0.0);
        assert_eq!(ratio(f32::NAN, 1.0), 0.0);
        assert_eq!(ratio(f32::INFINITY, 1.0), 0.0);
        assert_eq!(finite_or_zero(f32::MAX + f32::MAX), 0.0);
        assert_eq!(finite_or_zero(2.5), 2.5);
        assert_eq!(finite_or_zero(-2.5), -2.5);
        assert_eq!(finite_or_zero(f32::NAN), 0.0);
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -1e-30] {
            assert_eq!(finite_non_negative_or_zero(bad), 0.0, "{bad}");
        }
        assert_eq!(finite_non_negative_or_zero(f32::MAX), f32::MAX);
        assert_eq!(finite_non_negative_or_zero(0.25), 0.25);
    }
}
