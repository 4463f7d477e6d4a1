//! ADGI's irradiance texel: three log-encoded colour channels and a sample count in 32 bits
//! (sec. 4.5, Table 3).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::bits::BitField;
use crate::error::CodecError;
use crate::log_codec::{LogCodec, LogField, LogLanes, MAX_FIELD_BITS};
use crate::log_table::{FieldTable, LogTable};
use crate::quantize::Rounding;

/// Bit layout of an irradiance word: R, G, B fields of the log codec (eq. 21) and a count field.
///
/// # Bit map (bit 0 = least significant)
/// ```text
/// ADGI default (R9 G9 B8 + 6-bit count, β = 5, γ = 15):
///  31      26 25     18 17      9 8       0
/// [ count:6  | B:8     | G:9     | R:9     ]
/// general: R at [0, r), G at [r, r+g), B at [r+g, r+g+b), count at [32−c, 32)
/// ```
/// Widths are parameters (each colour field 1 ..= 16 bits, count 1 ..= 16 bits, summing to 32),
/// so e.g. [`IrradianceLayout::EQUAL_10`] gives RTXGI-style equal 10/10/10 channels with a 2-bit
/// count. The count's largest value 2^c − 1 bounds the moving average's N_max (ADGI uses 63).
///
/// # Round-trip error bound
/// Each channel obeys the [`LogField`] bound for its width: with ADGI's parameters and
/// [`Rounding::Down`], `0 ≤ v − v̂ < (1 − e^{−5/511})(v + 1/15)` ≈ 0.97 % of (v + 0.067) for R and
/// G, and `< (1 − e^{−5/255})(v + 1/15)` ≈ 1.94 % of (v + 0.067) for B, for v ≤ 9.83; above, each
/// channel saturates at (e⁵ − 1)/15 ≈ 9.83.
///
/// # Example
/// ```
/// use mcg_color_codec::{IrradianceLayout, Rounding, glam::Vec3};
/// let layout = IrradianceLayout::ADGI;
/// let word = layout.encode(Vec3::new(0.8, 0.4, 0.1), 5, Rounding::Down);
/// assert_eq!(layout.count(word), 5);
/// let rgb = layout.decode(word);
/// assert!((rgb - Vec3::new(0.8, 0.4, 0.1)).abs().max_element() < 0.02);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceLayout {
    fields: [LogField; 3],
    lanes: LogLanes,
    places: [BitField; 3],
    count: BitField,
    /// The three channels' tables when every channel has them (ADGI's codec at 8-10 bits):
    /// decode by three loads, round down by three table searches, the same bits as `lanes`.
    /// Held by value, not as `&'static LogTable`, so that where the layout is a constant (e.g.
    /// [`LogRgb::ADGI`](crate::LogRgb::ADGI) inlined into a loop) its γ, clamp, shift and mask
    /// fold into the code: the statics' contents are opaque to a caller in another crate.
    tables: Option<[LogTable; 3]>,
    /// Whether the tables' code for this layout is compiled with its widths as constants
    /// (ADGI's R9G9B8 and the 10/10/10 layout): then `encode` (round-down), `decode` and the
    /// slice loops run it whoever calls, even where the layout is a run-time value (a codec in
    /// a struct, behind a reference, captured by a closure): one predictable branch on this
    /// tag instead of loading the tables' pointers, γ, clamps and shifts for every colour.
    fixed: FixedWidths,
}

/// The widths whose table code is compiled with the tables and shifts as constants (see
/// [`IrradianceLayout`]'s `fixed`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FixedWidths {
    /// No tables, or other widths: the layout's run-time tables or the polynomial path.
    None,
    /// ADGI's R9 G9 B8 with tables.
    R9G9B8,
    /// Equal 10/10/10 with tables.
    R10G10B10,
}

/// Round-down of one colour by the tables of widths R, G, B (R at bit 0, G at R, B at R + G),
/// the tables and shifts constants: the colour bits of [`IrradianceLayout::encode`].
#[inline(always)]
fn pack_down_fixed<const R: u32, const G: u32, const B: u32>(c: Vec3) -> u32 {
    let (r, g, b) = (
        FieldTable::<R>::TABLE,
        FieldTable::<G>::TABLE,
        FieldTable::<B>::TABLE,
    );
    r.encode_down(c.x) | g.encode_down(c.y) << R | b.encode_down(c.z) << (R + G)
}

/// [`IrradianceLayout::decode`] by the tables of widths R, G, B, as [`pack_down_fixed`].
#[inline(always)]
fn unpack_fixed<const R: u32, const G: u32, const B: u32>(w: u32) -> Vec3 {
    let (r, g, b) = (
        FieldTable::<R>::TABLE,
        FieldTable::<G>::TABLE,
        FieldTable::<B>::TABLE,
    );
    Vec3::new(r.decode(w), g.decode(w >> R), b.decode(w >> (R + G)))
}

/// [`IrradianceLayout::encode_slice`]'s table loop for a layout of ADGI's codec with widths
/// R, G, B (R at bit 0, G at R, B at R + G), rounding down: the tables and shifts are
/// constants, whoever calls. `count_bits` is the count field, already in place.
#[inline(never)]
fn encode_down_fixed<const R: u32, const G: u32, const B: u32>(
    count_bits: u32,
    colours: &[Vec3],
    words: &mut [IrradianceWord],
) {
    for (w, &c) in words.iter_mut().zip(colours) {
        *w = IrradianceWord(count_bits | pack_down_fixed::<R, G, B>(c));
    }
}

/// [`IrradianceLayout::decode_slice`]'s table loop for widths R, G, B, as [`encode_down_fixed`].
#[inline(never)]
fn decode_fixed<const R: u32, const G: u32, const B: u32>(
    words: &[IrradianceWord],
    colours: &mut [Vec3],
) {
    for (c, &w) in colours.iter_mut().zip(words) {
        *c = unpack_fixed::<R, G, B>(w.0);
    }
}

/// A packed irradiance texel (see [`IrradianceLayout`] for its bit map); plain `u32` on the GPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
#[repr(transparent)]
pub struct IrradianceWord(pub u32);

const _: () = assert!(core::mem::size_of::<IrradianceWord>() == 4);

impl IrradianceLayout {
    /// ADGI's layout: R9 G9 B8, 6-bit count, log codec (β, γ) = (5, 15) (sec. 4.5, Table 3).
    pub const ADGI: IrradianceLayout = match IrradianceLayout::new(9, 9, 8, 6, LogCodec::IRRADIANCE)
    {
        Ok(layout) => layout,
        Err(_) => panic!("invalid ADGI irradiance layout"),
    };

    /// Equal 10/10/10 channels with a 2-bit count (N_max ≤ 3), log codec (5, 15): the split
    /// RTXGI moved to because unequal channel precision shifted colours.
    pub const EQUAL_10: IrradianceLayout =
        match IrradianceLayout::new(10, 10, 10, 2, LogCodec::IRRADIANCE) {
            Ok(layout) => layout,
            Err(_) => panic!("invalid 10/10/10 irradiance layout"),
        };

    /// A layout with the given widths and codec.
    ///
    /// # Errors
    /// [`CodecError::FieldWidthOutOfRange`] if a colour width is not in 1 ..= 16,
    /// [`CodecError::CountWidthOutOfRange`] if the count width is not in 1 ..= 16,
    /// [`CodecError::WidthsDoNotSumTo32`] otherwise if the widths do not add up to 32.
    pub const fn new(
        r_bits: u32,
        g_bits: u32,
        b_bits: u32,
        count_bits: u32,
        codec: LogCodec,
    ) -> Result<Self, CodecError> {
        let widths = [r_bits, g_bits, b_bits];
        let mut i = 0;
        while i < 3 {
            if widths[i] < 1 || widths[i] > MAX_FIELD_BITS {
                return Err(CodecError::FieldWidthOutOfRange { bits: widths[i] });
            }
            i += 1;
        }
        if count_bits < 1 || count_bits > MAX_FIELD_BITS {
            return Err(CodecError::CountWidthOutOfRange { bits: count_bits });
        }
        let sum = r_bits + g_bits + b_bits + count_bits;
        if sum != 32 {
            return Err(CodecError::WidthsDoNotSumTo32 { sum });
        }
        let fields = [
            codec.field(r_bits),
            codec.field(g_bits),
            codec.field(b_bits),
        ];
        let tables = match (fields[0].table(), fields[1].table(), fields[2].table()) {
            (Some(r), Some(g), Some(b)) => Some([*r, *g, *b]),
            _ => None,
        };
        let fixed = match (tables.is_some(), r_bits, g_bits, b_bits) {
            (true, 9, 9, 8) => FixedWidths::R9G9B8,
            (true, 10, 10, 10) => FixedWidths::R10G10B10,
            _ => FixedWidths::None,
        };
        Ok(Self {
            fields,
            lanes: LogLanes::new(
                [fields[0], fields[1], fields[2], fields[2]],
                [0, 1, 2, 2],
                [0, r_bits, r_bits + g_bits, 0],
                [true, true, true, false],
            ),
            places: [
                BitField::new(0, r_bits),
                BitField::new(r_bits, g_bits),
                BitField::new(r_bits + g_bits, b_bits),
            ],
            count: BitField::new(32 - count_bits, count_bits),
            tables,
            fixed,
        })
    }

    /// The log codec of the colour channels.
    #[inline]
    #[must_use]
    pub const fn codec(&self) -> LogCodec {
        self.fields[0].codec()
    }

    /// The quantised codec of channel `i` (0 = R, 1 = G, 2 = B; clamped to 2).
    #[inline]
    #[must_use]
    pub const fn channel(&self, i: usize) -> LogField {
        self.fields[if i > 2 { 2 } else { i }]
    }

    /// Widths `[R, G, B, count]` in bits.
    #[must_use]
    pub const fn widths(&self) -> [u32; 4] {
        [
            self.places[0].bits,
            self.places[1].bits,
            self.places[2].bits,
            self.count.bits,
        ]
    }

    /// Bit offsets `[R, G, B, count]` of the fields.
    #[must_use]
    pub const fn shifts(&self) -> [u32; 4] {
        [
            self.places[0].shift,
            self.places[1].shift,
            self.places[2].shift,
            self.count.shift,
        ]
    }

    /// The largest storable count, 2^c − 1.
    #[inline]
    #[must_use]
    pub const fn max_count(&self) -> u32 {
        self.count.max()
    }

    /// Packs `rgb` (each channel through eq. 21, rounded with `rounding`) and `count`
    /// (saturated at [`max_count`](Self::max_count)).
    ///
    /// Bad input: negative and NaN channels encode to 0, channels above (e⁵ − 1)/15 (and +∞)
    /// saturate. With [`Rounding::Stochastic`] each channel uses the caller's uniform rotated by
    /// a golden-ratio step, so one uniform serves the word.
    ///
    /// Round-down with tables (ADGI's codec at 8-10 bits) searches the tables; for ADGI's
    /// R9G9B8 and the 10/10/10 layout that code is compiled with the tables and shifts as
    /// constants, chosen by one branch on the layout, so it is as fast where the layout is a
    /// run-time value (a codec in a struct, behind a reference) as where it is a constant.
    /// Same codes as the polynomial path (tested at every code).
    #[inline(always)]
    #[must_use]
    pub fn encode(&self, rgb: Vec3, count: u32, rounding: Rounding) -> IrradianceWord {
        if let Rounding::Down = rounding {
            let count_bits = self.count.put(count.min(self.max_count()));
            let colour_bits = match (self.fixed, self.tables) {
                (FixedWidths::R9G9B8, _) => Some(pack_down_fixed::<9, 9, 8>(rgb)),
                (FixedWidths::R10G10B10, _) => Some(pack_down_fixed::<10, 10, 10>(rgb)),
                (FixedWidths::None, Some(_)) => Some(self.pack_out_of_line(rgb.x, rgb.y, rgb.z)),
                (FixedWidths::None, None) => None,
            };
            if let Some(bits) = colour_bits {
                return IrradianceWord(count_bits | bits);
            }
        }
        // Lane 3 repeats B (it has no field and is left out of the word): a constant there
        // would sit on a code boundary and send every word down round-down's slow path.
        IrradianceWord(
            self.count.put(count.min(self.max_count()))
                | self
                    .lanes
                    .encode_word3([rgb.x, rgb.y, rgb.z, rgb.z], rounding),
        )
    }

    /// Unpacks the colour; every word decodes to finite, non-negative channels.
    ///
    /// Layouts with tables decode by three loads (constant tables and shifts for ADGI's and
    /// the 10/10/10 layout, as in [`encode`](Self::encode)), the polynomial path's values.
    #[inline(always)]
    #[must_use]
    pub fn decode(&self, word: IrradianceWord) -> Vec3 {
        match self.fixed {
            FixedWidths::R9G9B8 => return unpack_fixed::<9, 9, 8>(word.0),
            FixedWidths::R10G10B10 => return unpack_fixed::<10, 10, 10>(word.0),
            FixedWidths::None => {}
        }
        if self.tables.is_some() {
            let [r, g, b] = self.unpack_out_of_line(word.0);
            return Vec3::new(r, g, b);
        }
        let [r, g, b, _] = self.lanes.decode_word(word.0);
        Vec3::new(r, g, b)
    }

    /// The colour fields of a word rounded down by the run-time tables (widths other than
    /// the constant ones), out of line: inlined into a caller's loop, the tables' pointers,
    /// clamps and shifts would hold registers there that the constant-width code needs.
    /// The channels come and go as scalars, not as a `Vec3` in memory, so that the caller's
    /// colour stays in registers. `#[cold]` only for the caller's block layout (the
    /// constant-width path falls through); the call itself costs a few instructions.
    #[cold]
    #[inline(never)]
    fn pack_out_of_line(&self, r: f32, g: f32, b: f32) -> u32 {
        match self.tables {
            Some(t) => self.pack(t, Vec3::new(r, g, b)),
            None => 0,
        }
    }

    /// [`decode`](Self::decode) by the run-time tables, out of line as
    /// [`pack_out_of_line`](Self::pack_out_of_line).
    #[cold]
    #[inline(never)]
    fn unpack_out_of_line(&self, word: u32) -> [f32; 3] {
        match self.tables {
            Some(t) => self.unpack(t, word).to_array(),
            None => [0.0; 3],
        }
    }

    /// A word's colour decoded by the tables.
    #[inline(always)]
    fn unpack(&self, [r, g, b]: [LogTable; 3], word: u32) -> Vec3 {
        let s = self.shifts();
        Vec3::new(
            r.decode(word >> s[0]),
            g.decode(word >> s[1]),
            b.decode(word >> s[2]),
        )
    }

    /// The colour fields of a word rounded down by the tables.
    #[inline(always)]
    fn pack(&self, [r, g, b]: [LogTable; 3], rgb: Vec3) -> u32 {
        let s = self.shifts();
        r.encode_down(rgb.x) << s[0] | g.encode_down(rgb.y) << s[1] | b.encode_down(rgb.z) << s[2]
    }

    /// Lanes for the batch form: every lane holds channel `i`'s field (R = 0, G = 1, B = 2) at
    /// its place in the word, and rounds stochastically like channel `i` of [`encode`](Self::encode).
    #[inline(always)]
    fn channel_lanes(&self, i: usize) -> LogLanes {
        let s = self.places[i].shift;
        LogLanes::new([self.fields[i]; 4], [i as u32; 4], [s; 4], [true; 4])
    }

    /// [`encode`](Self::encode) over a slice: `words[j] = self.encode(colours[j], count, rounding)`,
    /// bit for bit, for every `j` (the same `count` and `rounding` — so the same stochastic
    /// uniform, rotated per channel as in `encode` — for every colour).
    ///
    /// Batch form: four colours at a time are transposed into one 4-lane vector per channel
    /// (lane = colour), so the `ln` polynomial and the rounding run on four colours per
    /// evaluation with every lane useful; a tail of fewer than four colours goes through
    /// [`encode`](Self::encode). Round-down's exact check falls back per vector as in `encode`
    /// (any lane near a code boundary); lane by lane the operations are those of `encode`, hence
    /// the same codes (tested for every rounding mode, bad input and code boundaries).
    ///
    /// Layouts whose three fields have tables (ADGI's codec at 8-10 bits) round down colour by
    /// colour through the table search instead, as `encode` does (fewer instructions than the
    /// 4-lane polynomial); for ADGI's R9G9B8 and the 10/10/10 layout that loop is compiled with
    /// the tables and shifts as constants, whatever the caller (tested against the polynomial
    /// path at every code).
    ///
    /// # Panics
    /// If `colours` and `words` differ in length.
    ///
    /// # Example
    /// ```
    /// use mcg_color_codec::{IrradianceLayout, IrradianceWord, Rounding, glam::Vec3};
    /// let layout = IrradianceLayout::ADGI;
    /// let colours = [Vec3::new(0.8, 0.4, 0.1), Vec3::ONE, Vec3::ZERO, Vec3::splat(5.0), Vec3::X];
    /// let mut words = [IrradianceWord(0); 5];
    /// layout.encode_slice(&colours, 7, Rounding::Down, &mut words);
    /// for (w, &c) in words.iter().zip(&colours) {
    ///     assert_eq!(*w, layout.encode(c, 7, Rounding::Down));
    /// }
    /// ```
    pub fn encode_slice(
        &self,
        colours: &[Vec3],
        count: u32,
        rounding: Rounding,
        words: &mut [IrradianceWord],
    ) {
        assert_eq!(
            colours.len(),
            words.len(),
            "encode_slice: colours and words differ in length"
        );
        if let (Some(t), Rounding::Down) = (self.tables, rounding) {
            let count_bits = self.count.put(count.min(self.max_count()));
            // The tables are fixed by the widths (they exist only for ADGI's codec), and so
            // are the shifts: ADGI's and the 10/10/10 layout run loops with both as constants.
            match self.fixed {
                FixedWidths::R9G9B8 => encode_down_fixed::<9, 9, 8>(count_bits, colours, words),
                FixedWidths::R10G10B10 => {
                    encode_down_fixed::<10, 10, 10>(count_bits, colours, words)
                }
                FixedWidths::None => {
                    for (w, &c) in words.iter_mut().zip(colours) {
                        *w = IrradianceWord(count_bits | self.pack(t, c));
                    }
                }
            }
            return;
        }
        self.encode_slice_lanes(colours, count, rounding, words);
    }

    /// The batch form of [`encode_slice`](Self::encode_slice) (every path but the tables'
    /// round-down), out of line: `encode_slice` itself is then only the dispatch.
    #[inline(never)]
    fn encode_slice_lanes(
        &self,
        colours: &[Vec3],
        count: u32,
        rounding: Rounding,
        words: &mut [IrradianceWord],
    ) {
        // Spelled out, not `[0, 1, 2].map(..)`: LLVM left such closures un-inlined here.
        let lanes = [
            self.channel_lanes(0),
            self.channel_lanes(1),
            self.channel_lanes(2),
        ];
        let count_bits = self.count.put(count.min(self.max_count()));
        let mut colour_chunks = colours.chunks_exact(4);
        let mut word_chunks = words.chunks_exact_mut(4);
        for (c, w) in (&mut colour_chunks).zip(&mut word_chunks) {
            let r = lanes[0].encode([c[0].x, c[1].x, c[2].x, c[3].x], rounding);
            let g = lanes[1].encode([c[0].y, c[1].y, c[2].y, c[3].y], rounding);
            let b = lanes[2].encode([c[0].z, c[1].z, c[2].z, c[3].z], rounding);
            let s = self.shifts();
            for j in 0..4 {
                w[j] = IrradianceWord(count_bits | r[j] << s[0] | g[j] << s[1] | b[j] << s[2]);
            }
        }
        for (w, &c) in word_chunks
            .into_remainder()
            .iter_mut()
            .zip(colour_chunks.remainder())
        {
            *w = self.encode(c, count, rounding);
        }
    }

    /// [`decode`](Self::decode) over a slice: `colours[j] = self.decode(words[j])`, bit for bit.
    ///
    /// Batch form: four words at a time, one 4-lane vector per channel (lane = word), so the
    /// `exp2` polynomial runs on four colours per evaluation; a tail of fewer than four words
    /// goes through [`decode`](Self::decode). Layouts with tables decode by three loads per
    /// word, as `decode` does (constant tables and shifts for ADGI's and the 10/10/10 layout).
    ///
    /// # Panics
    /// If `words` and `colours` differ in length.
    pub fn decode_slice(&self, words: &[IrradianceWord], colours: &mut [Vec3]) {
        assert_eq!(
            words.len(),
            colours.len(),
            "decode_slice: words and colours differ in length"
        );
        if let Some(t) = self.tables {
            match self.fixed {
                FixedWidths::R9G9B8 => decode_fixed::<9, 9, 8>(words, colours),
                FixedWidths::R10G10B10 => decode_fixed::<10, 10, 10>(words, colours),
                FixedWidths::None => {
                    for (c, &w) in colours.iter_mut().zip(words) {
                        *c = self.unpack(t, w.0);
                    }
                }
            }
            return;
        }
        self.decode_slice_lanes(words, colours);
    }

    /// The batch form of [`decode_slice`](Self::decode_slice) for layouts without tables, out
    /// of line like [`encode_slice_lanes`](Self::encode_slice_lanes).
    #[inline(never)]
    fn decode_slice_lanes(&self, words: &[IrradianceWord], colours: &mut [Vec3]) {
        let lanes = [
            self.channel_lanes(0),
            self.channel_lanes(1),
            self.channel_lanes(2),
        ];
        let mut word_chunks = words.chunks_exact(4);
        let mut colour_chunks = colours.chunks_exact_mut(4);
        for (w, c) in (&mut word_chunks).zip(&mut colour_chunks) {
            let w = [w[0].0, w[1].0, w[2].0, w[3].0];
            let r = lanes[0].decode_words(w);
            let g = lanes[1].decode_words(w);
            let b = lanes[2].decode_words(w);
            for j in 0..4 {
                c[j] = Vec3::new(r[j], g[j], b[j]);
            }
        }
        for (c, &w) in colour_chunks
            .into_remainder()
            .iter_mut()
            .zip(word_chunks.remainder())
        {
            *c = self.decode(w);
        }
    }

    /// The channel codes `[R, G, B]` of a word.
    #[inline]
    #[must_use]
    pub fn codes(&self, word: IrradianceWord) -> [u32; 3] {
        [0, 1, 2].map(|i| self.places[i].get(word.0))
    }

    /// The sample count N stored in a word.
    #[inline]
    #[must_use]
    pub const fn count(&self, word: IrradianceWord) -> u32 {
        self.count.get(word.0)
    }

    /// `word` with its count replaced by `count` (saturated), colour unchanged. ADGI resets N
    /// to 16 for probes between the inner and outer camera volumes to make them adapt faster
    /// (sec. 4.8).
    #[inline]
    #[must_use]
    pub const fn with_count(&self, word: IrradianceWord, count: u32) -> IrradianceWord {
        let c = if count > self.max_count() {
            self.max_count()
        } else {
            count
        };
        IrradianceWord(self.count.set(word.0, c))
    }
}

impl From<u32> for IrradianceWord {
    fn from(bits: u32) -> Self {
        Self(bits)
    }
}

impl From<IrradianceWord> for u32 {
    fn from(word: IrradianceWord) -> Self {
        word.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction() {
        assert_eq!(IrradianceLayout::ADGI.widths(), [9, 9, 8, 6]);
        assert_eq!(IrradianceLayout::ADGI.shifts(), [0, 9, 18, 26]);
        assert_eq!(IrradianceLayout::ADGI.max_count(), 63);
        assert_eq!(IrradianceLayout::EQUAL_10.max_count(), 3);
        let c = LogCodec::IRRADIANCE;
        assert_eq!(
            IrradianceLayout::new(9, 9, 9, 6, c),
            Err(CodecError::WidthsDoNotSumTo32 { sum: 33 })
        );
        assert_eq!(
            IrradianceLayout::new(0, 13, 13, 6, c),
            Err(CodecError::FieldWidthOutOfRange { bits: 0 })
        );
        assert_eq!(
            IrradianceLayout::new(17, 7, 7, 1, c),
            Err(CodecError::FieldWidthOutOfRange { bits: 17 })
        );
        assert_eq!(
            IrradianceLayout::new(11, 11, 10, 0, c),
            Err(CodecError::CountWidthOutOfRange { bits: 0 })
        );
        assert!(IrradianceLayout::new(11, 11, 9, 1, c).is_ok());
    }

    #[test]
    fn fields_do_not_overlap() {
        let l = IrradianceLayout::ADGI;
        let w = l.encode(Vec3::splat(1e9), 63, Rounding::Down);
        assert_eq!(w.0, u32::MAX);
        let w = l.encode(Vec3::new(1e9, 0.0, 0.0), 0, Rounding::Down);
        assert_eq!(w.0, 0x1ff);
        let w = l.encode(Vec3::ZERO, 1000, Rounding::Down);
        assert_eq!(w.0, 63 << 26);
        assert_eq!(l.count(l.with_count(w, 16)), 16);
        assert_eq!(
            l.codes(l.with_count(IrradianceWord(0x3ff_ffff), 7)),
            [511, 511, 255]
        );
    }

    #[test]
    fn bad_input() {
        let l = IrradianceLayout::ADGI;
        let w = l.encode(
            Vec3::new(f32::NAN, -1.0, f32::INFINITY),
            3,
            Rounding::Nearest,
        );
        assert_eq!(l.codes(w), [0, 0, 255]);
        assert_eq!(l.count(w), 3);
        let rgb = l.decode(w);
        assert!(rgb.is_finite() && rgb.cmpge(Vec3::ZERO).all());
    }

    #[test]
    fn every_field_value_decodes_finite_non_negative() {
        for l in [IrradianceLayout::ADGI, IrradianceLayout::EQUAL_10] {
            for i in 0..3 {
                let f = l.channel(i);
                for q in 0..=f.max_code() {
                    let word = IrradianceWord(l.places[i].put(q) | l.count.put(u32::MAX));
                    let rgb = l.decode(word);
                    assert!(rgb.is_finite() && rgb.cmpge(Vec3::ZERO).all(), "{i} {q}");
                    assert_eq!(l.codes(word)[i], q);
                }
            }
        }
    }

    #[test]
    fn value_stability() {
        let l = IrradianceLayout::ADGI;
        let words = [
            l.encode(Vec3::new(0.8, 0.4, 0.1), 5, Rounding::Down).0,
            l.encode(Vec3::new(0.8, 0.4, 0.1), 5, Rounding::Nearest).0,
            l.encode(Vec3::new(0.8, 0.4, 0.1), 63, Rounding::Stochastic(0.5))
                .0,
            IrradianceLayout::EQUAL_10
                .encode(Vec3::new(2.0, 0.05, 7.0), 2, Rounding::Down)
                .0,
        ];
        assert_eq!(
            words,
            [0x14b9_8d06, 0x14bd_8f06, 0xfcb9_8f06, 0xbba1_cabe],
            "{words:#x?}"
        );
    }

    /// The four-lane word encoder and decoder give exactly what the channels' [`LogField`]s
    /// give one at a time (stochastic uniforms rotated per channel).
    #[test]
    fn word_lanes_match_the_fields() {
        for l in [
            IrradianceLayout::ADGI,
            IrradianceLayout::EQUAL_10,
            IrradianceLayout::new(16, 8, 7, 1, LogCodec::SQUARED_DISTANCE).unwrap(),
            IrradianceLayout::new(11, 11, 9, 1, LogCodec::new(0.5, 0.01).unwrap()).unwrap(),
        ] {
            let mut x = 1e-6_f32;
            let mut k = 0_u32;
            while x < 40.0 {
                let rgb = Vec3::new(x, x * 0.37 + 1e-3, 9.9 - (x * 0.21).min(9.9));
                for rounding in [
                    Rounding::Down,
                    Rounding::Nearest,
                    Rounding::Stochastic((k % 97) as f32 / 97.0),
                ] {
                    let w = l.encode(rgb, k, rounding);
                    let want: [u32; 3] = core::array::from_fn(|i| {
                        l.channel(i).encode(rgb[i], rounding.for_channel(i as u32))
                    });
                    assert_eq!(l.codes(w), want, "{rgb} {rounding:?}");
                    assert_eq!(l.count(w), k.min(l.max_count()));
                    let dec = l.decode(w);
                    for i in 0..3 {
                        assert_eq!(dec[i].to_bits(), l.channel(i).decode(want[i]).to_bits());
                    }
                }
                x *= 1.003;
                k += 1;
            }
        }
    }

    extern crate std;
    use std::vec::Vec;

    /// Channel values that stress the batch form: bad input (NaN, ±0, negatives, ±∞, huge,
    /// subnormal, tiny), every 7th code boundary of each channel's field with its neighbouring
    /// floats (round-down's slow path), half-way points (nearest), and pseudo-random values.
    fn batch_values(l: &IrradianceLayout) -> Vec<f32> {
        let mut v = std::vec![
            f32::NAN,
            -f32::NAN,
            0.0,
            -0.0,
            -1.0,
            -1e-30,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MAX,
            1e30,
            1e-40,
            f32::MIN_POSITIVE,
            1e-7,
            l.codec().max_value(),
        ];
        for i in 0..3 {
            let f = l.channel(i);
            for q in (0..=f.max_code()).step_by(7) {
                let d = f.decode(q);
                for k in -2..=2_i32 {
                    v.push(f32::from_bits(d.to_bits().saturating_add_signed(k)));
                }
                v.push(f.codec().inverse((q as f32 + 0.5) / f.max_code() as f32));
            }
        }
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..2000 {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (s >> 40) as f32 / (1u64 << 24) as f32;
            v.push(10f32.powf(u * 6.0 - 4.5));
        }
        v
    }

    /// Colours mixing the values across channels and lanes (three different strides, so every
    /// lane of a batch vector meets boundary and bad values next to ordinary ones).
    fn batch_colours(l: &IrradianceLayout) -> Vec<Vec3> {
        let v = batch_values(l);
        let n = v.len();
        (0..n)
            .map(|j| Vec3::new(v[j], v[(j * 7 + 3) % n], v[(j * 13 + 5) % n]))
            .collect()
    }

    fn batch_layouts() -> [IrradianceLayout; 4] {
        [
            IrradianceLayout::ADGI,
            IrradianceLayout::EQUAL_10,
            IrradianceLayout::new(16, 8, 7, 1, LogCodec::SQUARED_DISTANCE).unwrap(),
            IrradianceLayout::new(11, 11, 9, 1, LogCodec::new(0.5, 0.01).unwrap()).unwrap(),
        ]
    }

    const BATCH_MODES: [Rounding; 6] = [
        Rounding::Down,
        Rounding::Nearest,
        Rounding::Stochastic(0.37),
        Rounding::Stochastic(0.0),
        Rounding::Stochastic(1.0),
        Rounding::Stochastic(f32::NAN),
    ];

    /// `encode_slice` / `decode_slice` give exactly what `encode` / `decode` give colour by
    /// colour: for every layout and rounding mode, on the whole stress set (thousands of
    /// colours, so every code boundary meets the 4-wide path) and on every length 0 ..= 9 at
    /// several offsets (the per-colour tail).
    #[test]
    fn batch_matches_per_colour() {
        for l in batch_layouts() {
            let colours = batch_colours(&l);
            for rounding in BATCH_MODES {
                let count = 5;
                let mut words = std::vec![IrradianceWord(0xdead_beef); colours.len()];
                l.encode_slice(&colours, count, rounding, &mut words);
                for (j, (&c, &w)) in colours.iter().zip(&words).enumerate() {
                    assert_eq!(w, l.encode(c, count, rounding), "{j}: {c} {rounding:?}");
                }
                let mut dec = std::vec![Vec3::NAN; colours.len()];
                l.decode_slice(&words, &mut dec);
                for (&w, d) in words.iter().zip(&dec) {
                    let want = l.decode(w);
                    for i in 0..3 {
                        assert_eq!(d[i].to_bits(), want[i].to_bits(), "{w:x?}");
                    }
                }
                for n in 0..=9 {
                    for off in [0, 1, 3, 17, 101] {
                        let c = &colours[off..off + n];
                        let mut w = std::vec![IrradianceWord(1); n];
                        l.encode_slice(c, 70, rounding, &mut w);
                        let want: Vec<_> = c.iter().map(|&c| l.encode(c, 70, rounding)).collect();
                        assert_eq!(w, want, "n = {n}, off = {off}, {rounding:?}");
                        let mut d = std::vec![Vec3::ONE; n];
                        l.decode_slice(&w, &mut d);
                        for (d, &w) in d.iter().zip(&w) {
                            let want = l.decode(w);
                            assert_eq!(
                                d.to_array().map(f32::to_bits),
                                want.to_array().map(f32::to_bits)
                            );
                        }
                    }
                }
            }
        }
    }

    /// `decode_slice` on arbitrary words (count bits set, every field value pattern) matches
    /// `decode`, finite and non-negative.
    #[test]
    fn batch_decode_of_any_word_matches_per_word() {
        let mut s: u32 = 1;
        let mut words: Vec<IrradianceWord> = (0..4098)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                IrradianceWord(s)
            })
            .collect();
        words.extend([0, u32::MAX, 0x3ff_ffff, 0xfc00_0000, 0x8000_0000].map(IrradianceWord));
        for l in batch_layouts() {
            let mut dec = std::vec![Vec3::NAN; words.len()];
            l.decode_slice(&words, &mut dec);
            for (&w, d) in words.iter().zip(&dec) {
                assert!(d.is_finite() && d.cmpge(Vec3::ZERO).all());
                let want = l.decode(w);
                assert_eq!(
                    d.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits)
                );
            }
        }
    }

    /// Layouts with tables: the constant-width ones (ADGI's, 10/10/10) and two with run-time
    /// tables.
    fn table_layouts() -> [IrradianceLayout; 4] {
        [
            IrradianceLayout::ADGI,
            IrradianceLayout::EQUAL_10,
            IrradianceLayout::new(8, 9, 9, 6, LogCodec::IRRADIANCE).unwrap(),
            IrradianceLayout::new(10, 9, 8, 5, LogCodec::IRRADIANCE).unwrap(),
        ]
    }

    /// Colours for checking a table path against the polynomial path: for every code of every
    /// channel its value and 3 f32 neighbours either side (in every channel, and mixed across
    /// channels), a dense log sweep and bad input.
    fn table_check_colours(l: &IrradianceLayout) -> Vec<Vec3> {
        let mut values = std::vec![
            f32::NAN,
            -1.0,
            -0.0,
            0.0,
            1e-40,
            f32::INFINITY,
            1e30,
            l.codec().max_value(),
        ];
        for i in 0..3 {
            let f = l.channel(i);
            for q in 0..=f.max_code() {
                let d = l.lanes.decode_word(q << l.shifts()[i])[i];
                for k in -3..=3_i32 {
                    values.push(f32::from_bits(d.to_bits().wrapping_add_signed(k)));
                }
            }
        }
        let mut v = 1e-6_f32;
        while v < 20.0 {
            values.push(v);
            v *= 1.000_37;
        }
        let n = values.len();
        (0..n)
            .flat_map(|j| {
                [
                    Vec3::splat(values[j]),
                    Vec3::new(values[j], values[(j * 7 + 3) % n], values[(j * 13 + 5) % n]),
                ]
            })
            .collect()
    }

    /// Words for checking a table decoder: every field value, with the other fields and the
    /// count bits varying.
    fn table_check_words(l: &IrradianceLayout) -> Vec<IrradianceWord> {
        (0..1 << 16)
            .map(|q: u32| IrradianceWord(q.wrapping_mul(0x9e37_79b9) ^ q))
            .chain((0..1 << 10).flat_map(|q: u32| l.shifts().map(|s| IrradianceWord(q << s))))
            .collect()
    }

    /// The table loops of `encode_slice` / `decode_slice` (constant tables and shifts for
    /// ADGI's and the 10/10/10 layout, the runtime tables for other widths) give the words and
    /// values of the polynomial path, which the GPU twin runs: for every code of every channel
    /// (its value and 3 f32 neighbours either side, in every channel), a dense log sweep and bad
    /// input; and `decode_slice` of every field value.
    #[test]
    fn table_slices_match_the_polynomial_path() {
        for l in table_layouts() {
            assert!(l.tables.is_some());
            let colours = table_check_colours(&l);
            let mut words = std::vec![IrradianceWord(0); colours.len()];
            l.encode_slice(&colours, 5, Rounding::Down, &mut words);
            let count = l.count.put(5.min(l.max_count()));
            for (&c, &w) in colours.iter().zip(&words) {
                let want = count | l.lanes.encode_word3([c.x, c.y, c.z, c.z], Rounding::Down);
                assert_eq!(w.0, want, "{:?} {c}", l.widths());
            }
            words = table_check_words(&l);
            let mut dec = std::vec![Vec3::NAN; words.len()];
            l.decode_slice(&words, &mut dec);
            for (&w, d) in words.iter().zip(&dec) {
                let [r, g, b, _] = l.lanes.decode_word(w.0);
                assert_eq!(
                    d.to_array().map(f32::to_bits),
                    [r, g, b].map(f32::to_bits),
                    "{:?} {w:x?}",
                    l.widths()
                );
            }
        }
    }

    /// The per-colour `encode` (round down) and `decode` of layouts with tables (the
    /// constant-width code for ADGI's and the 10/10/10 layout, the out-of-line run-time tables
    /// for other widths), with the layout a constant and a run-time value, give the words and
    /// values of the polynomial path (the GPU twin's) on the colours and words of
    /// `table_slices_match_the_polynomial_path`; other rounding modes keep the polynomial path.
    #[test]
    fn per_colour_tables_match_the_polynomial_path() {
        for layout in table_layouts() {
            let fixed = match layout.widths() {
                [9, 9, 8, _] => FixedWidths::R9G9B8,
                [10, 10, 10, _] => FixedWidths::R10G10B10,
                _ => FixedWidths::None,
            };
            assert_eq!(layout.fixed, fixed, "{:?}", layout.widths());
            for l in [layout, core::hint::black_box(layout)] {
                let count = l.count.put(7.min(l.max_count()));
                for c in table_check_colours(&l) {
                    let want = count | l.lanes.encode_word3([c.x, c.y, c.z, c.z], Rounding::Down);
                    assert_eq!(
                        l.encode(c, 7, Rounding::Down).0,
                        want,
                        "{:?} {c}",
                        l.widths()
                    );
                    let rgb = [c.x, c.y, c.z, c.z];
                    for rounding in [Rounding::Nearest, Rounding::Stochastic(0.3)] {
                        let want = count | l.lanes.encode_word3(rgb, rounding);
                        assert_eq!(l.encode(c, 7, rounding).0, want, "{c} {rounding:?}");
                    }
                }
                for w in table_check_words(&l) {
                    let [r, g, b, _] = l.lanes.decode_word(w.0);
                    assert_eq!(
                        l.decode(w).to_array().map(f32::to_bits),
                        [r, g, b].map(f32::to_bits),
                        "{:?} {w:x?}",
                        l.widths()
                    );
                }
            }
        }
    }

    #[test]
    #[should_panic(expected = "differ in length")]
    fn batch_lengths_must_match() {
        let mut w = [IrradianceWord(0); 3];
        IrradianceLayout::ADGI.encode_slice(&[Vec3::ONE; 4], 0, Rounding::Down, &mut w);
    }

    /// A digest of many encodings and decodings, pinned: the same in the `std` and the `libm`
    /// build (`scripts/test` runs this crate's unit tests in both) and on every target, as the
    /// hot path uses neither `std` nor `libm` floats and no FMA.
    #[test]
    fn encodings_digest_is_pinned() {
        let l = IrradianceLayout::ADGI;
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u32| {
            h ^= x as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        };
        let mut x = 1e-6_f32;
        let mut k = 0_u32;
        while x < 12.0 {
            let rgb = Vec3::new(x, 1.7 * x % 10.0, 0.123 / x);
            for rounding in [
                Rounding::Down,
                Rounding::Nearest,
                Rounding::Stochastic(0.61),
            ] {
                let w = l.encode(rgb, k, rounding);
                eat(w.0);
                let d = l.decode(w);
                eat(d.x.to_bits() ^ d.y.to_bits().rotate_left(11) ^ d.z.to_bits().rotate_left(22));
            }
            x *= 1.000_9;
            k += 1;
        }
        assert_eq!(h, 0xbe41_c6b6_dbed_8127, "{h:#x}");
    }
}
