//! Criterion benchmarks of mcg-hashgrid, each group with its baseline in the same group: std's
//! `HashMap<u64, State>` with its default SipHash-1-3 hasher (the key packed into a `u64`),
//! holding the same keys.
//!
//! The key streams are a renderer's (`common/stream.rs`): MCPG adaptive-grid keys (several
//! levels, stochastic trilinear corners, normal classes) of the hit points of a camera's
//! 256 × 256 pixels in a room, 8 frames of a turning camera. The tables hold the n = 143 233
//! distinct keys of those frames in 2¹⁹ = 524 288 slots (power of two, mask) or 524 309 (the
//! next prime, modulo): load ≈ 0.27, 18.9 MB with a 32-byte state; the `HashMap` holds the same
//! keys in ≈ 10.5 MB. Lookups are the 65 536 keys of one of those frames (44 122 distinct).
//!
//! - `lookup` (scanline order), `lookup_tiles` (8 × 8 tiles), `lookup_random` (the same keys
//!   shuffled: no coherence): `HashTable::get` per key (`table_*`; `table_fold_pow2` is the
//!   default hash, the `mix` cases pcg4d; peers other than std's map: `benches/peers.rs`) and `HashTable::find_many`
//!   over the whole frame followed by the value reads (`*_find_many`), against `HashMap::get`;
//!   every pass reads one value per query on both sides. Criterion repeats a pass back to back,
//!   so the table's and the map's lines stay in the caches between passes (warm).
//!   `table_mix_pow2_dense`: 2¹⁸ slots (load ≈ 0.55, 9.4 MB), about the memory of the `HashMap`.
//! - `lookup_cold`: the scanline pass of `lookup`, but every pass starts (untimed) with a write
//!   to each cache line of a 64 MiB buffer (twice the L3), so table and map come from memory,
//!   as after the rest of a renderer's frame: this is where batching (`find_many`: the misses of
//!   a batch in flight together) pays most.
//! - `lookup_small`: the first 8192 keys in 32 768 slots (1.2 MB, cache-resident), queried by
//!   the lookup frame's keys that are among them: hashing, not memory, dominates.
//! - `insert`: the distinct keys inserted into an emptied table / map (emptying not timed).
//! - `concurrent_insert`: `ConcurrentTable::insert_or_get` by 1 and 2 threads of a persistent
//!   pool (`common/pool.rs`), each thread a contiguous share of the stream. Not timed: spawning
//!   (the two workers live for the whole group), emptying the table, evicting it from both
//!   cores' L2 (each worker streams a 2 MiB buffer, for 1 and 2 threads alike), and waking the
//!   parked workers. Timed: from the first working worker's start to the last one's end.
//!   `distinct_threads_*` inserts the distinct keys once (disjoint keys per thread);
//!   `pixels_threads_*` inserts every pixel's key of all 8 frames (524 288, repeats included,
//!   both threads touching the same cells: what a renderer does each frame).
//!
//! The xor-of-primes table cannot hold all keys (it clusters on this stream, see the demo),
//! so some of its lookups are misses. Criterion reports means, which slow spells of a shared
//! machine inflate for whichever case they hit (on the 2-vCPU VM the numbers were taken on, the
//! same `HashMap` pass took 20 ns per key in one process and 70–80 ns in another a minute
//! later). For ratios robust to that, see `examples/speed.rs`: the cases of a group take turns
//! and the minimum of many runs is compared.

use std::collections::HashMap;
use std::hint::black_box;
use std::sync::RwLock;
use std::time::{Duration, Instant};

use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use mcg_hashgrid::{BucketHash, CellKey, ConcurrentTable, HashTable};

#[path = "common/lookups.rs"]
mod lookups;
#[path = "common/pool.rs"]
mod pool;
#[path = "common/stream.rs"]
mod stream;

use lookups::{State, find_many_pass, get_pass, hashmap_pass};

use stream::{Inputs, inputs, pack};

const MAX_PROBES: u32 = 16;

fn table(cap: u32, hash: BucketHash, keys: &[CellKey]) -> HashTable<State> {
    let mut t = HashTable::<State>::new(cap, MAX_PROBES, hash).unwrap();
    let mut full = 0;
    for k in keys {
        match t.entry(k) {
            Some((state, _)) => state[0] = 1.0,
            None => full += 1,
        }
    }
    eprintln!(
        "{hash:?} capacity {cap}: load {:.3}, {full} keys did not fit",
        t.load_factor()
    );
    t
}

type Group<'a> = BenchmarkGroup<'a, criterion::measurement::WallTime>;

fn bench_get(g: &mut Group<'_>, name: &str, t: &HashTable<State>, queries: &[CellKey]) {
    g.bench_function(name, |b| b.iter(|| get_pass(t, queries)));
}

fn bench_find_many(g: &mut Group<'_>, name: &str, t: &HashTable<State>, queries: &[CellKey]) {
    let mut slots = vec![None; queries.len()];
    g.bench_function(name, |b| b.iter(|| find_many_pass(t, queries, &mut slots)));
}

fn bench_map(g: &mut Group<'_>, map: &HashMap<u64, State>, queries: &[CellKey]) {
    let packed: Vec<u64> = queries.iter().map(pack).collect();
    g.bench_function("hashmap_u64_baseline", |b| {
        b.iter(|| hashmap_pass(map, &packed))
    });
}

fn hashmap(inp: &Inputs) -> HashMap<u64, State> {
    let map: HashMap<u64, State> = inp.fill.iter().map(|k| (pack(k), [1.0; 8])).collect();
    assert_eq!(
        map.len(),
        inp.fill.len(),
        "packing is injective on this stream"
    );
    map
}

fn bench_lookup(c: &mut Criterion) {
    let inp = inputs();
    let map = hashmap(&inp);
    eprintln!(
        "lookup: {} keys, {} queries, capacities {} and {}",
        inp.fill.len(),
        inp.scanline.len(),
        inp.prime,
        inp.pow2
    );
    let mix_pow2 = table(inp.pow2, BucketHash::Mix, &inp.fill);
    let mut g = c.benchmark_group("lookup");
    g.throughput(Throughput::Elements(inp.scanline.len() as u64));
    bench_map(&mut g, &map, &inp.scanline);
    bench_get(&mut g, "table_mix_pow2", &mix_pow2, &inp.scanline);
    bench_find_many(&mut g, "table_mix_pow2_find_many", &mix_pow2, &inp.scanline);
    for (name, cap, hash) in [
        ("table_fold_pow2", inp.pow2, BucketHash::Fold),
        ("table_mix_prime", inp.prime, BucketHash::Mix),
        ("table_mix_coherent_pow2", inp.pow2, BucketHash::MixCoherent),
        ("table_xor_prime", inp.prime, BucketHash::XorPrimes),
        ("table_mix_pow2_dense", inp.pow2 / 2, BucketHash::Mix),
    ] {
        let t = table(cap, hash, &inp.fill);
        bench_get(&mut g, name, &t, &inp.scanline);
    }
    g.finish();

    for (group, queries) in [("lookup_tiles", &inp.tiles), ("lookup_random", &inp.random)] {
        let mut g = c.benchmark_group(group);
        g.throughput(Throughput::Elements(queries.len() as u64));
        bench_map(&mut g, &map, queries);
        bench_get(&mut g, "table_mix_pow2", &mix_pow2, queries);
        bench_find_many(&mut g, "table_mix_pow2_find_many", &mix_pow2, queries);
        g.finish();
    }
}

/// Bytes written before each `lookup_cold` pass: twice the 32 MiB L3 of the machine the
/// numbers were taken on.
const EVICT_BYTES: usize = 64 << 20;

fn bench_lookup_cold(c: &mut Criterion) {
    let inp = inputs();
    let map = hashmap(&inp);
    let t = table(inp.pow2, BucketHash::Mix, &inp.fill);
    let queries = &inp.scanline;
    let packed: Vec<u64> = queries.iter().map(pack).collect();
    let mut evict = vec![0_u8; EVICT_BYTES];
    let mut g = c.benchmark_group("lookup_cold");
    g.throughput(Throughput::Elements(queries.len() as u64));
    g.sample_size(10);
    // Each pass starts (untimed) with a write to every cache line of a buffer twice the L3,
    // so the table's lines come from memory, as after a renderer's other work of a frame.
    let evict_all = |e: &mut Vec<u8>| {
        for b in e.iter_mut().step_by(64) {
            *b = b.wrapping_add(1);
        }
        black_box(e);
    };
    g.bench_function("hashmap_u64_baseline", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut evict, evict_all, |_| {
                black_box(hashmap_pass(&map, &packed));
            })
        })
    });
    g.bench_function("table_mix_pow2", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut evict, evict_all, |_| {
                black_box(get_pass(&t, queries));
            })
        })
    });
    let mut slots = vec![None; queries.len()];
    g.bench_function("table_mix_pow2_find_many", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut evict, evict_all, |_| {
                black_box(find_many_pass(&t, queries, &mut slots));
            })
        })
    });
    g.finish();
}

fn bench_lookup_small(c: &mut Criterion) {
    let inp = inputs();
    let fill = &inp.fill[..8192];
    let set: std::collections::HashSet<CellKey> = fill.iter().copied().collect();
    let queries: Vec<CellKey> = inp
        .scanline
        .iter()
        .copied()
        .filter(|k| set.contains(k))
        .collect();
    let map: HashMap<u64, State> = fill.iter().map(|k| (pack(k), [1.0; 8])).collect();
    let mut g = c.benchmark_group("lookup_small");
    g.throughput(Throughput::Elements(queries.len() as u64));
    bench_map(&mut g, &map, &queries);
    for (name, hash) in [
        ("table_mix_pow2", BucketHash::Mix),
        ("table_mix_coherent_pow2", BucketHash::MixCoherent),
        ("table_xor_pow2", BucketHash::XorPrimes),
    ] {
        let t = table(32_768, hash, fill);
        bench_get(&mut g, name, &t, &queries);
        if hash == BucketHash::Mix {
            bench_find_many(&mut g, "table_mix_pow2_find_many", &t, &queries);
        }
    }
    g.finish();
}

/// Times `run` after an untimed `reset`, `iters` times.
fn timed<S>(
    iters: u64,
    state: &mut S,
    reset: impl Fn(&mut S),
    mut run: impl FnMut(&mut S),
) -> Duration {
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        reset(state);
        let start = Instant::now();
        run(state);
        total += start.elapsed();
    }
    total
}

fn bench_insert(c: &mut Criterion) {
    let inp = inputs();
    let keys = &inp.fill;
    let packed: Vec<u64> = keys.iter().map(pack).collect();
    let mut g = c.benchmark_group("insert");
    g.throughput(Throughput::Elements(keys.len() as u64));
    g.sample_size(20);
    let mut map: HashMap<u64, State> = HashMap::with_capacity(keys.len());
    g.bench_function("hashmap_u64_baseline", |b| {
        b.iter_custom(|iters| {
            timed(iters, &mut map, HashMap::clear, |m| {
                for &k in black_box(&packed) {
                    m.entry(k).or_insert([0.0; 8])[0] += 1.0;
                }
            })
        })
    });
    for (name, cap, hash) in [
        ("table_fold_pow2", inp.pow2, BucketHash::Fold),
        ("table_mix_pow2", inp.pow2, BucketHash::Mix),
        ("table_mix_prime", inp.prime, BucketHash::Mix),
        ("table_mix_coherent_pow2", inp.pow2, BucketHash::MixCoherent),
    ] {
        let mut t = HashTable::<State>::new(cap, MAX_PROBES, hash).unwrap();
        g.bench_function(name, |b| {
            b.iter_custom(|iters| {
                timed(iters, &mut t, HashTable::clear, |t| {
                    for k in black_box(keys) {
                        if let Some((s, _)) = t.entry(k) {
                            s[0] += 1.0;
                        }
                    }
                })
            })
        });
    }
    g.finish();
}

fn bench_concurrent(c: &mut Criterion) {
    let inp = inputs();
    // In an RwLock only so that the bench can empty it between runs (`clear` takes `&mut`); each
    // worker takes the read lock once per run.
    let table = RwLock::new(ConcurrentTable::new(inp.pow2, MAX_PROBES, BucketHash::Mix).unwrap());
    let mut g = c.benchmark_group("concurrent_insert");
    g.sample_size(20);
    for (stream, keys) in [("distinct", &inp.fill), ("pixels", &inp.pixels)] {
        g.throughput(Throughput::Elements(keys.len() as u64));
        // Persistent workers (`common/pool.rs`): no thread is spawned inside a timed run; the
        // table is emptied and evicted from both cores' L2 (untimed) before every run, for 1
        // and 2 threads alike; a run is timed from the first worker's start to the last
        // worker's end.
        pool::with_workers(
            |w, n| {
                let t = table.read().unwrap();
                let mut inserted = 0_u32;
                for k in black_box(pool::share(keys, w, n)) {
                    inserted += u32::from(t.insert_or_get(k).is_inserted());
                }
                black_box(inserted);
            },
            |workers| {
                for threads in [1_usize, 2] {
                    g.bench_function(format!("{stream}_threads_{threads}"), |b| {
                        b.iter_custom(|iters| {
                            (0..iters)
                                .map(|_| workers.run(threads, || table.write().unwrap().clear()))
                                .sum()
                        })
                    });
                }
            },
        );
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_lookup,
    bench_lookup_cold,
    bench_lookup_small,
    bench_insert,
    bench_concurrent
);
criterion_main!(benches);
