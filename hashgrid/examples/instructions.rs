//! One case of the peer benches (`benches/peers.rs`) run a given number of times, for
//! instruction counting under valgrind: `scripts/hashgrid-instructions` runs each case with 1
//! and with 3 passes under `callgrind` and divides the difference of the two instruction
//! totals by 2 · queries, so building the stream and the tables cancels out.
//!
//! `cargo run --release -p mcg-hashgrid --example instructions -- CASE BITS PASSES`, with
//! `MCG_BENCH_HASH` picks the table's hash as in the benches. CASE one of `mcg_get`, `mcg_find_many`, `mcg_get_many`, `hashbrown_get`, `fx_get`, `std_get`,
//! `mcg_insert`, `hashbrown_insert`, `fx_insert`, or the diagnostics `mcg_find` (`find` without
//! the value read) and `interleaved36_get` / `interleaved64_get` (`benches/common/interleaved.rs`:
//! a prototype with each checksum beside its value); BITS the log₂ of the slot count. With a
//! fourth argument `time`, it also prints the fastest pass in ns per operation (a quick
//! min-of-runs check; the criterion bench is the reference); with `cold` instead, every
//! lookup pass starts with the structure flushed from the caches (`common/flush.rs`, untimed),
//! as in the bench's `peers_lookup_cold`.

use std::collections::HashMap;
use std::time::Instant;

use mcg_hashgrid::HashTable;
use rustc_hash::FxBuildHasher;

#[path = "../benches/common/flush.rs"]
mod flush;
#[path = "../benches/common/interleaved.rs"]
mod interleaved;
#[path = "../benches/common/lookups.rs"]
mod lookups;
#[path = "../benches/common/stream.rs"]
mod stream;

use lookups::{State, find_many_pass, get_many_pass, get_pass};
use stream::{pack, sized};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: instructions CASE BITS PASSES";
    let case = args.get(1).expect(usage).as_str();
    let bits: u32 = args.get(2).expect(usage).parse().expect(usage);
    let passes: usize = args.get(3).expect(usage).parse().expect(usage);
    let s = sized(bits);
    let packed: Vec<u64> = s.queries.iter().map(pack).collect();
    let fill: Vec<u64> = s.fill.iter().map(pack).collect();
    let mut table = HashTable::<State>::new(1 << bits, 16, stream::bench_hash()).unwrap();
    let timing = args.get(4).is_some_and(|a| a == "time" || a == "cold");
    let cold = args.get(4).is_some_and(|a| a == "cold");
    let mut best = f64::INFINITY;
    // Called after each pass with its start: keeps the fastest pass.
    let mut lap = |t0: Instant, ops: usize| {
        best = best.min(t0.elapsed().as_secs_f64() * 1e9 / ops as f64);
    };
    let sum = match case {
        "mcg_get" | "mcg_find" | "mcg_find_many" | "mcg_get_many" | "mcg_insert" => {
            mcg_case(case, &s, &mut table, passes, cold, &mut lap)
        }
        "interleaved36_get" => interleaved_case::<9>(&s, bits, passes, cold, &mut lap),
        "interleaved64_get" => interleaved_case::<16>(&s, bits, passes, cold, &mut lap),
        "hashbrown_get" | "fx_get" | "std_get" => {
            get_case(case, &packed, &fill, passes, cold, &mut lap)
        }
        "hashbrown_insert" | "fx_insert" => insert_case(case, &fill, passes, &mut lap),
        _ => panic!("unknown case {case}; {usage}"),
    };
    let per_pass = if case.ends_with("_insert") {
        s.fill.len()
    } else {
        s.queries.len()
    };
    if timing {
        let caches = if cold { "cold" } else { "warm" };
        println!("{case} {bits} ({caches}): fastest pass {best:.2} ns per operation");
    }
    println!("{case} {bits} {passes} {per_pass} {sum}");
}

/// The table's cases (`mcg_get`, `mcg_find_many`, `mcg_insert`) run `passes` times; the sum.
fn mcg_case(
    case: &str,
    s: &stream::Sized,
    table: &mut HashTable<State>,
    passes: usize,
    cold: bool,
    lap: &mut impl FnMut(Instant, usize),
) -> f32 {
    let mut sum = 0.0_f32;
    match case {
        "mcg_get" | "mcg_find" | "mcg_find_many" | "mcg_get_many" => {
            let mut full = 0;
            for k in &s.fill {
                match table.entry(k) {
                    Some((v, _)) => v[0] = 1.0,
                    None => full += 1,
                }
            }
            eprintln!("{} keys, {full} did not fit", s.fill.len());
            let mut slots = vec![None; s.queries.len()];
            for _ in 0..passes {
                if cold {
                    flush::flush_table(table);
                }
                let t0 = Instant::now();
                sum += match case {
                    "mcg_get" => get_pass(table, &s.queries),
                    "mcg_find" => lookups::find_pass(table, &s.queries),
                    "mcg_get_many" => get_many_pass(table, &s.queries),
                    _ => find_many_pass(table, &s.queries, &mut slots),
                };
                lap(t0, s.queries.len());
            }
        }
        // Inserts: the fill keys into an emptied structure, `passes` times; a pass per
        // query count is reported by the script, so these print the key count to use.
        "mcg_insert" => {
            for _ in 0..passes {
                table.clear();
                let t0 = Instant::now();
                lookups::insert_pass(table, &s.fill);
                lap(t0, s.fill.len());
            }
            sum += table.len() as f32;
        }
        _ => unreachable!("not a table case: {case}"),
    }
    sum
}

/// The prototype of the checksum beside the value with `STRIDE`-word slots
/// (`interleaved36_get`: 9, packed; `interleaved64_get`: 16, aligned to the line), `passes`
/// lookup passes.
fn interleaved_case<const STRIDE: usize>(
    s: &stream::Sized,
    bits: u32,
    passes: usize,
    cold: bool,
    lap: &mut impl FnMut(Instant, usize),
) -> f32 {
    let mut table = interleaved::Interleaved::<STRIDE>::new(1 << bits, 16);
    let full = s
        .fill
        .iter()
        .filter(|k| !table.insert(k, &[1.0; 8]))
        .count();
    eprintln!("{} keys, {full} did not fit", s.fill.len());
    let mut sum = 0.0_f32;
    for _ in 0..passes {
        if cold {
            flush::flush(bytemuck::cast_slice(table.words()));
        }
        let t0 = Instant::now();
        sum += interleaved::interleaved_pass(&table, &s.queries);
        lap(t0, s.queries.len());
    }
    sum
}

/// The peer maps' lookup cases (`hashbrown_get`, `fx_get`, `std_get`) run `passes` times.
fn get_case(
    case: &str,
    packed: &[u64],
    fill: &[u64],
    passes: usize,
    cold: bool,
    lap: &mut impl FnMut(Instant, usize),
) -> f32 {
    let mut sum = 0.0_f32;
    match case {
        "hashbrown_get" => {
            let m: hashbrown::HashMap<u64, State> = fill.iter().map(|&k| (k, [1.0; 8])).collect();
            for _ in 0..passes {
                if cold {
                    flush::flush_entries(m.iter(), m.capacity());
                }
                let t0 = Instant::now();
                sum += lookups::hashbrown_pass(&m, packed);
                lap(t0, packed.len());
            }
        }
        "fx_get" => {
            let m: HashMap<u64, State, FxBuildHasher> =
                fill.iter().map(|&k| (k, [1.0; 8])).collect();
            for _ in 0..passes {
                if cold {
                    flush::flush_entries(m.iter(), m.capacity());
                }
                let t0 = Instant::now();
                sum += lookups::hashmap_pass(&m, packed);
                lap(t0, packed.len());
            }
        }
        "std_get" => {
            let m: HashMap<u64, State> = fill.iter().map(|&k| (k, [1.0; 8])).collect();
            for _ in 0..passes {
                let t0 = Instant::now();
                sum += lookups::hashmap_pass(&m, packed);
                lap(t0, packed.len());
            }
        }
        _ => unreachable!("not a peer lookup case: {case}"),
    }
    sum
}

/// The peer maps' insert cases (`hashbrown_insert`, `fx_insert`) run `passes` times.
fn insert_case(
    case: &str,
    fill: &[u64],
    passes: usize,
    lap: &mut impl FnMut(Instant, usize),
) -> f32 {
    let mut sum = 0.0_f32;
    match case {
        "hashbrown_insert" => {
            let mut m = hashbrown::HashMap::<u64, State>::with_capacity(fill.len());
            for _ in 0..passes {
                m.clear();
                let t0 = Instant::now();
                lookups::hashbrown_insert_pass(&mut m, fill);
                lap(t0, fill.len());
            }
            sum += m.len() as f32;
        }
        "fx_insert" => {
            let mut m = HashMap::<u64, State, FxBuildHasher>::with_capacity_and_hasher(
                fill.len(),
                FxBuildHasher,
            );
            for _ in 0..passes {
                m.clear();
                let t0 = Instant::now();
                lookups::hashmap_insert_pass(&mut m, fill);
                lap(t0, fill.len());
            }
            sum += m.len() as f32;
        }
        _ => unreachable!("not a peer insert case: {case}"),
    }
    sum
}
