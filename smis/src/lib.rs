//! # mcg-smis: stochastic and marginal multiple importance sampling
//!
//! Markov chain guiding (MCMM, Dittebrandt et al. 2023; MCPG, Alber et al. 2025) samples from
//! lobes whose parameters t come from a Markov chain with an unknown equilibrium density p(t),
//! so the marginal density p(x) = ∫ p(x | t) p(t) dt of a sample cannot be evaluated. Stochastic
//! MIS (West et al. 2020) and marginal MIS (West et al. 2022) replace it by a sum of the
//! *conditional* densities of a few drawn techniques, and stay unbiased. This crate gives
//! renderer authors those estimators, generic over the sample type, `#![no_std]` and
//! allocation-free, and the two permutations that keep them unbiased when the chains advance
//! with the very samples the estimator uses.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`Technique`] | conditional density p(x \| t) and sampling from explicit uniforms; classical techniques fit too | MMIS eq. 2 |
//! | [`pdf_sum`], [`mixture_pdf`], [`select_uniform`], [`sample_uniform_mixture`] | Σⱼ p(x \| tⱼ), its mean, uniform technique choice | MCMM eq. 8, 9 |
//! | [`mis_balance`], [`balance_denominator`] | multi-sample MIS with the balance heuristic (the reference) | MMIS eq. 1, 3, 4 |
//! | [`smis()`] | n-sample SMIS Σᵢ f(xᵢ) / Σⱼ p(xᵢ \| tⱼ) | MCMM eq. 8, MCPG eq. 7 |
//! | [`smis_one_sample`] | one-sample SMIS f(x) / ((1/n) Σⱼ p(x \| tⱼ)) with uniform (stratified) selection | MCMM eq. 9 |
//! | [`Mmis`] | MMIS over T technique spaces with nᵢ pairs each, classical techniques mixed in | MMIS eq. 6, sec. 3.1 |
//! | [`Defensive`] | classical technique with probability p plus a stochastic set: p·p_c + (1 − p)(1/n)Σⱼ p(x \| tⱼ) | MCMM Alg. 2, App. A; MCPG Alg. 2 |
//! | [`path_pdf`], [`path_mixture_pdf`], [`path_estimate`], [`path_pdf_naive`] | product over vertices of a sum over each vertex's set, linear in the vertex count (and the exponential reference) | MCPG eq. 6, MMIS eq. 14 |
//! | [`CyclicShift`], [`cyclic_source_lane`] | TSMIS: cyclic shift of chain states within a tile of ≤ 32 lanes | MCMM sec. 4.2 |
//! | [`XorPermutation`], [`xor_source_lane`] | SSMIS: xor-mask permutation within a power-of-two tile of ≤ 32 lanes | MCMM sec. 4.2 |
//! | [`finite_or_zero`], [`finite_non_negative_or_zero`] | how estimates, scores and weights that are NaN, infinite (or negative) are dropped | — |
//!
//! ## When the estimators are unbiased (MCMM appendix A)
//! 1. Given all auxiliary values t, the samples are independent and xᵢ ~ p(· | tᵢ); no t may
//!    depend on a sample that the same estimator uses. A chain that advances with its own
//!    sample violates this for its next lobe: decorrelate with [`CyclicShift`] (TSMIS) or
//!    [`XorPermutation`] (SSMIS) across a population of chains.
//! 2. The techniques cover the integrand: Σⱼ p(x | tⱼ) > 0 wherever f(x) ≠ 0. Stochastic lobes
//!    that have not found a light miss it; a [`Defensive`] classical technique guarantees it.
//!
//! The t's need not be independent of each other, and their density p(t) never appears.
//!
//! ## Conventions
//! - A [`Technique`] value is one *conditional* technique p(· | t): the auxiliary value t is
//!   baked into it (a lobe with its parameters). Estimators take slices of techniques, samples
//!   and values `f(x)` (which the renderer computes), never `Vec`s.
//! - No hidden randomness: sampling and selections take uniforms in [0, 1) from the caller.
//! - f32 throughout; sums over a set are accumulated in f32 in slice order (sets are tens of
//!   techniques, so the relative rounding error stays below n·2⁻²⁴; accumulate many estimates
//!   in f64 yourself). A sample whose denominator is not > 0 (outside every technique's support,
//!   or NaN), or whose quotient f/denominator overflows f32 (a subnormal density deep in a
//!   lobe's tail), contributes 0, and an estimate whose sum overflows is 0, so no estimator
//!   returns NaN or ∞ — one such sample would otherwise poison a whole accumulated pixel.
//! - Slices that must match in length are checked with `assert_eq!` (a programming error, not
//!   bad data). Constructors validate and return `Result<_, SmisError>`.
//!
//! ## Features
//! - `std` (default) and `libm`: accepted for uniformity with the other mcg math crates. This
//!   crate calls no float function outside `core`, so it builds `#![no_std]` with neither and
//!   depends on no other crate.
//!
//! ## Example
//! ```
//! use mcg_smis::{CyclicShift, Defensive, Technique, smis, smis_one_sample};
//!
//! /// Uniform density on [a, a + w): a "lobe" whose placement a is the auxiliary variable t.
//! #[derive(Clone, Copy)]
//! struct Boxcar { a: f32, w: f32 }
//! impl Technique for Boxcar {
//!     type Sample = f32;
//!     type Uniform = f32;
//!     fn pdf(&self, x: &f32) -> f32 {
//!         if *x >= self.a && *x < self.a + self.w { 1.0 / self.w } else { 0.0 }
//!     }
//!     fn sample(&self, u: f32) -> f32 { self.a + u * self.w }
//! }
//!
//! let f = |x: f32| 3.0 * x * x; // ∫₀¹ f = 1
//!
//! // n-sample SMIS (MCMM eq. 8): one sample from each of n drawn techniques.
//! let lobes = [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.5, w: 0.5 }];
//! let xs = [lobes[0].sample(0.3), lobes[1].sample(0.6)];
//! let estimate = smis(&lobes, &xs, &xs.map(f));
//! assert!(estimate > 0.0);
//!
//! // One-sample SMIS with a defensive uniform technique (p = 0.2) mixed in.
//! let mix = Defensive::new(Boxcar { a: 0.0, w: 1.0 }, 0.2, &lobes)?;
//! let x = mix.sample((0.7, 0.4));
//! let one = mix.estimate(&x, f(x));
//! assert!(one.is_finite());
//! assert_eq!(smis_one_sample(&lobes, &0.9, 1.0), 1.0 / ((1.0 + 2.0) / 2.0));
//!
//! // TSMIS decorrelation: shift chain states by one lane per step within a tile.
//! let mut states = [0_u8, 1, 2, 3];
//! CyclicShift::new(4, 1)?.apply(&mut states);
//! assert_eq!(states, [3, 0, 1, 2]);
//! # Ok::<(), mcg_smis::SmisError>(())
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(any(feature = "std", test))]
extern crate std;

mod defensive;
mod error;
mod mis;
mod mmis;
mod path;
mod smis;
mod ssmis;
mod technique;
mod tsmis;

pub use defensive::Defensive;
pub use error::SmisError;
pub use mis::{balance_denominator, mis_balance};
pub use mmis::Mmis;
pub use path::{
    MAX_NAIVE_PATH_VERTICES, path_estimate, path_mixture_pdf, path_pdf, path_pdf_naive,
};
pub use smis::{smis, smis_one_sample};
pub use ssmis::{XorPermutation, xor_source_lane};
pub use technique::{
    Technique, finite_non_negative_or_zero, finite_or_zero, mixture_pdf, pdf_sum,
    sample_uniform_mixture, select_uniform,
};
pub use tsmis::{CyclicShift, MAX_TILE_SIZE, cyclic_source_lane};

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

#[cfg(test)]
mod properties {
    use proptest::prelude::*;

    use crate::technique::tests::Boxcar;
    use crate::*;

    fn boxcar() -> impl Strategy<Value = Boxcar> {
        (
            0.0_f32..0.9,
            prop_oneof![0.05_f32..1.0, 1e-3_f32..1e-2, 1e10_f32..1e12],
        )
            .prop_map(|(a, w)| Boxcar { a, w })
    }

    proptest! {
        #![proptest_config(mcg_test_support::proptest_config(256, 0x7E57_0008))]

        /// The linear path form equals MMIS eq. 14 summed over every combination.
        #[test]
        fn path_linear_equals_naive(
            sets in proptest::collection::vec(proptest::collection::vec(boxcar(), 1..5), 1..6),
            xs in proptest::collection::vec(0.0_f32..1.0, 6),
        ) {
            let refs: std::vec::Vec<&[Boxcar]> = sets.iter().map(|s| s.as_slice()).collect();
            let xs = &xs[..sets.len()];
            let linear = path_pdf(&refs, xs);
            let naive = path_pdf_naive(&refs, xs);
            prop_assert!((linear - naive).abs() <= 1e-5 * naive.max(1e-30), "{linear} vs {naive}");
        }

        /// Estimators never return NaN or infinity, even for extreme values and tiny densities.
        #[test]
        fn estimators_stay_finite(
            set in proptest::collection::vec(boxcar(), 1..8),
            x in -0.5_f32..1.5,
            f in -1e30_f32..1e30,
            p in 0.0_f32..=1.0,
        ) {
            prop_assert!(smis_one_sample(&set, &x, f).is_finite());
            let xs = std::vec![x; set.len()];
            let fs = std::vec![f; set.len()];
            prop_assert!(smis(&set, &xs, &fs).is_finite());
            let mix = Defensive::new(Boxcar { a: 0.0, w: 1.0 }, p, &set).unwrap();
            prop_assert!(mix.estimate(&x, f).is_finite());
            let counts = std::vec![2_u32; set.len()];
            let xs2 = std::vec![x; 2 * set.len()];
            let fs2 = std::vec![f; 2 * set.len()];
            prop_assert!(mis_balance(&set, &counts, &xs2, &fs2).is_finite());
            let spaces = [set.as_slice()];
            prop_assert!(Mmis::new(&spaces).estimate(&xs, &fs).is_finite());
            let sets = [set.as_slice(), set.as_slice()];
            prop_assert!(path_estimate(f, &sets, &[x, x]).is_finite());
        }
    }
}
