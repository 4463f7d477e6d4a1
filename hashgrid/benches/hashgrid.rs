//! Criterion benchmarks of mcg-hashgrid, each group with its baseline in the same group:
//!
//! - `lookup`: `HashTable::get` on a realistic key stream against
//!   `std::collections::HashMap<u64, State>::get` (the key packed into a `u64`), both holding
//!   the same keys. Variants: bucket hash `mix`, `mix_coherent` and `xor` (xor of primes), each
//!   with a prime capacity (modulo) or a power-of-two capacity (mask), and `mix_pow2_dense`:
//!   half the slots (2¹⁸, load ≈ 0.55), about the memory of the `HashMap` (≈ 10.5 MB: 2¹⁸
//!   buckets of 40 bytes). Lookups are memory-bound, so the footprint decides.
//! - `lookup_small`: the same with the first 8192 keys in 32 768 slots (1.2 MB, cache-resident),
//!   queried by the keys of the lookup frame that are among them: the regime where hashing,
//!   not memory, dominates.
//! - `insert`: the same stream inserted into an emptied table / map (emptying is not timed).
//! - `concurrent_insert`: `ConcurrentTable::insert_or_get` of the stream by 1 and by 2 threads
//!   (each thread a contiguous half), table emptied (untimed) before each iteration.
//!
//! The stream: a camera 1.7 units above the floor of a 40 × 40 × 10 room renders 256 × 256
//! pixels and turns by 0.11 rad per frame; each pixel's hit gives MCPG's adaptive-grid key
//! (level from distance with jitter, stochastic trilinear corner, normal class) from seeded
//! uniforms, in scanline order, so consecutive queries are spatially coherent, as in a
//! renderer. The tables hold the n distinct keys of [`FILL_FRAMES`] frames (n = 143 233) in
//! 2¹⁹ = 524 288 slots (power of two ≥ 3n) or 524 309 (the next prime): load ≈ 0.27, the same
//! memory for both (18.9 MB); the `HashMap` holds the same keys. The lookups are the 65 536 keys
//! of one of those frames again, in scanline order (many repeat, as in a renderer).
//!
//! The xor-of-primes tables cannot hold all keys: ≈ 8 % of them find no free slot within the
//! 16 probes (it clusters on this stream, see the demo), so some of its lookups are misses.

use std::collections::HashMap;
use std::hint::black_box;

use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_hashgrid::glam::{Vec2, Vec3};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, CellKey, ConcurrentTable, HashTable, next_prime};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A 32-byte guiding state, as MCPG's (ours is ≤ 32 bytes plus the 4-byte checksum).
type State = [f32; 8];

const WIDTH: u32 = 256;
const MAX_PROBES: u32 = 16;
/// Frames whose keys fill the tables.
const FILL_FRAMES: usize = 8;

/// Hit point and normal of the ray from `camera` along `dir` inside the box room
/// [−20, 20] × [0, 10] × [−20, 20].
fn hit_room(camera: Vec3, dir: Vec3) -> (Vec3, Vec3) {
    let lo = Vec3::new(-20.0, 0.0, -20.0);
    let hi = Vec3::new(20.0, 10.0, 20.0);
    let inv = dir.recip();
    let t_exit = ((lo - camera) * inv).max((hi - camera) * inv);
    let t = t_exit.min_element();
    let axis = if t == t_exit.x {
        0
    } else if t == t_exit.y {
        1
    } else {
        2
    };
    let mut n = Vec3::ZERO;
    n[axis] = -dir[axis].signum();
    (camera + dir * t, n)
}

/// One frame's keys in scanline order.
fn frame_keys(grid: &AdaptiveGrid, frame: usize, rng: &mut Pcg64Mcg) -> Vec<CellKey> {
    let camera = Vec3::new(0.0, 1.7, 0.0);
    let (sin, cos) = (frame as f32 * 0.11).sin_cos();
    let mut keys = Vec::with_capacity((WIDTH * WIDTH) as usize);
    for j in 0..WIDTH {
        for i in 0..WIDTH {
            let s = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0;
            // 90° field of view looking along −z, slightly down.
            let d = Vec3::new(s.x, -s.y - 0.3, -1.0);
            let dir = Vec3::new(cos * d.x - sin * d.z, d.y, sin * d.x + cos * d.z).normalize();
            let (p, n) = hit_room(camera, dir);
            keys.push(grid.vertex_key(p, n, camera, rng.random(), rng.random()));
        }
    }
    keys
}

/// The key packed into a u64 for the `HashMap` baseline: 18 bits per coordinate, 6 bits of
/// level, 3 of class (what a user would write).
fn pack(k: &CellKey) -> u64 {
    let c = |v: i32| (v as u64) & 0x3_FFFF;
    c(k.cell.x)
        | c(k.cell.y) << 18
        | c(k.cell.z) << 36
        | u64::from(k.level & 0x3F) << 54
        | u64::from(k.class & 7) << 60
}

struct Inputs {
    fill: Vec<CellKey>,
    queries: Vec<CellKey>,
    prime: u32,
    pow2: u32,
}

fn inputs() -> Inputs {
    let grid = AdaptiveGrid::mcpg();
    let mut rng = Pcg64Mcg::seed_from_u64(0x4847);
    let mut fill = Vec::new();
    let mut frames = Vec::new();
    for frame in 0..FILL_FRAMES {
        frames.push(frame_keys(&grid, frame, &mut rng));
    }
    let mut seen = std::collections::HashSet::new();
    for f in &frames {
        fill.extend(f.iter().copied().filter(|k| seen.insert(*k)));
    }
    let queries = frames[FILL_FRAMES / 2].clone();
    let n = fill.len() as u32;
    let pow2 = (3 * n).next_power_of_two();
    Inputs {
        fill,
        queries,
        prime: next_prime(pow2).unwrap(),
        pow2,
    }
}

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

fn bench_lookup(c: &mut Criterion) {
    let inp = inputs();
    let map: HashMap<u64, State> = inp.fill.iter().map(|k| (pack(k), [1.0; 8])).collect();
    assert_eq!(
        map.len(),
        inp.fill.len(),
        "packing is injective on this stream"
    );
    let packed: Vec<u64> = inp.queries.iter().map(pack).collect();
    eprintln!(
        "lookup: {} keys, {} queries, capacities {} and {}",
        inp.fill.len(),
        inp.queries.len(),
        inp.prime,
        inp.pow2
    );

    let mut g = c.benchmark_group("lookup");
    g.throughput(Throughput::Elements(inp.queries.len() as u64));
    g.bench_function("hashmap_u64_baseline", |b| {
        b.iter(|| {
            black_box(&packed)
                .iter()
                .map(|k| map.get(k).map_or(0.0, |s| s[0]))
                .sum::<f32>()
        })
    });
    for (name, hash) in [
        ("mix", BucketHash::Mix),
        ("mix_coherent", BucketHash::MixCoherent),
        ("xor", BucketHash::XorPrimes),
    ] {
        for (cap_name, cap) in [("prime", inp.prime), ("pow2", inp.pow2)] {
            let t = table(cap, hash, &inp.fill);
            g.bench_function(format!("table_{name}_{cap_name}"), |b| {
                b.iter(|| {
                    black_box(&inp.queries)
                        .iter()
                        .map(|k| t.get(k).map_or(0.0, |s| s[0]))
                        .sum::<f32>()
                })
            });
        }
    }
    // Same memory as the HashMap (≈ 9.4 MB vs its ≈ 10.5 MB): 2¹⁸ slots, load ≈ 0.55.
    let dense = table(inp.pow2 / 2, BucketHash::Mix, &inp.fill);
    g.bench_function("table_mix_pow2_dense", |b| {
        b.iter(|| {
            black_box(&inp.queries)
                .iter()
                .map(|k| dense.get(k).map_or(0.0, |s| s[0]))
                .sum::<f32>()
        })
    });
    g.finish();
}

fn bench_lookup_small(c: &mut Criterion) {
    let inp = inputs();
    let fill = &inp.fill[..8192];
    let set: std::collections::HashSet<CellKey> = fill.iter().copied().collect();
    let queries: Vec<CellKey> = inp
        .queries
        .iter()
        .copied()
        .filter(|k| set.contains(k))
        .collect();
    let map: HashMap<u64, State> = fill.iter().map(|k| (pack(k), [1.0; 8])).collect();
    let packed: Vec<u64> = queries.iter().map(pack).collect();
    let mut g = c.benchmark_group("lookup_small");
    g.throughput(Throughput::Elements(queries.len() as u64));
    g.bench_function("hashmap_u64_baseline", |b| {
        b.iter(|| {
            black_box(&packed)
                .iter()
                .map(|k| map.get(k).map_or(0.0, |s| s[0]))
                .sum::<f32>()
        })
    });
    for (name, hash) in [
        ("mix", BucketHash::Mix),
        ("mix_coherent", BucketHash::MixCoherent),
        ("xor", BucketHash::XorPrimes),
    ] {
        let t = table(32_768, hash, fill);
        g.bench_function(format!("table_{name}_pow2"), |b| {
            b.iter(|| {
                black_box(&queries)
                    .iter()
                    .map(|k| t.get(k).map_or(0.0, |s| s[0]))
                    .sum::<f32>()
            })
        });
    }
    g.finish();
}

/// Times `run` after an untimed `reset`, `iters` times.
fn timed<S>(iters: u64, state: &mut S, reset: impl Fn(&mut S), run: impl Fn(&mut S)) -> Duration {
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
    for (name, hash) in [
        ("mix", BucketHash::Mix),
        ("mix_coherent", BucketHash::MixCoherent),
    ] {
        for (cap_name, cap) in [("prime", inp.prime), ("pow2", inp.pow2)] {
            let mut t = HashTable::<State>::new(cap, MAX_PROBES, hash).unwrap();
            g.bench_function(format!("table_{name}_{cap_name}"), |b| {
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
    }
    g.finish();
}

fn bench_concurrent(c: &mut Criterion) {
    let inp = inputs();
    let keys = &inp.fill;
    let mut table = ConcurrentTable::new(inp.prime, MAX_PROBES, BucketHash::Mix).unwrap();
    let mut g = c.benchmark_group("concurrent_insert");
    g.throughput(Throughput::Elements(keys.len() as u64));
    g.sample_size(20);
    for threads in [1_usize, 2] {
        g.bench_function(format!("threads_{threads}"), |b| {
            b.iter_custom(|iters| {
                timed(iters, &mut table, ConcurrentTable::clear, |t| {
                    let t = &*t;
                    let chunk = keys.len().div_ceil(threads);
                    std::thread::scope(|s| {
                        for part in keys.chunks(chunk) {
                            s.spawn(move || {
                                let mut inserted = 0_u32;
                                for k in black_box(part) {
                                    inserted += u32::from(t.insert_or_get(k).is_inserted());
                                }
                                inserted
                            });
                        }
                    });
                })
            })
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_lookup,
    bench_lookup_small,
    bench_insert,
    bench_concurrent
);
criterion_main!(benches);
