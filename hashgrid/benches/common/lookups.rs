//! The three lookup passes that the criterion bench (`benches/hashgrid.rs`) and the min-of-runs
//! probe (`examples/speed.rs`) time, written once. Each pass looks up every query and reads
//! one value word per hit (0 for a miss), so both sides of a comparison touch their values.

#![allow(dead_code)]

use std::collections::HashMap;
use std::hint::black_box;

use mcg_hashgrid::{CellKey, HashTable};

/// A 32-byte guiding state, as MCPG's (ours is ≤ 32 bytes plus the 4-byte checksum).
pub type State = [f32; 8];

/// std's `HashMap::get` per packed key: the baseline.
#[inline]
pub fn hashmap_pass(map: &HashMap<u64, State>, packed: &[u64]) -> f32 {
    black_box(packed)
        .iter()
        .map(|k| map.get(k).map_or(0.0, |s| s[0]))
        .sum()
}

/// `HashTable::get` per key.
#[inline]
pub fn get_pass(table: &HashTable<State>, queries: &[CellKey]) -> f32 {
    black_box(queries)
        .iter()
        .map(|k| table.get(k).map_or(0.0, |s| s[0]))
        .sum()
}

/// `HashTable::find` per key without the value read: one cache line per lookup, what a
/// layout with the checksum inside the value's line would approach (a diagnostic, not a peer).
#[inline]
pub fn find_pass(table: &HashTable<State>, queries: &[CellKey]) -> f32 {
    black_box(queries)
        .iter()
        .map(|k| table.find(k).map_or(0.0, |s| s as f32))
        .sum()
}

/// `HashTable::find_many` over all queries into `slots`, then the value reads.
#[inline]
pub fn find_many_pass(
    table: &HashTable<State>,
    queries: &[CellKey],
    slots: &mut [Option<u32>],
) -> f32 {
    table.find_many(black_box(queries), slots);
    slots
        .iter()
        .map(|s| s.map_or(0.0, |s| table.values()[s as usize][0]))
        .sum()
}
