//! The guides on the GPU: a WGSL module a renderer imports and a host object each.
//!
//! | guide | WGSL module | host object | CPU reference |
//! |---|---|---|---|
//! | MCPG (Alber et al. 2025) | `mcg::mcpg` ([`Module::Mcpg`](crate::shaders::Module::Mcpg)) | [`mcpg::GpuMcpgGuide`] (feature `runtime`) | `mcg_markov_guide::mcpg::Guide` |
//! | MCMM (Dittebrandt et al. 2023) | `mcg::mcmm` ([`Module::Mcmm`](crate::shaders::Module::Mcmm)) | [`mcmm::GpuMcmmGuide`] (feature `runtime`) | `mcg_markov_guide::mcmm` |
//! | ADGI's probe cache (texels, update, query; DDGI's blend) | `mcg::adgi` ([`Module::Adgi`](crate::shaders::Module::Adgi)) | [`adgi::GpuProbeCache`] (feature `runtime`) | `mcg_probe_cache::ProbeTexels` |
//! | ADGI's guiding function, probe chains, trigger smoothing | `mcg::adgi_chains` ([`Module::AdgiChains`](crate::shaders::Module::AdgiChains)) | [`adgi::GpuProbeChains`], [`adgi::GpuTriggerSmoothing`] (feature `runtime`) | `mcg_probe_cache::{GuidingFunction, ProbeChains, temporal_gradient::spatial_smoothing}` |

pub mod adgi;
pub mod mcmm;
pub mod mcpg;
