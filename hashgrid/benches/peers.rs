//! Criterion benchmarks of the tables against the maps a Rust renderer author picks, each group
//! holding `mcg-hashgrid` and its peers, per table size:
//!
//! - `hashbrown` with its default hasher (foldhash), `rustc_hash::FxHashMap`, std's `HashMap`
//!   (SipHash-1-3), all `<u64, [f32; 8]>` with the key packed into a `u64`
//!   (`common/stream.rs::pack`);
//! - for concurrent inserts, `DashMap` (with the Fx hasher) and `Mutex<FxHashMap>`.
//!
//! Sizes: 2ᵇ slots for the `b` in `MCG_BENCH_SLOTS` (default `16,19`; the full sweep
//! is `MCG_BENCH_SLOTS=16,19,22,24`); the table's hash: `MCG_BENCH_HASH` (default `fold`), filled to load 1/4 with distinct keys of a renderer's
//! frames (`common/stream.rs::sized`); lookups are 65 536 pixels' keys (all hits) in the
//! order the frames visited them. The maps hold the same keys (their own capacity).
//!
//! - `peers_lookup/2^b`: warm (criterion repeats the pass, so what fits stays in the caches):
//!   `mcg_get` (`HashTable::get` per key), `mcg_find_many` (one `find_many` over the pass, then
//!   the value reads), `mcg_get_many` (one `get_many` over the pass, the values summed as they
//!   come), and `get` of each map; every lookup reads one value word.
//!   `mcg_find_no_value` (`HashTable::find` alone, no value read) is a diagnostic: one cache
//!   line per lookup, what a slot layout with the checksum beside the value would approach.
//! - `peers_lookup_cold/2^b`: the same passes, each after flushing the structure's memory from
//!   every cache level (`clflush` over the table's two arrays; over every entry of a map and
//!   its control bytes, `common/flush.rs`), untimed. `hashbrown_load_quarter` is a control:
//!   hashbrown holding the same keys at the table's load of 1/4 (`with_capacity` of twice the
//!   keys), i.e. about the table's memory per key instead of half of it.
//! - `peers_insert/2^b`: the distinct keys into an emptied table / map (emptying not timed).
//! - `peers_concurrent_insert/2^b`: 2 threads of a persistent pool (`common/pool.rs`, what is
//!   timed is documented there), each inserting a contiguous half of the distinct keys:
//!   `ConcurrentTable::insert_or_get` (alone, and with an atomic add to the slot's entry of a
//!   separate value array), `ConcurrentSlots::insert_or_get` with the same add to the slot's
//!   value, `DashMap::entry().or_insert`, and the `entry` of an `FxHashMap` behind a
//!   `Mutex` locked per key (both adding to the value too).
//!
//! Instruction counts of the same passes (robust on a noisy machine):
//! `scripts/hashgrid-instructions`.

use std::collections::HashMap;
use std::hash::BuildHasher;
use std::hint::black_box;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Mutex, RwLock};
use std::time::{Duration, Instant};

use criterion::measurement::WallTime;
use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main,
};
use dashmap::DashMap;
use mcg_hashgrid::{ConcurrentSlots, ConcurrentTable, HashTable};
use rustc_hash::{FxBuildHasher, FxHashMap};

#[path = "common/flush.rs"]
mod flush;
#[path = "common/lookups.rs"]
mod lookups;
#[path = "common/pool.rs"]
mod pool;
#[path = "common/stream.rs"]
mod stream;

use flush::{flush_entries, flush_table};
use lookups::{
    State, find_many_pass, find_pass, get_many_pass, get_pass, hashbrown_insert_pass,
    hashbrown_pass, hashmap_insert_pass, hashmap_pass, insert_pass,
};
use stream::{Sized, bench_hash, pack, sized, slot_bits};

const MAX_PROBES: u32 = 16;

/// The table of `s`, filled. Linear probing loses a few keys to the probe limit even with an
/// ideal hash (≈ 4·10⁻⁵ of them at load 1/4 with 16 probes): they are counted and left out
/// (their lookups are misses).
fn table(s: &Sized) -> HashTable<State> {
    let mut t = HashTable::<State>::new(1 << s.bits, MAX_PROBES, bench_hash()).unwrap();
    let mut full = 0;
    for k in &s.fill {
        match t.entry(k) {
            Some((v, _)) => v[0] = 1.0,
            None => full += 1,
        }
    }
    eprintln!("2^{}: {} keys, {full} did not fit", s.bits, s.fill.len());
    t
}

fn map<S: BuildHasher + Default>(s: &Sized) -> HashMap<u64, State, S> {
    let m: HashMap<u64, State, S> = s.fill.iter().map(|k| (pack(k), [1.0; 8])).collect();
    assert_eq!(m.len(), s.fill.len(), "packing is injective on this stream");
    m
}

fn hashbrown_map(s: &Sized) -> hashbrown::HashMap<u64, State> {
    s.fill.iter().map(|k| (pack(k), [1.0; 8])).collect()
}

/// [`hashbrown_map`] sized to the table's load of 1/4: `with_capacity(2n)` gives the power of
/// two of buckets above 8/7 · 2n, i.e. 4n buckets for the streams' n = 2ᵇ/4 keys.
fn hashbrown_map_at_load_quarter(s: &Sized) -> hashbrown::HashMap<u64, State> {
    let mut m = hashbrown::HashMap::with_capacity(2 * s.fill.len());
    m.extend(s.fill.iter().map(|k| (pack(k), [1.0; 8])));
    m
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

/// The tables and maps of one slot count, filled, and the queries packed for the maps.
struct Lookups {
    s: Sized,
    t: HashTable<State>,
    brown: hashbrown::HashMap<u64, State>,
    brown_quarter: hashbrown::HashMap<u64, State>,
    fx: HashMap<u64, State, FxBuildHasher>,
    std_map: HashMap<u64, State>,
    packed: Vec<u64>,
}

fn bench_lookup(c: &mut Criterion) {
    for bits in slot_bits() {
        let s = sized(bits);
        let l = Lookups {
            t: table(&s),
            brown: hashbrown_map(&s),
            brown_quarter: hashbrown_map_at_load_quarter(&s),
            fx: map(&s),
            std_map: map(&s),
            packed: s.queries.iter().map(pack).collect(),
            s,
        };
        let mut slots = vec![None; l.s.queries.len()];
        bench_lookup_warm(c, bits, &l, &mut slots);
        bench_lookup_cold(c, bits, &l, &mut slots);
    }
}

/// Group `peers_lookup` at `2^bits` slots: the lookups with warm caches.
fn bench_lookup_warm(c: &mut Criterion, bits: u32, l: &Lookups, slots: &mut [Option<u32>]) {
    let id = |name: &str| BenchmarkId::new(name, format!("2^{bits}"));
    let mut g = c.benchmark_group("peers_lookup");
    g.throughput(Throughput::Elements(l.s.queries.len() as u64));
    g.bench_function(id("mcg_get"), |b| b.iter(|| get_pass(&l.t, &l.s.queries)));
    g.bench_function(id("mcg_find_many"), |b| {
        b.iter(|| find_many_pass(&l.t, &l.s.queries, slots))
    });
    g.bench_function(id("mcg_get_many"), |b| {
        b.iter(|| get_many_pass(&l.t, &l.s.queries))
    });
    g.bench_function(id("mcg_find_no_value"), |b| {
        b.iter(|| find_pass(&l.t, &l.s.queries))
    });
    g.bench_function(id("hashbrown_foldhash"), |b| {
        b.iter(|| hashbrown_pass(&l.brown, &l.packed))
    });
    g.bench_function(id("fxhashmap"), |b| {
        b.iter(|| hashmap_pass(&l.fx, &l.packed))
    });
    g.bench_function(id("std_hashmap"), |b| {
        b.iter(|| hashmap_pass(&l.std_map, &l.packed))
    });
    g.finish();
}

/// Group `peers_lookup_cold` at `2^bits` slots: each pass after flushing the structure.
fn bench_lookup_cold(c: &mut Criterion, bits: u32, l: &Lookups, slots: &mut [Option<u32>]) {
    let id = |name: &str| BenchmarkId::new(name, format!("2^{bits}"));
    let mut g = c.benchmark_group("peers_lookup_cold");
    g.throughput(Throughput::Elements(l.s.queries.len() as u64));
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(3));
    g.bench_function(id("mcg_get"), |b| {
        b.iter_custom(|n| {
            timed(
                n,
                &mut (),
                |_| flush_table(&l.t),
                |_| {
                    black_box(get_pass(&l.t, &l.s.queries));
                },
            )
        })
    });
    g.bench_function(id("mcg_find_no_value"), |b| {
        b.iter_custom(|n| {
            timed(
                n,
                &mut (),
                |_| flush_table(&l.t),
                |_| {
                    black_box(find_pass(&l.t, &l.s.queries));
                },
            )
        })
    });
    g.bench_function(id("mcg_find_many"), |b| {
        b.iter_custom(|n| {
            timed(
                n,
                &mut &mut *slots,
                |_| flush_table(&l.t),
                |sl| {
                    black_box(find_many_pass(&l.t, &l.s.queries, sl));
                },
            )
        })
    });
    g.bench_function(id("mcg_get_many"), |b| {
        b.iter_custom(|n| {
            timed(
                n,
                &mut (),
                |_| flush_table(&l.t),
                |_| {
                    black_box(get_many_pass(&l.t, &l.s.queries));
                },
            )
        })
    });
    for (name, map) in [
        ("hashbrown_foldhash", &l.brown),
        ("hashbrown_load_quarter", &l.brown_quarter),
    ] {
        g.bench_function(id(name), |b| {
            b.iter_custom(|n| {
                timed(
                    n,
                    &mut (),
                    |_| flush_entries(map.iter(), map.capacity()),
                    |_| {
                        black_box(hashbrown_pass(map, &l.packed));
                    },
                )
            })
        });
    }
    g.bench_function(id("fxhashmap"), |b| {
        b.iter_custom(|n| {
            timed(
                n,
                &mut (),
                |_| flush_entries(l.fx.iter(), l.fx.capacity()),
                |_| {
                    black_box(hashmap_pass(&l.fx, &l.packed));
                },
            )
        })
    });
    g.finish();
}

fn bench_insert(c: &mut Criterion) {
    for bits in slot_bits() {
        let s = sized(bits);
        let keys = &s.fill;
        let packed: Vec<u64> = keys.iter().map(pack).collect();
        let id = |name: &str| BenchmarkId::new(name, format!("2^{bits}"));
        let mut g = c.benchmark_group("peers_insert");
        g.throughput(Throughput::Elements(keys.len() as u64));
        g.sample_size(10);
        g.measurement_time(Duration::from_secs(3));
        let mut t = HashTable::<State>::new(1 << bits, MAX_PROBES, bench_hash()).unwrap();
        g.bench_function(id("mcg_entry"), |b| {
            b.iter_custom(|n| timed(n, &mut t, HashTable::clear, |t| insert_pass(t, keys)))
        });
        let mut brown = hashbrown::HashMap::<u64, State>::with_capacity(keys.len());
        g.bench_function(id("hashbrown_foldhash"), |b| {
            b.iter_custom(|n| {
                timed(n, &mut brown, hashbrown::HashMap::clear, |m| {
                    hashbrown_insert_pass(m, &packed)
                })
            })
        });
        let mut fx = FxHashMap::<u64, State>::with_capacity_and_hasher(keys.len(), FxBuildHasher);
        g.bench_function(id("fxhashmap"), |b| {
            b.iter_custom(|n| {
                timed(n, &mut fx, HashMap::clear, |m| {
                    hashmap_insert_pass(m, &packed)
                })
            })
        });
        let mut std_map = HashMap::<u64, State>::with_capacity(keys.len());
        g.bench_function(id("std_hashmap"), |b| {
            b.iter_custom(|n| {
                timed(n, &mut std_map, HashMap::clear, |m| {
                    hashmap_insert_pass(m, &packed)
                })
            })
        });
        g.finish();
    }
}

fn bench_concurrent(c: &mut Criterion) {
    for bits in slot_bits() {
        let s = sized(bits);
        let keys = &s.fill;
        let packed: Vec<u64> = keys.iter().map(pack).collect();
        let id = |name: &str| BenchmarkId::new(name, format!("2^{bits}"));
        let mut g = c.benchmark_group("peers_concurrent_insert");
        g.throughput(Throughput::Elements(keys.len() as u64));
        g.sample_size(10);
        g.measurement_time(Duration::from_secs(3));
        // In an RwLock only so that the bench can empty it between runs (`clear` takes
        // `&mut`); each worker takes the read lock once per run.
        let table = RwLock::new(ConcurrentTable::new(1 << bits, MAX_PROBES, bench_hash()).unwrap());
        two_thread_fill(
            &mut g,
            id("mcg_concurrent_table"),
            |w, n| {
                let t = table.read().unwrap();
                let mut inserted = 0_u32;
                for k in black_box(pool::share(keys, w, n)) {
                    inserted += u32::from(t.insert_or_get(k).is_inserted());
                }
                black_box(inserted);
            },
            || table.write().unwrap().clear(),
        );
        // The table with a separate value array, each insert adding 1 to its value's first
        // word: the layout `ConcurrentSlots` puts in one line.
        let values: Vec<[AtomicU32; 8]> = (0..1u32 << bits).map(|_| Default::default()).collect();
        two_thread_fill(
            &mut g,
            id("mcg_concurrent_table_values"),
            |w, n| {
                let t = table.read().unwrap();
                for k in black_box(pool::share(keys, w, n)) {
                    if let Some(value) = t.insert_or_get(k).slot().map(|s| &values[s as usize]) {
                        value[0].fetch_add(1, Ordering::Relaxed);
                    }
                }
            },
            || table.write().unwrap().clear(),
        );
        // The same inserts into the table that holds its values, each also adding 1 to its
        // value's first word (as the peers below do to theirs).
        let slots = RwLock::new(
            ConcurrentSlots::<[AtomicU32; 8]>::new(1 << bits, MAX_PROBES, bench_hash()).unwrap(),
        );
        two_thread_fill(
            &mut g,
            id("mcg_concurrent_slots"),
            |w, n| {
                let t = slots.read().unwrap();
                for k in black_box(pool::share(keys, w, n)) {
                    if let Some(value) = t.insert_or_get(k).slot().and_then(|s| t.value(s)) {
                        value[0].fetch_add(1, Ordering::Relaxed);
                    }
                }
            },
            || slots.write().unwrap().clear(),
        );
        let dash: DashMap<u64, State, FxBuildHasher> =
            DashMap::with_capacity_and_hasher(keys.len(), FxBuildHasher);
        two_thread_fill(
            &mut g,
            id("dashmap_fx"),
            |w, n| {
                for &k in black_box(pool::share(&packed, w, n)) {
                    dash.entry(k).or_insert([0.0; 8])[0] += 1.0;
                }
            },
            || dash.clear(),
        );
        let locked = Mutex::new(FxHashMap::<u64, State>::with_capacity_and_hasher(
            keys.len(),
            FxBuildHasher,
        ));
        two_thread_fill(
            &mut g,
            id("mutex_fxhashmap"),
            |w, n| {
                for &k in black_box(pool::share(&packed, w, n)) {
                    locked.lock().unwrap().entry(k).or_insert([0.0; 8])[0] += 1.0;
                }
            },
            || locked.lock().unwrap().clear(),
        );
        g.finish();
    }
}

/// One case of `group`: `fill(worker, workers)` on the pool's two threads per run, each run
/// timed from the first worker's start to the last one's end, the map emptied by `reset`
/// before it (untimed).
fn two_thread_fill(
    group: &mut BenchmarkGroup<'_, WallTime>,
    id: BenchmarkId,
    fill: impl Fn(usize, usize) + Sync,
    reset: impl Fn(),
) {
    pool::with_workers(fill, |workers| {
        group.bench_function(id, |b| {
            b.iter_custom(|n| (0..n).map(|_| workers.run(2, &reset)).sum())
        });
    });
}

criterion_group!(benches, bench_lookup, bench_insert, bench_concurrent);
criterion_main!(benches);
