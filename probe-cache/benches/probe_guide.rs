//! Criterion benchmarks of ADGI's guide in mcg-probe-cache, each group with its baseline so the
//! results read as ratios:
//!
//! - `chain_step`: one Metropolis step of [`ProbeChains::step_frame`] with the tabulated guide
//!   h (eq. 2, static form) evaluated at every proposal, per emitted-or-discarded step, against
//!   the choice a uniform DDGI-style scheduler makes per ray: a uniform random probe and a
//!   uniform direction from three uniforms. Both consume pre-generated uniforms. Also the same
//!   step on 2 threads ([`ProbeChains::step_frame_parallel`]).
//! - `guide_h`: one evaluation of [`GuidingFunction::h`] (nearest probe, octant, eq. 2) against
//!   a plain table read at a precomputed index.
//!
//! Grid 32 × 16 × 32 probes (16 384, 0.5 m), 1 024 chains, the default schedule (8 steps, 2
//! discarded).

use core::f32::consts::TAU;
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_probe_cache::glam::{UVec3, Vec3};
use mcg_probe_cache::{
    GuideParams, GuidingFunction, ProbeChains, ProbeGrid, ProbeStepUniforms, ProxyGrid,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const CHAINS: usize = 1024;

fn setup() -> (ProbeGrid, Vec<f32>, Vec<f32>, Vec<ProbeStepUniforms>) {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::new(32, 16, 32)).unwrap();
    let n = grid.probe_count() * 8;
    let f: Vec<f32> = (0..n)
        .map(|_| {
            if rng.random::<f32>() < 0.3 {
                0.0
            } else {
                rng.random()
            }
        })
        .collect();
    let g: Vec<f32> = (0..n).map(|_| rng.random::<f32>() * 0.5).collect();
    let uniforms = (0..CHAINS * 8 * 4)
        .map(|_| ProbeStepUniforms {
            proposal: std::array::from_fn(|_| rng.random()),
            accept: rng.random(),
        })
        .collect();
    (grid, f, g, uniforms)
}

fn chain_step(c: &mut Criterion) {
    let (grid, f, g, uniforms) = setup();
    let cells = ProxyGrid::probes(grid);
    let guide = GuidingFunction::new(cells, &f, Some(&g), GuideParams::STATIC).unwrap();
    let mut k = 0usize;
    let mut chains = ProbeChains::new_static(grid, CHAINS, || {
        k += 1;
        uniforms[k % uniforms.len()].proposal
    })
    .unwrap();
    // Warm the chains into the target.
    let mut next = 0usize;
    for _ in 0..20 {
        chains.step_frame(&guide, || {
            next = (next + 1) % uniforms.len();
            uniforms[next]
        });
    }
    let steps = (CHAINS * chains.schedule().iterations() as usize) as u64;
    let mut group = c.benchmark_group("chain_step");
    group.throughput(Throughput::Elements(steps));
    group.bench_function("metropolis_guided", |b| {
        b.iter(|| {
            let s = chains.step_frame(&guide, || {
                next = (next + 1) % uniforms.len();
                uniforms[next]
            });
            black_box(s.len())
        })
    });
    let n_uniforms = uniforms.len();
    let mut frame = 0usize;
    group.bench_function("metropolis_guided_2_threads", |b| {
        b.iter(|| {
            frame += 1;
            let base = frame * 7919;
            let s = chains.step_frame_parallel(
                &guide,
                |j, k| uniforms[(base + j * 9 + k as usize) % n_uniforms],
                2,
            );
            black_box(s.len())
        })
    });
    let probes = grid.probe_count();
    group.bench_function("uniform_probe_and_direction", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            let mut idx = 0usize;
            for _ in 0..steps {
                next = (next + 1) % uniforms.len();
                let u = &uniforms[next].proposal;
                let probe = ((u[0] * probes as f32) as usize).min(probes - 1);
                let z = 2.0 * u[1] - 1.0;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (s, co) = (TAU * u[2]).sin_cos();
                acc += Vec3::new(r * co, r * s, z);
                idx ^= probe;
            }
            black_box((acc, idx))
        })
    });
    group.finish();
}

fn guide_h(c: &mut Criterion) {
    let (grid, f, g, uniforms) = setup();
    let cells = ProxyGrid::probes(grid);
    let guide = GuidingFunction::new(cells, &f, Some(&g), GuideParams::STATIC).unwrap();
    let lo = grid.origin() - 0.5 * grid.spacing();
    let extent = grid.counts().as_vec3() * grid.spacing();
    let points: Vec<(Vec3, Vec3)> = uniforms
        .iter()
        .take(4096)
        .map(|u| {
            let p = &u.proposal;
            (
                lo + Vec3::new(p[0], p[1], p[2]) * extent,
                Vec3::new(p[3] - 0.5, p[4] - 0.5, u.accept - 0.5),
            )
        })
        .collect();
    let indices: Vec<usize> = points
        .iter()
        .map(|&(p, d)| cells.proxy_at(p).unwrap_or(0) * 8 + mcg_probe_cache::heuristics::octant(d))
        .collect();
    let mut group = c.benchmark_group("guide_h");
    group.throughput(Throughput::Elements(points.len() as u64));
    group.bench_function("guiding_function_h", |b| {
        b.iter(|| {
            let mut s = 0.0f32;
            for &(p, d) in &points {
                s += guide.guiding_value(black_box(p), black_box(d));
            }
            black_box(s)
        })
    });
    group.bench_function("table_read", |b| {
        b.iter(|| {
            let mut s = 0.0f32;
            for &i in &indices {
                s += f[black_box(i)];
            }
            black_box(s)
        })
    });
    group.finish();
}

criterion_group!(benches, chain_step, guide_h);
criterion_main!(benches);
