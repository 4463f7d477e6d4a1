//! Criterion benchmarks of the MCPG [`Guide`], per path vertex (a batch of vertices per
//! iteration; criterion reports time per element), each group with a cosine-hemisphere sample
//! as the baseline:
//!
//! - `guided_vertex`: one full guided vertex without tracing — [`Guide::begin`](mcg_markov_guide::mcpg::Guide::begin) (N_mc = 5
//!   candidates), [`GuidedVertex::sample`], one extra [`GuidedVertex::pdf`] and
//!   [`GuidedVertex::finish`] with a precomputed hit — on a trained guide, with and without the
//!   irradiance cache, against [`cosine_hemisphere`](mcg_markov_guide::cosine_hemisphere) of the same number of directions.
//! - `shared_guide_threads`: the same vertices (cache on) on one thread and split over two
//!   threads sharing one guide (`&Guide`), to read the scaling from the times per element.
//!
//! [`GuidedVertex::sample`]: mcg_markov_guide::mcpg::GuidedVertex::sample
//! [`GuidedVertex::pdf`]: mcg_markov_guide::mcpg::GuidedVertex::pdf
//! [`GuidedVertex::finish`]: mcg_markov_guide::mcpg::GuidedVertex::finish

mod common;

use std::hint::black_box;

use common::vertices::{BATCH, cosine_batch, cosine_inputs, inputs, trained_guide, vertices};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

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
