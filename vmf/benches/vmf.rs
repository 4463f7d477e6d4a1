//! Criterion benchmarks of mcg-vmf, each group with its baseline in the same group so that
//! results read as ratios:
//!
//! - `sample`: [`Vmf::sample`] vs uniform-sphere sampling from two uniforms (the floor any
//!   direction sampler pays: one `sin_cos`, one `sqrt`) and vs the textbook vMF sampler.
//! - `pdf`: [`Vmf::pdf`] vs the textbook density κ/(4π sinh κ)·e^{κ μ·ω}.
//! - `sample_with_pdf`: ours vs uniform sampling (with its constant pdf) and the textbook pair.
//! - `mixture_pdf/K`, `mixture_sample/K` for K = 8, 32: [`VmfMixture`] vs a straightforward
//!   mixture over the textbook formulas.
//!
//! Every iteration processes a batch of [`BATCH`] inputs so the loop overhead is amortised.

use core::f32::consts::{PI, TAU};
use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_vmf::glam::{Vec2, Vec3};
use mcg_vmf::{Vmf, VmfMixture};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 1024;

/// Inputs shared by all groups: uniforms, unit directions and lobes of mixed κ.
struct Inputs {
    uniforms: Vec<Vec2>,
    directions: Vec<Vec3>,
    lobes: Vec<Vmf>,
}

fn inputs() -> Inputs {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let uniforms: Vec<Vec2> = (0..BATCH)
        .map(|_| Vec2::new(rng.random(), rng.random()))
        .collect();
    let directions = uniforms.iter().map(|&u| uniform_sphere(u)).collect();
    let kappas = [0.5_f32, 2.0, 10.0, 50.0, 80.0];
    let lobes = (0..BATCH)
        .map(|i| {
            let mu = uniform_sphere(Vec2::new(rng.random(), rng.random()));
            Vmf::new(mu, kappas[i % kappas.len()]).unwrap()
        })
        .collect();
    Inputs {
        uniforms,
        directions,
        lobes,
    }
}

/// Baseline: uniform direction on S² from two uniforms (z = 1 − 2u, φ = 2πu).
#[inline]
fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.y;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (TAU * u.x).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Baseline: the textbook density κ/(4π sinh κ) e^{κ μ·ω} (overflows for κ > 88 in f32).
#[inline]
fn textbook_pdf(lobe: &Vmf, w: Vec3) -> f32 {
    let kappa = lobe.kappa();
    if kappa == 0.0 {
        return 0.25 / PI;
    }
    kappa / (4.0 * PI * kappa.sinh()) * (kappa * lobe.mu().dot(w)).exp()
}

/// Baseline: the textbook sampler, cos θ = 1 + ln(ξ + (1 − ξ) e^{−2κ})/κ, with a frame from
/// cross products.
#[inline]
fn textbook_sample(lobe: &Vmf, u: Vec2) -> Vec3 {
    let kappa = lobe.kappa();
    let cos_theta = if kappa == 0.0 {
        1.0 - 2.0 * u.y
    } else {
        1.0 + (u.y + (1.0 - u.y) * (-2.0 * kappa).exp()).ln() / kappa
    };
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (s, c) = (TAU * u.x).sin_cos();
    let n = lobe.mu();
    let helper = if n.x.abs() > 0.9 { Vec3::Y } else { Vec3::X };
    let t = n.cross(helper).normalize();
    let b = n.cross(t);
    t * (c * sin_theta) + b * (s * sin_theta) + n * cos_theta
}

fn bench_sample(c: &mut Criterion) {
    let inp = inputs();
    let mut g = c.benchmark_group("sample");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("uniform_sphere_baseline", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            for &u in black_box(&inp.uniforms) {
                acc += uniform_sphere(u);
            }
            acc
        })
    });
    g.bench_function("textbook", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            for (lobe, &u) in black_box(&inp.lobes).iter().zip(black_box(&inp.uniforms)) {
                acc += textbook_sample(lobe, u);
            }
            acc
        })
    });
    g.bench_function("vmf", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            for (lobe, &u) in black_box(&inp.lobes).iter().zip(black_box(&inp.uniforms)) {
                acc += lobe.sample(u);
            }
            acc
        })
    });
    g.finish();
}

fn bench_pdf(c: &mut Criterion) {
    let inp = inputs();
    let mut g = c.benchmark_group("pdf");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("textbook_baseline", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (lobe, &w) in black_box(&inp.lobes).iter().zip(black_box(&inp.directions)) {
                acc += textbook_pdf(lobe, w);
            }
            acc
        })
    });
    g.bench_function("vmf", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (lobe, &w) in black_box(&inp.lobes).iter().zip(black_box(&inp.directions)) {
                acc += lobe.pdf(w);
            }
            acc
        })
    });
    g.finish();
}

fn bench_sample_with_pdf(c: &mut Criterion) {
    let inp = inputs();
    let mut g = c.benchmark_group("sample_with_pdf");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("uniform_sphere_baseline", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            let mut pdf = 0.0;
            for &u in black_box(&inp.uniforms) {
                acc += uniform_sphere(u);
                pdf += 0.25 / PI;
            }
            (acc, pdf)
        })
    });
    g.bench_function("textbook", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            let mut pdf = 0.0;
            for (lobe, &u) in black_box(&inp.lobes).iter().zip(black_box(&inp.uniforms)) {
                let w = textbook_sample(lobe, u);
                acc += w;
                pdf += textbook_pdf(lobe, w);
            }
            (acc, pdf)
        })
    });
    g.bench_function("vmf", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            let mut pdf = 0.0;
            for (lobe, &u) in black_box(&inp.lobes).iter().zip(black_box(&inp.uniforms)) {
                let (w, p) = lobe.sample_with_pdf(u);
                acc += w;
                pdf += p;
            }
            (acc, pdf)
        })
    });
    g.finish();
}

/// Straightforward mixture over the textbook formulas: the baseline for `VmfMixture`.
struct TextbookMixture<const K: usize> {
    lobes: [Vmf; K],
    weights: [f32; K],
}

impl<const K: usize> TextbookMixture<K> {
    fn pdf(&self, w: Vec3) -> f32 {
        self.lobes
            .iter()
            .zip(&self.weights)
            .map(|(l, &p)| p * textbook_pdf(l, w))
            .sum()
    }

    fn sample(&self, u: Vec2) -> Vec3 {
        let mut cdf = 0.0;
        for (i, &p) in self.weights.iter().enumerate() {
            cdf += p;
            if u.x < cdf || i == K - 1 {
                let ux = ((u.x - (cdf - p)) / p).clamp(0.0, 0.999_999_9);
                return textbook_sample(&self.lobes[i], Vec2::new(ux, u.y));
            }
        }
        unreachable!("K > 0")
    }
}

fn mixtures<const K: usize>(inp: &Inputs) -> (VmfMixture<K>, TextbookMixture<K>) {
    let lobes: [Vmf; K] = core::array::from_fn(|i| inp.lobes[i]);
    let weights: [f32; K] = core::array::from_fn(|i| 1.0 + (i % 3) as f32);
    let ours = VmfMixture::new(lobes, weights).unwrap();
    let theirs = TextbookMixture {
        lobes,
        weights: *ours.weights(),
    };
    (ours, theirs)
}

fn bench_mixture_k<const K: usize>(c: &mut Criterion) {
    let inp = inputs();
    let (ours, theirs) = mixtures::<K>(&inp);
    let mut g = c.benchmark_group(format!("mixture_pdf/{K}"));
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("textbook_baseline", |b| {
        b.iter(|| {
            black_box(&inp.directions)
                .iter()
                .map(|&w| theirs.pdf(w))
                .sum::<f32>()
        })
    });
    g.bench_function("vmf_mixture", |b| {
        b.iter(|| {
            black_box(&inp.directions)
                .iter()
                .map(|&w| ours.pdf(w))
                .sum::<f32>()
        })
    });
    g.finish();

    let mut g = c.benchmark_group(format!("mixture_sample/{K}"));
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("uniform_sphere_baseline", |b| {
        b.iter(|| {
            black_box(&inp.uniforms)
                .iter()
                .map(|&u| uniform_sphere(u))
                .sum::<Vec3>()
        })
    });
    g.bench_function("textbook_baseline", |b| {
        b.iter(|| {
            black_box(&inp.uniforms)
                .iter()
                .map(|&u| theirs.sample(u))
                .sum::<Vec3>()
        })
    });
    g.bench_function("vmf_mixture", |b| {
        b.iter(|| {
            black_box(&inp.uniforms)
                .iter()
                .map(|&u| ours.sample(u))
                .sum::<Vec3>()
        })
    });
    g.finish();
}

fn bench_mixture(c: &mut Criterion) {
    bench_mixture_k::<8>(c);
    bench_mixture_k::<32>(c);
}

criterion_group!(
    benches,
    bench_sample,
    bench_pdf,
    bench_sample_with_pdf,
    bench_mixture
);
criterion_main!(benches);
