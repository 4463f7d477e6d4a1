//! The mcg primitives as a WGSL shader library for your own shaders, and their host side on
//! wgpu, in parity with the CPU crates.
//!
//! Renderer authors get the primitives of [`mcg_vmf`], [`mcg_hashgrid`], [`mcg_color_codec`]
//! and the chain states of [`mcg_markov_guide`] as WGSL modules they `#import` into their own
//! shaders ([`shaders`]: naga_oil modules `mcg::*`, or plain WGSL), with tests that hold the GPU
//! to the CPU crates' answers: bit for bit for hashes, checksums, table outcomes, packed words
//! and chain states; within a stated tolerance for the vMF lobes, where WGSL's `exp` and `log`
//! are less exact than the CPU's.
//!
//! | item | what it is |
//! |---|---|
//! | [`shaders`] | the library: [`Module`](shaders::Module)s, [`add_to_composer`](shaders::add_to_composer) (naga_oil), [`compose`](shaders::compose) / [`wgsl`](shaders::wgsl) (plain WGSL), the generated [`constants`](shaders::constants) |
//! | [`types`] | `Pod` twins of the WGSL structs the host uploads ([`HashgridTableParams`](types::HashgridTableParams), queries, parameters) |
//! | [`guides`] | the guides on the GPU: [`guides::mcpg`] (`mcg::mcpg` + [`GpuMcpgGuide`](guides::mcpg::GpuMcpgGuide)), [`guides::mcmm`] (`mcg::mcmm` + [`GpuMcmmGuide`](guides::mcmm::GpuMcmmGuide)), [`guides::adgi`] (`mcg::adgi` + [`GpuProbeCache`](guides::adgi::GpuProbeCache): ADGI's probe texels, update, query, DDGI's blend, clip volume, pilot rays; `mcg::adgi_chains` + [`GpuProbeChains`](guides::adgi::GpuProbeChains), [`GpuTriggerSmoothing`](guides::adgi::GpuTriggerSmoothing): guiding function, Metropolis probe chains, trigger smoothing) |
//! | [`codes`] | the integer codes of Rust enums in WGSL, defined once |
//! | [`sampling`] | the CPU twin of the GPU's random numbers |
//! | [`GpuContext`] (feature `runtime`) | a headless context or one on your own device ([`GpuContext::from_device`]); pipelines, buffers, dispatch, read-back |
//! | host types (feature `runtime`) | [`VmfKernels`], [`VmfMixtureKernel`], [`HashgridKernels`], [`CodecKernels`], [`MarkovKernels`]: typed kernels, pipelines built on first use; [`GpuHashTable`], [`GpuTexels`]: GPU-resident tables and texels |
//!
//! # Features
//! - `runtime` (default): the host side on [wgpu] (re-exported as [`wgpu`] so versions match).
//! - `compose` (default): [`shaders::add_to_composer`] for naga_oil.
//!
//! With `default-features = false` you get the WGSL sources, the plain-WGSL composer and the
//! `Pod` types without compiling wgpu or naga.
//!
//! # Conventions
//! - Every WGSL struct that crosses the bus has the byte layout of its Rust twin
//!   (`mcg_vmf::Vmf` 16 B, `mcg_vmf::SufficientStats` 24 B, `mcg_hashgrid::CellKey` 16 B,
//!   `mcg_markov_guide::mcpg::GridState` 32 B, `mcg_markov_guide::mcmm::PixelState` 28 B and
//!   the types in [`types`]); a naga test checks sizes and offsets.
//! - No hidden randomness: samplers take uniforms in [0, 1) from the caller, like the CPU.
//! - Kernels use workgroups of [`WORKGROUP_SIZE`] = 64 invocations and need no feature and
//!   no limit beyond WebGPU's defaults.
//! - Bit-exact twins (hashes, codes, states) wrap every product that feeds a sum in
//!   `mcg_rounded`, which keeps the shader compiler from fusing it into an FMA (WGSL has no
//!   `precise`; lavapipe fuses). The vMF twin does not: its `exp`/`log` differ from the CPU's
//!   anyway, and its parity tests allow for fused operations.
//!
//! # Numerics on real GPUs
//! WGSL promises less than IEEE arithmetic, and GPUs use the latitude (lavapipe mostly does
//! not, so the parity tests also feed the inputs that would expose it). The WGSL follows
//! these rules:
//! - Finiteness and NaN are read from the bits (`mcg_is_finite`, `mcg_is_nan`,
//!   `mcg_is_positive`, `mcg_positive_part3` in `mcg::math`), never from comparisons: WGSL lets
//!   a compiler assume no NaN or infinity, so `x != x` may fold to false and `!(x > 0.0)` may
//!   become `x <= 0.0`. Such guards sit where data enters (the caller's values, buffers the
//!   host writes); `min`, `max` and `clamp` return the operand that is not NaN.
//! - `log` is only accurate to 2⁻²¹ absolute on [½, 2], so quantities near 0 that are divided
//!   or compared relatively (expm1, ln(1 + x)) come from series there, not from `log` near 1.
//! - Division is not exact: x/x need not be 1 (an NVIDIA GPU gives 0.99999994), and products
//!   may fuse into FMAs; results that must match the CPU bit for bit wrap products in
//!   `mcg_rounded`, and none relies on a division being exact.
//!
//! [wgpu]: https://wgpu.rs
#![cfg_attr(docsrs, feature(doc_cfg))]

pub use mcg_color_codec;
pub use mcg_hashgrid;
pub use mcg_markov_guide;
pub use mcg_vmf;
#[cfg(feature = "compose")]
pub use naga_oil;
#[cfg(feature = "runtime")]
pub use wgpu;

pub mod codes;
// The host side's error type is needed without it too: `McpgGpuParams::new` returns it.
#[path = "runtime/error.rs"]
mod error;
pub mod guides;
#[cfg(feature = "runtime")]
mod runtime;
pub mod sampling;
pub mod shaders;
pub mod types;

pub use error::GpuError;
#[cfg(feature = "runtime")]
pub use runtime::{
    CodecKernels, CodecPackRead, ComputeKernel, GpuBuffer, GpuContext, GpuHashTable, GpuTexels,
    GridStateQueryRead, GridStateRead, GuidedKernel, HashgridKernels, LogLuvRead, MarkovKernels,
    PixelStateRead, VmfKernels, VmfMixtureEval, VmfMixtureKernel, buffer_entry, sized_buffer_entry,
    storage_entry, testing,
};

/// Invocations per workgroup of every kernel in this crate (WebGPU guarantees 256).
pub const WORKGROUP_SIZE: u32 = 64;

#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
