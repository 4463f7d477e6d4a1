//! Float functions that `core` lacks, taken from `std` or from `libm`, and exact integer
//! conversions that need no float library.

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("mcg-hashgrid needs the `std` feature (default) or the `libm` feature");

#[cfg(feature = "std")]
mod imp {
    #[inline(always)]
    pub fn exp(x: f32) -> f32 {
        x.exp()
    }
    #[inline(always)]
    pub fn ln(x: f32) -> f32 {
        x.ln()
    }
}

#[cfg(all(not(feature = "std"), feature = "libm"))]
mod imp {
    #[inline(always)]
    pub fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline(always)]
    pub fn ln(x: f32) -> f32 {
        libm::logf(x)
    }
}

#[cfg(any(feature = "std", feature = "libm"))]
pub(crate) use imp::*;

/// The largest f32 below 1: where uniforms are clamped so they stay in [0, 1).
pub(crate) const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// ⌊x⌋ as an `i32`, saturating at `i32::MIN`/`i32::MAX`; NaN gives 0.
#[inline(always)]
pub(crate) fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    t.saturating_sub(i32::from((t as f32) > x))
}

/// `u` moved into [0, 1): NaN and negatives give 0, values ≥ 1 give the largest f32 below 1.
#[inline(always)]
pub(crate) fn sanitize_uniform(u: f32) -> f32 {
    if u >= 0.0 {
        u.min(ONE_MINUS_EPSILON)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_i32_is_exact_and_saturates() {
        for (x, want) in [
            (0.0, 0),
            (-0.0, 0),
            (0.5, 0),
            (-0.5, -1),
            (-1.0, -1),
            (-1.000_000_1, -2),
            (2.999_999_8, 2),
            (1e10, i32::MAX),
            (-1e10, i32::MIN),
            (f32::NAN, 0),
            (f32::INFINITY, i32::MAX),
            (f32::NEG_INFINITY, i32::MIN),
        ] {
            assert_eq!(floor_i32(x), want, "floor({x})");
        }
        assert_eq!(ONE_MINUS_EPSILON, f32::from_bits(0x3F7F_FFFF));
        assert_eq!(sanitize_uniform(f32::NAN), 0.0);
        assert_eq!(sanitize_uniform(1.0), ONE_MINUS_EPSILON);
        assert_eq!(sanitize_uniform(0.25), 0.25);
    }
}
