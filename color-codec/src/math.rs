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

use crate::simd4::F4;

/// Adding then subtracting 1.5·2²³ rounds an f32 in (−2²², 2²²) to the nearest integer
/// (ties to even) in the default rounding mode, without a float → int conversion.
pub(crate) const ROUND_SHIFT: f32 = 12_582_912.0;

/// ln 2 split in a part exact in f32 times e (|e| ≤ 128) and a small remainder.
pub(crate) const LN2_HI: f32 = 0.693_359_4;
pub(crate) const LN2_LO: f32 = -2.121_944_4e-4;

/// Bits of √½ (rounded to f32): `fast_ln_ge1`'s reduction puts the mantissa in [√½, √2).
pub(crate) const SQRT_HALF_BITS: u32 = 0x3f35_04f3;

/// Cephes' `logf` polynomial P(t) = Σ cᵢ tⁱ, i = 0 ..= 8.
pub(crate) const LN_P: [f32; 9] = [
    0.333_333_3,
    -2.499_999_4e-1,
    2.000_071_5e-1,
    -1.666_805_8e-1,
    1.424_932_3e-1,
    -1.242_014_1e-1,
    1.167_699_9e-1,
    -1.151_461e-1,
    7.037_683_6e-2,
];

/// `(127 − bits(1.5·2²³)) << 23` (mod 2³²): with k = round(x) in the low mantissa bits of
/// `x + 1.5·2²³`, `(bits << 23) + POW2_OFFSET` is `(k + 127) << 23`, the bits of 2^k.
const POW2_OFFSET: u32 = 127_u32.wrapping_sub(ROUND_SHIFT.to_bits()) << 23;

/// Cephes' `exp2f` polynomial 2^f ≈ 1 + Σ cᵢ fⁱ, i = 1 ..= 6 (index 0 unused).
pub(crate) const EXP2_P: [f32; 7] = [
    1.0,
    6.931_472e-1,
    2.402_264_8e-1,
    5.550_332_5e-2,
    9.618_437e-3,
    1.339_887_4e-3,
    1.535_336_2e-4,
];

/// Natural logarithm of `x ≥ 1` (including +∞, which gives 128·ln 2 ≈ 88.7), branch-free and
/// division-free.
///
/// Splits `x = 2ᵉ·m` with m ∈ [√½, √2) from the bits (musl's reduction), then
/// `ln m = t − t²/2 + t³·P(t)`, t = m − 1, with the degree-8 minimax polynomial P of Cephes'
/// `logf` (S. Moshier), evaluated by Estrin's scheme in the fixed order written here (every
/// `a + b * c` is a rounded product then a rounded sum, never an FMA); the error is a few f32
/// ulps (tested against f64). Normal inputs below 1 also work; NaN, zero, subnormal and negative inputs give garbage (callers clamp first).
#[inline(always)]
pub(crate) fn fast_ln_ge1(x: f32) -> f32 {
    let (e, t, t2, p) = ln_reduce(x);
    let y = t * t2 * p + e * LN2_LO - 0.5 * t2;
    t + y + e * LN2_HI
}

/// The reduction and polynomial shared by [`fast_ln_ge1`] and `fast_ln_parts`: `x = 2ᵉ·m` with
/// m ∈ [√½, √2), t = m − 1, and the Cephes polynomial p(t), evaluated by Estrin's scheme (the
/// same polynomial as Horner's, a third of the dependency depth). Returns `(e, t, t², p)`.
#[inline(always)]
fn ln_reduce(x: f32) -> (f32, f32, f32, f32) {
    let bits = x.to_bits();
    let shifted = bits.wrapping_sub(SQRT_HALF_BITS);
    let e = (shifted as i32 >> 23) as f32;
    let m = f32::from_bits(bits.wrapping_sub(shifted & 0xff80_0000));
    let t = m - 1.0;
    let t2 = t * t;
    let t4 = t2 * t2;
    let [c0, c1, c2, c3, c4, c5, c6, c7, c8] = LN_P;
    let p01 = c0 + c1 * t;
    let p23 = c2 + c3 * t;
    let p45 = c4 + c5 * t;
    let p67 = c6 + c7 * t;
    let p03 = p01 + p23 * t2;
    let p47 = p45 + p67 * t2;
    (e, t, t2, p03 + p47 * t4 + c8 * (t4 * t4))
}

/// `(e, ln m)` with `x = 2ᵉ·m`, m ∈ [√½, √2): the two parts of [`fast_ln_ge1`] before they are
/// combined, so that a caller scaling the logarithm can fold ln 2 into its own scale
/// (`ln x · s = e · (s·ln 2) + ln m · s`, two products instead of the split-ln 2 sum and a
/// product). Same reduction and polynomial as [`fast_ln_ge1`]. The encoder runs the four-lane
/// [`fast_ln_parts_x4`]; this scalar form is its reference (tests, and what a GPU port mirrors).
#[cfg(test)]
pub(crate) fn fast_ln_parts(x: f32) -> (f32, f32) {
    let (e, t, t2, p) = ln_reduce(x);
    (e, t + (t * t2 * p - 0.5 * t2))
}

/// 2ˣ for x ∈ [−126, 127], branch-free: `2^round(x)` from the bits times a degree-6 polynomial
/// of 2^f on f ∈ [−½, ½] (Cephes `exp2f` coefficients, evaluated by Estrin's scheme in the order
/// written here; relative error ≈ 2·10⁻⁷, tested against f64). Exactly 1 at x = 0.
#[inline(always)]
pub(crate) const fn fast_exp2(x: f32) -> f32 {
    let shifted = x + ROUND_SHIFT;
    let i = shifted - ROUND_SHIFT;
    let f = x - i;
    let [_, c1, c2, c3, c4, c5, c6] = EXP2_P;
    // Estrin's scheme: 1 + c1 f + f²(c2 + c3 f + f²(c4 + c5 f + c6 f²)), depth 7 instead of 12.
    let f2 = f * f;
    let p = 1.0 + c1 * f + f2 * (c2 + c3 * f + f2 * (c4 + c5 * f + c6 * f2));
    // The low mantissa bits of `shifted` hold k = round(x) (two's complement for negatives).
    // 2^k = from_bits((k + 127) << 23) = from_bits((bits << 23) + POW2_OFFSET) (mod 2³²).
    p * f32::from_bits((shifted.to_bits() << 23).wrapping_add(POW2_OFFSET))
}

/// `fast_ln_parts` on four lanes: the same operations in the same order, so each lane is
/// bit-identical to the scalar function.
#[inline(always)]
pub(crate) fn fast_ln_parts_x4(x: F4) -> (F4, F4) {
    let c = F4::splat;
    let bits = x.to_bits();
    let shifted = bits.sub(SQRT_HALF_BITS as i32);
    let e = shifted.shr23().to_f32();
    let m = bits
        .sub_lanes(shifted.and(0xff80_0000_u32 as i32))
        .bits_to_f32();
    let t = m.sub(c(1.0));
    let t2 = t.mul(t);
    let t4 = t2.mul(t2);
    let [c0, c1, c2, c3, c4, c5, c6, c7, c8] = LN_P.map(c);
    let p01 = c0.add(c1.mul(t));
    let p23 = c2.add(c3.mul(t));
    let p45 = c4.add(c5.mul(t));
    let p67 = c6.add(c7.mul(t));
    let p03 = p01.add(p23.mul(t2));
    let p47 = p45.add(p67.mul(t2));
    let p = p03.add(p47.mul(t4)).add(c8.mul(t4.mul(t4)));
    (e, t.add(t.mul(t2).mul(p).sub(c(0.5).mul(t2))))
}

/// [`fast_exp2`] on four lanes, bit-identical per lane to the scalar function.
#[inline(always)]
pub(crate) fn fast_exp2_x4(x: F4) -> F4 {
    let c = F4::splat;
    let shifted = x.add(c(ROUND_SHIFT));
    let i = shifted.sub(c(ROUND_SHIFT));
    let f = x.sub(i);
    let [_, c1, c2, c3, c4, c5, c6] = EXP2_P.map(c);
    let f2 = f.mul(f);
    let inner = c4.add(c5.mul(f)).add(c6.mul(f2));
    let mid = c2.add(c3.mul(f)).add(f2.mul(inner));
    let p = c(1.0).add(c1.mul(f)).add(f2.mul(mid));
    p.mul(
        shifted
            .to_bits()
            .shl23()
            .add(POW2_OFFSET as i32)
            .bits_to_f32(),
    )
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
            mcg_test_support::assert_close!(
                got,
                want,
                4e-7 * want.max(1.0),
                "ln({x}) = {got} vs {want}"
            );
            x = x * 1.000_37 + 1e-6;
        }
        assert_eq!(fast_ln_ge1(1.0), 0.0);
        let inf = fast_ln_ge1(f32::INFINITY);
        mcg_test_support::assert_close!(inf, 128.0 * core::f32::consts::LN_2, 1e-4);
        // Also fine below 1 (normal floats).
        mcg_test_support::assert_close!(fast_ln_ge1(0.3) as f64, 0.3f64.ln(), 3e-7);
    }

    /// The four-lane versions are bit-identical to the scalar ones (the scalar ones are what a
    /// GPU port mirrors).
    #[test]
    fn x4_versions_match_scalar_bits() {
        let mut x = 1.0_f32;
        while x < 3e38 {
            let xs = [x, x * 1.37, x + 0.001, f32::from_bits(x.to_bits() + 1)];
            let (e, l) = fast_ln_parts_x4(F4::new(xs));
            let (e, l) = (e.to_bits().to_array(), l.to_bits().to_array());
            for i in 0..4 {
                let (se, sl) = fast_ln_parts(xs[i]);
                assert_eq!(
                    [e[i] as u32, l[i] as u32],
                    [se.to_bits(), sl.to_bits()],
                    "ln({})",
                    xs[i]
                );
            }
            x = x * 1.0013 + 1e-6;
        }
        let mut x = -120.0_f32;
        while x < 120.0 {
            let xs = [x, x + 0.5, -x * 0.3, x * 0.01];
            let got = fast_exp2_x4(F4::new(xs)).to_bits().to_array();
            for i in 0..4 {
                assert_eq!(got[i] as u32, fast_exp2(xs[i]).to_bits(), "exp2({})", xs[i]);
            }
            x += 0.000_71;
        }
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
