//! Float functions that `core` lacks, taken from `std` or from `libm`.

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("mcg-markov-guide needs the `std` feature (default) or the `libm` feature");

#[cfg(feature = "std")]
mod imp {
    #[inline(always)]
    pub fn ln(x: f32) -> f32 {
        x.ln()
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
    pub fn ln(x: f32) -> f32 {
        libm::logf(x)
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

/// How scores, weights and targets that are NaN, infinite or negative are kept out of chain
/// states: one rule, shared with the estimators.
pub(crate) use mcg_smis::finite_non_negative_or_zero;

/// `v.is_finite()` in two float operations per component and one compare: c − c is 0 for
/// finite c and NaN for ±∞ and NaN. LLVM lowers `f32::is_finite` to integer class tests,
/// several times the instructions, on the guide's per-vertex path.
#[inline(always)]
#[allow(clippy::eq_op)] // c − c is the test
pub(crate) fn all_finite(v: mcg_vmf::glam::Vec3) -> bool {
    (v.x - v.x) + (v.y - v.y) + (v.z - v.z) == 0.0
}

/// Radiance that may reach a chain's estimate or the irradiance cache: 0 when any component
/// is NaN or infinite, else `v` with negative components made 0 (one rule for both).
#[cfg(feature = "std")]
#[inline(always)]
pub(crate) fn finite_radiance(v: mcg_vmf::glam::Vec3) -> mcg_vmf::glam::Vec3 {
    if all_finite(v) {
        v.max(mcg_vmf::glam::Vec3::ZERO)
    } else {
        mcg_vmf::glam::Vec3::ZERO
    }
}
