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

    /// Encodes a slice: `words[j] = self.encode(colours[j])` for every `j`, bit for bit.
    ///
    /// The default is that loop, one colour at a time (for R11G11B10 and the other integer
    /// codecs the compiler vectorises it across colours); [`LogRgb`] overrides it with a batch
    /// form that runs four colours per vector, or for ADGI's round-down a table loop with its
    /// constants folded (see [`IrradianceLayout::encode_slice`]).
    ///
    /// # Panics
    /// If `colours` and `words` differ in length.
    fn encode_slice(&self, colours: &[Vec3], words: &mut [u32]) {
        assert_eq!(
            colours.len(),
            words.len(),
            "encode_slice: colours and words differ in length"
        );
        for (w, &c) in words.iter_mut().zip(colours) {
            *w = self.encode(c);
        }
    }

    /// Decodes a slice: `colours[j] = self.decode(words[j])` for every `j`, bit for bit.
    ///
    /// The default is that loop; [`LogRgb`] overrides it with a batch form (see
    /// [`IrradianceLayout::decode_slice`]).
    ///
    /// # Panics
    /// If `words` and `colours` differ in length.
    fn decode_slice(&self, words: &[u32], colours: &mut [Vec3]) {
        assert_eq!(
            words.len(),
            colours.len(),
            "decode_slice: words and colours differ in length"
        );
        for (c, &w) in colours.iter_mut().zip(words) {
            *c = self.decode(w);
        }
    }
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
    /// Batch form (four colours per vector, or the table loop for round-down with tables): bit
    /// for bit `encode` per colour, with
    /// [`LogRgb::rounding`] (the same stochastic uniform) for every colour.
    #[inline]
    fn encode_slice(&self, colours: &[Vec3], words: &mut [u32]) {
        self.layout
            .encode_slice(colours, 0, self.rounding, bytemuck::cast_slice_mut(words));
    }
    /// Batch form (four words per vector, or the table loop with tables): bit for bit `decode`
    /// per word.
    #[inline]
    fn decode_slice(&self, words: &[u32], colours: &mut [Vec3]) {
        self.layout
            .decode_slice(bytemuck::cast_slice(words), colours);
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::{Gamma5R10G10B10A2, LogLuv32, R11G11B10, Rgb9E5};

    /// Every codec's `encode_slice` / `decode_slice` (the default loop, or [`LogRgb`]'s batch
    /// form) equals its per-colour `encode` / `decode`, bit for bit, for lengths 0 ..= 9 and a
    /// long slice, on ordinary and bad input.
    #[test]
    fn slices_match_per_colour_for_every_codec() {
        let mut s: u64 = 7;
        let mut colours: Vec<Vec3> = (0..1031)
            .map(|_| {
                let mut u = || {
                    s = s
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    (s >> 40) as f32 / (1u64 << 24) as f32
                };
                Vec3::new(u(), u(), u()) * 10f32.powf(u() * 6.0 - 4.0)
            })
            .collect();
        colours[2] = Vec3::new(f32::NAN, -1.0, f32::INFINITY);
        colours[5] = Vec3::new(f32::NEG_INFINITY, 1e30, -0.0);
        colours[9] = Vec3::splat(1e-40);
        let codecs: [&dyn ColorCodec; 9] = [
            &R11G11B10,
            &Rgb9E5,
            &LogLuv32,
            &Gamma5R10G10B10A2,
            &LogRgb::ADGI,
            &LogRgb::ADGI_NEAREST,
            &LogRgb::EQUAL_10,
            &LogRgb {
                rounding: Rounding::Stochastic(0.8),
                ..LogRgb::ADGI
            },
            &LogRgb {
                rounding: Rounding::Stochastic(0.1),
                ..LogRgb::EQUAL_10
            },
        ];
        for codec in codecs {
            let name = codec.name();
            let mut lengths: Vec<usize> = (0..=9).collect();
            lengths.push(colours.len());
            for n in lengths {
                let c = &colours[..n];
                let mut words = std::vec![0u32; n];
                codec.encode_slice(c, &mut words);
                let want: Vec<u32> = c.iter().map(|&c| codec.encode(c)).collect();
                assert_eq!(words, want, "{name}, n = {n}");
                let mut dec = std::vec![Vec3::NAN; n];
                codec.decode_slice(&words, &mut dec);
                for (d, &w) in dec.iter().zip(&words) {
                    let want = codec.decode(w);
                    assert_eq!(
                        d.to_array().map(f32::to_bits),
                        want.to_array().map(f32::to_bits),
                        "{name}, n = {n}, {w:#x}"
                    );
                }
            }
        }
    }
}
