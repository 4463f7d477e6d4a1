//! World-space Markov chain path guiding (MCPG, Alber et al. 2025): chain states at hash-grid
//! vertices (Table 1), moved by grid resampling (Alg. 1), sampling (Alg. 2) and the acceptance
//! plus maximum-likelihood transition (Alg. 3), with the discard heuristic, the
//! previous-position lookup and velocity prediction of sec. 5.
//!
//! Per path vertex x with normal n at time T:
//! 1. Load N_mc candidates (adaptive grid with p = 0.7, else static), each with
//!    [`prepare_candidate`] (velocity prediction, collision and normal rejection), into a
//!    [`CandidateSet`]. In the first sample of a frame, load at the vertex's previous-frame
//!    position (sec. 5, "Dynamic Geometry"): the caller passes that position to its grid lookup.
//! 2. [`choose_technique`]: BSDF or the chosen state's lobe; sample ω; trace to hit_next.
//! 3. Estimate with f / [`CandidateSet::pdf`] (eq. 6-7), f_mc = lum of that estimate for the
//!    transition.
//! 4. [`update`] (eq. 8, Alg. 3) and store the returned state at a freshly chosen level and
//!    corner; or, for a rejected lobe sample, [`should_discard`] and zero the slot it came from.

#[cfg(feature = "std")]
mod grid;
#[cfg(feature = "std")]
mod guide;
#[cfg(feature = "std")]
mod irradiance_cache;
mod params;
mod resampling;
mod sampling;
#[cfg(feature = "std")]
mod shared_grid;
pub mod single_scattering;
mod state;
mod update;

#[cfg(feature = "std")]
pub use crate::error::GuideError;
#[cfg(feature = "std")]
pub use grid::{GridEnsemble, GridSlot, GridUniforms};
#[cfg(feature = "std")]
pub use guide::{
    BeginUniforms, CandidateUniforms, FinishUniforms, Guide, GuideConfig, GuidedSample,
    GuidedVertex, Hemisphere, IsotropicPhase, Lambertian, MAX_CANDIDATES, PAPER_SCENE_EXTENT,
    SampleUniforms, Scatter, Traced, Transition, Vertex, VertexObservation, luminance,
};
#[cfg(feature = "std")]
pub use irradiance_cache::{CacheCell, CacheConfig, IrradianceCache};
pub use params::{DiscardRule, McpgParams};
pub use resampling::{CandidateSet, GridKind, distance_prior, prepare_candidate};
pub use sampling::{CosineVertexTechnique, SampleChoice, choose_technique};
#[cfg(feature = "std")]
pub use shared_grid::{SharedGrid, SharedStates};
pub use state::GridState;
pub use update::{Observation, should_discard, update};
