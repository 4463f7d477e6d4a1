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
//! Not on the GPU yet: the guiding function, the Metropolis probe chains, the temporal trigger
//! and the pilot rays (`mcg_probe_cache::{guiding_function, probe_chains, temporal_gradient,
//! pilot_rays}`), which a renderer runs on the CPU and feeds with the GPU's rays.

#[cfg(feature = "runtime")]
mod guide;
mod params;

#[cfg(feature = "runtime")]
pub use guide::GpuProbeCache;
pub use params::{
    AdgiConfigError, AdgiGpuParams, GpuClipVolume, GpuClipVolumes, GpuIrradianceQuery,
    GpuRaySample, GpuStepParams, ProbeCacheConfig, rounding_code,
};
