//! Float functions that `core` lacks, taken from `std` or from `libm`.
//!
//! With the `std` feature the inherent `f32` methods are used (they compile to the
//! platform's libm); without it the `libm` crate provides the same functions, so the
//! crate builds for `no_std` targets such as Rust-to-SPIR-V shader crates.

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("mcg-vmf needs the `std` feature (default) or the `libm` feature");

#[cfg(feature = "std")]
mod imp {
    #[inline(always)]
    pub fn exp(x: f32) -> f32 {
        x.exp()
    }
    #[inline(always)]
    pub fn exp_m1(x: f32) -> f32 {
        x.exp_m1()
    }
    #[inline(always)]
    pub fn ln_1p(x: f32) -> f32 {
        x.ln_1p()
    }
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        x.sqrt()
    }
    #[inline(always)]
    pub fn sin_cos(x: f32) -> (f32, f32) {
        x.sin_cos()
    }
}

#[cfg(all(not(feature = "std"), feature = "libm"))]
mod imp {
    #[inline(always)]
    pub fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline(always)]
    pub fn exp_m1(x: f32) -> f32 {
        libm::expm1f(x)
    }
    #[inline(always)]
    pub fn ln_1p(x: f32) -> f32 {
        libm::log1pf(x)
    }
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
    #[inline(always)]
    pub fn sin_cos(x: f32) -> (f32, f32) {
        libm::sincosf(x)
    }
}

#[cfg(any(feature = "std", feature = "libm"))]
pub(crate) use imp::*;
