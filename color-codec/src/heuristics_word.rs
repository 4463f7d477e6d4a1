//! ADGI's heuristics texel: f_v, f_s, f_d as 6-10-10 bits plus 6 flag bits (sec. 4.3).

use bytemuck::{Pod, Zeroable};

use crate::bits::BitField;
use crate::error::CodecError;
use crate::log_codec::MAX_FIELD_BITS;
use crate::quantize::{Rounding, quantize};

/// The three heuristics of one probe octant and its flags, unpacked.
///
/// - `f_v`: probe visibility `e^{−2t/s}` (eq. 11), in [0, 1];
/// - `f_s`: the static guide `f_c·f_v` (eq. 19), in [0, 1];
/// - `f_d`: the dynamic guide `f_c f_v (f_Δv + μ f_Δr)` (eq. 20), stored in [0, 1]: larger
///   values saturate, so callers normalise it (e.g. by its bound 1 + μ when f_Δv, f_Δr ≤ 1).
/// - `flags`: the remaining bits, free for the caller (6 in ADGI's layout).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Heuristics {
    /// Probe visibility f_v ∈ [0, 1] (eq. 11).
    pub f_v: f32,
    /// Static heuristic f_s ∈ [0, 1] (eq. 19).
    pub f_s: f32,
    /// Dynamic heuristic f_d ∈ [0, 1] (eq. 20, normalised by the caller).
    pub f_d: f32,
    /// Flag bits (masked to the flag field's width).
    pub flags: u32,
}

/// Bit layout of a heuristics word: three linear UNORM fields on [0, 1] and a flag field.
///
/// # Bit map (bit 0 = least significant)
/// ```text
/// ADGI default (6-10-10 + 6 flags):
///  31      26 25        16 15         6 5      0
/// [ flags:6  | f_d:10     | f_s:10     | f_v:6  ]
/// general: f_v at [0, a), f_s at [a, a+b), f_d at [a+b, a+b+c), flags at [32−k, 32)
/// ```
/// Widths are parameters (value fields 1 ..= 16 bits, flags 0 ..= 16, summing to 32).
///
/// The heuristics are written once per construction pass, not averaged, so the fields are
/// linear (no log codec) and [`encode`](Self::encode) rounds to nearest by default.
///
/// # Round-trip error bound
/// For x ∈ [0, 1] and a k-bit field: |x − x̂| ≤ 1/(2(2^k − 1)) (nearest), < 1/(2^k − 1) (down);
/// i.e. 7.9·10⁻³ for f_v and 4.9·10⁻⁴ for f_s, f_d with ADGI's widths (nearest).
/// Inputs outside [0, 1] saturate; NaN encodes to 0.
///
/// # Example
/// ```
/// use mcg_color_codec::{Heuristics, HeuristicsLayout};
/// let l = HeuristicsLayout::ADGI;
/// let h = Heuristics { f_v: 0.5, f_s: 0.25, f_d: 0.9, flags: 0b101 };
/// let back = l.decode(l.encode(h));
/// assert!((back.f_s - 0.25).abs() < 1e-3 && back.flags == 0b101);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeuristicsLayout {
    places: [BitField; 3],
    flags: BitField,
}

/// A packed heuristics texel (see [`HeuristicsLayout`]); plain `u32` on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
#[repr(transparent)]
pub struct HeuristicsWord(pub u32);

const _: () = assert!(core::mem::size_of::<HeuristicsWord>() == 4);

impl HeuristicsLayout {
    /// ADGI's layout: f_v 6 bits, f_s 10, f_d 10, 6 flag bits (sec. 4.3).
    pub const ADGI: HeuristicsLayout = match HeuristicsLayout::new(6, 10, 10, 6) {
        Ok(layout) => layout,
        Err(_) => panic!("invalid ADGI heuristics layout"),
    };

    /// A layout with the given widths.
    ///
    /// # Errors
    /// [`CodecError::FieldWidthOutOfRange`] if a value width is not in 1 ..= 16 or the flag
    /// width is above 16, [`CodecError::WidthsDoNotSumTo32`] if they do not add up to 32.
    pub const fn new(
        f_v_bits: u32,
        f_s_bits: u32,
        f_d_bits: u32,
        flag_bits: u32,
    ) -> Result<Self, CodecError> {
        let widths = [f_v_bits, f_s_bits, f_d_bits];
        let mut i = 0;
        while i < 3 {
            if widths[i] < 1 || widths[i] > MAX_FIELD_BITS {
                return Err(CodecError::FieldWidthOutOfRange { bits: widths[i] });
            }
            i += 1;
        }
        if flag_bits > MAX_FIELD_BITS {
            return Err(CodecError::FieldWidthOutOfRange { bits: flag_bits });
        }
        let sum = f_v_bits + f_s_bits + f_d_bits + flag_bits;
        if sum != 32 {
            return Err(CodecError::WidthsDoNotSumTo32 { sum });
        }
        Ok(Self {
            places: [
                BitField::new(0, f_v_bits),
                BitField::new(f_v_bits, f_s_bits),
                BitField::new(f_v_bits + f_s_bits, f_d_bits),
            ],
            flags: BitField::new(32 - flag_bits, flag_bits),
        })
    }

    /// Widths `[f_v, f_s, f_d, flags]` in bits.
    #[must_use]
    pub const fn widths(&self) -> [u32; 4] {
        [
            self.places[0].bits,
            self.places[1].bits,
            self.places[2].bits,
            self.flags.bits,
        ]
    }

    /// Bit offsets `[f_v, f_s, f_d, flags]`.
    #[must_use]
    pub const fn shifts(&self) -> [u32; 4] {
        [
            self.places[0].shift,
            self.places[1].shift,
            self.places[2].shift,
            self.flags.shift,
        ]
    }

    /// Packs `h`, rounding each value to the nearest code.
    #[inline]
    #[must_use]
    pub fn encode(&self, h: Heuristics) -> HeuristicsWord {
        self.encode_with(h, Rounding::Nearest)
    }

    /// Packs `h` with the given rounding (values clamped to [0, 1], NaN → 0, flags masked).
    #[inline]
    #[must_use]
    pub fn encode_with(&self, h: Heuristics, rounding: Rounding) -> HeuristicsWord {
        let values = [h.f_v, h.f_s, h.f_d];
        let mut word = self.flags.put(h.flags);
        for (i, value) in values.into_iter().enumerate() {
            let place = self.places[i];
            let max = place.max();
            let code = quantize(value * max as f32, max, rounding.for_channel(i as u32));
            word |= place.put(code);
        }
        HeuristicsWord(word)
    }

    /// Unpacks a word; every value decodes into [0, 1].
    #[inline]
    #[must_use]
    pub fn decode(&self, word: HeuristicsWord) -> Heuristics {
        let v = |i: usize| {
            let p: BitField = self.places[i];
            p.get(word.0) as f32 / p.max() as f32
        };
        Heuristics {
            f_v: v(0),
            f_s: v(1),
            f_d: v(2),
            flags: self.flags.get(word.0),
        }
    }

    /// The flag bits of a word.
    #[inline]
    #[must_use]
    pub const fn flags(&self, word: HeuristicsWord) -> u32 {
        self.flags.get(word.0)
    }

    /// `word` with its flags replaced by `flags` (masked to the flag width).
    #[inline]
    #[must_use]
    pub const fn with_flags(&self, word: HeuristicsWord, flags: u32) -> HeuristicsWord {
        HeuristicsWord(self.flags.set(word.0, flags))
    }
}

impl From<u32> for HeuristicsWord {
    fn from(bits: u32) -> Self {
        Self(bits)
    }
}

impl From<HeuristicsWord> for u32 {
    fn from(word: HeuristicsWord) -> Self {
        word.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout() {
        let l = HeuristicsLayout::ADGI;
        assert_eq!(l.widths(), [6, 10, 10, 6]);
        assert_eq!(l.shifts(), [0, 6, 16, 26]);
        assert_eq!(
            HeuristicsLayout::new(6, 10, 10, 7),
            Err(CodecError::WidthsDoNotSumTo32 { sum: 33 })
        );
        assert_eq!(
            HeuristicsLayout::new(0, 16, 10, 6),
            Err(CodecError::FieldWidthOutOfRange { bits: 0 })
        );
        assert!(HeuristicsLayout::new(16, 8, 8, 0).is_ok());
        let all = Heuristics {
            f_v: 1.0,
            f_s: 7.0,
            f_d: f32::INFINITY,
            flags: 0xff,
        };
        assert_eq!(l.encode(all).0, u32::MAX);
        let none = Heuristics {
            f_v: f32::NAN,
            f_s: -1.0,
            f_d: 0.0,
            flags: 0,
        };
        assert_eq!(l.encode(none).0, 0);
        assert_eq!(l.flags(l.with_flags(HeuristicsWord(0), 0b110011)), 0b110011);
    }

    #[test]
    fn round_trip_and_every_value() {
        let l = HeuristicsLayout::ADGI;
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            let h = l.decode(l.encode(Heuristics {
                f_v: x,
                f_s: x,
                f_d: x,
                flags: 1,
            }));
            mcg_test_support::assert_close!(h.f_v, x, 0.5 / 63.0 + 1e-6);
            mcg_test_support::assert_close!(h.f_s, x, 0.5 / 1023.0 + 1e-6);
            mcg_test_support::assert_close!(h.f_d, x, 0.5 / 1023.0 + 1e-6);
        }
        for i in 0..3 {
            let p = l.places[i];
            for q in 0..=p.max() {
                let h = l.decode(HeuristicsWord(p.put(q)));
                for v in [h.f_v, h.f_s, h.f_d] {
                    assert!((0.0..=1.0).contains(&v));
                }
                assert_eq!(l.encode(h).0, p.put(q), "decode ∘ encode ∘ decode");
            }
        }
    }

    #[test]
    fn zero_flag_bits() {
        // Issue 14 row 5: a layout without flag bits shifted by 32 (debug panic).
        let l = HeuristicsLayout::new(10, 11, 11, 0).unwrap();
        assert_eq!(l.widths(), [10, 11, 11, 0]);
        let h = Heuristics {
            f_v: 1.0,
            f_s: 0.5,
            f_d: 1.0,
            flags: u32::MAX,
        };
        let w = l.encode(h);
        assert_eq!(w.0 >> 21, 0x7ff);
        let back = l.decode(w);
        assert_eq!((back.f_v, back.f_d, back.flags), (1.0, 1.0, 0));
        assert_eq!(l.flags(HeuristicsWord(u32::MAX)), 0);
        assert_eq!(
            l.with_flags(HeuristicsWord(0x1234_5678), u32::MAX).0,
            0x1234_5678
        );
        for word in [0, 1, 0x8000_0000, u32::MAX] {
            let h = l.decode(HeuristicsWord(word));
            assert_eq!(l.encode(h), HeuristicsWord(word), "{word:#x}");
        }
    }

    #[test]
    fn value_stability() {
        let l = HeuristicsLayout::ADGI;
        let w = l.encode(Heuristics {
            f_v: 0.3,
            f_s: 0.6,
            f_d: 0.01,
            flags: 0b10_0001,
        });
        assert_eq!(w.0, 0x840a_9993, "{:#x}", w.0);
    }
}
