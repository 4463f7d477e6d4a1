//! # mcg-probe-cache: DDGI probe grids with ADGI's atomic texels and adaptive updates
//!
//! *Adaptive Dynamic Global Illumination* (ADGI) keeps DDGI's grid of irradiance probes but
//! stores each texel in one 32-bit word updated by compare-and-swap, and spends its ray budget
//! where a guiding function says it matters, placed by Metropolis chains. This crate gives
//! renderer authors that grid — usable as plain DDGI storage — and ADGI's adaptive sampling.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`ProbeGrid`], [`ProbeCell`] | probe lattice: origin, spacing, counts; trilinear cell lookup | DDGI; ADGI sec. 3.1 |
//! | `scene` (feature `scene`): `Scene`, `DynamicScene` | CPU test fixture: boxes, spheres, a rectangular light, one-bounce probe rays, a door that opens | ADGI sec. 5 (Fig. 1, 8) |
//! | `reference` (feature `scene`): `reference_irradiance`, `reference_texel_irradiance` | reference probe irradiance, many stratified rays per texel direction (or per texel of a map) | ADGI sec. 5, "Reference" |
//! | [`heuristics`], [`HeuristicParams`] | camera distance f_c, probe visibility f_v, incoming radiance f_r; f_s, f_d; the 6-10-10 heuristics word | ADGI eq. 10-12, 19-20, sec. 4.3 |
//! | [`GuidingFunction`], [`GuideParams`], [`Guide`], [`guiding_function::octant_feedback`] | h(p, ω) = exp(α ĝ/f)·f per probe octant; static and dynamic forms; the feedback ĝ | ADGI eq. 2, sec. 4.8, 4.9 |
//! | [`ProxyGrid`] | probes grouped into 3×3×3 virtual proxies, max-pooled octants | ADGI sec. 4.9 |
//! | [`temporal_gradient`], [`ChangeDetector`], [`TemporalTrigger`], [`SmoothingKernel`] | temporal gradients of f_v, f_r, trigger, 5×5×5 × octant smoothing | ADGI eq. 13-18, Fig. 6a |
//! | [`pilot_rays`], [`PilotSchedule`], [`PilotFrame`], [`PilotRay`], [`PilotHit`] | one stratified pilot ray per octant, `AABBCC…` direction pattern | ADGI sec. 4.1, 4.4 |
//! | [`ProbeChains`], [`ProbeSample`], [`ChainKind`] | static and dynamic Metropolis chains over (position, cos θ, φ), sequential or on threads | ADGI Alg. 1, 5, sec. 4.8, 4.9 |
//! | [`octahedral_encode`], [`octahedral_decode`], [`octahedral_solid_angle`] | RTXGI's octahedral sphere ↔ square map; exact texel solid angle | Cigolle et al. 2014; DDGI; RTXGI |
//! | [`equal_area_encode`], [`equal_area_decode`], [`equal_area_solid_angle`] | Clarberg's equal-area map (4π/n² per texel) | Clarberg 2008 |
//! | [`TexelMap`], [`MapKind`] | a probe's texel grid: direction ↔ texel, solid angle, RTXGI 1-texel border, bilinear taps | RTXGI; ADGI sec. 3.1, 4.5-4.6 |
//! | [`ProbeTexels`], [`TexelConfig`], [`RoundingMode`] | a grid's irradiance and visibility words in `AtomicU32` (GPU layout), moving average N_max 63/10 | ADGI sec. 4.5-4.7, Alg. 3-4, Table 3, App. B |
//! | [`RaySample`], [`BlendWeights`], [`ProbeTexels::update_sample`], [`ProbeTexels::update_sample_at`], [`ProbeTexels::blend_rays`] | ADGI's per-sample CAS update (at a probe or the nearest one); DDGI's cosine-weighted blend | ADGI Alg. 2-4; DDGI sec. 4 |
//! | [`QueryConfig`], [`TexelContent`], [`ProbeTexels::irradiance_at`], [`ProbeTexels::convolved`] | irradiance from 8 probes: trilinear, wrap, Chebyshev, biases, bilinear; radiance texels → irradiance texels | DDGI sec. 4-5; RTXGI; ADGI sec. 4.8 |
//! | [`ProbeUpdater`], [`UpdatePolicy`], [`UpdateConfig`], [`ProbeRayRequest`], [`FrameRays`] | the per-frame update a renderer calls: DDGI's uniform rays + blend, or ADGI's pilot rays → heuristics → dynamic → static chains in one ray budget, or mcg's extensions (refill; blend: staggered pilot pairs steering DDGI's blend); tracing through a batch callback | ADGI sec. 4, Fig. 4; DDGI sec. 4 |
//! | [`uniform_rays`], [`UniformRays`], [`spherical_fibonacci`], [`sequence_direction`] | a probe's uniform rays: DDGI's rotated spherical Fibonacci set per frame, or mcg's per-probe R2 sequence continued over frames | DDGI sec. 4; Roberts 2018 (R2) |
//! | [`clip_volume`], [`ClipVolumes`], [`Frustum`] | inner / outer clip volumes, shell count reset N ≤ 16 | ADGI Fig. 6b, sec. 4.4, 4.8 |
//!
//! ## Conventions
//! - Positions and directions are [`glam::Vec3`] (f32); colours are linear RGB.
//! - No hidden randomness: every random decision takes the caller's uniforms in [0, 1).
//! - Texel storage is plain `u32` words (the packed layouts of `mcg-color-codec`), so a grid's
//!   memory uploads to the GPU as it is.
//! - Texel maps: 8 × 8 / 16 × 16 count stored texels with RTXGI's 1-texel border (6 × 6 /
//!   14 × 14 cover the sphere); square coordinates in `[−1, 1]²`, +z at the centre.
//! - Irradiance texels hold `E/π` (DDGI's blend) or radiance (ADGI's per-sample update; see
//!   [`TexelContent`]); queries return irradiance `E` (π·L for a constant environment L).
//!   Visibility texels hold distances in cell diagonals ([`ProbeGrid::cell_diagonal`]).
//!
//! ## Features
//! - `scene`: the CPU fixture that the tests, examples and demo render with — a mini ray tracer
//!   (module `scene`) and reference probe irradiance (module `reference`). A renderer that only
//!   stores and queries probes does not need it.
//!
//! ## Dependencies
//! The crate depends on `mcg-markov-guide` only for the Metropolis random walk of
//! [`ProbeChains`] (ADGI Alg. 1, 5); that pulls in `mcg-vmf`, `mcg-smis` and `mcg-hashgrid`
//! as well, which a DDGI-only user compiles but does not call.
//!
//! ## Example
//! ```
//! use mcg_probe_cache::{ProbeGrid, glam::{UVec3, Vec3}};
//!
//! let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(1.0), UVec3::new(4, 4, 4))?;
//! let cell = grid.cell(Vec3::new(1.25, 2.5, 0.75));
//! let weights: f32 = (0..8).map(|c| grid.corner(cell, c).1).sum();
//! assert!((weights - 1.0).abs() < 1e-6);
//! # Ok::<(), mcg_probe_cache::ProbeError>(())
//! ```
#![cfg_attr(docsrs, feature(doc_cfg))]

pub use glam;
pub use mcg_color_codec;

pub mod clip_volume;
mod equal_area;
mod error;
mod grid;
pub mod guiding_function;
pub mod heuristics;
mod irradiance_query;
mod octahedral;
pub mod pilot_rays;
pub mod probe_chains;
mod probe_texels;
pub mod probe_update;
pub mod proxies;
#[cfg(feature = "scene")]
#[cfg_attr(docsrs, doc(cfg(feature = "scene")))]
pub mod reference;
#[cfg(feature = "scene")]
#[cfg_attr(docsrs, doc(cfg(feature = "scene")))]
pub mod scene;
pub mod temporal_gradient;
#[cfg(test)]
mod test_support;
mod texel_map;
mod texel_update;
pub mod uniform_rays;

pub use clip_volume::{ClipRegion, ClipVolume, ClipVolumes, Frustum};
pub use equal_area::{equal_area_decode, equal_area_encode, equal_area_solid_angle};
pub use error::{ChainError, ControlError, GridError, LayoutError, ParameterError, ProbeError};
pub use grid::{ProbeCell, ProbeGrid};
pub use guiding_function::{Guide, GuideParams, GuidingFunction, HeuristicField};
pub use heuristics::HeuristicParams;
pub use irradiance_query::{QueryConfig, TexelContent, WRAP_SHADING_OFFSET};
pub use octahedral::{
    octahedral_decode, octahedral_encode, octahedral_solid_angle, octahedron_point,
};
pub use pilot_rays::{PilotFrame, PilotHit, PilotPhase, PilotRay, PilotSchedule};
pub use probe_chains::{
    ChainKind, FrameStats, ProbeChainState, ProbeChains, ProbeSample, ProbeStepUniforms,
};
pub use probe_texels::{
    ProbeTexels, RoundingMode, TEXEL_UNIFORM_PERIOD, TEXEL_UNIFORM_STEP, TexelConfig,
};
pub use probe_update::{
    AdgiParts, FrameRays, ProbeRayRequest, ProbeUpdater, UpdateConfig, UpdatePolicy, hash_uniform,
};
pub use proxies::ProxyGrid;
#[cfg(feature = "scene")]
pub use reference::{reference_irradiance, reference_texel_irradiance};
#[cfg(feature = "scene")]
pub use scene::{DynamicScene, ProbeRay, Scene, SceneEvent};
pub use temporal_gradient::{ChangeDetector, SmoothingKernel, TemporalTrigger};
pub use texel_map::{MAX_MAP_SIDE, MapKind, TexelMap};
pub use texel_update::{BLEND_WEIGHT_EPSILON, BlendWeights, RaySample};
pub use uniform_rays::{
    SEQUENCE_SEED_SALT, SEQUENCE_STEPS, UniformRays, sequence_direction, spherical_fibonacci,
};

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
