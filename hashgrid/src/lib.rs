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
//! | [`BucketHash`], [`hash_xor_primes`], [`hash_mix`], [`hash_mix_coherent`] | bucket hash: xor of primes (Instant-NGP), pcg4d mixing, or mixing that keeps runs of 4 along x together | MCPG sec. 4, `hash(x) = ⊕ πᵢxᵢ mod B` |
//! | [`pcg4d`], [`mix_and_checksum`] | the 4-word permutation behind the mixing hash and the checksum, one pass for both | Jarzynski & Olano 2020, "pcg4d" |
//! | [`checksum`] | separate full 32-bit hash stored in the slot, 0 = empty | MCPG sec. 4, Table 1 "hash" |
//! | [`AdaptiveGrid`], [`LevelParams`], [`geometric_jitter`] | level from camera distance, jitter to coarser levels | MCPG sec. 4, Step 1 |
//! | [`StaticGrid`] | fixed cell width, no normal | MCPG sec. 4 "static grid" |
//! | [`stochastic_trilinear`], [`jittered_vertex`] | vertex with probability = trilinear weight | MCPG sec. 4 |
//! | [`SlotIndexer`] | `h mod B` for any capacity, a mask for powers of two | MCPG sec. 4 |
//! | [`HashTable`] | fixed-capacity table, checksum array + `Pod` value array, bounded wrapping probing, ages | MCPG sec. 4, Alg. 1 `grid.load` |
//! | [`ConcurrentTable`] | lock-free insert by compare-and-swap on the checksum | MCPG sec. 4 "Synchronization" |
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
//! ## Design choices (measured in the `hashgrid` suites and the demo's section `hashgrid`)
//! - **Bucket hash.** [`BucketHash::Mix`] (the default) passes chi-square occupancy tests on
//!   planes, lines, a voxelised sphere and a camera's multi-level key stream, and loses as few
//!   inserts to the probe limit as random keys do. MCPG's xor of primes is cheaper and keeps
//!   x-neighbours in neighbouring slots, but on the multi-level stream it is over-dispersed
//!   (X²/df ≈ 1.5) and loses ~9 % of inserts at load 0.25 with 8 probes.
//!   [`BucketHash::MixCoherent`] sits between: uniform runs of 4 along x, more clustering, and
//!   a second mixing pass for the checksum; on the benches' renderer streams (stochastic
//!   trilinear corners of neighbouring pixels) its locality did not pay for that.
//! - **Capacity.** Any capacity works: the index is `h mod B` ([`SlotIndexer`], an exact fast
//!   modulo on the CPU, `%` on the GPU) and a mask when `B` is a power of two. With `Mix` both
//!   behave the same; a prime `B` helps weak hashes. (merian-quake's sizes 32 777 259 and
//!   800 009 are odd but not prime.)
//! - **Probing.** Linear, at most `max_probes` slots, wrapping from the last slot to slot 0;
//!   [`Insert::Full`] beyond. Linear probing clusters: even ideal hashing fails ≈ 2.5 % of
//!   inserts at load 0.5 with 8 probes, so size tables for a load ≲ 0.25 or raise the limit.
//! - **Checksum.** Another word of the same [`pcg4d`] permutation as the mixing hash, all 32 bits
//!   kept in a `u32` array beside the values: distinct keys share it with probability 2⁻³², and
//!   because the two words are 64 bits of one 128-bit permutation (not functions of each
//!   other), two such keys also need to share a probe window to be confused. One pcg4d (12
//!   multiplies) gives both, where the first version ran Murmur3 twice (two seeds): hashing
//!   a stream of keys takes ≈ 2.9 ns per key instead of ≈ 3.9 ns, and a cache-resident
//!   [`HashTable::get`] ≈ 7.3 ns instead of ≈ 10 ns (pcg4d's multiplies are independent
//!   across words, Murmur3's rounds one long chain, so more of the lookup overlaps).
//! - **Speed.** Measured with `cargo run --release -p mcg-hashgrid --example speed` (cases of a
//!   group taking turns, minimum of many runs, on a shared 2-vCPU AMD EPYC VM) and the
//!   criterion bench, against `std::collections::HashMap<u64, [f32; 8]>` (SipHash-1-3)
//!   holding the same 143 233 keys, one value read per query on both sides. On a 19 MB table
//!   (2¹⁹ slots, 32-byte values) whose lines stay in the caches between passes:
//!   [`HashTable::find_many`] plus the value reads ≈ 8 ns per key (7.9–8.4) against
//!   ≈ 20–22 ns (×2.4–2.8), per-key [`HashTable::get`] ≈ 13–14 ns (×1.5), in scanline,
//!   8 × 8-tile or random order alike; cache-resident (1.2 MB): `find_many` ≈ 5.9 ns, `get`
//!   ≈ 7 ns, against ≈ 14 ns. With the caches evicted before every pass (the tables come from
//!   memory, as after the rest of a renderer's frame): `find_many` plus values ≈ 18–19.5 ns
//!   against ≈ 74–76 ns (×3.8–4.1; criterion means ×3.5–3.7), `get` ≈ 43 ns (×1.7). The
//!   issue's 3× is therefore met by `find_many` when the table comes from memory, and not
//!   quite with warm caches (the `HashMap`'s own minimum there also moves between ≈ 20 and
//!   ≈ 40 ns from one process to the next; the ratios above use its fastest, ≈ 20–22 ns).
//!   Where the warm time goes: `find_many` alone ≈ 5.5 ns (hashing ≈ 2–3 ns, then the
//!   checksum reads and decisions), the value reads ≈ 2 ns. `find_many` runs one copy of its
//!   batch loop per hash and kind of capacity, so the loop branches on neither per key; with
//!   the mask and [`BucketHash::Mix`], LLVM then hashes 4 keys at once in SSE2 lanes
//!   (`pmuludq`): ≈ 8 instead of ≈ 9.3 ns per key with value reads (forcing scalar hashing
//!   there: 10.1–10.5 ns). Batches of 256 keys: from memory ≈ 20 ns per key against ≈ 25 ns
//!   with batches of 16 (more misses in flight); 64 to 1024 alike with warm caches.
//!   Tried and dropped, measured on the same streams: a batched value lookup that also reads
//!   each home slot's value before deciding (so both misses overlap; with a plain read, as
//!   `unsafe` is not used for a prefetch) and hands values to a closure: 9.6–12 ns for
//!   batches of 8 to 1024 (before the per-kind loops), the early read itself +0.5–0.9 ns;
//!   pipelining it (hash and read batch i + 1 before deciding batch i): 10–12.7 ns; separate
//!   home and checksum arrays, deciding the keys not in their home slot in a second pass, or
//!   reading two slots per key up front: no gain (±0.3 ns). A real prefetch instruction
//!   (`_mm_prefetch`, `unsafe`) measured ≈ 7 ns warm (×2.8–3.0) and ≈ 17 ns from memory
//!   (×4.1–4.4); it is not used.
//!   Probe windows that do not wrap are taken as one sub-slice (one bounds check, no `unsafe`);
//!   comparing four checksums at once into bit masks measured slower. A power-of-two capacity
//!   (mask) and a prime one (exact fast modulo) differ by ≲ 15 %.
//!   [`ConcurrentTable::insert_or_get`] from 2 threads of a persistent pool (each thread a
//!   contiguous half of the stream; spawning, emptying the table, evicting it from both
//!   cores' L2 and waking the workers not timed, see the bench's docs), minimum of runs:
//!   ×1.5–1.6 of one thread for the 143 233 distinct keys in 2¹⁹ slots (≈ 14 → 9 ns per
//!   insert), ×1.8 in 2²¹ slots, ×1.8–1.96 for every pixel's key (repeats); criterion means
//!   swing between ×1.3 and ×2.3 with the neighbours. On the same machine 2 threads of pure
//!   hashing give ×2.0 and of read-only `find`s of the same keys ×1.9: the rest is cache
//!   lines that both cores write moving between them (a 2 MB table of 32 768 lines, ≈ 4
//!   inserts per line from both threads; the 8 MB table shares fewer). `examples/speed.rs`,
//!   section `concurrent`, prints all of it with 1- and 2-thread runs alternating.
//! - **Concurrency.** [`ConcurrentTable`] claims slots by compare-and-swap on the checksum
//!   word and owns no values; the thread that gets [`Insert::Inserted`] initialises the value in
//!   the caller's own array (typically atomics). Evictions and the plain `&[u32]` upload view
//!   need `&mut self`; the view is the crate's only `unsafe` (an `&[AtomicU32]` read as `&[u32]`,
//!   which std documents as having the same size and bit validity).
//!
//! ## Features
//! - `std` (default): float functions from the standard library; implies `alloc`.
//! - `alloc`: the tables ([`HashTable`], [`ConcurrentTable`]). Without it the crate is keys,
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
//! let mut table = HashTable::<[f32; 8]>::new(1_000_003, 8, BucketHash::Mix)?;
//! let (state, fresh) = table.entry(&key).expect("table is not full");
//! assert!(fresh);
//! state[0] += 1.0;
//! assert_eq!(table.get(&key).unwrap()[0], 1.0);
//! assert!(matches!(table.insert_or_get(&key), Insert::Found(_)));
//! # Ok::<(), mcg_hashgrid::TableError>(())
//! ```
#![no_std]
#![deny(missing_docs)]
// One `unsafe` block: `ConcurrentTable::checksums` views `&[AtomicU32]` as `&[u32]` for upload
// (documented there); everything else is safe code.
#![deny(unsafe_code)]
// `!(x > 0.0)` is how this crate rejects NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
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
pub use concurrent::ConcurrentTable;
pub use error::{GridError, TableError};
pub use hash::{
    BucketHash, checksum, hash_mix, hash_mix_coherent, hash_xor_primes, mix_and_checksum, pcg4d,
};
pub use key::{CellKey, normal_class};
pub use level::{
    AdaptiveGrid, LevelParams, StaticGrid, geometric_jitter, geometric_jitter_probability,
};
pub use probe::Insert;
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
