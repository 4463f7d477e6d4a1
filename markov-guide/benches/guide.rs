//! Criterion benchmarks of the MCPG [`Guide`], per path vertex (a batch of vertices per
//! iteration; criterion reports time per element), each group with a cosine-hemisphere sample
//! as the baseline:
//!
//! - `guided_vertex`: one full guided vertex without tracing — [`Guide::begin`] (N_mc = 5
//!   candidates), [`GuidedVertex::sample`], one extra [`GuidedVertex::pdf`] and
//!   [`GuidedVertex::finish`] with a precomputed hit — on a trained guide, with and without the
//!   irradiance cache, against [`cosine_hemisphere`] of the same number of directions.
//! - `shared_guide_threads`: the same vertices (cache on) on one thread and split over two
//!   threads sharing one guide (`&Guide`), to read the scaling from the times per element.
//!
//! [`GuidedVertex::sample`]: mcg_markov_guide::mcpg::GuidedVertex::sample
//! [`GuidedVertex::pdf`]: mcg_markov_guide::mcpg::GuidedVertex::pdf
//! [`GuidedVertex::finish`]: mcg_markov_guide::mcpg::GuidedVertex::finish

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_markov_guide::cosine_hemisphere;
use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcpg::{
    BeginUniforms, FinishUniforms, Guide, GuideConfig, Lambertian, SampleUniforms, Vertex,
    VertexObservation,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 4096;

/// One vertex's inputs: the shading point and all its uniforms, and the hit to report.
struct Input {
    x: Vec3,
    begin: BeginUniforms,
    sample: SampleUniforms,
    finish: FinishUniforms,
    hit: VertexObservation,
    extra: Vec3,
}

/// Shading points on the floor of a unit room in raster order (a 64-wide grid, jittered, as
/// a renderer visits its pixels), hits on a 0.2-wide patch of the ceiling.
fn inputs(rng: &mut Pcg64Mcg, n: usize) -> Vec<Input> {
    (0..n)
        .map(|i| {
            let (col, row) = ((i % 64) as f32, (i / 64) as f32);
            let rows = (n / 64) as f32;
            let x = Vec3::new(
                (col + rng.random::<f32>()) / 64.0,
                0.0,
                (row + rng.random::<f32>()) / rows,
            );
            let target = Vec3::new(
                0.4 + 0.2 * rng.random::<f32>(),
                1.0,
                0.4 + 0.2 * rng.random::<f32>(),
            );
            Input {
                x,
                begin: BeginUniforms::from_fn(5, || rng.random()),
                sample: SampleUniforms::from_fn(|| rng.random()),
                finish: FinishUniforms::from_fn(|| rng.random()),
                hit: VertexObservation::hit(target, -Vec3::Y, Vec3::splat(5.0), Vec3::splat(0.7)),
                extra: Vec3::new(rng.random::<f32>() - 0.5, 1.0, rng.random::<f32>() - 0.5)
                    .normalize(),
            }
        })
        .collect()
}

fn trained_guide(cache: bool, inputs: &[Input]) -> Guide {
    // A 64-pixel-high image with a 60° field of view (cells of about 8 pixels).
    let mut config =
        GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE).for_camera(60f32.to_radians(), 64);
    if !cache {
        config.cache = None;
    }
    let mut guide = Guide::new(config).unwrap();
    guide.set_camera(Vec3::new(0.5, 0.5, 1.5));
    for _ in 0..8 {
        vertices(&guide, inputs);
        guide.end_frame();
    }
    guide
}

/// Runs every input as one full vertex; returns a checksum of the pdfs.
fn vertices(guide: &Guide, inputs: &[Input]) -> f32 {
    let mut total = 0.0;
    for input in inputs {
        let v = guide.begin(
            Vertex::surface(input.x, Vec3::Y),
            Lambertian { normal: Vec3::Y },
            &input.begin,
        );
        let s = v.sample(&input.sample);
        total += s.pdf + v.pdf(input.extra);
        v.finish(&s, &input.hit, &input.finish);
    }
    total
}

fn cosine_inputs(rng: &mut Pcg64Mcg, n: usize) -> Vec<Vec2> {
    (0..n)
        .map(|_| Vec2::new(rng.random(), rng.random()))
        .collect()
}

fn cosine_batch(us: &[Vec2]) -> f32 {
    us.iter()
        .map(|&u| {
            let (w, pdf) = cosine_hemisphere(Vec3::Y, u);
            w.x + pdf
        })
        .sum()
}

fn bench_guided_vertex(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let inputs = inputs(&mut rng, BATCH);
    let us = cosine_inputs(&mut rng, BATCH);
    let mut g = c.benchmark_group("guided_vertex");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("cosine_hemisphere_baseline", |b| {
        b.iter(|| cosine_batch(black_box(&us)))
    });
    for (name, cache) in [("full_vertex_no_cache", false), ("full_vertex_cache", true)] {
        let guide = trained_guide(cache, &inputs);
        g.bench_function(name, |b| b.iter(|| vertices(black_box(&guide), &inputs)));
    }
    g.finish();
}

fn bench_threads(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(2);
    let inputs = inputs(&mut rng, 4 * BATCH);
    let us = cosine_inputs(&mut rng, 4 * BATCH);
    let guide = trained_guide(true, &inputs);
    let mut g = c.benchmark_group("shared_guide_threads");
    g.throughput(Throughput::Elements(inputs.len() as u64));
    g.bench_function("cosine_hemisphere_baseline", |b| {
        b.iter(|| cosine_batch(black_box(&us)))
    });
    g.bench_function("one_thread", |b| {
        b.iter(|| vertices(black_box(&guide), &inputs))
    });
    g.bench_function("two_threads", |b| {
        b.iter(|| {
            let (a, bb) = inputs.split_at(inputs.len() / 2);
            std::thread::scope(|s| {
                let h = s.spawn(|| vertices(&guide, a));
                vertices(&guide, bb) + h.join().unwrap()
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench_guided_vertex, bench_threads);
criterion_main!(benches);
