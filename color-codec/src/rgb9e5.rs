//! RGB9E5 shared exponent (`GL_EXT_texture_shared_exponent`, `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32`).

use glam::Vec3;

use crate::codec::ColorCodec;

/// Three 9-bit mantissas sharing one 5-bit exponent (bias 15), no implicit leading bit.
///
/// # Bit map (Vulkan `E5B9G9R9_UFLOAT_PACK32`)
/// ```text
///  31   27 26      18 17       9 8        0
/// [ E:5   | B:9      | G:9      | R:9      ]
/// ```
/// A channel with mantissa m decodes to `m · 2^{E − 15 − 9}`.
///
/// # Conversion (the spec this implements)
/// The encoding algorithm of `GL_EXT_texture_shared_exponent` (issue "How are RGB9E5 values
/// computed?"), with N = 9, B = 15, E_max = 31:
/// ```text
/// c'    = clamp(c, 0, sharedexp_max)            sharedexp_max = (2⁹ − 1)/2⁹ · 2^{31−15} = 65408
/// e'    = max(−B − 1, ⌊log₂ max(r', g', b')⌋) + 1 + B
/// m_max = ⌊max(r', g', b') / 2^{e' − B − N} + ½⌋
/// e     = e' + 1 if m_max = 2⁹ else e'
/// m_c   = ⌊c' / 2^{e − B − N} + ½⌋
/// ```
/// ⌊log₂⌋ is read exactly from the f32 exponent bits. NaN encodes as 0 (the extension clamps
/// NaN to 0 as well, via "max(0, ...)" on an undefined comparison; we make it explicit).
///
/// # Round-trip error bound
/// Every channel is rounded to nearest on the shared grid 2^{e−24}, and that step is at most
/// max(r, g, b)·2⁻⁸ (2⁻²⁴ at the bottom), so `|c − ĉ| ≤ max(max(r, g, b)·2⁻⁹, 2⁻²⁵)` for inputs up
/// to 65408: the error of a dark channel is set by the brightest one — the format's colour shift.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rgb9E5;

/// Largest representable channel value, (2⁹ − 1)/2⁹ · 2¹⁶ = 65408.
pub const RGB9E5_MAX: f32 = 65408.0;

/// 2^k as an f32, for k ∈ [−126, 127], from the exponent bits.
#[inline(always)]
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

impl Rgb9E5 {
    /// Packs a colour with the extension's algorithm.
    #[inline]
    #[must_use]
    pub fn pack(rgb: Vec3) -> u32 {
        // `max` then `min` with NaN → 0: `v >= 0.0` is false for NaN.
        // `v > 0` (not `>=`): −0 becomes +0, whose zero exponent bits the algorithm expects
        // (the sign bit of −0 would read as exponent 17).
        let clamp = |v: f32| if v > 0.0 { v.min(RGB9E5_MAX) } else { 0.0 };
        let (r, g, b) = (clamp(rgb.x), clamp(rgb.y), clamp(rgb.z));
        let max_c = r.max(g).max(b);
        // ⌊log₂ max_c⌋ from the exponent field (0 and f32 denormals give −127, clamped below).
        let floor_log2 = ((max_c.to_bits() >> 23) as i32) - 127;
        let exp_p = floor_log2.max(-16) + 16;
        let max_m = (max_c * pow2(24 - exp_p) + 0.5) as u32;
        let exp = exp_p + (max_m == 512) as i32;
        let scale = pow2(24 - exp);
        let m = |c: f32| ((c * scale + 0.5) as u32).min(511);
        m(r) | (m(g) << 9) | (m(b) << 18) | ((exp as u32) << 27)
    }

    /// Unpacks a word: `m · 2^{E − 24}` per channel (every word is a finite colour).
    #[inline]
    #[must_use]
    pub fn unpack(word: u32) -> Vec3 {
        let scale = pow2((word >> 27) as i32 - 24);
        Vec3::new(
            (word & 0x1ff) as f32,
            ((word >> 9) & 0x1ff) as f32,
            ((word >> 18) & 0x1ff) as f32,
        ) * scale
    }
}

impl ColorCodec for Rgb9E5 {
    #[inline]
    fn encode(&self, rgb: Vec3) -> u32 {
        Self::pack(rgb)
    }
    #[inline]
    fn decode(&self, word: u32) -> Vec3 {
        Self::unpack(word)
    }
    fn name(&self) -> &'static str {
        "RGB9E5"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The extension's algorithm in f64, literally (log2 and pow from the f64 library).
    fn reference(rgb: [f64; 3]) -> u32 {
        let max = 511.0 / 512.0 * 2f64.powi(16);
        let c = rgb.map(|v| v.clamp(0.0, max));
        let max_c = c[0].max(c[1]).max(c[2]);
        let mut exp_p = (-16f64).max(max_c.log2().floor()) as i32 + 16;
        if max_c == 0.0 {
            exp_p = 0;
        }
        let max_s = (max_c / 2f64.powi(exp_p - 24) + 0.5).floor();
        let exp = if max_s == 512.0 { exp_p + 1 } else { exp_p };
        let m = c.map(|v| (v / 2f64.powi(exp - 24) + 0.5).floor() as u32);
        m[0] | (m[1] << 9) | (m[2] << 18) | ((exp as u32) << 27)
    }

    #[test]
    fn matches_the_extension_algorithm() {
        let mut x = 1e-9_f32;
        while x < 7e4 {
            for rgb in [
                Vec3::new(x, x * 0.5, x * 0.01),
                Vec3::new(0.3, x, 1.0),
                Vec3::new(x, 2.0 * x, 0.0),
            ] {
                let want = reference(rgb.to_array().map(f64::from));
                assert_eq!(Rgb9E5::pack(rgb), want, "{rgb}");
            }
            x *= 1.013;
        }
    }

    #[test]
    fn every_field_value_decodes_finite_and_round_trips() {
        for e in 0..32u32 {
            for m in 0..512u32 {
                let w = m | (m << 9) | (m << 18) | (e << 27);
                let c = Rgb9E5::unpack(w);
                assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all());
                // decode ∘ encode ∘ decode = decode (the word may be normalised differently).
                assert_eq!(Rgb9E5::unpack(Rgb9E5::pack(c)), c, "e = {e}, m = {m}");
            }
        }
    }

    #[test]
    fn bad_input_and_value_stability() {
        assert_eq!(Rgb9E5::pack(Vec3::new(f32::NAN, -1.0, -0.0)), 0);
        // Issue 14: all-(−0) packed to 0x88000000 (exponent 17); the extension gives 0.
        assert_eq!(Rgb9E5::pack(Vec3::splat(-0.0)), 0);
        assert_eq!(Rgb9E5::pack(Vec3::new(-0.0, 0.0, -0.0)), 0);
        assert_eq!(
            Rgb9E5::pack(Vec3::new(-0.0, 1.0, -0.0)),
            Rgb9E5::pack(Vec3::Y)
        );
        let w = Rgb9E5::pack(Vec3::new(f32::INFINITY, 1e9, 1.0));
        assert_eq!(Rgb9E5::unpack(w).x, RGB9E5_MAX);
        // max = 1 → E = 16, step 2⁻⁸: mantissas 256, 128, 64.
        assert_eq!(
            Rgb9E5::pack(Vec3::new(1.0, 0.5, 0.25)),
            256 | (128 << 9) | (64 << 18) | (16 << 27)
        );
    }
}
