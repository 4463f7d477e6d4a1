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
//! The sampling side is `mcg::adgi_chains` with its host objects: [`GpuProbeChains`], ADGI's
//! guiding function h = exp(min(α ĝ/f, cap)) · f (eq. 2; static chains: f_s and the feedback ĝ
//! with α = 1, cap 1, sec. 4.8; dynamic chains: f_d max-pooled into 3 × 3 × 3 virtual proxies
//! with α = 0, sec. 4.9) and the static and dynamic Metropolis probe chains (Alg. 1 with the
//! random walk of Alg. 5 over (p, cos θ, φ)), and [`GpuTriggerSmoothing`], the 5 × 5 × 5 ×
//! octant smoothing of the triggers into f_Δv, f_Δr (eq. 15, 18). Their CPU twins are
//! `mcg_probe_cache::{GuidingFunction, ProxyGrid::max_pool, ProbeChains,
//! temporal_gradient::spatial_smoothing}`; fed the same uniforms
//! ([`chain_step_uniforms`]), the chains make the CPU's decisions. The guide's inputs are
//! computed on the GPU too: the feedback ĝ from the cache's irradiance words
//! ([`GpuProbeChains::record_feedback`], `guiding_function::octant_feedback`) and the
//! heuristics words from the pilot state's f_v and the smoothed triggers
//! ([`GpuTriggerSmoothing::record_compose`], `heuristics::compose_grid`).

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
    GpuComposeParams, GpuGuideQuery, GpuIrradianceQuery, GpuPilotStep, GpuProbeSample,
    GpuRaySample, GpuSmoothingPass, GpuStepParams, ProbeCacheConfig, chain_step_uniforms,
    rounding_code,
};
