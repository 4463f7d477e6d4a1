//! Ward's LogLuv32: 15-bit log luminance and 8-bit u′, v′ chromaticity (Larson 1998, TIFF
//! `SGILOG` compression, `COMPRESSION_SGILOG`, `SGILOGDATAFMT` 32-bit).

use glam::{Mat3, Vec3};

use crate::codec::ColorCodec;
use crate::math::exp2;

/// Ward's 32-bit LogLuv: a sign bit, 15 bits of `256(log₂ Y + 64)` and the CIE 1976 (u′, v′)
/// chromaticity at 410 steps per unit, 8 bits each.
///
/// # Bit map
/// ```text
///  31  30             16 15     8 7      0
/// [ s | Le:15           | ue:8    | ve:8   ]
/// ```
///
/// # Conversion (the spec this implements)
/// G. W. Larson, "LogLuv encoding for full-gamut, high-dynamic range images", JGT 3(1), 1998,
/// and libtiff's `tif_luv.c` (`LogL16fromY`, `Luv32fromXYZ`, `Luv32toXYZ`) without dithering
/// (`SGILOGENCODE_NODITHER`, i.e. truncation):
/// ```text
/// Le = ⌊256 (log₂ Y + 64)⌋ for 5.4136769·10⁻²⁰ < Y < 2^{32767/256 − 64} ≈ 1.8396865·10¹⁹  (0 below, 0x7fff above)
/// ue = min(⌊410 u′⌋, 255), ve = min(⌊410 v′⌋, 255),  u′ = 4X/(X + 15Y + 3Z), v′ = 9Y/(X + 15Y + 3Z)
///      (u′, v′ = 0.2105, 0.4737, the neutral point, when Le = 0)
/// Y = 2^{(Le + ½)/256 − 64},  u′ = (ue + ½)/410,  v′ = (ve + ½)/410   (decode; Le = 0 → black)
/// ```
/// Colours are linear sRGB / Rec. 709 primaries with D65 white, converted to CIE XYZ with the
/// standard matrix (IEC 61966-2-1). Encoding computes the logarithm and (u′, v′) in f64, as
/// libtiff does, so codes are bit-exact with its double-precision reference; decoding is f32.
/// Departures, for non-colours only: the sign bit is never set by `encode` (negative channels
/// count as 0, NaN as 0) and words with the sign bit decode to black; decoded RGB channels are
/// clamped at 0 (chromaticities outside the sRGB gamut give negative channels otherwise).
/// Le saturates at 0x7fff from Y = 2^{32767/256 − 64}, where the formula itself reaches
/// 0x7fff, rather than from libtiff's 1.8371976·10¹⁹: libtiff's bound lies below the decoded
/// luminance of Le = 0x7ffe (1.8371976·10¹⁹ + 2·10¹¹), so with it that code re-encoded as
/// 0x7fff and no word with Le = 0x7ffe round-tripped. Codes differ from libtiff only for Y in
/// [1.8371976·10¹⁹, 1.8396865·10¹⁹), which get 0x7ffe.
///
/// # Round-trip error bound
/// In XYZ: `|Ŷ/Y − 1| ≤ 2^{1/512} − 1 ≈ 0.136 %` for Y in range, and `|û′ − u′|, |v̂′ − v′| ≤ 1/820`
/// (which moves RGB by up to a few per cent of Y in saturated colours).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LogLuv32;

/// Linear sRGB (Rec. 709, D65) → CIE XYZ (IEC 61966-2-1).
pub const SRGB_TO_XYZ: Mat3 = Mat3::from_cols_array(&[
    0.412_456_4,
    0.212_672_9,
    0.019_333_9, // column R
    0.357_576_1,
    0.715_152_2,
    0.119_192, // column G
    0.180_437_5,
    0.072_175,
    0.950_304_1, // column B
]);

/// CIE XYZ → linear sRGB (Rec. 709, D65), the inverse of [`SRGB_TO_XYZ`].
pub const XYZ_TO_SRGB: Mat3 = Mat3::from_cols_array(&[
    3.240_454_2,
    -0.969_266,
    0.055_643_4,
    -1.537_138_5,
    1.876_010_8,
    -0.204_025_9,
    -0.498_531_4,
    0.041_556,
    1.057_225_2,
]);

/// u′ of the neutral point written for black (Le = 0).
pub(crate) const U_NEUTRAL: f64 = 0.210_526_316;
/// v′ of the neutral point written for black.
pub(crate) const V_NEUTRAL: f64 = 0.473_684_211;
/// Chromaticity steps per unit of u′ and v′.
pub(crate) const UV_SCALE: f64 = 410.0;
/// 1/410 in f32, the decoder's step.
pub(crate) const INV_UV_SCALE: f32 = 1.0 / 410.0;
/// Largest 15-bit log-luminance code (written for Y at or above [`Y_MAX`]).
pub(crate) const LE_MAX: u32 = 0x7fff;
/// Y at or above which Le saturates at [`LE_MAX`]: 2^{32767/256 − 64}, the smallest Y whose
/// code by the formula is 0x7fff (libtiff's 1.8371976·10¹⁹ is below the decoded value of
/// Le = 0x7ffe, which then did not round-trip).
pub(crate) const Y_MAX: f64 = 1.839_686_511_232_855_4e19;
/// Y at or below which Le is 0 (black).
pub(crate) const Y_MIN: f64 = 5.413_676_9e-20;

#[inline(always)]
fn log2_f64(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.log2()
    }
    #[cfg(all(not(feature = "std"), feature = "libm"))]
    {
        libm::log2(x)
    }
}

impl LogLuv32 {
    /// Encodes CIE XYZ (non-negative; negatives and NaN count as 0).
    #[must_use]
    pub fn pack_xyz(xyz: Vec3) -> u32 {
        let c = xyz
            .to_array()
            .map(|v| if v >= 0.0 { f64::from(v) } else { 0.0 });
        let (x, y, z) = (c[0], c[1], c[2]);
        let le = if y >= Y_MAX {
            LE_MAX
        } else if y > Y_MIN {
            ((256.0 * (log2_f64(y) + 64.0)) as u32).min(LE_MAX)
        } else {
            0
        };
        let s = x + 15.0 * y + 3.0 * z;
        let (u, v) = if le == 0 || !(s > 0.0) {
            (U_NEUTRAL, V_NEUTRAL)
        } else {
            (4.0 * x / s, 9.0 * y / s)
        };
        let ue = ((UV_SCALE * u) as u32).min(255);
        let ve = ((UV_SCALE * v) as u32).min(255);
        (le << 16) | (ue << 8) | ve
    }

    /// Decodes to CIE XYZ (finite; black for Le = 0 and for words with the sign bit).
    #[must_use]
    pub fn unpack_xyz(word: u32) -> Vec3 {
        let le = (word >> 16) & LE_MAX;
        if le == 0 || word >> 31 != 0 {
            return Vec3::ZERO;
        }
        let y = exp2((le as f32 + 0.5) * (1.0 / 256.0) - 64.0);
        let u = (((word >> 8) & 0xff) as f32 + 0.5) * INV_UV_SCALE;
        let v = ((word & 0xff) as f32 + 0.5) * INV_UV_SCALE;
        let s = 1.0 / (6.0 * u - 16.0 * v + 12.0);
        let cx = 9.0 * u * s;
        let cy = 4.0 * v * s;
        Vec3::new(cx / cy * y, y, (1.0 - cx - cy) / cy * y)
    }
}

impl ColorCodec for LogLuv32 {
    #[inline]
    fn encode(&self, rgb: Vec3) -> u32 {
        Self::pack_xyz(SRGB_TO_XYZ * rgb.max(Vec3::ZERO))
    }
    #[inline]
    fn decode(&self, word: u32) -> Vec3 {
        (XYZ_TO_SRGB * Self::unpack_xyz(word)).max(Vec3::ZERO)
    }
    fn name(&self) -> &'static str {
        "LogLuv32"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn uv(xyz: Vec3) -> (f64, f64) {
        let [x, y, z] = xyz.to_array().map(f64::from);
        let s = x + 15.0 * y + 3.0 * z;
        (4.0 * x / s, 9.0 * y / s)
    }

    #[test]
    fn matrices_are_inverse() {
        let m = XYZ_TO_SRGB * SRGB_TO_XYZ;
        assert!(m.abs_diff_eq(Mat3::IDENTITY, 1e-5), "{m}");
        // White (1, 1, 1) has Y = 1 and the D65 chromaticity.
        let w = SRGB_TO_XYZ * Vec3::ONE;
        mcg_test_support::assert_close!(w.y, 1.0, 1e-5);
    }

    #[test]
    fn luminance_and_chromaticity_within_bounds() {
        let mut y = 1e-15_f32;
        while y < 1e15 {
            for xyz in [
                Vec3::new(0.9 * y, y, 1.1 * y),
                Vec3::new(0.2 * y, y, 0.05 * y),
            ] {
                let back = LogLuv32::unpack_xyz(LogLuv32::pack_xyz(xyz));
                mcg_test_support::assert_close!(
                    (back.y / xyz.y) as f64,
                    1.0,
                    2f64.powf(1.0 / 512.0) - 1.0 + 1e-6
                );
                let (u0, v0) = uv(xyz);
                let (u1, v1) = uv(back);
                assert!(
                    (u0 - u1).abs() <= 1.0 / 820.0 + 1e-6 && (v0 - v1).abs() <= 1.0 / 820.0 + 1e-6
                );
            }
            y *= 1.37;
        }
    }

    #[test]
    fn every_field_value_decodes_finite_non_negative() {
        let check = |w: u32| {
            let c = LogLuv32.decode(w);
            assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all(), "{w:#x}");
            assert!(LogLuv32::unpack_xyz(w).is_finite());
        };
        for le in 0..0x8000u32 {
            check(le << 16 | 0x4a_c3);
            check(le << 16 | 0xffff);
            check(le << 16);
        }
        for uv in 0..0x10000u32 {
            check(0x7fff_0000 | uv);
            check(0x0001_0000 | uv);
            check(0x8000_0000 | 0x4000_0000 | uv);
        }
    }

    #[test]
    fn idempotent_and_bad_input() {
        for w in [0x4000_5ab0_u32, 0x1234_6070, 0x7fff_4f4f, 0x0001_5050] {
            let c = LogLuv32::unpack_xyz(w);
            assert_eq!(LogLuv32::pack_xyz(c), w, "{w:#x}");
        }
        assert_eq!(
            LogLuv32.encode(Vec3::new(f32::NAN, -1.0, 0.0)),
            (86 << 8) | 194
        );
        assert_eq!(LogLuv32.decode(0x8000_0000 | 0x4000_5ab0), Vec3::ZERO);
        assert_eq!(LogLuv32.encode(Vec3::splat(f32::INFINITY)) >> 16, 0x7fff);
    }

    #[test]
    fn every_luminance_code_round_trips_in_xyz() {
        // Issue 14 row 20: Le = 0x7ffe decoded to Y = 1.8371976·10¹⁹ + 2·10¹¹, at or above
        // libtiff's saturation bound, and re-encoded as 0x7fff.
        for le in 1..=LE_MAX {
            for uv in [0x4a_c3, 0x51_c0, 0x60_70] {
                let w = le << 16 | uv;
                assert_eq!(LogLuv32::pack_xyz(LogLuv32::unpack_xyz(w)), w, "{w:#x}");
            }
        }
        // Saturation starts exactly where the formula reaches 0x7fff.
        // The smallest f32 at or above Y_MAX (`as` rounds to nearest, here down).
        let top = f32::from_bits((Y_MAX as f32).to_bits() + 1);
        assert!(f64::from(top) >= Y_MAX && f64::from(f32::from_bits(top.to_bits() - 1)) < Y_MAX);
        assert_eq!(LogLuv32::pack_xyz(Vec3::new(top, top, top)) >> 16, LE_MAX);
        let below = f32::from_bits(top.to_bits() - 1);
        assert_eq!(
            LogLuv32::pack_xyz(Vec3::new(below, below, below)) >> 16,
            LE_MAX - 1
        );
        assert_eq!(
            LogLuv32::pack_xyz(Vec3::splat(1.837_197_6e19)) >> 16,
            LE_MAX - 1
        );
    }

    #[test]
    fn value_stability() {
        // White: Y = 1 → Le = 256·64; D65 (u′, v′) = (0.1978, 0.4683) → (81, 192).
        assert_eq!(LogLuv32.encode(Vec3::ONE), 0x4000_51c0);
        assert_eq!(LogLuv32.encode(Vec3::new(0.9, 0.1, 0.02)), 1_041_536_215);
    }
}
