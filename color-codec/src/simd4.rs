//! Four-lane f32 / i32 vectors for the log codec's hot path.
//!
//! [`F4`] wraps [`glam::Vec4`], which is an SSE2 register on `x86_64` (NEON on `aarch64`,
//! SIMD128 on `wasm32` with that feature, plain floats elsewhere), so the float work of the
//! three colour channels runs as one vector without `unsafe` in this crate. [`I4`] holds the
//! few integer / bit steps as a plain `[i32; 4]` between two vectors, which LLVM turns into
//! vector integer instructions. Relying on the auto-vectoriser for everything proved fragile:
//! with three live channels (the fourth lane dead or constant) LLVM's SLP vectoriser split the
//! work 2 + 1 and ran a third of it scalar.
//!
//! Every operation is a plain IEEE-754 single-precision add, sub, mul or ordered compare, a
//! select, an exact i32 → f32 conversion or a bit operation, lane by lane in a fixed order:
//! nothing contracts `a * b + c` into an FMA and no platform `libm` is called, so the lanes are
//! bit-identical to the scalar functions in `math` (tested), across targets, and to a WGSL port
//! that keeps the order.

use glam::{BVec4A, Vec4};

/// Four f32 lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct F4(Vec4);

/// Four i32 lanes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct I4([i32; 4]);

/// Four lane flags (the result of a comparison).
#[derive(Clone, Copy, Debug)]
pub(crate) struct M4(BVec4A);

impl F4 {
    #[inline(always)]
    pub fn new(a: [f32; 4]) -> Self {
        F4(Vec4::from_array(a))
    }
    #[inline(always)]
    pub fn splat(a: f32) -> Self {
        F4(Vec4::splat(a))
    }
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        self.0.to_array()
    }
    #[inline(always)]
    pub fn add(self, b: F4) -> F4 {
        F4(self.0 + b.0)
    }
    #[inline(always)]
    pub fn sub(self, b: F4) -> F4 {
        F4(self.0 - b.0)
    }
    #[inline(always)]
    pub fn mul(self, b: F4) -> F4 {
        F4(self.0 * b.0)
    }
    /// `if a < b { a } else { b }` per lane for lanes that are never NaN (SSE2 `minps`, glam's
    /// scalar fallback spells out the same; callers never compare −0 with +0, where NEON's
    /// `vminq` could pick the other zero).
    #[inline(always)]
    pub fn min(self, b: F4) -> F4 {
        F4(self.0.min(b.0))
    }
    /// `if a > b { a } else { b }` per lane for lanes that are never NaN, as [`F4::min`].
    #[inline(always)]
    pub fn max(self, b: F4) -> F4 {
        F4(self.0.max(b.0))
    }
    /// |a| (clears the sign bit).
    #[inline(always)]
    pub fn abs(self) -> F4 {
        F4(self.0.abs())
    }
    #[inline(always)]
    pub fn lt(self, b: F4) -> M4 {
        M4(self.0.cmplt(b.0))
    }
    #[inline(always)]
    pub fn le(self, b: F4) -> M4 {
        M4(self.0.cmple(b.0))
    }
    #[inline(always)]
    pub fn gt(self, b: F4) -> M4 {
        M4(self.0.cmpgt(b.0))
    }
    #[inline(always)]
    pub fn ge(self, b: F4) -> M4 {
        M4(self.0.cmpge(b.0))
    }
    /// `if mask { a } else { b }` per lane.
    #[inline(always)]
    pub fn select(mask: M4, a: F4, b: F4) -> F4 {
        F4(Vec4::select(mask.0, a.0, b.0))
    }
    /// `f32::to_bits` per lane, as i32.
    #[inline(always)]
    pub fn to_bits(self) -> I4 {
        I4(bytemuck::cast(self.0.to_array()))
    }
}

impl I4 {
    #[inline(always)]
    pub fn new(a: [i32; 4]) -> Self {
        I4(a)
    }
    #[inline(always)]
    pub fn to_array(self) -> [i32; 4] {
        self.0
    }
    /// Wrapping per-lane `self + b`.
    #[inline(always)]
    pub fn add(self, b: i32) -> I4 {
        I4(self.0.map(|a| a.wrapping_add(b)))
    }
    /// Wrapping per-lane `self − b`.
    #[inline(always)]
    pub fn sub(self, b: i32) -> I4 {
        I4(self.0.map(|a| a.wrapping_sub(b)))
    }
    /// Wrapping per-lane `self − b`.
    #[inline(always)]
    pub fn sub_lanes(self, b: I4) -> I4 {
        I4(core::array::from_fn(|i| self.0[i].wrapping_sub(b.0[i])))
    }
    #[inline(always)]
    pub fn and_lanes(self, b: I4) -> I4 {
        I4(core::array::from_fn(|i| self.0[i] & b.0[i]))
    }
    #[inline(always)]
    pub fn and(self, b: i32) -> I4 {
        I4(self.0.map(|a| a & b))
    }
    /// Arithmetic shift right by 23 (the f32 exponent field).
    #[inline(always)]
    pub fn shr23(self) -> I4 {
        I4(self.0.map(|a| a >> 23))
    }
    /// Shift left by 23 (into the f32 exponent field).
    #[inline(always)]
    pub fn shl23(self) -> I4 {
        I4(self.0.map(|a| a << 23))
    }
    /// `as f32` per lane (exact for magnitudes below 2²⁴).
    #[inline(always)]
    pub fn to_f32(self) -> F4 {
        F4(Vec4::from_array(self.0.map(|a| a as f32)))
    }
    /// `f32::from_bits` per lane.
    #[inline(always)]
    pub fn bits_to_f32(self) -> F4 {
        F4(Vec4::from_array(bytemuck::cast(self.0)))
    }
}

impl M4 {
    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.any()
    }
}
