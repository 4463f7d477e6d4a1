//! R11G11B10 unsigned float (`VK_FORMAT_B10G11R11_UFLOAT_PACK32`, `DXGI_FORMAT_R11G11B10_FLOAT`).

use glam::Vec3;

use crate::codec::ColorCodec;

/// Packed unsigned floats: R and G as 11-bit floats (5-bit exponent, 6-bit mantissa), B as a
/// 10-bit float (5-bit exponent, 5-bit mantissa), exponent bias 15, no sign bit.
///
/// # Bit map (Vulkan `B10G11R11_UFLOAT_PACK32`)
/// ```text
///  31        22 21          11 10           0
/// [ B: e5 m5   | G: e5 m6     | R: e5 m6     ]
/// ```
/// Value of a field with exponent e and mantissa m (n mantissa bits), Vulkan spec
/// "Unsigned 11-Bit / 10-Bit Floating-Point Numbers": `m·2^{−14−n}` for e = 0,
/// `2^{e−15}(1 + m/2ⁿ)` for 0 < e < 31, and ∞ / NaN for e = 31.
///
/// # Conversion (the spec this implements)
/// Float → small float rounds to **nearest, ties to even** (IEEE 754 default, D3D11.3
/// functional spec §3.2.2 for float conversions), including into the denormal range. Departures
/// from the GPU formats, all on inputs a colour codec never wants: negative values, −0 and NaN
/// encode to 0 (D3D/Vulkan: 0 for negatives, NaN for NaN); values that would round above the
/// largest finite value (65024 for R/G, 64512 for B), and +∞, saturate to it (DirectXMath's
/// `XMStoreFloat3PK` behaviour; the GPU would store ∞); and the e = 31 words (∞, NaN) — which
/// `encode` never produces — decode to the largest finite value, so every word decodes finite.
///
/// # Round-trip error bound
/// For 0 ≤ v ≤ max: `|v − v̂| ≤ max(v·2^{−(n+1)}, 2^{−15−n})` with n = 6 (R, G) or 5 (B): a
/// relative error of 0.78 % (R, G) / 1.56 % (B) in the normal range (v ≥ 2⁻¹⁴), an absolute one of
/// half a denormal step below.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct R11G11B10;

/// Largest finite 11-bit float, e = 30, m = 63: 65024.
pub const R11_MAX: f32 = 65024.0;
/// Largest finite 10-bit float, e = 30, m = 31: 64512.
pub const B10_MAX: f32 = 64512.0;

/// The most mantissa bits [`f32_to_ufloat`] and [`ufloat_to_f32`] support: 22 (one fewer than
/// f32's, so encoding always rounds at least one bit away); larger `n` is treated as 22.
pub const UFLOAT_MAX_MANTISSA_BITS: u32 = 22;

/// Encodes `v` to an unsigned float with 5 exponent bits and `n` mantissa bits, rounding to
/// nearest even; negatives and NaN → 0, too large and +∞ → the largest finite code.
/// `n` above [`UFLOAT_MAX_MANTISSA_BITS`] is treated as 22.
#[inline(always)]
#[must_use]
pub fn f32_to_ufloat(v: f32, n: u32) -> u32 {
    let n = n.min(UFLOAT_MAX_MANTISSA_BITS);
    let max_code = (30u32 << n) | ((1 << n) - 1);
    let v = if v > 0.0 { v } else { 0.0 };
    let bits = v.to_bits();
    let exp32 = bits >> 23;
    // Significand with the implicit bit (none for zero; f32 denormals are far below the
    // smallest target step and round to 0 anyway).
    let sig = (bits & 0x7f_ffff) | (((exp32 != 0) as u32) << 23);
    // Target biased exponent e = exp32 − 127 + 15; below 1 the value is denormal there and
    // the significand shifts further right.
    let e = exp32 as i32 - 112;
    let shift = (23 - n as i32 + (1 - e).max(0)).min(31) as u32;
    let q = sig >> shift;
    let rem = sig & ((1u32 << shift) - 1);
    let half = 1u32 << (shift - 1);
    let q = q + (rem > half || (rem == half && q & 1 == 1)) as u32;
    // (max(e, 1) − 1)·2ⁿ + q: the implicit bit of q carries into the exponent.
    let code = (((e.max(1) - 1) as u32) << n).wrapping_add(q);
    code.min(max_code)
}

/// Decodes an unsigned float with 5 exponent bits and `n` mantissa bits; e = 31 words decode
/// to the largest finite value. `n` above [`UFLOAT_MAX_MANTISSA_BITS`] is treated as 22.
#[inline(always)]
#[must_use]
pub fn ufloat_to_f32(code: u32, n: u32) -> f32 {
    let n = n.min(UFLOAT_MAX_MANTISSA_BITS);
    let max_code = (30u32 << n) | ((1 << n) - 1);
    let code = (code & ((1 << (n + 5)) - 1)).min(max_code);
    // Placing the bits under the f32 exponent field gives 2^{e−127}(1 + m/2ⁿ) (or the f32
    // denormal m·2^{−126−n} for e = 0); 2^112 rescales exactly to bias 15.
    f32::from_bits(code << (23 - n)) * f32::from_bits((127 + 112) << 23)
}

impl R11G11B10 {
    /// Packs a colour (R, G: 11 bits, B: 10 bits).
    #[inline]
    #[must_use]
    pub fn pack(rgb: Vec3) -> u32 {
        f32_to_ufloat(rgb.x, 6) | (f32_to_ufloat(rgb.y, 6) << 11) | (f32_to_ufloat(rgb.z, 5) << 22)
    }

    /// Unpacks a word.
    #[inline]
    #[must_use]
    pub fn unpack(word: u32) -> Vec3 {
        Vec3::new(
            ufloat_to_f32(word & 0x7ff, 6),
            ufloat_to_f32((word >> 11) & 0x7ff, 6),
            ufloat_to_f32(word >> 22, 5),
        )
    }
}

impl ColorCodec for R11G11B10 {
    #[inline]
    fn encode(&self, rgb: Vec3) -> u32 {
        Self::pack(rgb)
    }
    #[inline]
    fn decode(&self, word: u32) -> Vec3 {
        Self::unpack(word)
    }
    fn name(&self) -> &'static str {
        "R11G11B10F"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Value of a small-float code by the spec's formula, in f64.
    fn spec_value(code: u32, n: u32) -> f64 {
        let (e, m) = (code >> n, code & ((1 << n) - 1));
        let scale = (1u32 << n) as f64;
        if e == 0 {
            m as f64 * 2f64.powi(-14) / scale
        } else {
            2f64.powi(e as i32 - 15) * (1.0 + m as f64 / scale)
        }
    }

    #[test]
    fn every_code_decodes_as_the_spec_says_and_round_trips() {
        for n in [6, 5] {
            let max = (30u32 << n) | ((1 << n) - 1);
            for code in 0..(1u32 << (n + 5)) {
                let v = ufloat_to_f32(code, n);
                assert!(v.is_finite() && v >= 0.0);
                let want = spec_value(code.min(max), n);
                assert_eq!(v as f64, want, "n = {n}, code {code:#x}");
                assert_eq!(
                    f32_to_ufloat(v, n),
                    code.min(max),
                    "n = {n}, code {code:#x}"
                );
            }
            assert_eq!(
                ufloat_to_f32(max, n),
                if n == 6 { R11_MAX } else { B10_MAX }
            );
        }
    }

    #[test]
    fn rounds_to_nearest_even() {
        for n in [6, 5] {
            let max = (30u32 << n) | ((1 << n) - 1);
            for code in 0..max {
                let (a, b) = (spec_value(code, n), spec_value(code + 1, n));
                let mid = ((a + b) / 2.0) as f32;
                let want = if code % 2 == 0 { code } else { code + 1 };
                assert_eq!(
                    f32_to_ufloat(mid, n),
                    want,
                    "tie between {code} and {}",
                    code + 1
                );
                let below = f32::from_bits(mid.to_bits() - 1);
                let above = f32::from_bits(mid.to_bits() + 1);
                assert_eq!(f32_to_ufloat(below, n), code);
                assert_eq!(f32_to_ufloat(above, n), code + 1);
            }
        }
    }

    #[test]
    fn bad_input_and_saturation() {
        assert_eq!(R11G11B10::pack(Vec3::new(-1.0, f32::NAN, -0.0)), 0);
        let w = R11G11B10::pack(Vec3::new(f32::INFINITY, 1e30, 65535.0));
        assert_eq!(R11G11B10::unpack(w), Vec3::new(R11_MAX, R11_MAX, B10_MAX));
        assert_eq!(f32_to_ufloat(1e-30, 6), 0);
        assert_eq!(f32_to_ufloat(f32::from_bits(1), 6), 0);
        // Smallest denormal 2^-20: half of it ties to even (0), just above rounds up.
        assert_eq!(f32_to_ufloat(2f32.powi(-21), 6), 0);
        assert_eq!(f32_to_ufloat(2f32.powi(-21) * 1.001, 6), 1);
    }

    #[test]
    fn wide_mantissas_are_clamped() {
        // Issue 14 row 6: n ≥ 23 overflowed a shift (debug panic, release garbage).
        for n in [22, 23, 24, 26, 31, 32, u32::MAX] {
            for v in [
                0.0,
                1.0,
                0.3,
                65000.0,
                1e-9,
                f32::MAX,
                f32::INFINITY,
                f32::NAN,
            ] {
                let code = f32_to_ufloat(v, n);
                assert_eq!(code, f32_to_ufloat(v, 22), "{v} {n}");
                let back = ufloat_to_f32(code, n);
                assert!(back.is_finite() && back >= 0.0, "{v} {n}: {back}");
            }
        }
        // 22 mantissa bits are f32 with one bit rounded away.
        assert_eq!(ufloat_to_f32(f32_to_ufloat(0.3, 22), 22), 0.3_f32);
        assert_eq!(ufloat_to_f32(f32_to_ufloat(1.5, 40), 40), 1.5);
    }

    #[test]
    fn value_stability() {
        let w = R11G11B10::pack(Vec3::new(1.0, 0.5, 0.25));
        // R: e = 15, m = 0 → 0x3c0; G: e = 14 → 0x380; B: e = 13, n = 5 → 0x1a0.
        assert_eq!(w, 0x3c0 | (0x380 << 11) | (0x1a0 << 22));
        assert_eq!(R11G11B10::pack(Vec3::new(0.1, 3.3, 1e-3)), 677_466_854);
    }
}
