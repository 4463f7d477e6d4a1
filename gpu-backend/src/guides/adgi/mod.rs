//! ADGI on the GPU: `mcg::adgi`, the probe cache as one WGSL module, and its host object.
//!
//! A renderer's WGSL shaders import the cache and bind one group:
//!
//! ```wgsl
//! #import mcg::adgi::{adgi_irradiance_at, adgi_update_sample}
//!
//! // probe ray traced by the renderer from probe `p` in direction ω:
//! adgi_update_sample(p, omega, radiance, hit_distance, u, max_count);   // ADGI Alg. 2-4
//! // shading:
//! let e = adgi_irradiance_at(x, n, to_viewer);                          // DDGI sec. 4-5
//! ```
//!
//! composed with [`GpuProbeCache::shader_defs`]`(group)`, its pipeline layout holding
//! [`GpuProbeCache::bind_group_layout`] at `group`, and [`GpuProbeCache::bind_group`] set there.
//! The cache's own steps (ADGI's per-sample update from a sample buffer, DDGI's blend as the
//! baseline on the same words, the query, the clip-volume reset) are recorded into the
//! renderer's encoder, one dispatch each.
//!
//! The functions mirror `mcg_probe_cache::ProbeTexels`; for the same words, samples and
//! uniforms the updates write the same words bit for bit (the parity tests hold them to it).
//! The query agrees within f32 rounding (WGSL's `sqrt`, `pow` and fused products differ from
//! the CPU's in the last bits).
//!
//! The pilot rays (ADGI sec. 4.4) run on the GPU too: their directions per probe and octant in
//! V_out, and from their hits the heuristics f_v, f_r (eq. 11-12), the temporal gradient and
//! the trigger (eq. 13-17), kept per probe and octant in the cache's pilot state.
//!
//! Not on the GPU yet: the 5 × 5 × 5 × octant smoothing of the trigger states, the guiding
//! function and the Metropolis probe chains (`mcg_probe_cache::{temporal_gradient::
//! spatial_smoothing, guiding_function, probe_chains}`), which a renderer runs on the CPU from
//! the pilot state it reads back, feeding the chains' samples to the GPU's per-sample update.

#[cfg(feature = "runtime")]
mod chains;
#[cfg(feature = "runtime")]
mod guide;
mod params;

#[cfg(feature = "runtime")]
pub use chains::{GpuProbeChains, GpuTriggerSmoothing};
#[cfg(feature = "runtime")]
pub use guide::GpuProbeCache;
pub use params::{
    AdgiConfigError, AdgiGpuParams, GpuChainParams, GpuChainState, GpuClipVolume, GpuClipVolumes,
    GpuGuideQuery, GpuIrradianceQuery, GpuPilotStep, GpuProbeSample, GpuRaySample,
    GpuSmoothingPass, GpuStepParams, ProbeCacheConfig, chain_step_uniforms, rounding_code,
};
