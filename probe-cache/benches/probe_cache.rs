//! Criterion benchmarks of mcg-probe-cache, each group with its baseline in the same group so
//! that results read as ratios:
//!
//! - `texel_update_1thread`: [`ProbeTexels::update_irradiance`] (ADGI's 32-bit word, moving
//!   average in a CAS loop, stochastic rounding) vs the store a user would write: an RGB32F +
//!   count texel (`[f32; 4]`, 16 bytes) updated in place with the same moving average;
//!   `adgi_word_nonatomic` is the word update without the CAS (codec cost alone).
//! - `texel_update_2threads`: the same from two threads at once; the baseline needs
//!   synchronisation to lose nothing and takes the most natural one, a `std::sync::Mutex`
//!   per texel (a 4 × `AtomicU32` f32-bit CAS would not update the four fields as one).
//! - `irradiance_query`: [`ProbeTexels::irradiance_at`] (DDGI constants) vs the same query
//!   reading RGBA32F irradiance and RG32F distance-moment texels (same maps, same taps, same
//!   weights; only the texel fetch differs); also ADGI's radiance texels (cosine convolution).
//!
//! Updates hit random texels of a 16 × 16 × 8 grid (2048 probes × 64 texels, like ADGI's
//! Metropolis samples), [`UPDATES`] per iteration; queries use random points and normals in an
//! 8 × 8 × 8 grid (`irradiance_query`, texels in cache) and a 48 × 48 × 32 grid
//! (`irradiance_query_large_grid`, memory-bound), [`QUERIES`] per iteration. `main` also
//! prints bytes per probe.

use std::hint::black_box;
use std::sync::Mutex;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_probe_cache::glam::{UVec3, Vec2, Vec3};
use mcg_probe_cache::{ProbeGrid, ProbeTexels, QueryConfig, TexelConfig, TexelContent, TexelMap};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const UPDATES: usize = 16_384;
const QUERIES: usize = 1024;
const N_MAX: f32 = 63.0;

fn unit(rng: &mut Pcg64Mcg) -> Vec3 {
    let z: f32 = rng.random::<f32>() * 2.0 - 1.0;
    let phi: f32 = rng.random::<f32>() * core::f32::consts::TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// One update: (probe, texel, value, uniform).
type Update = (usize, usize, Vec3, f32);

fn updates(grid: &ProbeGrid, map: &TexelMap, n: usize, seed: u64) -> Vec<Update> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let probe = rng.random_range(0..grid.probe_count());
            let texel = map.index(map.texel(unit(&mut rng)));
            let v = Vec3::new(rng.random(), rng.random(), rng.random()) * 3.0;
            (probe, texel, v, rng.random())
        })
        .collect()
}

/// The baseline moving average on an RGB32F + count texel (same N_max).
#[inline(always)]
fn f32_update(t: &mut [f32; 4], v: Vec3) {
    let n = (t[3] + 1.0).min(N_MAX);
    let inv = 1.0 / n;
    t[0] += (v.x - t[0]) * inv;
    t[1] += (v.y - t[1]) * inv;
    t[2] += (v.z - t[2]) * inv;
    t[3] = n;
}

fn bench_updates(c: &mut Criterion) {
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(16, 16, 8)).unwrap();
    let map = TexelMap::ADGI_IRRADIANCE;
    let texel_count = grid.probe_count() * map.texel_count();
    let ups = updates(&grid, &map, UPDATES, 1);
    let adgi = ProbeTexels::new(grid, TexelConfig::ADGI);
    let mut plain = vec![[0.0f32; 4]; texel_count];

    let mut g = c.benchmark_group("texel_update_1thread");
    g.throughput(Throughput::Elements(UPDATES as u64));
    g.bench_function("adgi_word_cas", |b| {
        b.iter(|| {
            for &(p, t, v, u) in &ups {
                black_box(adgi.update_irradiance(p, t, v, u));
            }
        })
    });
    let mut words = vec![0u32; texel_count];
    let config = TexelConfig::ADGI;
    g.bench_function("adgi_word_nonatomic", |b| {
        b.iter(|| {
            for &(p, t, v, u) in &ups {
                let w = &mut words[p * 64 + t];
                *w = config.moving_average.update(
                    &config.irradiance_layout,
                    *w,
                    v,
                    config.rounding.with_uniform(u),
                );
            }
            black_box(&words);
        })
    });
    g.bench_function("rgb32f_count_baseline", |b| {
        b.iter(|| {
            for &(p, t, v, _) in &ups {
                f32_update(&mut plain[p * 64 + t], v);
            }
            black_box(&plain);
        })
    });
    g.finish();

    let halves = [
        updates(&grid, &map, UPDATES, 2),
        updates(&grid, &map, UPDATES, 3),
    ];
    let locked: Vec<Mutex<[f32; 4]>> = (0..texel_count).map(|_| Mutex::new([0.0; 4])).collect();
    let mut g = c.benchmark_group("texel_update_2threads");
    g.throughput(Throughput::Elements(2 * UPDATES as u64));
    g.bench_function("adgi_word_cas", |b| {
        b.iter(|| {
            std::thread::scope(|s| {
                for h in &halves {
                    let adgi = &adgi;
                    s.spawn(move || {
                        for &(p, t, v, u) in h {
                            black_box(adgi.update_irradiance(p, t, v, u));
                        }
                    });
                }
            })
        })
    });
    g.bench_function("rgb32f_count_mutex_baseline", |b| {
        b.iter(|| {
            std::thread::scope(|s| {
                for h in &halves {
                    let locked = &locked;
                    s.spawn(move || {
                        for &(p, t, v, _) in h {
                            f32_update(&mut locked[p * 64 + t].lock().unwrap(), v);
                        }
                    });
                }
            })
        })
    });
    g.finish();
}

/// The query a user would write over RGBA32F irradiance / RG32F moment texels: the same maps,
/// taps and weights as [`ProbeTexels::irradiance_at`] with [`QueryConfig::DDGI`].
struct F32Probes {
    grid: ProbeGrid,
    irradiance: Vec<[f32; 4]>,
    moments: Vec<[f32; 2]>,
}

impl F32Probes {
    fn from(t: &ProbeTexels) -> Self {
        let ni = t.config().irradiance_map.texel_count();
        let nv = t.config().visibility_map.texel_count();
        let mut irradiance = Vec::new();
        let mut moments = Vec::new();
        for p in 0..t.grid().probe_count() {
            for i in 0..ni {
                let e = t.irradiance(p, i);
                irradiance.push([e.x, e.y, e.z, 1.0]);
            }
            for i in 0..nv {
                let m = t.visibility(p, i);
                moments.push([m.x, m.y]);
            }
        }
        Self {
            grid: *t.grid(),
            irradiance,
            moments,
        }
    }

    fn irradiance_at(&self, x: Vec3, n: Vec3, v: Vec3, q: &QueryConfig) -> Vec3 {
        let imap = TexelMap::ADGI_IRRADIANCE;
        let vmap = TexelMap::ADGI_VISIBILITY;
        let grid = &self.grid;
        let bias = (n * q.normal_bias + v * q.view_bias) * grid.spacing().min_element();
        let biased = x + bias;
        let cell = grid.cell(biased);
        let inv_diag = 1.0 / grid.cell_diagonal();
        let taps = imap.bilinear(n);
        let mut sum = Vec3::ZERO;
        let mut wsum = 0.0;
        for corner in 0..8u32 {
            let step = UVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let coords = (cell.base + step).min(grid.counts() - UVec3::ONE);
            let tri = Vec3::select(step.cmpeq(UVec3::ONE), cell.alpha, Vec3::ONE - cell.alpha)
                .max(Vec3::splat(q.min_trilinear));
            let probe = grid.probe_index(coords);
            let p = grid.probe_position(coords);
            let d = (p - x).normalize_or_zero();
            let s = (n.dot(d) + 1.0) * 0.5;
            let mut w = s * s + 0.2;
            let to_probe = p - biased;
            let r = to_probe.length();
            if r > 0.0 {
                let mut m = Vec2::ZERO;
                for (i, tw) in vmap.bilinear(-to_probe / r) {
                    let t = self.moments[probe * 256 + i];
                    m += tw * Vec2::new(t[0], t[1]);
                }
                let r = r * inv_diag;
                if r > m.x {
                    let var = (m.y - m.x * m.x).abs();
                    let delta = r - m.x;
                    let c = var / (var + delta * delta);
                    w *= (c * c * c).max(q.chebyshev_floor);
                }
            }
            w = w.max(q.min_weight);
            if w < q.crush_threshold {
                w *= w * w / (q.crush_threshold * q.crush_threshold);
            }
            w *= tri.x * tri.y * tri.z;
            let mut e = Vec3::ZERO;
            for (i, tw) in taps {
                let t = self.irradiance[probe * 64 + i];
                e += tw * Vec3::new(t[0], t[1], t[2]);
            }
            sum += w * (core::f32::consts::PI * e).powf(0.5);
            wsum += w;
        }
        let e = sum / wsum;
        e * e
    }
}

fn bench_queries(c: &mut Criterion) {
    query_group(c, "irradiance_query", UVec3::splat(8));
    query_group(c, "irradiance_query_large_grid", UVec3::new(48, 48, 32));
}

/// Random queries over a grid of `counts` probes: 8³ (texels in cache: 0.66 MB of words,
/// 1.6 MB of f32) or 48 × 48 × 32 (94 MB of words, 226 MB of f32: memory-bound, the regime of
/// ADGI's millions of probes).
fn query_group(c: &mut Criterion, name: &str, counts: UVec3) {
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, counts).unwrap();
    let t = ProbeTexels::new(grid, TexelConfig::ADGI);
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    for p in 0..grid.probe_count() {
        for i in 0..64 {
            let v = Vec3::new(rng.random(), rng.random(), rng.random());
            t.set_irradiance(p, i, v, 30);
        }
        for i in 0..256 {
            let d: f32 = rng.random::<f32>() * 0.8 + 0.1;
            t.set_visibility(p, i, Vec2::new(d, d * d * 1.1), 30);
        }
    }
    let baseline = F32Probes::from(&t);
    let inputs: Vec<(Vec3, Vec3, Vec3)> = (0..QUERIES)
        .map(|_| {
            let x = Vec3::new(rng.random(), rng.random(), rng.random())
                * (counts - UVec3::ONE).as_vec3();
            (x, unit(&mut rng), unit(&mut rng))
        })
        .collect();
    // The two implementations agree (same math, same texel values).
    for &(x, n, v) in &inputs[..16] {
        let a = t.irradiance_at(x, n, v, &QueryConfig::DDGI);
        let b = baseline.irradiance_at(x, n, v, &QueryConfig::DDGI);
        assert!(
            (a - b).abs().max_element() < 1e-3 * (1.0 + a.max_element()),
            "{a} vs {b}"
        );
    }
    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(QUERIES as u64));
    g.bench_function("adgi_words", |b| {
        b.iter(|| {
            for &(x, n, v) in &inputs {
                black_box(t.irradiance_at(x, n, v, &QueryConfig::DDGI));
            }
        })
    });
    g.bench_function("rgba32f_baseline", |b| {
        b.iter(|| {
            for &(x, n, v) in &inputs {
                black_box(baseline.irradiance_at(x, n, v, &QueryConfig::DDGI));
            }
        })
    });
    let radiance = QueryConfig {
        content: TexelContent::Radiance,
        ..QueryConfig::DDGI
    };
    g.bench_function("adgi_words_radiance_content", |b| {
        b.iter(|| {
            for &(x, n, v) in &inputs {
                black_box(t.irradiance_at(x, n, v, &radiance));
            }
        })
    });
    g.finish();
}

fn print_bytes_per_probe(_: &mut Criterion) {
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::ONE).unwrap();
    let t = ProbeTexels::new(grid, TexelConfig::ADGI);
    let texels = 64 + 256;
    println!(
        "bytes per probe (8x8 irradiance + 16x16 visibility, border included): ADGI words {} B, \
         RGB32F+count (16 B texels) {} B ({:.1}x), RGBA32F irradiance + RG32F moments {} B ({:.1}x)",
        t.bytes_per_probe(),
        16 * texels,
        (16 * texels) as f64 / t.bytes_per_probe() as f64,
        16 * 64 + 8 * 256,
        (16 * 64 + 8 * 256) as f64 / t.bytes_per_probe() as f64,
    );
}

criterion_group!(benches, print_bytes_per_probe, bench_updates, bench_queries);
criterion_main!(benches);
