//! The renderer key streams shared by the criterion bench (`benches/hashgrid.rs`) and the
//! min-of-runs probe (`examples/speed.rs`).
//!
//! A camera 1.7 units above the floor of a 40 × 40 × 10 room renders `WIDTH × WIDTH` pixels and
//! turns by 0.11 rad per frame; each pixel's hit gives MCPG's adaptive-grid key (level from
//! distance with the geometric jitter, so several levels at once; stochastic trilinear corner;
//! normal class) from seeded uniforms. The tables hold the distinct keys of [`FILL_FRAMES`]
//! frames; the lookups are the keys of one of those frames again, in the order a renderer
//! visits its pixels:
//!
//! - `scanline`: row by row (a CPU tracer's loop over the image);
//! - `tiles`: 8 × 8 pixel tiles, row-major inside a tile (a GPU compute dispatch's
//!   workgroups, or a CPU tracer's buckets);
//! - `random`: the same keys shuffled (no coherence at all: the honest worst case).

#![allow(dead_code)]

use mcg_hashgrid::glam::{Vec2, Vec3};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, CellKey, next_prime};
use mcg_test_support::hit_room;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Image width and height in pixels.
pub const WIDTH: u32 = 256;
/// Frames whose keys fill the tables.
pub const FILL_FRAMES: usize = 8;
/// Tile edge of the `tiles` order.
pub const TILE: u32 = 8;

/// One frame's keys, indexed by pixel `j * WIDTH + i` (scanline order).
fn frame_keys(grid: &AdaptiveGrid, frame: usize, rng: &mut Pcg64Mcg) -> Vec<CellKey> {
    frame_keys_from(grid, Vec3::new(0.0, 1.7, 0.0), frame as f32 * 0.11, rng)
}

/// One frame's keys seen from `camera` turned by `yaw` radians.
fn frame_keys_from(
    grid: &AdaptiveGrid,
    camera: Vec3,
    yaw: f32,
    rng: &mut Pcg64Mcg,
) -> Vec<CellKey> {
    let (sin, cos) = yaw.sin_cos();
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
pub fn pack(k: &CellKey) -> u64 {
    let c = |v: i32| (v as u64) & 0x3_FFFF;
    c(k.cell.x)
        | c(k.cell.y) << 18
        | c(k.cell.z) << 36
        | u64::from(k.level & 0x3F) << 54
        | u64::from(k.class & 7) << 60
}

/// The keys and query orders of the benches.
pub struct Inputs {
    /// Distinct keys of the fill frames, in first-seen order.
    pub fill: Vec<CellKey>,
    /// Every pixel's key of all fill frames, frame after frame in scanline order (repeats
    /// included: what a renderer inserts per frame).
    pub pixels: Vec<CellKey>,
    /// One frame's keys in scanline order.
    pub scanline: Vec<CellKey>,
    /// The same keys in 8 × 8 tiles.
    pub tiles: Vec<CellKey>,
    /// The same keys shuffled.
    pub random: Vec<CellKey>,
    /// Next prime ≥ `pow2`.
    pub prime: u32,
    /// Smallest power of two ≥ 3 · `fill.len()`.
    pub pow2: u32,
}

/// Builds the streams (deterministic).
pub fn inputs() -> Inputs {
    let grid = AdaptiveGrid::mcpg();
    let mut rng = Pcg64Mcg::seed_from_u64(0x4847);
    let frames: Vec<Vec<CellKey>> = (0..FILL_FRAMES)
        .map(|f| frame_keys(&grid, f, &mut rng))
        .collect();
    let mut seen = std::collections::HashSet::new();
    let mut fill = Vec::new();
    for f in &frames {
        fill.extend(f.iter().copied().filter(|k| seen.insert(*k)));
    }
    let scanline = frames[FILL_FRAMES / 2].clone();
    let pixels = frames.concat();
    let mut tiles = Vec::with_capacity(scanline.len());
    for tj in (0..WIDTH).step_by(TILE as usize) {
        for ti in (0..WIDTH).step_by(TILE as usize) {
            for j in tj..tj + TILE {
                for i in ti..ti + TILE {
                    tiles.push(scanline[(j * WIDTH + i) as usize]);
                }
            }
        }
    }
    let mut random = scanline.clone();
    for i in (1..random.len()).rev() {
        let j = rng.random_range(0..=i);
        random.swap(i, j);
    }
    let n = fill.len() as u32;
    let pow2 = (3 * n).next_power_of_two();
    Inputs {
        fill,
        pixels,
        scanline,
        tiles,
        random,
        prime: next_prime(pow2).unwrap(),
        pow2,
    }
}

/// The peer benches' sizes: log₂ of the slot counts, from `MCG_BENCH_SLOTS` (e.g.
/// `16,19,22,24`), else 16 and 19 (what a default run on 2 cores affords).
pub fn slot_bits() -> Vec<u32> {
    std::env::var("MCG_BENCH_SLOTS")
        .ok()
        .map(|s| {
            s.split(',')
                .map(|b| {
                    b.trim()
                        .parse()
                        .expect("MCG_BENCH_SLOTS: comma-separated log2 sizes")
                })
                .collect()
        })
        .unwrap_or_else(|| vec![16, 19])
}

/// The bucket hash of the peer benches' tables: `MCG_BENCH_HASH` (a [`BucketHash::name`], e.g.
/// `mix`), else the default.
pub fn bench_hash() -> BucketHash {
    std::env::var("MCG_BENCH_HASH").map_or(BucketHash::default(), |name| {
        BucketHash::ALL
            .into_iter()
            .find(|h| h.name() == name)
            .expect("MCG_BENCH_HASH: xor-primes, mix, mix-coherent or fold")
    })
}

/// A table of `1 << bits` slots filled to load 1/4, and the lookups of a renderer.
pub struct Sized {
    /// log₂ of the slot count.
    pub bits: u32,
    /// `(1 << bits) / 4` distinct keys, in first-seen order.
    pub fill: Vec<CellKey>,
    /// 65 536 pixels' keys that are in `fill`, in the order the frames visited them
    /// (scanline, frame after frame; repeated when the frames had fewer).
    pub queries: Vec<CellKey>,
}

/// The keys of frames seen from random camera positions and headings in the room (seeded),
/// until `(1 << bits) / 4` distinct keys: 16 384 for 2¹⁶ slots, 4 194 304 for 2²⁴.
pub fn sized(bits: u32) -> Sized {
    let grid = AdaptiveGrid::mcpg();
    let mut rng = Pcg64Mcg::seed_from_u64(0x5153 + u64::from(bits));
    let n = (1_usize << bits) / 4;
    let mut seen = std::collections::HashSet::with_capacity(n);
    let mut fill = Vec::with_capacity(n);
    let mut pixels = Vec::new();
    while fill.len() < n {
        let camera = Vec3::new(
            rng.random_range(-18.0..18.0),
            rng.random_range(0.5..9.0),
            rng.random_range(-18.0..18.0),
        );
        let keys = frame_keys_from(&grid, camera, rng.random_range(0.0..6.3), &mut rng);
        for k in &keys {
            if fill.len() < n && seen.insert(*k) {
                fill.push(*k);
            }
        }
        if pixels.len() < 1 << 16 {
            pixels.extend(keys.into_iter().filter(|k| seen.contains(k)));
        }
    }
    // Small tables: the first frames' hits repeated up to 65 536 lookups.
    let seen_pixels = pixels.len();
    while pixels.len() < 1 << 16 {
        pixels.push(pixels[pixels.len() - seen_pixels]);
    }
    pixels.truncate(1 << 16);
    Sized {
        bits,
        fill,
        queries: pixels,
    }
}
