//! WGSL twins of the mcg primitives on [wgpu], in parity with the CPU crates.
//!
//! Renderer authors on wgpu get the primitives of [`mcg_vmf`], [`mcg_hashgrid`] and
//! [`mcg_color_codec`] (and the MCPG grid state of [`mcg_markov_guide`]) as WGSL they can
//! drop into their own compute pipelines, with tests that hold the GPU to the CPU crates'
//! answers: bit for bit for hashes, checksums, table outcomes and packed words; within a
//! stated tolerance for the vMF lobes, where WGSL's `exp` and `log` are less exact than the
//! CPU's.
//!
//! | item | what it is | source |
//! |---|---|---|
//! | [`shaders::PRELUDE`], [`prelude::generate`] | generated `const` declarations of every constant shared with the CPU crates | the crates' `constants` |
//! | [`shaders::VMF`], [`shaders::VMF_MIXTURE`] | vMF pdf (stable form), sampling from explicit uniforms, mean cosine ↔ κ (Banerjee and exact), the sufficient-statistics update and the reconstruction with a MAP prior, product, convolution; the K-lobe mixture with one reused uniform | MCMM eq. 4-5, Alg. 2-3; MCPG Alg. 2-3; Jakob 2012 |
//! | [`shaders::HASHGRID`], [`shaders::HASHGRID_TABLE`], [`shaders::HASHGRID_AGES`] | cell keys (adaptive and static grid), xor-primes / pcg4d hashes, checksums, slot index, stochastic trilinear and jittered vertices, level choice; lock-free insert-or-get and lookup with a compare-and-swap loop; the age counter and eviction of stale cells | MCPG sec. 4 "Hash Grid"; Jarzynski and Olano 2020 |
//! | [`shaders::COLOR_CODEC`], [`shaders::COLOR_CODEC_LOGLUV`], [`shaders::COLOR_CODEC_TEXELS`] | R11G11B10, RGB9E5, gamma-5 R10G10B10A2, LogLuv32 (Larson 1998), the log codec, the 9/9/8 + 6 irradiance, 13/13 + 6 visibility and 6/10/10 + 6 heuristics words, the moving average as a compare-and-swap loop | ADGI eq. 21, sec. 4.3-4.7 |
//! | [`shaders::MARKOV_GUIDE`] | the MCPG `GridState` (32 B): f16 velocity, count, sufficient statistics; the MCMM `PixelState` (28 B): validity, resampling score, lobe | MCPG Table 1; MCMM Table 1, Alg. 1-2 |
//! | [`GpuContext`] | headless instance, adapter, device; pipelines, buffers, dispatch, read-back | — |
//! | [`kernels`] | typed pipelines: [`VmfKernels`](kernels::VmfKernels) (pdf, sampling, statistics update, reconstruction, product, convolution), [`VmfMixtureKernel`](kernels::VmfMixtureKernel), [`HashgridKernels`](kernels::HashgridKernels) (hashes, vertex keys), [`GpuHashTable`](kernels::GpuHashTable) (insert-or-get, lookup, insert-and-touch, eviction), [`GpuTexels`](kernels::GpuTexels), [`MarkovKernels`](kernels::MarkovKernels) (grid and pixel states) | — |
//! | [`types`] | `Pod` twins of the kernels' WGSL structs | — |
//!
//! # Conventions
//! - Every WGSL struct that crosses the bus has the byte layout of its Rust twin
//!   (`mcg_vmf::Vmf` 16 B, `mcg_vmf::SufficientStats` 24 B, `mcg_hashgrid::CellKey` 16 B,
//!   `mcg_markov_guide::mcpg::GridState` 32 B, `mcg_markov_guide::mcmm::PixelState` 28 B and
//!   the types in [`types`]); a naga test checks sizes and offsets.
//! - No hidden randomness: samplers take uniforms in [0, 1) from the caller, like the CPU.
//! - Kernels use workgroups of [`WORKGROUP_SIZE`] = 64 invocations and need no feature and
//!   no limit beyond WebGPU's defaults.
//! - Bit-exact twins (hashes, codes) wrap every product that feeds a sum in a `max` that
//!   keeps the shader compiler from fusing it into an FMA (WGSL has no `precise`; lavapipe
//!   fuses). The vMF twin does not: its `exp`/`log` differ from the CPU's anyway, and its
//!   parity tests allow for fused operations.
//!
//! # Example
//! Put a vMF lobe's density into your own compute shader:
//! ```
//! use mcg_gpu_backend::shaders;
//! let my_shader = format!(
//!     "{}\n{}",
//!     shaders::VMF_MODULE,
//!     "@group(0) @binding(0) var<storage, read_write> out: array<f32>;
//!      @compute @workgroup_size(64)
//!      fn main(@builtin(global_invocation_id) id: vec3<u32>) {
//!          let lobe = Vmf(vec3<f32>(0.0, 0.0, 1.0), 10.0);
//!          out[id.x] = vmf_pdf(lobe, vec3<f32>(0.0, 0.0, 1.0));
//!      }"
//! );
//! // Build it with `GpuContext::compute_kernel(&my_shader, "main")` (needs an adapter),
//! // or with your own `wgpu::Device::create_shader_module`.
//! assert!(my_shader.contains("fn vmf_pdf("));
//! ```
//!
//! [wgpu]: https://wgpu.rs
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]

pub use mcg_color_codec;
pub use mcg_hashgrid;
pub use mcg_markov_guide;
pub use mcg_vmf;
pub use wgpu;

mod buffer;
mod context;
mod error;
pub mod kernels;
pub mod prelude;
pub mod shaders;
pub mod testing;
pub mod types;

pub use buffer::GpuBuffer;
pub use context::{ComputeKernel, GpuContext};
pub use error::GpuError;

/// Invocations per workgroup of every kernel in this crate (WebGPU guarantees 256).
pub const WORKGROUP_SIZE: u32 = 64;

#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
