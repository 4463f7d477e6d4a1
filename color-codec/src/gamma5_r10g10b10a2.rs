//! RTXGI's irradiance format: `E^{1/5}` in R10G10B10A2 UNORM.

use glam::Vec3;

use crate::codec::ColorCodec;
use crate::math::{ROUND_SHIFT, fast_exp2, fast_ln_ge1};

/// The RTXGI DDGI irradiance encoding: each channel raised to 1/γ with γ = 5
/// (`probeIrradianceEncodingGamma`) and stored as 10-bit UNORM, alpha 2 bits.
///
/// # Bit map (`DXGI_FORMAT_R10G10B10A2_UNORM`, Vulkan `A2B10G10R10_UNORM_PACK32`)
/// ```text
///  31 30 29      20 19      10 9        0
/// [ A:2 | B:10     | G:10     | R:10     ]
/// ```
///
/// # Conversion (the spec this implements)
/// `c = clamp(v, 0, 1)^{1/5}`, then the float → UNORM rule of the Vulkan spec ("Conversion from
/// Floating-Point to Normalized Fixed-Point"): `round(c · 1023)`, ties to even. Alpha is written
/// as 3 (1.0) and ignored on decode, `v̂ = (q/1023)⁵`. The range is [0, 1] (UNORM): brighter
/// values saturate at 1 — RTXGI relies on exposure to keep irradiance there.
/// `c` is computed with this crate's fast `ln`/`exp2` (relative error below 10⁻⁶), so the code
/// equals the exact `round(v^{1/5}·1023)` except when `v^{1/5}·1023` lies within ~10⁻³ of a
/// half-integer (GPUs evaluate `pow` with similar, implementation-defined precision).
///
/// # Round-trip error bound
/// With `c = v^{1/5}` and `|ĉ − c| ≤ 1/2046`: `|v − v̂| ≤ (c + 1/2046)⁵ − c⁵` (≈ 5c⁴/2046, i.e. a
/// relative error of about 0.24 %/c … 0.5 % at v = 1), and v̂ = 0 exactly for v < (1/2046)⁵.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gamma5R10G10B10A2;

/// RTXGI's irradiance encoding gamma.
pub const RTXGI_IRRADIANCE_GAMMA: f32 = 5.0;

/// The largest 10-bit channel code of [`Gamma5R10G10B10A2`] (its channel mask).
pub(crate) const GAMMA5_MAX_CODE: u32 = 1023;

/// Inputs at or below this (≈ 2⁻¹⁰⁰) encode to 0: their code would be 0 anyway, and it keeps 0,
/// subnormals and NaN away from the logarithm.
pub(crate) const GAMMA5_MIN_INPUT: f32 = 7.9e-31;

impl Gamma5R10G10B10A2 {
    /// `round(clamp(v, 0, 1)^{1/5} · 1023)`, ties to even; NaN and negatives → 0.
    #[inline(always)]
    #[must_use]
    pub fn encode_channel(v: f32) -> u32 {
        // Below 2⁻¹⁰⁰ the code is 0 anyway ((2⁻¹⁰⁰)^{1/5}·1023 ≈ 10⁻³); this also keeps 0,
        // subnormals and NaN away from the logarithm.
        let v = if v > GAMMA5_MIN_INPUT {
            v.min(1.0)
        } else {
            0.0
        };
        let c = fast_exp2(
            fast_ln_ge1(v.max(GAMMA5_MIN_INPUT))
                * (core::f32::consts::LOG2_E / RTXGI_IRRADIANCE_GAMMA),
        );
        let c = if v > 0.0 { c.min(1.0) } else { 0.0 };
        // Adding 2²³·1.5 rounds to the nearest integer, ties to even; the low bits hold it.
        ((c * GAMMA5_MAX_CODE as f32 + ROUND_SHIFT).to_bits() & 0x7ff).min(GAMMA5_MAX_CODE)
    }

    /// `(q/1023)⁵` by multiplication (exact to f32 rounding).
    #[inline(always)]
    #[must_use]
    pub fn decode_channel(code: u32) -> f32 {
        let c = (code & GAMMA5_MAX_CODE) as f32 * (1.0 / GAMMA5_MAX_CODE as f32);
        let c2 = c * c;
        c2 * c2 * c
    }
}

impl ColorCodec for Gamma5R10G10B10A2 {
    #[inline]
    fn encode(&self, rgb: Vec3) -> u32 {
        Self::encode_channel(rgb.x)
            | (Self::encode_channel(rgb.y) << 10)
            | (Self::encode_channel(rgb.z) << 20)
            | (3 << 30)
    }
    #[inline]
    fn decode(&self, word: u32) -> Vec3 {
        Vec3::new(
            Self::decode_channel(word),
            Self::decode_channel(word >> 10),
            Self::decode_channel(word >> 20),
        )
    }
    fn name(&self) -> &'static str {
        "gamma-5 R10G10B10A2"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_exact_pow_away_from_ties() {
        let mut v = 1e-20_f32;
        let (mut checked, mut ties) = (0, 0);
        while v <= 1.0 {
            let exact = f64::from(v).powf(0.2) * 1023.0;
            let frac = exact - exact.floor();
            let got = Gamma5R10G10B10A2::encode_channel(v);
            if (frac - 0.5).abs() > 1e-3 {
                assert_eq!(got, exact.round() as u32, "v = {v}");
                checked += 1;
            } else {
                mcg_test_support::assert_close!(got as f64, exact, 0.501);
                ties += 1;
            }
            v *= 1.0007;
        }
        assert!(checked > 50_000 && ties < checked / 100, "{checked} {ties}");
    }

    #[test]
    fn every_code_round_trips_and_decodes_in_range() {
        for q in 0..1024 {
            let v = Gamma5R10G10B10A2::decode_channel(q);
            assert!((0.0..=1.0).contains(&v));
            assert_eq!(Gamma5R10G10B10A2::encode_channel(v), q, "q = {q}");
        }
        assert_eq!(
            Gamma5R10G10B10A2.encode(Vec3::new(f32::NAN, -1.0, 5.0)),
            (1023 << 20) | (3 << 30)
        );
        assert_eq!(Gamma5R10G10B10A2.decode(u32::MAX), Vec3::ONE);
    }

    #[test]
    fn value_stability() {
        // 0.5^⅕·1023 = 890.6 → 891, 0.1^⅕·1023 = 645.5 → 645, 0.001^⅕·1023 = 257.0 → 257, alpha 3.
        assert_eq!(
            Gamma5R10G10B10A2.encode(Vec3::new(0.5, 0.1, 0.001)),
            891 | (645 << 10) | (257 << 20) | (3 << 30)
        );
    }
}
