//! ADGI's visibility texel: log-encoded mean distance and mean squared distance and a sample
//! count in 32 bits (sec. 4.6, Table 3), the moments of Chebyshev visibility.

use bytemuck::{Pod, Zeroable};
use glam::Vec2;

use crate::bits::BitField;
use crate::error::CodecError;
use crate::log_codec::{LogCodec, LogField, LogLanes, MAX_FIELD_BITS};
use crate::quantize::Rounding;

/// Bit layout of a visibility word: mean distance d̄ and mean squared distance d̄² through their
/// own log codecs (eq. 21), and a count field. Distances are normalised by the probe cage
/// diagonal (sec. 4.6) by the caller.
///
/// # Bit map (bit 0 = least significant)
/// ```text
/// ADGI default (13 + 13 + 6; d̄ with (β, γ) = (5, 15), d̄² with (8, 20)):
///  31      26 25                13 12                 0
/// [ count:6  | mean sq. dist.:13  | mean distance:13   ]
/// general: d̄ at [0, a), d̄² at [a, a+b), count at [32−c, 32)
/// ```
///
/// # Round-trip error bound
/// Each field obeys the [`LogField`] bound: with ADGI's parameters and [`Rounding::Down`],
/// `0 ≤ d − d̂ < (1 − e^{−5/8191})(d + 1/15)` ≈ 0.061 % of (d + 0.067) for d ≤ 9.83, and
/// `0 ≤ s − ŝ < (1 − e^{−8/8191})(s + 1/20)` ≈ 0.098 % of (s + 0.05) for s = d² ≤ 149.
///
/// # Example
/// ```
/// use mcg_color_codec::{VisibilityLayout, Rounding, glam::Vec2};
/// let layout = VisibilityLayout::ADGI;
/// let t = 0.6; // hit distance / cage diagonal
/// let word = layout.encode(Vec2::new(t, t * t), 1, Rounding::Down);
/// let m = layout.decode(word);
/// assert!((m.x - t).abs() < 1e-3 && (m.y - t * t).abs() < 1e-3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilityLayout {
    fields: [LogField; 2],
    places: [BitField; 2],
    count: BitField,
    /// Both fields as one 4-lane codec (lanes 0, 1 = d̄, d̄² at their places; lanes 2, 3 repeat
    /// d̄² and are not packed), built once so `encode`/`decode` run one vector evaluation
    /// instead of a per-field codec set-up; lane for lane the same operations as
    /// [`LogField::encode`]/[`LogField::decode`], so the same bits.
    lanes: LogLanes,
}

/// A packed visibility texel (see [`VisibilityLayout`] for its bit map); plain `u32` on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
#[repr(transparent)]
pub struct VisibilityWord(pub u32);

const _: () = assert!(core::mem::size_of::<VisibilityWord>() == 4);

impl VisibilityLayout {
    /// ADGI's layout: 13-bit d̄ with (5, 15), 13-bit d̄² with (8, 20), 6-bit count (sec. 4.6).
    pub const ADGI: VisibilityLayout =
        match VisibilityLayout::new(13, 13, 6, LogCodec::DISTANCE, LogCodec::SQUARED_DISTANCE) {
            Ok(layout) => layout,
            Err(_) => panic!("invalid ADGI visibility layout"),
        };

    /// A layout with the given widths and codecs.
    ///
    /// # Errors
    /// [`CodecError::FieldWidthOutOfRange`], [`CodecError::CountWidthOutOfRange`] (widths
    /// outside 1 ..= 16) or [`CodecError::WidthsDoNotSumTo32`].
    pub const fn new(
        mean_bits: u32,
        mean_sq_bits: u32,
        count_bits: u32,
        mean_codec: LogCodec,
        mean_sq_codec: LogCodec,
    ) -> Result<Self, CodecError> {
        if mean_bits < 1 || mean_bits > MAX_FIELD_BITS {
            return Err(CodecError::FieldWidthOutOfRange { bits: mean_bits });
        }
        if mean_sq_bits < 1 || mean_sq_bits > MAX_FIELD_BITS {
            return Err(CodecError::FieldWidthOutOfRange { bits: mean_sq_bits });
        }
        if count_bits < 1 || count_bits > MAX_FIELD_BITS {
            return Err(CodecError::CountWidthOutOfRange { bits: count_bits });
        }
        let sum = mean_bits + mean_sq_bits + count_bits;
        if sum != 32 {
            return Err(CodecError::WidthsDoNotSumTo32 { sum });
        }
        Ok(Self {
            fields: [
                mean_codec.field(mean_bits),
                mean_sq_codec.field(mean_sq_bits),
            ],
            places: [
                BitField::new(0, mean_bits),
                BitField::new(mean_bits, mean_sq_bits),
            ],
            count: BitField::new(32 - count_bits, count_bits),
            lanes: LogLanes::new(
                [
                    mean_codec.field(mean_bits),
                    mean_sq_codec.field(mean_sq_bits),
                    mean_sq_codec.field(mean_sq_bits),
                    mean_sq_codec.field(mean_sq_bits),
                ],
                [0, 1, 1, 1],
                [0, mean_bits, mean_bits, mean_bits],
                [true, true, false, false],
            ),
        })
    }

    /// The quantised codec of the mean distance (`0`) or the mean squared distance (`1`; any
    /// other index is clamped to 1).
    #[inline]
    #[must_use]
    pub const fn channel(&self, i: usize) -> LogField {
        self.fields[if i > 1 { 1 } else { i }]
    }

    /// Widths `[mean, mean squared, count]` in bits.
    #[must_use]
    pub const fn widths(&self) -> [u32; 3] {
        [self.places[0].bits, self.places[1].bits, self.count.bits]
    }

    /// Bit offsets `[mean, mean squared, count]`.
    #[must_use]
    pub const fn shifts(&self) -> [u32; 3] {
        [self.places[0].shift, self.places[1].shift, self.count.shift]
    }

    /// The largest storable count, 2^c − 1.
    #[inline]
    #[must_use]
    pub const fn max_count(&self) -> u32 {
        self.count.max()
    }

    /// Packs the moments `(d̄, d̄²)` and `count` (saturated). Negative and NaN moments encode
    /// to 0, too large ones saturate.
    #[inline]
    #[must_use]
    pub fn encode(&self, moments: Vec2, count: u32, rounding: Rounding) -> VisibilityWord {
        let [m, m2, _, _] = self
            .lanes
            .encode([moments.x, moments.y, moments.y, moments.y], rounding);
        let word = self.places[0].put(m)
            | self.places[1].put(m2)
            | self.count.put(count.min(self.max_count()));
        VisibilityWord(word)
    }

    /// Unpacks `(d̄, d̄²)`; every word decodes to finite, non-negative values.
    #[inline]
    #[must_use]
    pub fn decode(&self, word: VisibilityWord) -> Vec2 {
        let [m, m2, _, _] = self.lanes.decode_word(word.0);
        Vec2::new(m, m2)
    }

    /// The field codes `[mean, mean squared]`.
    #[inline]
    #[must_use]
    pub fn codes(&self, word: VisibilityWord) -> [u32; 2] {
        [self.places[0].get(word.0), self.places[1].get(word.0)]
    }

    /// The sample count N stored in a word.
    #[inline]
    #[must_use]
    pub const fn count(&self, word: VisibilityWord) -> u32 {
        self.count.get(word.0)
    }

    /// `word` with its count replaced by `count` (saturated).
    #[inline]
    #[must_use]
    pub const fn with_count(&self, word: VisibilityWord, count: u32) -> VisibilityWord {
        let c = if count > self.max_count() {
            self.max_count()
        } else {
            count
        };
        VisibilityWord(self.count.set(word.0, c))
    }
}

impl From<u32> for VisibilityWord {
    fn from(bits: u32) -> Self {
        Self(bits)
    }
}

impl From<VisibilityWord> for u32 {
    fn from(word: VisibilityWord) -> Self {
        word.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction_and_layout() {
        let l = VisibilityLayout::ADGI;
        assert_eq!(l.widths(), [13, 13, 6]);
        assert_eq!(l.shifts(), [0, 13, 26]);
        let c = LogCodec::DISTANCE;
        assert_eq!(
            VisibilityLayout::new(13, 13, 7, c, c),
            Err(CodecError::WidthsDoNotSumTo32 { sum: 33 })
        );
        assert_eq!(
            VisibilityLayout::new(20, 6, 6, c, c),
            Err(CodecError::FieldWidthOutOfRange { bits: 20 })
        );
        assert_eq!(
            VisibilityLayout::new(16, 16, 0, c, c),
            Err(CodecError::CountWidthOutOfRange { bits: 0 })
        );
        let w = l.encode(Vec2::splat(1e9), 99, Rounding::Down);
        assert_eq!(w.0, u32::MAX);
        assert_eq!(l.count(l.with_count(w, 16)), 16);
        assert_eq!(l.codes(w), [8191, 8191]);
    }

    #[test]
    fn bad_input_and_every_field_value() {
        let l = VisibilityLayout::ADGI;
        let w = l.encode(Vec2::new(f32::NAN, f32::NEG_INFINITY), 1, Rounding::Nearest);
        assert_eq!(l.codes(w), [0, 0]);
        for i in 0..2 {
            for q in 0..=l.channel(i).max_code() {
                let m = l.decode(VisibilityWord(l.places[i].put(q) | 0xfc00_0000));
                assert!(m.is_finite() && m.cmpge(Vec2::ZERO).all(), "{i} {q}");
            }
        }
    }

    /// The 4-lane form equals the per-field codec bit for bit.
    #[test]
    fn lanes_match_per_field_codec() {
        let l = VisibilityLayout::ADGI;
        let mut x = 0x1234_5678u32;
        for i in 0..20_000u32 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let m = l.decode(VisibilityWord(x));
            assert_eq!(
                m.x.to_bits(),
                l.fields[0].decode(l.places[0].get(x)).to_bits()
            );
            assert_eq!(
                m.y.to_bits(),
                l.fields[1].decode(l.places[1].get(x)).to_bits()
            );
            let v = Vec2::new((x & 0xffff) as f32 * 1.7e-4, (x >> 16) as f32 * 2.3e-3);
            let u = (i as f32 * 0.618_034) % 1.0;
            for r in [Rounding::Down, Rounding::Nearest, Rounding::Stochastic(u)] {
                let w = l.encode(v, 3, r);
                let want = l.places[0].put(l.fields[0].encode(v.x, r))
                    | l.places[1].put(l.fields[1].encode(v.y, r.for_channel(1)))
                    | l.count.put(3);
                assert_eq!(w.0, want, "{v} {r:?}");
            }
        }
    }

    #[test]
    fn value_stability() {
        let l = VisibilityLayout::ADGI;
        let words = [
            l.encode(Vec2::new(0.6, 0.36), 1, Rounding::Down).0,
            l.encode(Vec2::new(3.0, 11.0), 63, Rounding::Nearest).0,
        ];
        assert_eq!(words, [0x050d_4ebc, 0xfeb2_f880], "{words:#x?}");
    }
}
