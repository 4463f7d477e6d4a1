//! Load-robust timing of `Vmf::sample` and `sample_batch` against uniform-sphere sampling, for
//! a shared, noisy machine where criterion's means drift with the other jobs: the same inputs
//! as the criterion group `sample` (`benches/vmf.rs`: 1024 lobes with κ ∈ {0.5, 2, 10, 50, 80}
//! and, for "concentrated", {20, 50, 200, 10³, 10⁴}), each batch timed 3000 times, keeping the
//! fastest. Every variant sums its directions, as the criterion bench does. Prints ns per
//! direction and the ratio to the uniform baseline.
//!
//! `cargo run --release -p mcg-vmf --example min_timing`

use std::hint::black_box;
use std::time::Instant;

use mcg_vmf::glam::{Vec2, Vec3};
use mcg_vmf::{Vmf, sample_batch, uniform_sphere};

const BATCH: usize = 1024;

/// Fastest of 3000 timings of `f`, in ns per direction.
fn fastest(mut f: impl FnMut() -> Vec3) -> f64 {
    let mut best = f64::MAX;
    for _ in 0..3000 {
        let start = Instant::now();
        black_box(f());
        best = best.min(start.elapsed().as_nanos() as f64);
    }
    best / BATCH as f64
}

fn main() {
    // A PCG-style LCG; any fixed sequence will do.
    let mut s: u64 = 12_345;
    let mut uniform = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let uniforms: Vec<Vec2> = (0..BATCH)
        .map(|_| Vec2::new(uniform(), uniform()))
        .collect();
    let lobe_set = |kappas: [f32; 5], uniform: &mut dyn FnMut() -> f32| -> Vec<Vmf> {
        (0..BATCH)
            .map(|i| {
                let mu = uniform_sphere(Vec2::new(uniform(), uniform()));
                Vmf::new(mu, kappas[i % 5]).expect("valid lobe")
            })
            .collect()
    };
    let mixed = lobe_set([0.5, 2.0, 10.0, 50.0, 80.0], &mut uniform);
    let concentrated = lobe_set([20.0, 50.0, 200.0, 1e3, 1e4], &mut uniform);
    let mut out = vec![Vec3::ZERO; BATCH];

    let baseline = fastest(|| {
        black_box(&uniforms)
            .iter()
            .map(|&u| uniform_sphere(u))
            .sum()
    });
    let per_call = |lobes: &[Vmf]| {
        fastest(|| {
            black_box(lobes)
                .iter()
                .zip(&uniforms)
                .map(|(lobe, &u)| lobe.sample(u))
                .sum()
        })
    };
    let rows = [
        ("Vmf::sample, mixed κ", per_call(&mixed)),
        ("Vmf::sample, concentrated", per_call(&concentrated)),
        (
            "sample_batch, mixed κ",
            fastest(|| {
                sample_batch(black_box(&mixed), black_box(&uniforms), &mut out);
                out.iter().copied().sum()
            }),
        ),
    ];
    println!("uniform sphere (baseline)   {baseline:6.2} ns");
    for (name, ns) in rows {
        println!("{name:27} {ns:6.2} ns   {:.2}× baseline", ns / baseline);
    }
}
