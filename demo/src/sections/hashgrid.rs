//! Section "World-space hash grids": probe lengths and failed inserts against the load factor,
//! and the memory of MCPG's configuration.
//!
//! 1. [`load_sweep`]: fill a [`HashTable`] with the adaptive-grid keys that a camera in a box
//!    room produces, frame after frame, and record at each load factor the mean probe length of
//!    a successful lookup and the rate of failed inserts (probe limit reached), for each bucket
//!    hash (xor of primes, mix) and capacity choice (prime → modulo, power of two → mask).
//! 2. A memory table for MCPG's 10⁶ slots.

use std::collections::HashSet;

use mcg_hashgrid::constants::DEFAULT_MAX_PROBES;
use mcg_hashgrid::glam::{Vec2, Vec3};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, CellKey, HashTable, Insert, next_prime};
use mcg_tests::hit_room;
use plotters::style::RGBColor;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Context;
use crate::plot::{self, Axis, LineChart, PALETTE, Series, SeriesLabelPosition};
use crate::report::{Section, Table};
use crate::{Config, Result, group_thousands};

/// Load factors at which the sweep reports, 0.05 to 0.95.
pub const LOADS: [f64; 19] = [
    0.05, 0.10, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40, 0.45, 0.50, 0.55, 0.60, 0.65, 0.70, 0.75, 0.80,
    0.85, 0.90, 0.95,
];

/// Colour of the random-key reference (brown) and of Knuth's formula (black).
const REFERENCE_COLOR: RGBColor = RGBColor(140, 86, 75);
const KNUTH_COLOR: RGBColor = RGBColor(0, 0, 0);

/// Failed-insert rates are drawn clamped to this floor on the log axis (0 is drawn there).
const RATE_FLOOR: f64 = 1e-5;

/// One capacity choice of the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Capacity {
    /// A prime number of slots: `h mod B`.
    Prime(u32),
    /// A power of two: `h & (B − 1)`.
    PowerOfTwo(u32),
}

impl Capacity {
    /// Number of slots.
    pub fn slots(self) -> u32 {
        match self {
            Capacity::Prime(n) | Capacity::PowerOfTwo(n) => n,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Capacity::Prime(_) => "prime (mod)",
            Capacity::PowerOfTwo(_) => "2ⁿ (mask)",
        }
    }
}

/// What the sweep measured at one load factor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadPoint {
    /// Occupied slots / capacity.
    pub load: f64,
    /// Mean probe length of a successful lookup of every key in the table.
    pub mean_probe: f64,
    /// Failed inserts / insert attempts of new keys since the previous load point.
    pub failed_rate: f64,
}

/// At least `count` distinct adaptive-grid keys (MCPG defaults) from frames of a `width²`
/// camera in a box room that turns a little every frame, each pixel with seeded uniforms for
/// the level jitter and the trilinear corner; in order of first appearance.
pub fn room_keys(count: usize, width: u32, seed: u64) -> Vec<CellKey> {
    let grid = AdaptiveGrid::mcpg();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let camera = Vec3::new(0.0, 1.7, 0.0);
    let mut seen = HashSet::new();
    let mut keys = Vec::with_capacity(count);
    for frame in 0..200 {
        let yaw = frame as f32 * 0.11;
        let (s, c) = yaw.sin_cos();
        for j in 0..width {
            for i in 0..width {
                let p = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) / width as f32 * 2.0 - 1.0;
                let d = Vec3::new(p.x, -p.y - 0.3, -1.0);
                let dir = Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z).normalize();
                let (hit, n) = hit_room(camera, dir);
                let key = grid.vertex_key(hit, n, camera, rng.random(), rng.random());
                if seen.insert(key) {
                    keys.push(key);
                    if keys.len() == count {
                        return keys;
                    }
                }
            }
        }
    }
    keys
}

/// Inserts `keys` in order into a table of `capacity` slots with `hash` and the default probe
/// limit, and reports at each of [`LOADS`] (as long as keys last).
pub fn load_sweep(
    keys: &[CellKey],
    capacity: Capacity,
    hash: BucketHash,
) -> Result<Vec<LoadPoint>> {
    let cap = capacity.slots();
    let mut table = HashTable::<u32>::new(cap, DEFAULT_MAX_PROBES, hash)?;
    let mut probe_sum = 0_u64;
    let (mut attempts, mut failed) = (0_u64, 0_u64);
    let mut points = Vec::new();
    let mut next = 0;
    for key in keys {
        if next == LOADS.len() {
            break;
        }
        let home = table.home_slot(key);
        attempts += 1;
        match table.insert_or_get(key) {
            Insert::Inserted(slot) => probe_sum += u64::from((slot + cap - home) % cap) + 1,
            Insert::Found(_) => attempts -= 1,
            Insert::Full => failed += 1,
        }
        let load = table.load_factor();
        if load >= LOADS[next] {
            points.push(LoadPoint {
                load,
                mean_probe: probe_sum as f64 / f64::from(table.len()),
                failed_rate: failed as f64 / attempts.max(1) as f64,
            });
            (attempts, failed) = (0, 0);
            next += 1;
        }
    }
    Ok(points)
}

/// Knuth's mean probe count of a successful search with linear probing and ideal hashing,
/// ½(1 + 1/(1 − α)) (TAOCP vol. 3, sec. 6.4), without a probe limit.
pub fn knuth_successful(load: f64) -> f64 {
    0.5 * (1.0 + 1.0 / (1.0 - load))
}

/// Builds the section.
pub fn build(ctx: &Context<'_>) -> Result<Section> {
    let mut section = Section::new("hashgrid", "World-space hash grids");
    section.paragraph(
        "MCPG stores its Markov chain states at the vertices of world-space hash grids (MCPG \
         sec. 4, \"Hash Grid\"): a vertex key (integer coordinate, level, normal class) is \
         hashed to a home slot `hash(key) mod B`, and a separate 32-bit checksum in the slot tells \
         whether it holds this key. `mcg_hashgrid::HashTable` probes at most 8 consecutive \
         slots (wrapping at the end) and answers `Full` beyond. How far it probes, and how \
         often it gives up, depends on the load factor, on the bucket hash and on how the hash \
         is reduced to a slot: a prime capacity uses every bit of the hash (modulo), a power \
         of two only its low bits (mask).",
    );
    load_sweeps(ctx, &mut section)?;
    memory(&mut section);
    Ok(section)
}

/// The load sweeps of every hash and capacity over one key stream, and the ideal-hashing
/// reference.
struct LoadSweeps {
    /// Pixels per image side of the key stream.
    width: u32,
    /// Distinct keys inserted.
    keys: usize,
    /// The prime capacity.
    prime: u32,
    /// The power-of-two capacity.
    pow2: u32,
    /// One sweep per (hash, capacity).
    results: Vec<(BucketHash, Capacity, Vec<LoadPoint>)>,
    /// Keys with random coordinates, mix hash, prime capacity.
    reference: Vec<LoadPoint>,
}

/// The load-sweep subsection: compute, charts, text and table.
fn load_sweeps(ctx: &Context<'_>, section: &mut Section) -> Result<()> {
    let sweeps = compute_load_sweeps(ctx)?;
    let (probe_file, rate_file) = load_sweep_charts(ctx, &sweeps)?;
    load_sweep_text(section, &sweeps, probe_file, rate_file);
    Ok(())
}

/// Runs the sweeps: room keys into every (hash, capacity), random keys as the reference.
fn compute_load_sweeps(ctx: &Context<'_>) -> Result<LoadSweeps> {
    let full = ctx.config.samples >= Config::DEFAULT_SAMPLES;
    let pow2: u32 = if full { 1 << 16 } else { 1 << 13 };
    let prime = next_prime(pow2).ok_or("no prime")?;
    let width = if full { 256 } else { 128 };
    let bar = ctx.progress(6, "hash grid load sweeps");
    let keys = room_keys(prime as usize, width, ctx.config.seed);
    let configs = [
        (BucketHash::XorPrimes, Capacity::Prime(prime)),
        (BucketHash::XorPrimes, Capacity::PowerOfTwo(pow2)),
        (BucketHash::Mix, Capacity::Prime(prime)),
        (BucketHash::Mix, Capacity::PowerOfTwo(pow2)),
        (BucketHash::MixCoherent, Capacity::Prime(prime)),
        (BucketHash::MixCoherent, Capacity::PowerOfTwo(pow2)),
    ];
    let mut results = Vec::new();
    for (hash, cap) in configs {
        results.push((hash, cap, load_sweep(&keys, cap, hash)?));
        bar.inc(1);
    }
    bar.finish_and_clear();
    // Reference: keys with random coordinates, i.e. ideal hashing with the same probe limit.
    let mut rng = Pcg64Mcg::seed_from_u64(ctx.config.seed ^ 0x4847);
    let random_keys: Vec<CellKey> = (0..prime)
        .map(|_| CellKey::new(rng.random::<[i32; 3]>().into(), 0, 0))
        .collect();
    let reference = load_sweep(&random_keys, Capacity::Prime(prime), BucketHash::Mix)?;
    Ok(LoadSweeps {
        width,
        keys: keys.len(),
        prime,
        pow2,
        results,
        reference,
    })
}

/// The probe-length and failed-insert charts; returns their file names.
fn load_sweep_charts(
    ctx: &Context<'_>,
    sweeps: &LoadSweeps,
) -> Result<(&'static str, &'static str)> {
    let LoadSweeps {
        results, reference, ..
    } = sweeps;
    let label = |h: BucketHash, c: Capacity| format!("{}, {}", h.name(), c.name());
    let probes = |points: &[LoadPoint]| -> Vec<(f64, f64)> {
        points.iter().map(|p| (p.load, p.mean_probe)).collect()
    };
    let rates = |points: &[LoadPoint]| -> Vec<(f64, f64)> {
        points
            .iter()
            .map(|p| (p.load, p.failed_rate.max(RATE_FLOOR)))
            .collect()
    };
    let mut probe_series = Vec::new();
    let mut rate_series = Vec::new();
    for (i, (hash, cap, points)) in results.iter().enumerate() {
        probe_series.push(Series::line(
            &label(*hash, *cap),
            PALETTE[i],
            probes(points),
        ));
        rate_series.push(Series::line(&label(*hash, *cap), PALETTE[i], rates(points)));
    }
    probe_series.push(Series::dots(
        "random keys (ideal hashing), same limit",
        REFERENCE_COLOR,
        probes(reference),
    ));
    rate_series.push(Series::dots(
        "random keys (ideal hashing)",
        REFERENCE_COLOR,
        rates(reference),
    ));
    probe_series.push(Series::dots(
        "Knuth ½(1 + 1/(1 − α)), no limit",
        KNUTH_COLOR,
        LOADS.iter().map(|&a| (a, knuth_successful(a))).collect(),
    ));
    let probe_file = "hashgrid-probe-length.png";
    plot::line_chart(
        &ctx.figure_path(probe_file),
        (1100, 620),
        &LineChart {
            title: "Mean probe length of a successful lookup".to_owned(),
            x: Axis::linear("load factor α", 0.0..1.0),
            y: Axis::linear("slots read", 1.0..4.0),
            series: probe_series,
            legend: SeriesLabelPosition::UpperLeft,
        },
    )?;
    let rate_file = "hashgrid-failed-inserts.png";
    plot::line_chart(
        &ctx.figure_path(rate_file),
        (1100, 620),
        &LineChart {
            title: format!("Failed inserts (probe limit {DEFAULT_MAX_PROBES})"),
            x: Axis::linear("load factor α", 0.0..1.0),
            y: Axis::log10("failed / attempted inserts", RATE_FLOOR..1.0),
            series: rate_series,
            legend: SeriesLabelPosition::UpperLeft,
        },
    )?;
    Ok((probe_file, rate_file))
}

/// The text, the figure captions, the table at three load factors and the summary.
fn load_sweep_text(section: &mut Section, sweeps: &LoadSweeps, probe_file: &str, rate_file: &str) {
    let LoadSweeps {
        width,
        keys,
        prime,
        pow2,
        results,
        reference,
    } = sweeps;
    section.paragraph(&format!(
        "Key stream: a camera 1.7 units above the floor of a 40 × 40 × 10 room renders {width}² \
         pixels per frame and turns by 0.11 rad between frames; each hit gives MCPG's \
         adaptive-grid key (default 0.6° resolution, level jitter and stochastic trilinear \
         corner from seeded uniforms, normal class of the wall). The first {} distinct keys \
         are inserted in order of appearance into tables of {} (prime) and {} (2ⁿ) slots.",
        group_thousands(*keys),
        group_thousands(*prime as usize),
        group_thousands(*pow2 as usize),
    ));
    section.figure(
        probe_file,
        "Mean number of slots a successful lookup reads, over every key in the table, against \
         the load factor; dots: Knuth's formula for ideal hashing without a probe limit.",
    );
    section.figure(
        rate_file,
        &format!(
            "Failed inserts (all {DEFAULT_MAX_PROBES} probed slots taken) among the new keys \
             inserted since the previous load point; zero is drawn at {RATE_FLOOR:e}."
        ),
    );
    section.table(load_table(sweeps));
    let rate_at = |points: &[LoadPoint], target: f64| {
        points
            .iter()
            .find(|p| p.load >= target)
            .map_or(f64::NAN, |p| p.failed_rate)
    };
    let mut summary =
        String::from("Failed inserts in the window ending at α = 0.25 and at α = 0.5: ");
    for (hash, cap, points) in results {
        summary.push_str(&format!(
            "{}, {}: {:.1e} / {:.1e}; ",
            hash.name(),
            cap.name(),
            rate_at(points, 0.25),
            rate_at(points, 0.5)
        ));
    }
    summary.push_str(&format!(
        "random keys (ideal hashing): {:.1e} / {:.1e}. Linear probing clusters, so even ideal \
         hashing loses inserts at α = 0.5 with a limit of {DEFAULT_MAX_PROBES} probes: size \
         the buffer for α ≲ 0.25, or raise the limit. The mean probe length stays below \
         Knuth's curve because keys that would need more than {DEFAULT_MAX_PROBES} slots are \
         rejected instead of stored far from home.",
        rate_at(reference, 0.25),
        rate_at(reference, 0.5),
    ));
    section.paragraph(&summary);
}

/// The probe length and failed-insert rate of each sweep (and of random keys) at the first
/// load points past α = 0.5, 0.75 and 0.9.
fn load_table(sweeps: &LoadSweeps) -> Table {
    let LoadSweeps {
        prime,
        results,
        reference,
        ..
    } = sweeps;
    let mut table = Table::new(
        "Probe length and failed inserts at three load factors",
        ["hash", "capacity", "α", "mean probe", "failed inserts"],
    );
    let rows = results
        .iter()
        .map(|(hash, cap, points)| (hash.name(), cap.name(), points))
        .chain([(
            "mix, random keys",
            Capacity::Prime(*prime).name(),
            reference,
        )]);
    for (hash, cap, points) in rows {
        for target in [0.5, 0.75, 0.9] {
            if let Some(p) = points.iter().find(|p| p.load >= target) {
                table.push_row([
                    hash.to_owned(),
                    cap.to_owned(),
                    format!("{:.2}", p.load),
                    format!("{:.3}", p.mean_probe),
                    format!("{:.2e}", p.failed_rate),
                ]);
            }
        }
    }
    table
}

fn memory(section: &mut Section) {
    const SLOTS: f64 = 1e6;
    let mb = |bytes_per_slot: f64| format!("{:.0} MB", bytes_per_slot * SLOTS / 1e6);
    let ours = std::mem::size_of::<[f32; 8]>() + std::mem::size_of::<u32>();
    let table = Table::new(
        "Memory of MCPG's adaptive-grid buffer, 10⁶ slots (MCPG sec. 6: 0.6° resolution, 10⁶ \
         slots, 44 MB)",
        ["layout", "bytes per slot", "10⁶ slots"],
    )
    .row([
        "MCPG paper: 44-byte state with the 16-bit key hash inside (Table 1)".to_owned(),
        "44".to_owned(),
        mb(44.0),
    ])
    .row([
        "merian-quake later: 36-byte state (f16 velocity, u16 N, u16 hash)".to_owned(),
        "36".to_owned(),
        mb(36.0),
    ])
    .row([
        "mcg: `HashTable<S>` with our MCPG state S ≤ 32 bytes + the u32 checksum array \
         (full 32-bit checksum)"
            .to_owned(),
        format!("≤ {ours} (32 + 4)"),
        mb(ours as f64),
    ])
    .row([
        "mcg with age tracking (one more u32 per slot)".to_owned(),
        format!("≤ {}", ours + 4),
        mb((ours + 4) as f64),
    ]);
    section.table(table);
    section.paragraph(
        "Our MCPG state (in `mcg-markov-guide`) will be at most 32 bytes; the checksum lives \
         in its own `u32` array beside the state array, so the key costs 4 bytes and keeps all \
         32 bits (false match ≈ 2⁻³² per pair, against 2⁻¹⁶ for a 16-bit hash in the state). \
         Both arrays upload to the GPU as they are; at 36 bytes per slot a single wgpu binding \
         of the default 128 MiB maximum holds the 32-byte state array of up to 4.19 million \
         slots.",
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_reports_increasing_loads() {
        let keys = room_keys(3000, 64, 7);
        assert_eq!(keys.len(), 3000);
        let points = load_sweep(&keys, Capacity::Prime(3001), BucketHash::Mix).unwrap();
        assert!(points.len() >= 15);
        assert!(points.windows(2).all(|w| w[0].load < w[1].load));
        assert!(points[0].mean_probe >= 1.0 && points[0].mean_probe < 1.2);
        mcg_tests::assert_close!(knuth_successful(0.5), 1.5, 1e-12);
    }
}
