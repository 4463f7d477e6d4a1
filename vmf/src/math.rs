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
    const ROUNDING_SHIFT: f32 = 12_582_912.0;
    let quarter_turns = 4.0 * t;
    let shifted = quarter_turns + ROUNDING_SHIFT;
    let quadrant = shifted - ROUNDING_SHIFT;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_turns_is_accurate() {
        for i in -4000..=8000 {
            let t = i as f32 / 4000.0 + 1.3e-4;
            let (s, c) = sin_cos_turns(t);
            let angle = core::f64::consts::TAU * t as f64;
            assert!((s as f64 - angle.sin()).abs() < 2.5e-7, "sin at {t}");
            assert!((c as f64 - angle.cos()).abs() < 2.5e-7, "cos at {t}");
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
            assert!((exp_m1(tiny) / tiny - 1.0).abs() < 1e-6);
        }
        assert_eq!(exp_m1(0.0), 0.0);
        assert_eq!(exp_m1(-200.0), -1.0);
        assert_eq!(exp_m1(200.0), f32::INFINITY);
    }
}
