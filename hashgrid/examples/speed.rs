//! Min-of-runs timing of the lookup and insert benches, for a shared, noisy machine.
//!
//! Criterion reports means, which a busy neighbour process inflates by whatever share of the
//! core (or of the shared L3 and memory) it takes. This probe runs each case many times (each
//! run a whole pass over the stream, ≈ 0.1–5 ms) and prints the *minimum* and the median time
//! per key: the minimum is the time of a run that was not disturbed, the figure a quiet machine
//! gives. Run it with `cargo run --release -p mcg-hashgrid --example speed` and state
//! `uptime`'s load with the numbers; `-- 1500 concurrent` runs one section (`lookup`, `insert`,
//! `concurrent`) with 1.5 s per case. The streams are those of the criterion bench
//! (`benches/common/stream.rs`).
//!
//! - `diag`: parts of a lookup (hashing, `find` alone, the memory reads with the slots known,
//!   a cache-resident table) to see where the time goes.
//! - `lookup_cold`, `lookup/{scanline,tiles,random}`: the criterion groups. The cases of a
//!   group take turns (one untimed run, then 4 timed ones, per turn), so a slow spell of a
//!   neighbour hits the `HashMap` baseline and the tables alike; ratios are of minima. In
//!   `lookup_cold` every timed run is preceded (untimed) by a write to each line of a 64 MiB
//!   buffer (twice the L3), and there is no untimed run.
//! - `insert`: the distinct keys into an emptied table / map.
//! - `concurrent`: 1 vs 2 threads on the persistent workers of `benches/common/pool.rs` (what
//!   is timed is documented there), 1- and 2-thread runs alternating: two calibrations that
//!   show what the machine allows (pure hashing; read-only `find` of every pixel's key in the
//!   filled table: the same random reads, no writes), then `ConcurrentTable::insert_or_get`
//!   of the distinct keys and of every pixel's key, with 2¹⁹ and 2²¹ slots.

use std::collections::HashMap;
use std::hint::black_box;
use std::time::{Duration, Instant};

use mcg_hashgrid::{BucketHash, CellKey, ConcurrentTable, HashTable, checksum, mix_and_checksum};

#[path = "../benches/common/lookups.rs"]
mod lookups;
#[path = "../benches/common/pool.rs"]
mod pool;
#[path = "../benches/common/stream.rs"]
mod stream;

use lookups::{State, find_many_pass, get_pass, hashmap_pass};

const MAX_PROBES: u32 = 16;

/// (min, median) nanoseconds per element of `run` over `budget`.
fn time(elements: usize, budget: Duration, mut run: impl FnMut()) -> (f64, f64) {
    run();
    let mut samples = Vec::new();
    let start = Instant::now();
    while start.elapsed() < budget || samples.len() < 10 {
        let t = Instant::now();
        run();
        samples.push(t.elapsed().as_secs_f64() * 1e9 / elements as f64);
    }
    samples.sort_by(f64::total_cmp);
    (samples[0], samples[samples.len() / 2])
}

/// Min and median ns per element of each case, the cases taking turns (so a slow spell of a
/// neighbour on the shared machine hits all of them alike): per turn one untimed run (it
/// brings the case's own tables back into the caches after the other cases) and
/// [`RUNS_PER_TURN`] timed ones, for `budget` per case in all. Ratios are against case 0's
/// minimum.
///
/// With `cold`, no untimed run: `cold` is called (untimed) before every timed run instead.
fn interleaved(
    group: &str,
    elements: usize,
    budget: Duration,
    cases: &mut [Case<'_>],
    mut cold: Option<&mut dyn FnMut()>,
) {
    let mut samples = vec![Vec::new(); cases.len()];
    let start = Instant::now();
    while start.elapsed() < budget * cases.len() as u32 || samples[0].len() < 10 {
        for ((_, run), samples) in cases.iter_mut().zip(&mut samples) {
            if cold.is_none() {
                run();
            }
            for _ in 0..RUNS_PER_TURN {
                if let Some(evict) = cold.as_mut() {
                    evict();
                }
                let t = Instant::now();
                run();
                samples.push(t.elapsed().as_secs_f64() * 1e9 / elements as f64);
            }
        }
    }
    let mut base = None;
    for ((name, _), samples) in cases.iter().zip(&mut samples) {
        samples.sort_by(f64::total_cmp);
        let min = report(group, name, base, (samples[0], samples[samples.len() / 2]));
        base.get_or_insert(min);
    }
}

/// A named pass of a group of [`interleaved`].
type Case<'a> = (String, Box<dyn FnMut() + 'a>);

/// Timed runs per turn of [`interleaved`].
const RUNS_PER_TURN: usize = 4;

fn report(group: &str, name: &str, base: Option<f64>, (min, med): (f64, f64)) -> f64 {
    let ratio = base.map_or(String::new(), |b| format!("  ×{:.2} vs baseline", b / min));
    println!("{group:<14} {name:<28} min {min:7.2} ns  median {med:7.2} ns{ratio}");
    min
}

fn table(cap: u32, hash: BucketHash, keys: &[CellKey]) -> HashTable<State> {
    let mut t = HashTable::<State>::new(cap, MAX_PROBES, hash).unwrap();
    for k in keys {
        if let Some((s, _)) = t.entry(k) {
            s[0] = 1.0;
        }
    }
    t
}

fn main() {
    let budget = Duration::from_millis(
        std::env::args()
            .nth(1)
            .and_then(|a| a.parse().ok())
            .unwrap_or(1500),
    );
    // Optional second argument: run only the sections whose name contains it
    // (`lookup`, `insert`, `concurrent`).
    let filter = std::env::args().nth(2).unwrap_or_default();
    let only = |section: &str| section.contains(filter.as_str());
    let inp = stream::inputs();
    println!(
        "{} keys, {} queries; capacities {} / {}",
        inp.fill.len(),
        inp.scanline.len(),
        inp.pow2,
        inp.prime
    );
    hash_throughput(&inp.fill, budget);
    if only("lookup") {
        let map: HashMap<u64, State> = inp
            .fill
            .iter()
            .map(|k| (stream::pack(k), [1.0; 8]))
            .collect();
        let tables = lookup_tables(&inp);
        lookup_diagnostics(&inp, &tables, budget);
        lookup_cold(&inp, &map, &tables[0].1, budget);
        lookup_orders(&inp, &map, &tables, budget);
    }
    if only("insert") {
        insert(&inp, budget);
    }
    if only("concurrent") {
        concurrent(&inp, budget);
    }
}

/// The bucket hash and checksum of every fill key, nothing else: the arithmetic floor.
fn hash_throughput(keys: &[CellKey], budget: Duration) {
    let (hmin, _) = time(keys.len(), budget, || {
        black_box(
            keys.iter()
                .map(|k| checksum(k) ^ mcg_hashgrid::hash_mix(k))
                .fold(0, |a, b| a ^ b),
        );
    });
    println!("hash           mix+checksum                 min {hmin:7.2} ns");
}

/// The filled tables of the lookup groups: `Mix` and `MixCoherent` at the power-of-two and the
/// prime capacity, and both hashes at half the power-of-two capacity (dense).
fn lookup_tables(inp: &stream::Inputs) -> [(&'static str, HashTable<State>); 6] {
    let keys = &inp.fill;
    [
        ("mix_pow2", table(inp.pow2, BucketHash::Mix, keys)),
        ("mix_prime", table(inp.prime, BucketHash::Mix, keys)),
        (
            "coherent_pow2",
            table(inp.pow2, BucketHash::MixCoherent, keys),
        ),
        (
            "coherent_prime",
            table(inp.prime, BucketHash::MixCoherent, keys),
        ),
        ("mix_pow2_dense", table(inp.pow2 / 2, BucketHash::Mix, keys)),
        (
            "coherent_pow2_dense",
            table(inp.pow2 / 2, BucketHash::MixCoherent, keys),
        ),
    ]
}

/// Group `diag`: the parts of a scanline lookup (`find` alone, hashing alone, a cache-resident
/// table, the memory reads with the slots known) to see where the time goes.
fn lookup_diagnostics(
    inp: &stream::Inputs,
    tables: &[(&'static str, HashTable<State>)],
    budget: Duration,
) {
    let q = &inp.scanline;
    let distinct: std::collections::HashSet<_> = q.iter().collect();
    let same = q.windows(2).filter(|w| w[0] == w[1]).count();
    println!(
        "scanline: {} distinct keys, {:.1} % equal to the previous",
        distinct.len(),
        100.0 * same as f64 / q.len() as f64
    );
    find_and_hash_only(q, tables, budget);
    in_cache_tables(&inp.fill, budget);
    memory_floor(q, &tables[0].1, budget);
    in_cache_hashmap(&inp.fill, budget);
}

/// Memory floor of the big table: slots known, only the checksum word and the value read.
fn memory_floor(q: &[CellKey], t: &HashTable<State>, budget: Duration) {
    let found: Vec<u32> = q.iter().map(|k| t.find(k).unwrap()).collect();
    report(
        "diag",
        "floor: checksum+value reads",
        None,
        time(q.len(), budget, || {
            black_box(
                black_box(&found)
                    .iter()
                    .map(|&s| t.checksums()[s as usize] as f32 + t.values()[s as usize][0])
                    .sum::<f32>(),
            );
        }),
    );
}

/// `find` alone in the `mix_pow2` and `coherent_pow2` tables, and the home slot and checksum
/// alone (no memory reads).
fn find_and_hash_only(
    q: &[CellKey],
    tables: &[(&'static str, HashTable<State>)],
    budget: Duration,
) {
    for (label, t) in [
        ("find_only mix_pow2", &tables[0].1),
        ("find_only coherent_pow2", &tables[2].1),
    ] {
        report(
            "diag",
            label,
            None,
            time(q.len(), budget, || {
                black_box(
                    black_box(q)
                        .iter()
                        .map(|k| t.find(k).unwrap_or(0))
                        .fold(0, |a, b| a ^ b),
                );
            }),
        );
    }
    let t = &tables[2].1;
    report(
        "diag",
        "home+checksum only",
        None,
        time(q.len(), budget, || {
            black_box(
                black_box(q)
                    .iter()
                    .map(|k| t.home_slot(k) ^ checksum(k))
                    .fold(0, |a, b| a ^ b),
            );
        }),
    );
}

/// `get` and `find_many` of 8192 keys in a table small enough to stay in the caches.
fn in_cache_tables(keys: &[CellKey], budget: Duration) {
    let small = table(32768, BucketHash::Mix, &keys[..8192]);
    let sq: Vec<CellKey> = keys[..8192].to_vec();
    report(
        "diag",
        "get in-cache (8192 in 32768)",
        None,
        time(sq.len(), budget, || {
            black_box(get_pass(&small, &sq));
        }),
    );
    let mut sslots = vec![None; sq.len()];
    report(
        "diag",
        "find_many+values in-cache",
        None,
        time(sq.len(), budget, || {
            black_box(find_many_pass(&small, &sq, &mut sslots));
        }),
    );
}

/// The `HashMap` baseline of [`in_cache_tables`]: 8192 keys in a map that stays in the caches.
fn in_cache_hashmap(keys: &[CellKey], budget: Duration) {
    let sq = &keys[..8192];
    let smap: HashMap<u64, State> = keys[..8192]
        .iter()
        .map(|k| (stream::pack(k), [1.0; 8]))
        .collect();
    let sp: Vec<u64> = sq.iter().map(stream::pack).collect();
    report(
        "diag",
        "hashmap in-cache (8192)",
        None,
        time(sq.len(), budget, || {
            black_box(hashmap_pass(&smap, &sp));
        }),
    );
}

/// Group `lookup_cold`: scanline lookups with cold caches. Before every pass (untimed) a write
/// to each cache line of a 64 MiB buffer (twice the L3), so the table's lines come from memory.
fn lookup_cold(
    inp: &stream::Inputs,
    map: &HashMap<u64, State>,
    t: &HashTable<State>,
    budget: Duration,
) {
    let q = &inp.scanline;
    let packed: Vec<u64> = q.iter().map(stream::pack).collect();
    let mut evict = vec![0_u8; 64 << 20];
    let mut evict_all = || {
        for b in evict.iter_mut().step_by(64) {
            *b = b.wrapping_add(1);
        }
        black_box(&mut evict);
    };
    let mut slots = vec![None; q.len()];
    let mut cases: Vec<Case<'_>> = vec![
        (
            "hashmap_siphash".into(),
            Box::new(|| {
                black_box(hashmap_pass(map, &packed));
            }),
        ),
        (
            "mix_pow2".into(),
            Box::new(|| {
                black_box(get_pass(t, q));
            }),
        ),
        (
            "mix_pow2_find_many".into(),
            Box::new(|| {
                black_box(find_many_pass(t, q, &mut slots));
            }),
        ),
    ];
    interleaved(
        "lookup_cold",
        q.len(),
        budget,
        &mut cases,
        Some(&mut evict_all),
    );
}

/// Groups `lookup/{scanline,tiles,random}`: the `HashMap` baseline, `find_many` in the first
/// two tables and `get` in every table, for each query order.
fn lookup_orders(
    inp: &stream::Inputs,
    map: &HashMap<u64, State>,
    tables: &[(&'static str, HashTable<State>)],
    budget: Duration,
) {
    for (order, queries) in [
        ("scanline", &inp.scanline),
        ("tiles", &inp.tiles),
        ("random", &inp.random),
    ] {
        let packed: Vec<u64> = queries.iter().map(stream::pack).collect();
        let mut cases: Vec<Case<'_>> = vec![(
            "hashmap_siphash".into(),
            Box::new(|| {
                black_box(hashmap_pass(map, &packed));
            }),
        )];
        for (name, t) in &tables[..2] {
            let mut slots = vec![None; queries.len()];
            cases.push((
                format!("{name}_find_many"),
                Box::new(move || {
                    black_box(find_many_pass(t, queries, &mut slots));
                }),
            ));
        }
        for (name, t) in tables {
            cases.push((
                name.to_string(),
                Box::new(move || {
                    black_box(get_pass(t, queries));
                }),
            ));
        }
        interleaved(
            &format!("lookup/{order}"),
            queries.len(),
            budget,
            &mut cases,
            None,
        );
    }
}

/// Group `insert`: the distinct fill keys into an emptied `HashMap` (baseline) and tables.
fn insert(inp: &stream::Inputs, budget: Duration) {
    let keys = &inp.fill;
    let packed: Vec<u64> = keys.iter().map(stream::pack).collect();
    let mut m: HashMap<u64, State> = HashMap::with_capacity(keys.len());
    let base = report(
        "insert",
        "hashmap_siphash",
        None,
        time(keys.len(), budget, || {
            m.clear();
            for &k in black_box(&packed) {
                m.entry(k).or_insert([0.0; 8])[0] += 1.0;
            }
        }),
    );
    for (name, cap, hash) in [
        ("mix_pow2", inp.pow2, BucketHash::Mix),
        ("coherent_pow2", inp.pow2, BucketHash::MixCoherent),
    ] {
        let mut t = HashTable::<State>::new(cap, MAX_PROBES, hash).unwrap();
        report(
            "insert",
            name,
            Some(base),
            time(keys.len(), budget, || {
                t.clear();
                for k in black_box(keys) {
                    if let Some((s, _)) = t.entry(k) {
                        s[0] += 1.0;
                    }
                }
            }),
        );
    }
}

/// Min and median over `budget` of 1- and 2-thread runs of `work(worker, threads)` on the
/// persistent workers of `common/pool.rs` (runs alternate, so both see the same neighbours;
/// each run after `reset` and the L2 eviction, both untimed); prints ns per element and the
/// speed-up 2 vs 1 thread.
fn scaling(
    name: &str,
    elements: usize,
    budget: Duration,
    work: impl Fn(usize, usize) + Sync,
    reset: impl Fn(),
) {
    let mut samples = [Vec::new(), Vec::new()];
    pool::with_workers(work, |w| {
        let start = Instant::now();
        while start.elapsed() < budget || samples[1].len() < 10 {
            for threads in [1_usize, 2] {
                let d = w.run(threads, &reset);
                samples[threads - 1].push(d.as_secs_f64() * 1e9 / elements as f64);
            }
        }
    });
    for v in &mut samples {
        v.sort_by(f64::total_cmp);
    }
    let min = samples.each_ref().map(|v| v[0]);
    let med = samples.each_ref().map(|v| v[v.len() / 2]);
    println!(
        "concurrent     {name:<26} {} runs: 1 thread min {:6.2} / median {:6.2} ns; \
         2 threads min {:6.2} / median {:6.2} ns; speed-up ×{:.2} (min), ×{:.2} (median)",
        samples[0].len(),
        min[0],
        med[0],
        min[1],
        med[1],
        min[0] / min[1],
        med[0] / med[1],
    );
}

/// 2 vs 1 thread: `ConcurrentTable::insert_or_get`, and two calibrations that show what the
/// machine allows (the same split and workers, no table writes).
fn concurrent(inp: &stream::Inputs, budget: Duration) {
    let pixels = &inp.pixels;
    // Calibration 1: pure arithmetic (hashing every pixel key), which scales with the number
    // of cores the machine actually gives us.
    scaling(
        "hash_only (pixels)",
        pixels.len(),
        budget,
        |w, n| {
            black_box(
                pool::share(pixels, w, n)
                    .iter()
                    .fold(0, |a, k| a ^ mix_and_checksum(k).0),
            );
        },
        || {},
    );
    for cap in [inp.pow2, 4 * inp.pow2] {
        // Calibration 2: read-only lookups (`find`, `&self`) of every pixel key in the
        // filled table: the same random reads of the same memory as the inserts, without
        // writes or compare-and-swap: the memory system's ceiling for this access pattern.
        let filled = ConcurrentTable::new(cap, MAX_PROBES, BucketHash::Mix).unwrap();
        for k in &inp.fill {
            filled.insert_or_get(k);
        }
        scaling(
            &format!("find_only {cap}"),
            pixels.len(),
            budget,
            |w, n| {
                black_box(
                    pool::share(pixels, w, n)
                        .iter()
                        .fold(0, |a, k| a ^ filled.find(k).unwrap_or(0)),
                );
            },
            || {},
        );
        // Inserts into the emptied table: the distinct keys (disjoint per thread) and every
        // pixel's key of all frames (repeats, both threads on the same cells). The table sits
        // in an RwLock only so that the calling thread can empty it between runs (`clear`
        // takes `&mut`); the workers take the read lock once per run.
        let table =
            std::sync::RwLock::new(ConcurrentTable::new(cap, MAX_PROBES, BucketHash::Mix).unwrap());
        for (name, keys) in [("distinct", &inp.fill), ("pixels", &inp.pixels)] {
            scaling(
                &format!("insert_{name} {cap}"),
                keys.len(),
                budget,
                |w, n| {
                    let t = table.read().unwrap();
                    let mut inserted = 0_u32;
                    for k in pool::share(keys, w, n) {
                        inserted += u32::from(t.insert_or_get(k).is_inserted());
                    }
                    black_box(inserted);
                },
                || table.write().unwrap().clear(),
            );
        }
    }
}
