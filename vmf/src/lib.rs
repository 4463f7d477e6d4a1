//! # mcg-vmf: von Mises-Fisher lobes for path guiding
//!
//! The von Mises-Fisher (vMF) distribution is the lobe that Markov chain guiding samples from:
//! MCMM (Dittebrandt et al. 2023) in screen space, MCPG (Alber et al. 2025) in world-space hash
//! grids. This crate gives renderer authors that lobe with numerics that hold in f32 for every
//! concentration a guide produces, and the statistics both papers fit it with.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`Vmf`] | lobe V(ω \| μ, κ): `pdf`, `sample`, `sample_with_pdf` | MCMM eq. 4, MCPG eq. 4 |
//! | [`sample_batch`] | `Vmf::sample` over slices of lobes, branch-free so the loop vectorises | — |
//! | [`mean_cosine_from_kappa`], [`kappa_from_mean_cosine`], [`kappa_from_mean_cosine_exact`] | A₃(κ) = coth κ − 1/κ and its inverses | MCMM Alg. 2 l. 7, MCPG Alg. 2 l. 8 |
//! | [`SufficientStats`], [`FitParams`], [`MapPrior`] | parallax-aware fit (ȳ, r̄, w̄, N) with α = max(1/N, α_min) and the N² MAP prior | MCMM Table 1, Alg. 2-3; MCPG Table 1, Alg. 2-3 |
//! | [`Vmf::product`], [`Vmf::convolve`], [`Vmf::clamped_cosine`] | closed-form product with its scale, approximate convolution, cosine lobe | — |
//! | [`VmfLanes`] | a weighted mixture of a few lobes stored lane-wise, its density in one vectorised pass | MCPG eq. 6-7 |
//! | [`LobeInputs`] | the lanes' statistics and MAP posterior parts, for building [`VmfLanes`] in whole-lane passes | MCPG Alg. 2 lines 6-8 |
//! | [`VmfMixture`] | K-lobe mixture, one uniform reused for the component choice | MCMM eq. 5 |
//! | [`Frame`] | branchless orthonormal frame | Duff et al. 2017 |
//! | [`uniform_sphere`], [`UNIFORM_SPHERE_PDF`] | uniform directions on S², the baseline of every guided sampler | pbrt-v4 `SampleUniformSphere` |
//! | [`constants`] | switch points, series and polynomial coefficients, as typed constants and as tables for the GPU backend's WGSL prelude | — |
//!
//! ## Conventions
//! - Directions are unit [`glam::Vec3`] in world space; angles in radians; densities are per
//!   steradian (solid angle measure).
//! - No hidden randomness: sampling takes uniforms in [0, 1) from the caller
//!   (`sample(u: Vec2)`), so CPU and GPU make identical decisions from identical uniforms.
//!   With the `rand` feature, [`Vmf`] and [`VmfMixture`] implement
//!   `rand::distr::Distribution<Vec3>` for convenience.
//! - Constructors validate and return `Result`; hot-path functions document what they do with
//!   NaN, infinities and degenerate input and never return NaN for valid lobes.
//! - f32 throughout. [`Vmf`] and [`SufficientStats`] are `#[repr(C)]` + [`bytemuck::Pod`] with
//!   asserted sizes (16 and 24 bytes), ready to upload to the GPU.
//!
//! ## Features
//! - `std` (default): float functions from the standard library.
//! - `libm`: float functions from the `libm` crate, for `#![no_std]` builds
//!   (`default-features = false, features = ["libm"]`).
//! - `rand`: `rand::distr::Distribution<Vec3>` for [`Vmf`] and [`VmfMixture`].
//!
//! ## Example
//! ```
//! use mcg_vmf::{FitParams, MapPrior, SufficientStats, Vmf, glam::{Vec2, Vec3}};
//!
//! // A lobe, its density and a sample from two caller-supplied uniforms.
//! let lobe = Vmf::new(Vec3::new(0.0, 1.0, 1.0), 25.0)?;
//! let (w, pdf) = lobe.sample_with_pdf(Vec2::new(0.3, 0.8));
//! assert!(pdf > 0.0 && (w.length() - 1.0).abs() < 1e-6);
//!
//! // Fit statistics from traced samples and rebuild the lobe at another shading point.
//! let mut stats = SufficientStats::EMPTY;
//! stats.update(Vec3::ZERO, Vec3::new(0.0, 4.0, 4.0), 1.5, &FitParams::MCMM);
//! let at = stats.to_vmf(Vec3::new(0.1, 0.0, 0.0), MapPrior::uninformed(0.2)).unwrap();
//! assert!(at.mu().dot(lobe.mu()) > 0.99);
//! # Ok::<(), mcg_vmf::VmfError>(())
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(any(feature = "std", test))]
extern crate std;

pub use glam;

mod batch;
pub mod constants;
mod error;
mod frame;
mod lanes;
mod math;
mod mean_cosine;
mod mixture;
mod product;
mod sphere;
mod sufficient_stats;
mod vmf;

#[cfg(feature = "rand")]
mod features {
    mod impl_rand;
}

pub use batch::sample_batch;
pub use error::{MixtureError, VmfError};
pub use frame::Frame;
pub use lanes::{LobeInputs, VmfLanes};
pub use mean_cosine::{
    KAPPA_MAX, kappa_from_mean_cosine, kappa_from_mean_cosine_exact, mean_cosine_from_kappa,
};
pub use mixture::VmfMixture;
pub use product::CLAMPED_COSINE_KAPPA;
pub use sphere::{UNIFORM_SPHERE_PDF, uniform_sphere};
pub use sufficient_stats::{FitParams, MapPrior, MeanCosineUpdate, PriorDecay, SufficientStats};
pub use vmf::Vmf;

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
