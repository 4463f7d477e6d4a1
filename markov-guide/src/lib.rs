//! # mcg-markov-guide: Markov chain guiding state and transitions
//!
//! Markov chains whose states are sufficient statistics of von Mises-Fisher lobes, moved by
//! resampling, acceptance and maximum-likelihood steps, so that a population of single lobes
//! becomes a mixture that follows the light; plus the Metropolis random walk that ADGI uses to
//! place probe updates. The crate traces no rays: the renderer asks for a technique, samples a
//! direction, traces, and hands the result back.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`mcmm::PixelState`], [`mcmm::PixelStateBuffers`] | screen-space chain state (ȳ, r̄, w̄, N, f) and its frame buffers | MCMM Table 1 |
//! | [`mcmm::collaborative_discovery`], [`mcmm::bspline_offset`] | weighted resampling of neighbour states | MCMM Alg. 1 |
//! | [`mcmm::choose_technique`], [`mcmm::technique_pdf`] | defensive hemisphere / lobe choice and its pdf | MCMM Alg. 2, App. A |
//! | [`mcmm::update`] | acceptance min(1, f/S_c.f), reset, MLE update | MCMM Alg. 3 |
//! | [`mcmm::ScoreDensity`] | the density in the score f: the chain's technique (paper) or the tile's mixture (SSMIS denominator; our extension) | MCMM Alg. 3 line 1, eq. 9 |
//! | [`mcmm::CosineChainTechnique`], [`mcmm::McmmPrior`] | a chain as an `mcg_smis::Technique`; uninformed or light-size prior | MCMM eq. 8-9, sec. 5 |
//! | [`mcpg::Guide`], [`mcpg::GuidedVertex`], [`mcpg::GuideConfig`] | MCPG as one object: `begin` / `sample` / `pdf` / `finish` per vertex through `&self` from many threads, `end_frame` per frame; scene and camera scaling, cosine product | MCPG Alg. 1-3, sec. 4-5 |
//! | [`mcpg::SharedGrid`], [`mcpg::SharedState`] | lock-free grid of 32-byte states (seqlock per slot), each slot one cache line of `mcg_hashgrid::ConcurrentSlots` | MCPG sec. 4 "Synchronization" |
//! | [`mcpg::IrradianceCache`], [`mcpg::CacheCell`] | adaptive hash grid of radiance, coarser levels on collision, small accumulation factor; `Pod` cells | MCPG sec. 4 "Irradiance Caching" |
//! | [`mcpg::GridState`] | world-space chain state (w̄, N, ȳ, r̄, T, v) in 32 bytes | MCPG Table 1 |
//! | [`mcpg::prepare_candidate`], [`mcpg::CandidateSet`], [`mcpg::GridEnsemble`] | candidates from the adaptive and static grids, velocity prediction, collision and normal rejection, reservoir choice | MCPG Alg. 1, eq. 10 |
//! | [`mcpg::choose_technique`], [`mcpg::CandidateSet::pdf`], [`mcpg::CosineVertexTechnique`] | BSDF or lobe with the distance prior; the estimator's pdf over all accessed states, as an `mcg_smis::Technique` for the path form | MCPG Alg. 2, eq. 6-7 |
//! | [`mcpg::update`], [`mcpg::update_from`], [`mcpg::should_discard`] | acceptance against the mean candidate score, MLE update, velocity; discard heuristic | MCPG eq. 8-9, Alg. 3, sec. 5 |
//! | [`mcpg::single_scattering`] | phase function and jittered view direction instead of BSDF and normal | MCPG sec. 4 |
//! | [`Reservoir`] | one-pass weighted reservoir sampling | Chao 1982; MCMM Alg. 1, MCPG Alg. 1 |
//! | [`cosine_hemisphere`], [`cosine_hemisphere_concentric`] | the defensive cosine technique (polar map; concentric map for stratified uniforms) | MCMM Alg. 2, MCPG Alg. 2; Shirley and Chiu 1997 |
//! | [`RandomWalk`], [`MetropolisChain`], [`FrameSchedule`] | Metropolis random walk on ℝᴰ with burn-in per frame | ADGI Alg. 1, 5, sec. 4.8-4.9 |
//! | `toy_scene::ToyScene` (feature `toy`) | lights on a plane with closed-form irradiance, for tests and examples | — |
//! | `toy_renderer` (feature `toy`) | the full renderer loops of MCMM (TSMIS, SSMIS, unshuffled) and MCPG on the toy scene, with cosine baselines | MCMM sec. 4; MCPG sec. 4-5 |
//!
//! ## Conventions
//! - Directions are unit [`glam::Vec3`] in world space; densities are per steradian.
//! - No hidden randomness: every decision takes uniforms in [0, 1) from the caller.
//! - Scores and weights are luminance; NaN, infinite and negative values are treated as 0 and
//!   never reach a state.
//! - State types are `#[repr(C)]` + [`bytemuck::Pod`] with asserted sizes; all zeros is empty.
//!
//! ## Features
//! - `std` (default): float functions from the standard library and the frame buffers.
//! - `libm`: float functions from `libm` for `#![no_std]` builds.
//! - `toy`: the test fixture — the toy scene (`toy_scene`) and the reference renderer loops of
//!   `toy_renderer` (with `std` and `rand`).
//!
//! ## Example
//! ```
//! use mcg_markov_guide::glam::Vec3;
//! use mcg_markov_guide::mcmm::{McmmParams, PixelState, SampleChoice, choose_technique, update};
//!
//! // One MCMM iteration at shading point x: choose a technique, let the renderer sample and
//! // trace (here: a light straight above was hit with score f = 2), then update the chain.
//! let params = McmmParams::PAPER;
//! let x = Vec3::ZERO;
//! let (mut state, mut current) = (PixelState::EMPTY, PixelState::EMPTY);
//! assert_eq!(choose_technique(&state, x, 0.5, &params), SampleChoice::Hemisphere);
//! let accepted = update(&mut state, &mut current, x, Vec3::new(0.0, 0.0, 3.0), 2.0, true, 0.7, &params);
//! assert!(accepted && current.is_valid());
//! // The next sample comes from a lobe pointing at the light.
//! let SampleChoice::Lobe(lobe) = choose_technique(&state, x, 0.5, &params) else { unreachable!() };
//! assert!(lobe.mu().z > 0.999);
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(any(feature = "std", test))]
extern crate std;

pub use glam;
pub use mcg_hashgrid;
pub use mcg_smis;
pub use mcg_vmf;

mod error;
mod hemisphere;
mod math;
pub mod mcmm;
pub mod mcpg;
mod metropolis;
mod reservoir;
#[cfg(feature = "toy")]
pub mod toy_renderer;
#[cfg(feature = "toy")]
#[cfg_attr(docsrs, doc(cfg(feature = "toy")))]
pub mod toy_scene;

pub use error::{BufferError, GuideError, ParamsError, WalkError};
pub use hemisphere::{cosine_hemisphere, cosine_hemisphere_concentric, cosine_hemisphere_pdf};
pub use metropolis::{
    ADGI_DIRECTION_STEP, FrameSchedule, MetropolisChain, NORMAL_QUANTILE_CENTRAL,
    NORMAL_QUANTILE_SWITCH, NORMAL_QUANTILE_TAIL, NORMAL_QUANTILE_U_MIN, RandomWalk, StepUniforms,
    standard_normal_from_uniform,
};
pub use reservoir::Reservoir;

/// The crate README's example, compiled and run as a doctest (it renders the toy scene).
#[cfg(all(doctest, feature = "toy"))]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
