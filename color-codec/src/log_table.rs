//! Table forms of the log codec for ADGI's parameters: decoding by one load, rounding down by
//! one index load, one load and a compare. Bit for bit the results of the polynomial path
//! ([`LogLanes`](crate::log_codec::LogLanes)), so the GPU twin, which keeps the polynomials,
//! still agrees on every code.
//!
//! - **Decode.** `decode[q]` is the polynomial decoder's value of code q, computed at compile
//!   time by the same f32 operations in the same order (Rust's const evaluation rounds every
//!   operation as IEEE-754 binary32, as the run-time SSE2/NEON code does, and never contracts
//!   into an FMA). A test compares every entry with the run-time decoder.
//! - **Round down.** [`Rounding::Down`](crate::Rounding::Down) returns q*, the largest code
//!   whose decoded value is ≤ v (the `LogField` docs, "Rounding down exactly"), i.e. a search
//!   in the increasing `decode` table. An index over the bits of y = γv + 1 (its exponent and
//!   top `k` mantissa bits: a piecewise-linear log₂) gives a code `lo ≤ q*`, and q* is `lo`
//!   plus 1 if `decode[lo + 1]` ≤ v. Why `lo ≤ q*`: `index[b]`
//!   is the largest code q whose y(`decode[q]`) falls in a bucket below b; y(·) is monotone
//!   (a rounded product by γ > 0 and a rounded sum), so a v in bucket b has y(v) > y(`decode[q]`)
//!   and hence v > `decode[q]`. Why one step suffices: every code q* can reach has its
//!   y(`decode[q]`) in bucket b or below, and `k = bits − 2` makes a bucket ≈ 0.8 codes wide, so
//!   at most one code falls past `lo` (checked for every bucket by a test).
//!
//! Tables exist for (β, γ) = (5, 15) at 8, 9 and 10 bits: ADGI's irradiance and distance
//! codecs in the R9G9B8 and 10/10/10 layouts; every other field keeps the polynomial path.

use core::fmt;

use crate::log_codec::{LogCodec, LogField};
use crate::math::fast_exp2;

/// The decode and round-down tables of one field.
#[derive(Clone, Copy, PartialEq)]
pub(crate) struct LogTable {
    /// `decode[q]` for q ∈ 0 ..= M, then +∞ (the round-down step reads `lo + 1 ≤ M + 1`).
    /// Every table has the same power-of-two length, so a masked index needs no bounds check.
    decode: &'static [f32; DECODE_LEN],
    /// `index[b]`: the largest code whose y = γ·decode + 1 lies in a bucket below b (0 if
    /// none); buckets past the top code's hold M.
    index: &'static [u16; INDEX_LEN],
    /// `next[b] = decode[index[b] + 1]`: the value the round-down step compares with, read by
    /// the same index as `index[b]` (two independent loads instead of two dependent ones).
    next: &'static [f32; INDEX_LEN],
    gamma: f32,
    /// `decode[M]`: inputs are clamped to it.
    top: f32,
    /// 23 − k: a bucket is `(bits(y) − bits(1)) >> shift`.
    shift: u32,
    max_code: u32,
}

impl fmt::Debug for LogTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("LogTable")
            .field("codes", &(self.max_code + 1))
            .field("bits", &self.max_code.count_ones())
            .finish()
    }
}

/// Octaves of y = γv + 1 the index covers: y ∈ [1, 2⁸) ⊇ [1, e⁵].
const OCTAVES: usize = 8;
/// Widest field with a table.
const MAX_BITS: u32 = 10;
/// Length of every decode table: M + 2 ≤ 2¹⁰ + 1 entries used, rounded up to a power of two.
const DECODE_LEN: usize = 2 << MAX_BITS;
/// Length of every index: `OCTAVES · 2^k` buckets with k = bits − 2 ≤ 8.
const INDEX_LEN: usize = OCTAVES << (MAX_BITS - 2);

/// The polynomial decoder's value of code `q` (the operations of `LogLanes::decode_word`).
const fn decode_value(f: &LogField, q: u32) -> f32 {
    let d = (fast_exp2(q as f32 * f.decode_scale()) - 1.0) * f.inv_gamma();
    if d > 0.0 { d } else { 0.0 }
}

/// `decode[q]` for q ∈ 0 ..= M, then +∞.
const fn decode_table(bits: u32) -> [f32; DECODE_LEN] {
    let f = LogCodec::IRRADIANCE.raw_field(bits);
    let mut t = [f32::INFINITY; DECODE_LEN];
    let mut q = 0;
    while q <= f.max_code() as usize {
        t[q] = decode_value(&f, q as u32);
        q += 1;
    }
    t
}

/// The bucket of y = γv + 1 for v ≥ 0: exponent and top 23 − `shift` mantissa bits of y.
#[inline(always)]
const fn bucket(gamma: f32, v: f32, shift: u32) -> usize {
    let y = gamma * v + 1.0;
    ((y.to_bits() - 1.0_f32.to_bits()) >> shift) as usize
}

/// `index[b]` = the largest q with `bucket(decode[q]) < b`, 0 if none, for the
/// `OCTAVES · 2^k` buckets of a `bits`-bit field (M past them). `decode` increases, so the
/// buckets of the codes do not decrease: one sweep.
const fn index_table(decode: &[f32; DECODE_LEN], bits: u32) -> [u16; INDEX_LEN] {
    let shift = 23 - (bits - 2);
    let buckets = OCTAVES << (bits - 2);
    let gamma = LogCodec::IRRADIANCE.gamma();
    let max_code = (1 << bits) - 1;
    assert!(bucket(gamma, decode[max_code], shift) < buckets);
    let mut t = [max_code as u16; INDEX_LEN];
    // `below`: how many codes lie in buckets below b.
    let mut below = 0;
    let mut b = 0;
    while b < buckets {
        while below <= max_code && bucket(gamma, decode[below], shift) < b {
            below += 1;
        }
        t[b] = if below == 0 { 0 } else { (below - 1) as u16 };
        b += 1;
    }
    t
}

/// `next[b] = decode[index[b] + 1]` for every bucket b.
const fn next_table(decode: &[f32; DECODE_LEN], index: &[u16; INDEX_LEN]) -> [f32; INDEX_LEN] {
    let mut t = [0.0; INDEX_LEN];
    let mut b = 0;
    while b < INDEX_LEN {
        t[b] = decode[index[b] as usize + 1];
        b += 1;
    }
    t
}

const DECODE_8: [f32; DECODE_LEN] = decode_table(8);
const DECODE_9: [f32; DECODE_LEN] = decode_table(9);
const DECODE_10: [f32; DECODE_LEN] = decode_table(10);
static DECODE_8_S: [f32; DECODE_LEN] = DECODE_8;
static DECODE_9_S: [f32; DECODE_LEN] = DECODE_9;
static DECODE_10_S: [f32; DECODE_LEN] = DECODE_10;
const INDEX_8: [u16; INDEX_LEN] = index_table(&DECODE_8, 8);
const INDEX_9: [u16; INDEX_LEN] = index_table(&DECODE_9, 9);
const INDEX_10: [u16; INDEX_LEN] = index_table(&DECODE_10, 10);
static INDEX_8_S: [u16; INDEX_LEN] = INDEX_8;
static INDEX_9_S: [u16; INDEX_LEN] = INDEX_9;
static INDEX_10_S: [u16; INDEX_LEN] = INDEX_10;
static NEXT_8: [f32; INDEX_LEN] = next_table(&DECODE_8, &INDEX_8);
static NEXT_9: [f32; INDEX_LEN] = next_table(&DECODE_9, &INDEX_9);
static NEXT_10: [f32; INDEX_LEN] = next_table(&DECODE_10, &INDEX_10);

const fn table(
    decode: &'static [f32; DECODE_LEN],
    index: &'static [u16; INDEX_LEN],
    next: &'static [f32; INDEX_LEN],
    bits: u32,
) -> LogTable {
    let max_code = (1_u32 << bits) - 1;
    LogTable {
        decode,
        index,
        next,
        gamma: LogCodec::IRRADIANCE.gamma(),
        top: decode[max_code as usize],
        shift: 23 - (bits - 2),
        max_code,
    }
}

static TABLE_8: LogTable = FieldTable::<8>::TABLE;
static TABLE_9: LogTable = FieldTable::<9>::TABLE;
static TABLE_10: LogTable = FieldTable::<10>::TABLE;

/// The table of ADGI's codec at `BITS` bits (8, 9 or 10) as a constant, for loops whose
/// layout is fixed at compile time: its γ, clamp, shift and mask become immediates.
pub(crate) struct FieldTable<const BITS: u32>;

impl<const BITS: u32> FieldTable<BITS> {
    /// [`LogTable::find`]`(LogCodec::IRRADIANCE, BITS)`, by value.
    pub(crate) const TABLE: LogTable = match BITS {
        8 => table(&DECODE_8_S, &INDEX_8_S, &NEXT_8, 8),
        9 => table(&DECODE_9_S, &INDEX_9_S, &NEXT_9, 9),
        10 => table(&DECODE_10_S, &INDEX_10_S, &NEXT_10, 10),
        _ => panic!("no table at this width"),
    };
}

impl LogTable {
    /// The tables of `codec` quantised to `bits`, if there are any: (β, γ) = (5, 15) at 8, 9
    /// or 10 bits.
    pub(crate) const fn find(codec: LogCodec, bits: u32) -> Option<&'static LogTable> {
        if !(codec.beta() == 5.0 && codec.gamma() == 15.0) {
            return None;
        }
        match bits {
            8 => Some(&TABLE_8),
            9 => Some(&TABLE_9),
            10 => Some(&TABLE_10),
            _ => None,
        }
    }

    /// The value of `code` (masked to the field's bits): `LogField::decode`, bit for bit.
    #[inline(always)]
    pub(crate) fn decode(&self, code: u32) -> f32 {
        self.decode[(code & self.max_code) as usize % DECODE_LEN]
    }

    /// The largest code whose value is ≤ v: `LogField::encode(v, Rounding::Down)`, bit for
    /// bit (NaN and negative v give 0, v above the top value gives M).
    #[inline(always)]
    pub(crate) fn encode_down(&self, v: f32) -> u32 {
        let v = if v > 0.0 { v } else { 0.0 };
        let v = if v < self.top { v } else { self.top };
        // b < the field's bucket count ≤ INDEX_LEN (v ≤ top, asserted when the index is
        // built), so the mask only spares the bounds check.
        let b = bucket(self.gamma, v, self.shift) % INDEX_LEN;
        u32::from(self.index[b]) + u32::from(self.next[b] <= v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rounding;
    use crate::log_codec::LogLanes;

    fn tables() -> [(u32, &'static LogTable); 3] {
        [8, 9, 10].map(|bits| (bits, LogTable::find(LogCodec::IRRADIANCE, bits).unwrap()))
    }

    /// The polynomial path of a field, without its table.
    fn lanes(bits: u32) -> LogLanes {
        let f = LogCodec::IRRADIANCE.raw_field(bits);
        LogLanes::new([f; 4], [0; 4], [0; 4], [true; 4])
    }

    #[test]
    fn only_adgi_parameters_have_tables() {
        assert!(LogTable::find(LogCodec::IRRADIANCE, 11).is_none());
        assert!(LogTable::find(LogCodec::SQUARED_DISTANCE, 9).is_none());
        assert!(LogTable::find(LogCodec::new(5.0, 14.0).unwrap(), 9).is_none());
    }

    #[test]
    fn field_tables_are_the_found_tables() {
        let fixed = [
            FieldTable::<8>::TABLE,
            FieldTable::<9>::TABLE,
            FieldTable::<10>::TABLE,
        ];
        for ((bits, t), f) in tables().into_iter().zip(fixed) {
            assert_eq!(f, *t, "{bits} bits");
        }
    }

    #[test]
    fn next_is_the_value_after_index() {
        for (bits, t) in tables() {
            for (b, (&lo, &next)) in t.index.iter().zip(t.next).enumerate() {
                assert_eq!(
                    next.to_bits(),
                    t.decode[lo as usize + 1].to_bits(),
                    "{bits} {b}"
                );
            }
        }
    }

    #[test]
    fn decode_table_is_the_polynomial_decoder() {
        for (bits, t) in tables() {
            let l = lanes(bits);
            for code in 0..=t.max_code + 5 {
                let want = l.decode_word(code & t.max_code)[0];
                assert_eq!(
                    t.decode(code).to_bits(),
                    want.to_bits(),
                    "{bits} bits {code}"
                );
            }
            assert!(
                t.decode[..=t.max_code as usize]
                    .windows(2)
                    .all(|w| w[0] < w[1])
            );
        }
    }

    #[test]
    fn one_step_covers_every_bucket() {
        // Codes per bucket: the round-down search steps at most once past index[b].
        for (bits, t) in tables() {
            let mut per_bucket = std::vec![0_u32; t.index.len()];
            for &d in &t.decode[..=t.max_code as usize] {
                per_bucket[bucket(t.gamma, d, t.shift)] += 1;
            }
            for (b, &n) in per_bucket.iter().enumerate() {
                let below = t.index[b];
                // Every code of this bucket is above index[b] (except code 0 in bucket 0).
                assert!(n <= 1, "{bits} bits bucket {b}: {n} codes");
                let first_above = (0..=t.max_code)
                    .filter(|&q| bucket(t.gamma, t.decode(q), t.shift) >= b)
                    .min();
                if let Some(q) = first_above {
                    assert_eq!(
                        u32::from(below),
                        q.saturating_sub(1),
                        "{bits} bits bucket {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn round_down_is_the_polynomial_encoder() {
        // Every code's value and its f32 neighbours (the boundaries), a dense log sweep and
        // bad input: the table search against the polynomial encoder (which the GPU twin runs).
        for (bits, t) in tables() {
            let l = lanes(bits);
            let mut inputs = std::vec![0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, 1e30, 9.9, 1e-30];
            for q in 0..=t.max_code {
                let d = t.decode(q);
                for k in -3_i32..=3 {
                    inputs.push(f32::from_bits(d.to_bits().wrapping_add_signed(k)));
                }
            }
            let mut v = 1e-6_f32;
            while v < 20.0 {
                inputs.push(v);
                v *= 1.000_37;
            }
            for v in inputs {
                let want = l.encode([v; 4], Rounding::Down)[0];
                assert_eq!(t.encode_down(v), want, "{bits} bits v = {v:e}");
            }
        }
    }
}
