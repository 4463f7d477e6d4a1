//! # mcg-color-codec: packed, log-encoded texels that survive atomic updates
//!
//! ADGI (*Adaptive Dynamic Global Illumination*) stores probe irradiance, visibility and
//! heuristics in 32-bit words that a GPU updates with compare-and-swap. This crate gives
//! renderer authors those words — the log colour codec, the packed layouts with a count field,
//! the moving average and its lock-free update — and the formats they would otherwise choose,
//! bit-exact and behind one trait, so the choice can be measured.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`LogCodec`], [`LogField`] | `u = min(ln(γv + 1), β)/β`, quantised to k bits; (5, 15) and (8, 20) | ADGI eq. 21, sec. 4.5-4.6, App. B |
//! | [`Rounding`], [`quantize()`] | round down (ADGI), nearest, stochastic (caller's uniform) | ADGI App. B |
//! | [`IrradianceLayout`], [`IrradianceWord`] | R9 G9 B8 + 6-bit count (widths configurable) | ADGI sec. 4.5, Table 3 |
//! | [`VisibilityLayout`], [`VisibilityWord`] | 13-bit d̄ + 13-bit d̄² + 6-bit count | ADGI sec. 4.6, Table 3 |
//! | [`HeuristicsLayout`], [`HeuristicsWord`], [`Heuristics`] | f_v, f_s, f_d as 6-10-10 bits + 6 flags | ADGI sec. 4.3, eq. 11, 19, 20 |
//! | [`MovingAverage`], [`CountedLayout`] | 1/N average up to N_max, then hysteresis (N_max − 1)/N_max; `word → word` and an `AtomicU32` CAS loop | ADGI sec. 4.7, Alg. 3 |
//! | [`ColorCodec`], [`LogRgb`] | one trait over every colour codec (per colour and slices; batch form for the log codec) | — |
//! | [`R11G11B10`], [`Rgb9E5`], [`LogLuv32`], [`Gamma5R10G10B10A2`] | Vulkan/D3D packed float, shared exponent, Ward's LogLuv, RTXGI's gamma-5 UNORM | specs cited per type |
//! | [`CONSTANTS`] | layouts, β, γ, N_max as one table for the WGSL prelude | — |
//!
//! ## Conventions
//! - Colours are linear RGB [`glam::Vec3`] (sRGB / Rec. 709 primaries where it matters:
//!   LogLuv's XYZ conversion); distances are normalised by the probe cage diagonal (ADGI 4.6).
//! - Bad input never poisons a word: every `encode` maps negative channels and NaN to 0 and
//!   saturates too-large values and +∞; every `decode` accepts any `u32` and returns finite,
//!   non-negative values (tested for every value of every field); the moving average ignores
//!   NaN samples without advancing the count.
//! - No hidden randomness: stochastic rounding takes the caller's uniform in [0, 1).
//! - Each layout documents its bit map and a derived round-trip error bound; the tests check
//!   them on dense log-spaced sweeps.
//! - f32 throughout; the log codec's `ln`/`exp` are branch-free polynomials on the float bits,
//!   evaluated for the three channels at once as one 4-lane `glam::Vec4` with plain IEEE
//!   operations in a fixed order (no FMA, no platform `libm`), so results do not depend on the
//!   `std`/`libm` choice or the target, and a WGSL port can reproduce them bit for bit. Words are `#[repr(transparent)]` `u32`
//!   and [`bytemuck::Pod`].
//!
//! ## Performance
//! ADGI's log codec (R9G9B8, round down) decodes from a table and rounds down by a table
//! search (the polynomials' exact results, run with the tables and shifts as constants per
//! colour and in the slice API, whether or not the caller's layout is a constant): a round trip
//! takes 0.91–0.94× R11G11B10's time per colour with the codec a run-time value as in the
//! criterion bench (0.77–0.81× where the caller's loop keeps it in registers) and 0.87–0.88×
//! through the slice API (fastest of repeated runs on a shared 2-vCPU AMD EPYC VM, baseline
//! x86-64: `cargo run --release -p mcg-color-codec --example codec_min_timing`); 81 (75) and 67
//! instructions per colour against R11G11B10's 70 and 77 (`scripts/codec-instructions`). The
//! criterion groups (`cargo bench -p mcg-color-codec --bench color_codec -- round_trip`, load
//! 0.7–3.2) gave 1.05–1.14× per colour and 0.71–0.95× for the slices; numbers and diary:
//! `benches/README.md`.
//!
//! ## Features
//! - `std` (default): float functions from the standard library.
//! - `libm`: float functions from the `libm` crate, for `#![no_std]` builds.
//!
//! ## Example
//! ```
//! use core::sync::atomic::AtomicU32;
//! use mcg_color_codec::{ColorCodec, IrradianceLayout, MovingAverage, R11G11B10, Rounding, glam::Vec3};
//!
//! // A probe texel updated by several rays (here one thread; the CAS loop makes it safe for many).
//! let layout = IrradianceLayout::ADGI;
//! let texel = AtomicU32::new(0);
//! for (i, radiance) in [Vec3::new(0.9, 0.6, 0.3), Vec3::new(1.1, 0.6, 0.3)].into_iter().enumerate() {
//!     let u = 0.25 + 0.5 * i as f32; // the caller's uniforms
//!     MovingAverage::STATIC.update_atomic(&layout, &texel, radiance, Rounding::Stochastic(u));
//! }
//! let word = texel.into_inner().into();
//! assert_eq!(layout.count(word), 2);
//! assert!((layout.decode(word) - Vec3::new(1.0, 0.6, 0.3)).abs().max_element() < 0.02);
//!
//! // The format you would otherwise pick, through the same trait.
//! let c = R11G11B10.decode(R11G11B10.encode(Vec3::new(1.0, 0.6, 0.3)));
//! assert!((c - Vec3::new(1.0, 0.6, 0.3)).abs().max_element() < 0.01);
//! ```
#![no_std]
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(any(feature = "std", test))]
extern crate std;

pub use glam;

mod bits;
mod codec;
mod constants;
mod error;
mod gamma5_r10g10b10a2;
mod heuristics_word;
mod irradiance_word;
mod log_codec;
mod log_table;
mod logluv32;
mod math;
mod moving_average;
mod quantize;
mod r11g11b10;
mod rgb9e5;
mod simd4;
mod visibility_word;

pub use codec::{ColorCodec, LogRgb};
pub use constants::{CONSTANTS, ConstantValue, NamedConstant};
pub use error::CodecError;
pub use gamma5_r10g10b10a2::{Gamma5R10G10B10A2, RTXGI_IRRADIANCE_GAMMA};
pub use heuristics_word::{Heuristics, HeuristicsLayout, HeuristicsWord};
pub use irradiance_word::{IrradianceLayout, IrradianceWord};
pub use log_codec::{LogCodec, LogField, MAX_FIELD_BITS};
pub use logluv32::{LogLuv32, SRGB_TO_XYZ, XYZ_TO_SRGB};
pub use moving_average::{CountedLayout, MovingAverage};
pub use quantize::{MAX_QUANTIZE_CODE, Rounding, quantize, quantize_unorm};
pub use r11g11b10::{
    B10_MAX, R11_MAX, R11G11B10, UFLOAT_MAX_MANTISSA_BITS, f32_to_ufloat, ufloat_to_f32,
};
pub use rgb9e5::{RGB9E5_MAX, Rgb9E5};
pub use visibility_word::{VisibilityLayout, VisibilityWord};

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
