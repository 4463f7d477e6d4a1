//! Float functions: the fast, branch-free `ln`/`exp2` of the hot paths, and `exp2`
//! from `std` or `libm` for LogLuv's decoder.
//!
//! `core` has no transcendental functions. With the `std` feature the inherent `f32` methods are
//! used; without it the `libm` crate provides them, so the crate builds for `no_std` targets.
//! The codec hot paths do not call either: [`fast_ln_ge1`] and [`fast_exp2`] are a few
//! multiply-adds on the float's bits, identical under `std` and `libm` (so encodings do not
//! depend on the feature), and vectorise.

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("mcg-color-codec needs the `std` feature (default) or the `libm` feature");

#[cfg(feature = "std")]
mod imp {
    #[inline(always)]
    pub fn exp2(x: f32) -> f32 {
        x.exp2()
    }
}

#[cfg(all(not(feature = "std"), feature = "libm"))]
mod imp {
    #[inline(always)]
    pub fn exp2(x: f32) -> f32 {
        libm::exp2f(x)
    }
}

#[cfg(any(feature = "std", feature = "libm"))]
pub(crate) use imp::*;

/// Adding then subtracting 1.5·2²³ rounds an f32 in (−2²², 2²²) to the nearest integer
/// (ties to even) in the default rounding mode, without a float → int conversion.
pub(crate) const ROUND_SHIFT: f32 = 12_582_912.0;

/// Natural logarithm of `x ≥ 1` (including +∞, which gives 128·ln 2 ≈ 88.7), branch-free and
/// division-free.
///
/// Splits `x = 2ᵉ·m` with m ∈ [√½, √2) from the bits (musl's reduction), then
/// `ln m = t − t²/2 + t³·P(t)`, t = m − 1, with the degree-8 minimax polynomial P of Cephes'
/// `logf` (S. Moshier); the error is a few f32 ulps (tested against f64). Normal inputs below 1
/// also work; NaN, zero, subnormal and negative inputs give garbage (callers clamp first).
#[inline(always)]
pub(crate) fn fast_ln_ge1(x: f32) -> f32 {
    const SQRT_HALF_BITS: u32 = 0x3f35_04f3;
    let bits = x.to_bits();
    let shifted = bits.wrapping_sub(SQRT_HALF_BITS);
    let e = (shifted as i32 >> 23) as f32;
    let m = f32::from_bits(bits.wrapping_sub(shifted & 0xff80_0000));
    let t = m - 1.0;
    let t2 = t * t;
    let p = 7.037_683_6e-2;
    let p = p * t - 1.151_461e-1;
    let p = p * t + 1.167_699_9e-1;
    let p = p * t - 1.242_014_1e-1;
    let p = p * t + 1.424_932_3e-1;
    let p = p * t - 1.666_805_8e-1;
    let p = p * t + 2.000_071_5e-1;
    let p = p * t - 2.499_999_4e-1;
    let p = p * t + 0.333_333_3;
    // ln 2 split in a part exact in f32 times e (|e| ≤ 128) and a small remainder.
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    let y = t * t2 * p + e * LN2_LO - 0.5 * t2;
    t + y + e * LN2_HI
}

/// 2ˣ for x ∈ [−126, 127], branch-free: `2^round(x)` from the bits times a degree-6 polynomial
/// of 2^f on f ∈ [−½, ½] (Cephes `exp2f` coefficients, relative error ≈ 2·10⁻⁷, tested
/// against f64). Exactly 1 at x = 0.
#[inline(always)]
pub(crate) fn fast_exp2(x: f32) -> f32 {
    let shifted = x + ROUND_SHIFT;
    let i = shifted - ROUND_SHIFT;
    let f = x - i;
    let p = 1.0
        + f * (6.931_472e-1
            + f * (2.402_264_8e-1
                + f * (5.550_332_5e-2
                    + f * (9.618_437e-3 + f * (1.339_887_4e-3 + f * 1.535_336_2e-4)))));
    // The low mantissa bits of `shifted` hold round(x) (two's complement for negatives).
    let k = (shifted.to_bits() as i32).wrapping_sub(ROUND_SHIFT.to_bits() as i32);
    p * f32::from_bits(((k + 127) as u32) << 23)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_ln_is_accurate() {
        let mut x = 1.0_f32;
        while x < 3e38 {
            let want = (x as f64).ln();
            let got = fast_ln_ge1(x) as f64;
            assert!(
                (got - want).abs() <= 4e-7 * want.max(1.0),
                "ln({x}) = {got} vs {want}"
            );
            x = x * 1.000_37 + 1e-6;
        }
        assert_eq!(fast_ln_ge1(1.0), 0.0);
        let inf = fast_ln_ge1(f32::INFINITY);
        assert!((inf - 128.0 * core::f32::consts::LN_2).abs() < 1e-4);
        // Also fine below 1 (normal floats).
        assert!((fast_ln_ge1(0.3) as f64 - 0.3f64.ln()).abs() < 3e-7);
    }

    #[test]
    fn fast_exp2_is_accurate() {
        let mut x = -120.0_f32;
        while x < 120.0 {
            let want = (x as f64).exp2();
            let got = fast_exp2(x) as f64;
            assert!(
                ((got - want) / want).abs() < 3e-7,
                "exp2({x}) = {got} vs {want}"
            );
            x += 0.001_37;
        }
        assert_eq!(fast_exp2(0.0), 1.0);
        assert_eq!(fast_exp2(3.0), 8.0);
    }
}
