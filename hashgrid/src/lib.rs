//! # mcg-hashgrid: world-space hashed grids for guiding states and caches
//!
//! MCPG (Alber et al. 2025, sec. 4 "Hash Grid", Algorithm 1) keeps its Markov chain states and
//! its irradiance cache in world-space hash grids: an adaptive multi-resolution grid whose
//! level follows the camera distance, a coarse static grid, stochastic trilinear access to
//! grid vertices, the surface normal folded into the key, and a checksum that detects
//! collisions. Renderer authors use the same structure for radiance caches. This crate gives
//! the pieces, with the CPU tables laid out as the GPU buffers and the hashes bit for bit
//! those of the WGSL twin.
//!
//! | item | what it is | paper |
//! |---|---|---|
//! | [`CellKey`], [`normal_class`] | vertex key `[x, y, z, level·class·extra]`, cube-map class of the normal | MCPG sec. 4 "Hash Grid" |
//! | [`BucketHash`], [`hash_fold`], [`hash_xor_primes`], [`hash_mix`], [`hash_mix_coherent`] | bucket hash: two folds and a finisher (default), xor of primes (Instant-NGP), pcg4d mixing, or mixing that keeps runs of 4 along x together | MCPG sec. 4, `hash(x) = ⊕ πᵢxᵢ mod B` |
//! | [`fold_and_checksum`], [`pcg4d`], [`mix_and_checksum`] | bucket hash and checksum in one pass; the 4-word permutation behind the mixing hash | Jarzynski & Olano 2020, "pcg4d" |
//! | [`checksum`] | separate full 32-bit hash stored in the slot, 0 = empty | MCPG sec. 4, Table 1 "hash" |
//! | [`AdaptiveGrid`], [`LevelParams`], [`geometric_jitter`] | level from camera distance, jitter to coarser levels | MCPG sec. 4, Step 1 |
//! | [`StaticGrid`] | fixed cell width, no normal | MCPG sec. 4 "static grid" |
//! | [`stochastic_trilinear`], [`jittered_vertex`] | vertex with probability = trilinear weight | MCPG sec. 4 |
//! | [`SlotIndexer`] | `h mod B` for any capacity, a mask for powers of two | MCPG sec. 4 |
//! | [`HashTable`] | fixed-capacity table, checksum array + `Pod` value array, bounded wrapping probing, ages | MCPG sec. 4, Alg. 1 `grid.load` |
//! | [`ConcurrentTable`] | lock-free insert by compare-and-swap on the checksum | MCPG sec. 4 "Synchronization" |
//! | [`ConcurrentSlots`] | the same table with each slot's checksum, age and value in one cache line | MCPG sec. 4 "Synchronization" |
//! | [`constants`] | every prime, seed and default, as tables for the WGSL prelude | — |
//!
//! ## Conventions
//! - Positions are world-space [`glam::Vec3`] in scene units; a grid vertex of width `w` at
//!   integer coordinate `c` sits at `c · w`. Normals need not be normalised.
//! - No hidden randomness: level jitter and vertex choice take uniforms in [0, 1) from the
//!   caller. Out-of-range or NaN uniforms are clamped into [0, 1), never propagated.
//! - Hashes are wrapping `u32` arithmetic only, so the WGSL twin reproduces them exactly.
//!   Checksums are never 0 ([`constants::EMPTY`]) or 1 ([`constants::TOMBSTONE`]).
//! - Constructors validate and return `Result`; table operations never loop without bound
//!   (a key not found within `max_probes` slots is [`Insert::Full`]).
//! - [`CellKey`] is `#[repr(C)]` + [`bytemuck::Pod`] (16 bytes); tables store plain `u32`
//!   checksums and `Pod` values that upload as they are.
//!
//! ## Design choices
//! - [`BucketHash::Fold`] is the default bucket hash: it passes the chi-square occupancy tests
//!   on a renderer's multi-level key stream in a third of [`BucketHash::Mix`]'s instructions;
//!   MCPG's xor of primes is cheaper but over-dispersed there.
//! - Any capacity works (`h mod B` by [`SlotIndexer`], a mask for powers of two).
//! - Probing is linear and bounded by `max_probes` ([`Insert::Full`] beyond): size tables for
//!   a load ≲ 0.25 or raise the limit.
//! - [`ConcurrentTable`] claims slots by compare-and-swap on the checksum word; the caller owns
//!   the values. [`ConcurrentSlots`] does the same with the values inside the table, a slot's
//!   checksum, age and value in one cache line: one line per lookup instead of three.
//! - The crate's five `unsafe` blocks: its `&[AtomicU32]` → `&[u32]` upload view, three SSE2
//!   compare intrinsics in the probe loop, the prefetch (`_mm_prefetch`, a hint) of
//!   [`HashTable::find_many`], [`HashTable::get_many`], [`ConcurrentTable::locate`],
//!   [`ConcurrentSlots::locate`] and [`prefetch_line`], the batched lookups' SSE2 hash of four
//!   keys at once (register arithmetic, no pointers), and the call of their AVX2 hash of eight
//!   keys at once, only after `is_x86_feature_detected!("avx2")` (with the `std` feature).
//!
//! The measurements behind these choices, the peer benchmarks (hashbrown, `FxHashMap`,
//! `DashMap`, std's `HashMap`) and how to run them are in `benches/README.md`.
//!
//! ## Performance
//! Against hashbrown (foldhash) holding the same keys: peer ÷ mcg (> 1: mcg faster), baseline
//! x86-64, 2-vCPU VMs, 2¹⁶ / 2¹⁹ slots at the table's load of 1/4, fastest of repeated passes:
//!
//! | operation | warm caches | caches flushed |
//! |---|---|---|
//! | [`HashTable::get`] (33 instructions, hashbrown 33) | 0.80–0.81 / 0.66–0.70 | 0.75–0.83 (AMD EPYC), 0.92–0.99 (Intel Ice Lake); 1.08–1.39 from 2²⁰ slots |
//! | [`HashTable::find_many`] + value reads | 1.08–1.10 / 1.02–1.07 (AVX2; SSE2 0.87–0.96) | 1.31–1.41 |
//! | [`HashTable::get_many`] | 1.01–1.03 / 0.73–0.78 | 1.25–1.56 |
//! | insert | 0.87–1.06 / 0.71–0.75 | — |
//! | [`ConcurrentTable`], inserts from 2 threads, ÷ `DashMap` | 3.4–5.4× at 2¹⁹, 3.9–10.1× at 2²² | — |
//!
//! What is left of the warm gap is the 4-word key's hash (20 of `get`'s 33 instructions; no
//! cheaper finisher passes the occupancy suite); of the cold gap below 2²⁰ slots, the memory
//! per key that load 1/4 costs (hashbrown held at load 1/4 is the slower, 1.01–1.20). Run
//! `cargo bench -p mcg-hashgrid --bench peers`, `scripts/hashgrid-instructions` or
//! `cargo run --release -p mcg-hashgrid --example instructions -- CASE BITS PASSES time`
//! (`cold` instead of `time` flushes the caches first); numbers and diary: `benches/README.md`.
//!
//! ## Features
//! - `std` (default): float functions from the standard library; implies `alloc`. On x86-64
//!   it also lets [`HashTable::find_many`] and [`HashTable::get_many`] hash eight keys at
//!   once with AVX2 where the CPU has it (detected at run time; same results).
//! - `alloc`: the tables ([`HashTable`], [`ConcurrentTable`], [`ConcurrentSlots`]). Without it the crate is keys,
//!   hashes, levels and vertex choice only.
//! - `libm`: float functions from `libm` for `#![no_std]` builds
//!   (`default-features = false, features = ["libm"]`, add `"alloc"` for the tables).
//!
//! ## Example
//! ```
//! use mcg_hashgrid::{AdaptiveGrid, BucketHash, HashTable, Insert, glam::Vec3};
//!
//! // MCPG's adaptive grid: level from the camera distance, corner by stochastic trilinear.
//! let grid = AdaptiveGrid::mcpg();
//! let (hit, normal, camera) = (Vec3::new(3.0, 0.5, -2.0), Vec3::Y, Vec3::new(0.0, 2.0, 8.0));
//! let key = grid.vertex_key(hit, normal, camera, 0.3, 0.7);
//! assert_eq!(key.class, 2); // +y
//!
//! // A table of 10⁶ slots of 32-byte states, probing at most 8 slots.
//! let mut table = HashTable::<[f32; 8]>::new(1_000_003, 8, BucketHash::Fold)?;
//! let (state, fresh) = table.entry(&key).expect("table is not full");
//! assert!(fresh);
//! state[0] += 1.0;
//! assert_eq!(table.get(&key).unwrap()[0], 1.0);
//! assert!(matches!(table.insert_or_get(&key), Insert::Found(_)));
//! # Ok::<(), mcg_hashgrid::TableError>(())
//! ```
#![no_std]
// Five `unsafe` blocks: `ConcurrentTable::checksums` views `&[AtomicU32]` as `&[u32]` for upload
// (documented there), `probe::group_masks` calls SSE2 compare intrinsics (no pointers),
// `probe::prefetch` calls `_mm_prefetch` (a hint that never faults, whatever the address; the
// public `prefetch_line` passes it a reference's address),
// `probe::fold4_sse2` calls SSE2 arithmetic and shuffle intrinsics (the `Fold` hash of four keys
// in the lanes of registers; no pointers, the keys come in and the results go out by
// `bytemuck::cast`), and `<probe::Fold as LaneHash>::chunk` calls the safe
// `#[target_feature(enable = "avx2")]` function `probe::fold16_avx2` (the same hash of eight
// keys at once) only after `std::is_x86_feature_detected!("avx2")` said the CPU has AVX2 (with
// the `std` feature; without it the SSE2 path); everything else is safe code. Hence `unsafe_code = "deny"` (not "forbid") in Cargo.toml.
#![cfg_attr(docsrs, feature(doc_cfg))]

#[cfg(feature = "alloc")]
extern crate alloc;
#[cfg(any(feature = "std", test))]
extern crate std;

pub use bytemuck;
pub use glam;

mod capacity;
#[cfg(feature = "alloc")]
mod concurrent;
#[cfg(feature = "alloc")]
mod concurrent_slots;
pub mod constants;
mod error;
mod hash;
mod key;
mod level;
mod math;
#[cfg_attr(not(feature = "alloc"), allow(dead_code))]
mod probe;
#[cfg(feature = "alloc")]
mod table;
mod trilinear;

pub use capacity::{SlotIndexer, next_prime};
#[cfg(feature = "alloc")]
pub use concurrent::{ConcurrentTable, Located};
#[cfg(feature = "alloc")]
pub use concurrent_slots::ConcurrentSlots;
pub use error::{GridError, TableError};
pub use hash::{
    BucketHash, checksum, fold_and_checksum, hash_fold, hash_mix, hash_mix_coherent,
    hash_xor_primes, mix_and_checksum, pcg4d,
};
pub use key::{CellKey, normal_class};
pub use level::{
    AdaptiveGrid, LevelParams, StaticGrid, geometric_jitter, geometric_jitter_probability,
};
pub use probe::{Insert, prefetch_line};
#[cfg(feature = "alloc")]
pub use table::HashTable;
pub use trilinear::{
    cell_and_fraction, floor_ivec3, jittered_vertex, stochastic_corner, stochastic_trilinear,
    trilinear_weights,
};

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
