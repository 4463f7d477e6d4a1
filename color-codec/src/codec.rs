//! One trait over every colour codec of the crate, so that formats can be swapped and compared.

use glam::Vec3;

use crate::irradiance_word::{IrradianceLayout, IrradianceWord};
use crate::quantize::Rounding;

/// A colour encoding into one 32-bit word.
///
/// Contract, shared by every implementation in this crate:
/// - `encode` accepts any `Vec3`: negative channels and NaN encode as 0, values beyond the
///   format's range (and +∞) saturate to its largest finite value;
/// - `decode` accepts any `u32` and returns finite, non-negative channels;
/// - `decode(encode(decode(w))) == decode(w)` for every word the codec produces (for
///   [`LogLuv32`](crate::LogLuv32) in XYZ, and in RGB for colours inside the sRGB gamut: its
///   decoder clamps out-of-gamut chromaticities to RGB ≥ 0).
///
/// # Example
/// ```
/// use mcg_color_codec::{ColorCodec, R11G11B10, Rgb9E5, glam::Vec3};
/// let codecs: [&dyn ColorCodec; 2] = [&R11G11B10, &Rgb9E5];
/// for codec in codecs {
///     let c = codec.decode(codec.encode(Vec3::new(0.25, 1.5, 0.0)));
///     assert!((c - Vec3::new(0.25, 1.5, 0.0)).abs().max_element() < 0.02, "{}", codec.name());
/// }
/// ```
pub trait ColorCodec {
    /// Packs a linear RGB colour into a word.
    fn encode(&self, rgb: Vec3) -> u32;
    /// Unpacks a word into a linear RGB colour (finite, non-negative).
    fn decode(&self, word: u32) -> Vec3;
    /// A short name for tables and legends.
    fn name(&self) -> &'static str;
}

/// An [`IrradianceLayout`] used as a plain colour codec (count field left at 0) with a fixed
/// rounding mode, e.g. ADGI's `[R9][G9][B8]` with round-down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogRgb {
    /// The packed layout (its count field stays 0).
    pub layout: IrradianceLayout,
    /// How channels are rounded (a [`Rounding::Stochastic`] uniform is reused on every call).
    pub rounding: Rounding,
    /// The name [`ColorCodec::name`] returns.
    pub name: &'static str,
}

impl LogRgb {
    /// ADGI's irradiance encoding, R9 G9 B8 with (β, γ) = (5, 15), rounded down.
    pub const ADGI: LogRgb = LogRgb {
        layout: IrradianceLayout::ADGI,
        rounding: Rounding::Down,
        name: "log R9G9B8 (down)",
    };

    /// ADGI's encoding rounded to nearest.
    pub const ADGI_NEAREST: LogRgb = LogRgb {
        layout: IrradianceLayout::ADGI,
        rounding: Rounding::Nearest,
        name: "log R9G9B8 (nearest)",
    };

    /// Equal 10/10/10 log channels, rounded down.
    pub const EQUAL_10: LogRgb = LogRgb {
        layout: IrradianceLayout::EQUAL_10,
        rounding: Rounding::Down,
        name: "log R10G10B10 (down)",
    };
}

impl ColorCodec for LogRgb {
    #[inline(always)]
    fn encode(&self, rgb: Vec3) -> u32 {
        self.layout.encode(rgb, 0, self.rounding).0
    }
    #[inline(always)]
    fn decode(&self, word: u32) -> Vec3 {
        self.layout.decode(IrradianceWord(word))
    }
    fn name(&self) -> &'static str {
        self.name
    }
}
