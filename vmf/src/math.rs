//! Float functions that `core` lacks, taken from `std` or from `libm`.
//!
//! With the `std` feature the inherent `f32` methods are used (they compile to the
//! platform's libm); without it the `libm` crate provides the same functions, so the
//! crate builds for `no_std` targets such as Rust-to-SPIR-V shader crates.

use crate::constants::{ATANH_SERIES, EXP_POLY, LN2_HI, LN2_LO};

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("mcg-vmf needs the `std` feature (default) or the `libm` feature");

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
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        x.sqrt()
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
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        libm::sqrtf(x)
    }
}

#[cfg(any(feature = "std", feature = "libm"))]
pub(crate) use imp::*;

/// eˣ − 1 without cancellation near 0, from `exp` and `ln` (which are much faster than the
/// platform's `expm1f`).
///
/// For |x| > 0.5 the result is at least 0.39 in magnitude, so `exp(x) − 1` loses nothing. Near
/// 0 Kahan's identity `expm1(x) = (u − 1) · x / ln(u)` with `u = fl(eˣ)` cancels the rounding
/// error of `u` (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., sec. 1.14.1),
/// leaving a few ulps. Overflows to +∞ and tends to −1 like `expm1`.
#[cfg(any(feature = "std", feature = "libm"))]
#[inline(always)]
pub(crate) fn exp_m1(x: f32) -> f32 {
    if !(x.abs() <= crate::constants::EXP_M1_KAHAN_LIMIT) {
        return exp(x) - 1.0;
    }
    let u = exp(x);
    if u == 1.0 {
        return x;
    }
    (u - 1.0) * x / ln(u)
}

/// `v.is_finite()` as float arithmetic and one compare: c − c is 0 for finite c and NaN for
/// ±∞ and NaN. LLVM lowers `f32::is_finite` to integer class tests, several times the
/// instructions, on the per-sample update path.
#[inline(always)]
#[allow(clippy::eq_op)] // c − c is the test
pub(crate) fn all_finite(v: glam::Vec3) -> bool {
    (v.x - v.x) + (v.y - v.y) + (v.z - v.z) == 0.0
}

/// `v / |v|` that keeps full precision for every finite non-zero `v`, or `None` for zero and
/// non-finite vectors.
///
/// Where |v|² is a normal f32 this is exactly `v.try_normalize()` (bit-identical); where it
/// underflows into the subnormals (|v| < 1.1·10⁻¹⁹, where squaring loses bits and the result
/// drifts off unit length) or overflows (|v| > 1.8·10¹⁹), `v` is first divided by its largest
/// component magnitude.
#[inline]
pub(crate) fn normalize_robust(v: glam::Vec3) -> Option<glam::Vec3> {
    let length_squared = v.length_squared();
    if (f32::MIN_POSITIVE..=f32::MAX).contains(&length_squared) {
        // `v.try_normalize()` (1/|v| and its finiteness test), with the test as two compares.
        let rcp = 1.0 / sqrt(length_squared);
        return ((rcp > 0.0) & (rcp < f32::INFINITY)).then(|| v * rcp);
    }
    let largest = v.abs().max_element();
    if !(largest > 0.0 && largest <= f32::MAX) {
        return None;
    }
    (v / largest).try_normalize()
}

/// |v| without overflow: `v.length()` (bit-identical) where |v|² is finite, else the length of
/// `v` scaled by its largest component magnitude, saturating at `f32::MAX` (NaN stays NaN).
#[inline]
pub(crate) fn length_robust(v: glam::Vec3) -> f32 {
    let length_squared = v.length_squared();
    if length_squared.is_finite() {
        return sqrt(length_squared);
    }
    let largest = v.abs().max_element();
    if !(largest <= f32::MAX) {
        // ±∞ gives +∞ saturated, NaN stays NaN.
        return if largest.is_nan() { f32::NAN } else { f32::MAX };
    }
    (largest * (v / largest).length()).min(f32::MAX)
}

/// (sin 2πt, cos 2πt) for a turn fraction `t` (usually a uniform in [0, 1)).
///
/// Reduces exactly in turns (t·4 − round(t·4) is exact in f32, unlike 2πt), then evaluates
/// minimax polynomials of sin and cos on [−π/4, π/4] (degree 7 and 8, error < 6·10⁻⁸)
/// and rotates by the quadrant with bit operations, so nothing branches on the random input.
#[inline(always)]
pub(crate) fn sin_cos_turns(t: f32) -> (f32, f32) {
    // Adding 1.5·2²³ rounds to the nearest integer in the low mantissa bits (valid for
    // |4t| < 2²²); subtracting it again gives that integer as a float, without a float → int
    // conversion (which Rust saturates, at a cost).
    let quarter_turns = 4.0 * t;
    let shifted = quarter_turns + ROUND_SHIFT;
    let quadrant = shifted - ROUND_SHIFT;
    let x = (quarter_turns - quadrant) * core::f32::consts::FRAC_PI_2;
    let x2 = x * x;
    // Minimax polynomials on [−π/4, π/4] (coefficients of Cephes' sinf/cosf, S. Moshier):
    // absolute error below 6·10⁻⁸ for both.
    let [s0, s1, s2] = crate::constants::SIN_POLY;
    let [c0, c1, c2] = crate::constants::COS_POLY;
    let sin = x + x * x2 * (s0 + x2 * (s1 + x2 * s2));
    let cos = 1.0 - 0.5 * x2 + x2 * x2 * (c0 + x2 * (c1 + x2 * c2));
    // Rotate by the quadrant q without branches (a uniform t makes q unpredictable):
    // q = 0: (s, c), 1: (c, −s), 2: (−s, −c), 3: (−c, s). Odd q swaps the pair, bit 1 of q
    // negates the sine slot, bit 1 of q + 1 the cosine slot.
    let q = shifted.to_bits();
    let swap = 0u32.wrapping_sub(q & 1);
    let (sin_bits, cos_bits) = (sin.to_bits(), cos.to_bits());
    let first = (sin_bits & !swap) | (cos_bits & swap);
    let second = (cos_bits & !swap) | (sin_bits & swap);
    (
        f32::from_bits(first ^ ((q & 2) << 30)),
        f32::from_bits(second ^ ((q.wrapping_add(1) & 2) << 30)),
    )
}

/// Adding then subtracting 1.5·2²³ rounds an f32 in (−2²², 2²²) to the nearest integer in the
/// default rounding mode, without a float → int conversion.
const ROUND_SHIFT: f32 = 12_582_912.0;

/// Natural logarithm of a positive, normal `x`, branch-free and inlinable (so that loops over
/// it vectorise): x = 2ᵏ m with m ∈ [√½, √2), s = (m − 1)/(m + 1), and
/// ln x = 2 atanh s + k ln 2 = 2s Σ s^{2i}/(2i + 1) + k ln 2, summed for i = 0 ..= 4
/// ([`ATANH_SERIES`]; |s| ≤ 0.172, so the first omitted term is below 10⁻⁹ relative). m − 1
/// is exact (Sterbenz), so the result keeps its relative precision as x → 1 and is exactly 0
/// at x = 1; where k ≠ 0, |ln x| ≥ ½ ln 2, so the single rounding of k ln 2 costs at most
/// half an ulp of the result (no Cody–Waite split needed, unlike `exp`'s reduction); relative error a few ulps (tested through the sampler against f64). Zero,
/// subnormal, infinite and NaN inputs give finite garbage or NaN: callers keep x in the
/// normal range.
#[inline(always)]
pub(crate) fn ln_fast(x: f32) -> f32 {
    const SQRT_HALF_BITS: u32 = 0x3f35_04f3;
    // Shift the exponent so that mantissas in [√½, 1) land in the next binade down.
    let bits = x.to_bits().wrapping_add(0x3f80_0000 - SQRT_HALF_BITS);
    let k = ((bits >> 23) as i32 - 127) as f32;
    let m = f32::from_bits((bits & 0x007f_ffff) + SQRT_HALF_BITS);
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = ATANH_SERIES[..4]
        .iter()
        .rev()
        .fold(ATANH_SERIES[4], |p, &c| p * s2 + c);
    2.0 * s * series + k * core::f32::consts::LN_2
}

/// `(eˣ, eˣ − 1)` for x in [−87, 0], branch-free and inlinable, with the polynomial of
/// Cephes' `expf` (S. L. Moshier): x = n ln 2 + r, |r| ≤ ½ ln 2, eʳ = 1 + r + r² P(r),
/// eˣ = 2ⁿ eʳ. For n = 0 (|x| < ½ ln 2) eˣ − 1 is taken as r + r² P(r) before the 1 is added,
/// so it keeps full relative precision as x → 0; otherwise |eˣ − 1| ≥ 0.29 and the subtraction
/// is exact to an ulp. Relative error of both below 2⁻²². The caller keeps x in [−87, 0]
/// (below, 2ⁿ is not a normal float).
#[inline(always)]
pub(crate) fn exp_expm1_fast(x: f32) -> (f32, f32) {
    let shifted = x * core::f32::consts::LOG2_E + ROUND_SHIFT;
    let n = shifted - ROUND_SHIFT;
    let r = x - n * LN2_HI - n * LN2_LO;
    let p = EXP_POLY[1..].iter().fold(EXP_POLY[0], |p, &c| p * r + c);
    let expm1_r = p * (r * r) + r;
    // n sits in the low mantissa bits of `shifted`; (n + 127) << 23 are the bits of 2ⁿ.
    let two_n = f32::from_bits(
        shifted
            .to_bits()
            .wrapping_sub(ROUND_SHIFT.to_bits())
            .wrapping_add(127)
            << 23,
    );
    let e = (expm1_r + 1.0) * two_n;
    (e, if n == 0.0 { expm1_r } else { e - 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_turns_is_accurate() {
        for i in -4000..=8000 {
            let t = i as f32 / 4000.0 + 1.3e-4;
            let (s, c) = sin_cos_turns(t);
            let angle = core::f64::consts::TAU * t as f64;
            mcg_test_support::assert_close!(s as f64, angle.sin(), 2.5e-7, "sin at {t}");
            mcg_test_support::assert_close!(c as f64, angle.cos(), 2.5e-7, "cos at {t}");
        }
        assert_eq!(sin_cos_turns(0.0), (0.0, 1.0));
        assert_eq!(sin_cos_turns(0.25).1, 0.0);
        assert_eq!(sin_cos_turns(0.5), (-0.0, -1.0));
    }

    #[test]
    fn exp_m1_is_accurate() {
        let mut x = -30.0_f32;
        while x < 30.0 {
            let e = exp_m1(x) as f64;
            let want = (x as f64).exp_m1();
            assert!(
                ((e - want) / want).abs() < 4.0 * f32::EPSILON as f64,
                "expm1({x}) = {e} vs {want}"
            );
            x += 0.013_7;
        }
        for tiny in [1e-30_f32, -1e-20, 1e-9, -3e-8, 2e-7] {
            mcg_test_support::assert_close!(exp_m1(tiny) / tiny, 1.0, 1e-6);
        }
        assert_eq!(exp_m1(0.0), 0.0);
        assert_eq!(exp_m1(-200.0), -1.0);
        assert_eq!(exp_m1(200.0), f32::INFINITY);
    }
}
