//! The lookup and insert passes that the criterion benches (`benches/hashgrid.rs`, `benches/peers.rs`) and
//! the min-of-runs probes (`examples/speed.rs`, `examples/instructions.rs`) time, written once.
//! Each pass looks up every query and reads one value word per hit (0 for a miss), so both
//! sides of a comparison touch their values; each insert pass inserts every key (or finds it)
//! and adds 1 to the first word of its value.
//!
//! Every pass is `#[inline(never)]`: compiled on its own, each loop gets the registers it
//! needs. Inlined into a large caller (the `instructions` example's `main`), the table's `get`
//! loop had kept its running sum in a stack slot (a store and a reload per lookup on the
//! sum's dependency chain) where hashbrown's loop, inlined into the same `main`, kept it in a
//! register: a harness artefact of ≈ 1 ns per lookup at 2¹⁶ slots, not a property of either
//! map.

#![allow(dead_code)]

use std::collections::HashMap;
use std::hash::BuildHasher;
use std::hint::black_box;

use mcg_hashgrid::{CellKey, HashTable};

/// A 32-byte guiding state, as MCPG's (ours is ≤ 32 bytes plus the 4-byte checksum).
pub type State = [f32; 8];

/// `get` per packed key of std's `HashMap` with any hasher (SipHash: the baseline; Fx: a
/// peer).
#[inline(never)]
pub fn hashmap_pass<S: BuildHasher>(map: &HashMap<u64, State, S>, packed: &[u64]) -> f32 {
    black_box(packed)
        .iter()
        .map(|k| map.get(k).map_or(0.0, |s| s[0]))
        .sum()
}

/// hashbrown's `get` (foldhash) per packed key: the peer of the lookup targets.
#[inline(never)]
pub fn hashbrown_pass(map: &hashbrown::HashMap<u64, State>, packed: &[u64]) -> f32 {
    black_box(packed)
        .iter()
        .map(|k| map.get(k).map_or(0.0, |s| s[0]))
        .sum()
}

/// `HashTable::get` per key.
#[inline(never)]
pub fn get_pass(table: &HashTable<State>, queries: &[CellKey]) -> f32 {
    black_box(queries)
        .iter()
        .map(|k| table.get(k).map_or(0.0, |s| s[0]))
        .sum()
}

/// `HashTable::find` per key without the value read: one cache line per lookup, what a
/// layout with the checksum inside the value's line would approach (a diagnostic, not a peer).
#[inline(never)]
pub fn find_pass(table: &HashTable<State>, queries: &[CellKey]) -> f32 {
    black_box(queries)
        .iter()
        .map(|k| table.find(k).map_or(0.0, |s| s as f32))
        .sum()
}

/// `HashTable::find_many` over all queries into `slots`, then the value reads.
#[inline(never)]
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

/// `HashTable::get_many` over all queries, summing the values' first words as they come.
#[inline(never)]
pub fn get_many_pass(table: &HashTable<State>, queries: &[CellKey]) -> f32 {
    let mut sum = 0.0;
    table.get_many(black_box(queries), |_, v| sum += v.map_or(0.0, |s| s[0]));
    sum
}

/// `HashTable::entry` per key, adding 1 to the value's first word.
#[inline(never)]
pub fn insert_pass(table: &mut HashTable<State>, keys: &[CellKey]) {
    for k in black_box(keys) {
        if let Some((v, _)) = table.entry(k) {
            v[0] += 1.0;
        }
    }
}

/// hashbrown's `entry().or_insert` per packed key, adding 1 to the value's first word.
#[inline(never)]
pub fn hashbrown_insert_pass(map: &mut hashbrown::HashMap<u64, State>, packed: &[u64]) {
    for &k in black_box(packed) {
        map.entry(k).or_insert([0.0; 8])[0] += 1.0;
    }
}

/// std's `HashMap::entry().or_insert` per packed key (any hasher), adding 1 to the value's
/// first word.
#[inline(never)]
pub fn hashmap_insert_pass<S: BuildHasher>(map: &mut HashMap<u64, State, S>, packed: &[u64]) {
    for &k in black_box(packed) {
        map.entry(k).or_insert([0.0; 8])[0] += 1.0;
    }
}
