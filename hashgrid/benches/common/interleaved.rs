//! A prototype of the layout `HashTable` does not have (issue 21, "the checksum beside the
//! value"), for measuring what it would give before the GPU buffers change: each slot is its
//! checksum word followed by the 32-byte [`State`], in one flat `u32` array of `STRIDE`-word
//! slots. Same hash, checksum, home slot and bounded linear probing as `HashTable` with its
//! defaults (`fold_and_checksum`, power-of-two capacity, 16 probes), and the same lookup: the
//! home slot inline (the slots cut to the capacity, so without a bounds check), the walk out of
//! line. No ages, no tombstones.
//!
//! - `STRIDE` 9 (36 bytes, packed): the smallest slot; with 64-byte lines, slots start at 16
//!   different offsets and 8 of them straddle two lines (a caller that reads the whole state
//!   then touches two lines; the benches' passes read its first word, in the checksum's line
//!   for 15 of the 16 offsets);
//! - `STRIDE` 16 (64 bytes, slots aligned to the line): one line per slot, 1.8× the memory of
//!   the table's two arrays (36 bytes per slot).

#![allow(dead_code)]

use mcg_hashgrid::{CellKey, fold_and_checksum};

use super::lookups::State;

/// The prototype table: slot `s` is `words[offset + STRIDE·s ..][..STRIDE]`, its checksum
/// first, then the state's bits.
pub struct Interleaved<const STRIDE: usize> {
    words: Vec<u32>,
    offset: usize,
    mask: u32,
    max_probes: u32,
}

impl<const STRIDE: usize> Interleaved<STRIDE> {
    /// An empty table of `capacity` (a power of two) slots. With `STRIDE` 16 the first slot
    /// starts on a 64-byte boundary.
    pub fn new(capacity: u32, max_probes: u32) -> Self {
        assert!(capacity.is_power_of_two() && STRIDE > State::default().len());
        let words = vec![0_u32; STRIDE * capacity as usize + 16];
        let misalignment = (words.as_ptr() as usize % 64) / 4;
        let offset = if STRIDE == 16 {
            (16 - misalignment) % 16
        } else {
            0
        };
        Self {
            words,
            offset,
            mask: capacity - 1,
            max_probes,
        }
    }

    /// The words of the slots (for flushing).
    pub fn words(&self) -> &[u32] {
        &self.words
    }

    /// The slots, cut to the capacity (`mask + 1`).
    #[inline(always)]
    fn slots(&self) -> &[[u32; STRIDE]] {
        let (slots, _) = self.words[self.offset..].as_chunks::<STRIDE>();
        &slots[..=self.mask as usize]
    }

    /// Inserts `key` with `value` (or overwrites its value); `false` when its probe window is
    /// full.
    pub fn insert(&mut self, key: &CellKey, value: &State) -> bool {
        let (h, c) = fold_and_checksum(key);
        let (mask, offset) = (self.mask, self.offset);
        let (slots, _) = self.words[offset..].as_chunks_mut::<STRIDE>();
        for i in 0..self.max_probes {
            let slot = &mut slots[(h.wrapping_add(i) & mask) as usize];
            if slot[0] == c || slot[0] == 0 {
                slot[0] = c;
                for (d, s) in slot[1..].iter_mut().zip(value) {
                    *d = s.to_bits();
                }
                return true;
            }
        }
        false
    }

    /// The first word of the state of `key`, if the table holds it.
    #[inline(always)]
    pub fn get_first(&self, key: &CellKey) -> Option<f32> {
        let (h, c) = fold_and_checksum(key);
        let slot = &self.slots()[(h & self.mask) as usize];
        if slot[0] == c {
            Some(f32::from_bits(slot[1]))
        } else if slot[0] == 0 {
            None
        } else {
            self.walk(h, c)
        }
    }

    /// The walk of `get_first` past a home slot that holds another key.
    #[inline(never)]
    fn walk(&self, h: u32, c: u32) -> Option<f32> {
        let slots = self.slots();
        for i in 1..self.max_probes {
            let slot = &slots[(h.wrapping_add(i) & self.mask) as usize];
            if slot[0] == c {
                return Some(f32::from_bits(slot[1]));
            }
            if slot[0] == 0 {
                return None;
            }
        }
        None
    }
}

/// `Interleaved::get_first` per key, summed (the `get_pass` of the prototype).
#[inline(never)]
pub fn interleaved_pass<const STRIDE: usize>(
    table: &Interleaved<STRIDE>,
    queries: &[CellKey],
) -> f32 {
    std::hint::black_box(queries)
        .iter()
        .map(|k| table.get_first(k).unwrap_or(0.0))
        .sum()
}
