//! World-space Markov chain path guiding (MCPG, Alber et al. 2025): chain states at hash-grid
//! vertices (Table 1), moved by grid resampling (Alg. 1), sampling (Alg. 2) and the acceptance
//! plus maximum-likelihood transition (Alg. 3), with the discard heuristic, the
//! previous-position lookup and velocity prediction of sec. 5, and the irradiance cache of
//! sec. 4.
//!
//! # The guide
//! [`Guide`] is MCPG as one object (feature `std`): the adaptive and static grids, the
//! irradiance cache and the constants, every per-vertex call through `&self` from any number of
//! threads. Per path vertex: [`Guide::begin`] (Alg. 1), [`GuidedVertex::sample`] and
//! [`GuidedVertex::pdf`] (Alg. 2, the exact density to divide by), trace, then
//! [`GuidedVertex::finish`] (Alg. 3 and the cache); per frame [`Guide::end_frame`]. A forward
//! path tracer multiplies its throughput by f·|cos θ|/p at each vertex, with p =
//! [`GuidedSample::pdf`]; that per-vertex product is eq. 6.
//!
//! # What to expect
//! - **Warm-up.** The grids start empty: the first vertices sample the BSDF until chains are
//!   accepted, and the stores of a frame are seen by the rest of that frame. In the
//!   `guided_room` example (128 × 128, 8 samples per pixel and frame, 3 bounces, light hidden
//!   behind a panel) the per-frame MSE relative to cosine sampling was 0.39 in frame 1, 0.2-0.5
//!   in frames 2-4 and 0.10-0.16 from frame 5 on (occasional frames up to 0.5 when a rare path
//!   reaches the light through an untrained direction). How fast the first lobes become useful
//!   depends on the prior's scale: see [`GuideConfig::for_scene`].
//! - **p_bsdf is also the chain-restart rate.** After a BSDF sample the transition continues
//!   from the empty state (Alg. 2 line 4), so an accepted BSDF sample stores a fresh
//!   one-sample chain over whatever it overwrites. A large p_bsdf finds new light sooner but
//!   keeps resetting good chains: in `guided_room` (96 × 96) the MSE relative to cosine sampling was 0.15
//!   with p_bsdf = 0.1 (the default; the authors' engine uses 0.1-0.15), 0.24 with 0.2 and
//!   0.38 with 0.5, which loses to cosine sampling at equal time.
//! - **Young chains.** Under Alg. 2 a chain of one sample gets 1 − p_bsdf of the choices at
//!   once; where one sample says little (a room lit indirectly, many small lights) those lobes
//!   send most paths to whatever they first saw. [`McpgParams::confidence_samples`] (mcg's
//!   extension, off by default) lets young chains lend their share to the BSDF and continue
//!   after its samples: in mcg-demo's renderer it cut the error 10-20 % on a room lit from
//!   behind a panel and 4× on a room of many small lights; on a single small light with few
//!   samples it slows the first chains down (the field's docs have the numbers).
//! - **Scale.** The paper's lengths are in Quake units; [`GuideConfig::for_scene`] carries
//!   them to any scene and documents how each parameter scales, [`GuideConfig::for_camera`]
//!   sets the angular resolution from the image.
//! - **Hemisphere.** Lobes live on the whole sphere; [`Hemisphere::CosineProduct`] multiplies
//!   each by a vMF fit of the clamped cosine, so fewer directions go below the surface.
//!
//! # Performance
//! One full guided vertex without tracing (`begin` with N_mc = 5, `sample`, one more `pdf`,
//! `finish`) executes about 4,340 instructions, 49 times a cosine-hemisphere sample (89); with
//! the irradiance cache about 5,370 (60 times); on a 2-vCPU Intel Ice Lake server VM that is
//! about 0.48-0.54 µs (0.63-0.66 µs with the cache) against 7-9 ns (before the lobes' inputs
//! were formed lane-wise: 0.53-0.56 µs against 6.9 ns on an idle AMD Zen 4 core, 0.96 µs
//! against 11 ns on the Ice Lake). `begin` hashes (and prefetches)
//! all its candidates before it probes any: 160 instructions more than probing each in turn,
//! which renderers, whose states do not stay in the caches, get back as a 4-5 % cheaper guided
//! frame; and each grid slot keeps its checksum, age and state in one cache line
//! ([`SharedGrid`]), which took another 2-8 % off that frame against three arrays (a third
//! fewer first-level cache misses). The lobes' inputs (the distance prior, the posterior's parts,
//! the shares) are formed in passes over all lanes ([`mcg_vmf::LobeInputs`]), which the compiler
//! runs four wide: 5 % fewer instructions and about 18 % less time per vertex than candidate by
//! candidate. No single step dominates: the five keys, lookups and seqlocked loads, the five
//! lobes (μ, posterior κ, cosine product, C(κ)), the densities and the transition with its
//! store each take 10-25 %. Two threads sharing one
//! `&Guide` ran 1.8-2.1 times as fast as one.
//!
//! In mcg-demo's 3-bounce CPU path tracer of a small room lit from behind a panel (128 × 128, 8
//! samples per pixel × 64 frames, no light sampling, [`McpgParams::confidence_samples`] 16), the
//! guide also draws more directions per vertex from the begun vertex's whole mixture
//! ([`GuidedVertex::sample_mixture`]) for the emission they meet: K = 6 on average, spread over the
//! path's depths and over classes of like expected contribution (the throughput times
//! [`GuidedVertex::weight_sum`]) by [`EmissionAllocation`], the emission along each of the K + 1
//! directions weighted 1/(K + 1) (mcg's extension; mcg-demo's `--mcpg-emission-samples` and
//! `--mcpg-emission-allocation`). Its relative MSE is then 0.035 of BSDF sampling's at equal
//! samples, and 4.3 times lower than with the paper's one direction. Against light sampling
//! (next-event estimation with MIS, what renderers use today) it is about even at equal CPU time, a
//! little ahead: 0.90-0.97 of its error × time (0.935 on average over four seeds) on an Intel
//! Ice Lake server core, where a guided frame costs 3.9-4.0 times a light-sampled one; with the
//! directions spread by depth only (and the lobes built candidate by candidate) it was 1.07 there
//! and 0.93 on an AMD Zen 4 core, whose guided frame cost 3.5 times. The extra directions are a third of a guided frame. Beside light sampling — the guide
//! sampling the scattered direction, one light sample per vertex, MIS with [`GuidedVertex::pdf`],
//! the chains learning only the MIS-weighted share of the emission
//! ([`VertexObservation::emission_weight`]) — it reaches 0.28 of light sampling's relative MSE,
//! 0.70-0.74 at equal CPU time (`benches/README.md` has the commands).
//!
//! # The parts
//! Per path vertex x with normal n at time T:
//! 1. Load N_mc candidates (adaptive grid with p = 0.7, else static), each with
//!    [`prepare_candidate`] (velocity prediction, collision and normal rejection), into a
//!    [`CandidateSet`]. In the first sample of a frame, load at the vertex's previous-frame
//!    position (sec. 5, "Dynamic Geometry"): the caller passes that position to its grid lookup.
//! 2. [`choose_technique`]: BSDF or the chosen state's lobe; sample ω; trace to hit_next.
//! 3. Divide f·cos by [`CandidateSet::pdf`] (eq. 6-7, per vertex); f_mc = lum of that
//!    estimate for the transition.
//! 4. [`update()`] or [`update_from`] (eq. 8, Alg. 3) and store the returned state at a freshly
//!    chosen level and corner; or, for a rejected lobe sample, [`should_discard`] and zero the
//!    slot it came from.

#[cfg(feature = "std")]
mod emission_allocation;
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
pub use emission_allocation::{
    CLASS_MEMORY, CONTRIBUTION_BINS, CONTRIBUTION_CAP, DEPTH_CAP, DirectionMoments,
    EMISSION_DEPTHS, EmissionAllocation, EmissionClass, EmissionMoments, EmissionPolicy,
    MIN_PER_VERTEX, allocate, contribution_bin, round_stochastically,
};
#[cfg(feature = "std")]
pub use grid::{GridEnsemble, GridSlot, GridUniforms};
#[cfg(feature = "std")]
pub use guide::{
    BeginUniforms, CandidateUniforms, FinishUniforms, Guide, GuideConfig, GuidedSample,
    GuidedVertex, Hemisphere, IsotropicPhase, Lambertian, MAX_ADAPTIVE_CAPACITY, MAX_CANDIDATES,
    PAPER_SCENE_EXTENT, PendingFinish, SLOTS_PER_PIXEL, SampleUniforms, Scatter, Traced,
    Transition, Vertex, VertexObservation, luminance,
};
#[cfg(feature = "std")]
pub use irradiance_cache::{CacheCell, CacheConfig, IrradianceCache};
pub use params::{DiscardRule, McpgParams};
pub use resampling::{CandidateSet, GridKind, distance_prior, prepare_candidate};
pub use sampling::{CosineVertexTechnique, SampleChoice, choose_technique};
#[cfg(feature = "std")]
pub use shared_grid::{SharedGrid, SharedState};
pub use state::GridState;
pub use update::{Observation, should_discard, update, update_from};
