//! Criterion benchmarks of mcg-smis, each group with its baselines so that results read as
//! ratios. Techniques are vMF-like lobes on S² (`C · e^{κ(μ·ω − 1)}`, one `exp` per density,
//! as a guiding lobe costs), defined here so the crate keeps no dependency.
//!
//! - `smis_n/{n}` for n = 2, 4, 8, 16, 32: one n-sample SMIS estimate (MCMM eq. 8, n² pdf
//!   evaluations) with [`smis`]; baselines: the same double loop written by hand
//!   (`naive_loop`) and single-technique importance sampling of the same n samples,
//!   Σᵢ f(xᵢ)/p(xᵢ | tᵢ) (`single_is`, n evaluations — the floor an estimator pays).
//! - `path/{k}` for k = 1…6 vertices with 4 techniques per vertex: [`path_pdf`] (linear,
//!   4k evaluations) against [`path_pdf_naive`] (MMIS eq. 14 as written, k·4ᵏ evaluations).
//!
//! Every iteration evaluates a batch of [`BATCH`] independent inputs.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_smis::{Technique, path_pdf, path_pdf_naive, smis};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 64;

/// A vMF-like lobe on S² with precomputed normalisation.
#[derive(Clone, Copy, Debug)]
struct Lobe {
    mu: [f32; 3],
    kappa: f32,
    norm: f32,
}

impl Lobe {
    fn new(mu: [f32; 3], kappa: f32) -> Self {
        let norm = kappa / (std::f32::consts::TAU * (1.0 - (-2.0 * kappa).exp()));
        Self { mu, kappa, norm }
    }
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `mcg_vmf::uniform_sphere` on the plain arrays this crate's techniques use.
fn uniform_sphere(u: [f32; 2]) -> [f32; 3] {
    mcg_vmf::uniform_sphere(u.into()).to_array()
}

impl Technique for Lobe {
    type Sample = [f32; 3];
    type Uniform = [f32; 2];

    #[inline]
    fn pdf(&self, w: &[f32; 3]) -> f32 {
        self.norm * (self.kappa * (dot(self.mu, *w) - 1.0)).exp()
    }

    /// Not a vMF sampler (the benches only evaluate densities); a uniform direction.
    fn sample(&self, u: [f32; 2]) -> [f32; 3] {
        uniform_sphere(u)
    }
}

fn random_lobe(rng: &mut Pcg64Mcg) -> Lobe {
    Lobe::new(
        uniform_sphere([rng.random(), rng.random()]),
        1.0 + 99.0 * rng.random::<f32>(),
    )
}

/// One SMIS input: n techniques, their samples and f values.
struct SmisInput {
    techniques: Vec<Lobe>,
    samples: Vec<[f32; 3]>,
    values: Vec<f32>,
}

fn smis_inputs(n: usize, rng: &mut Pcg64Mcg) -> Vec<SmisInput> {
    (0..BATCH)
        .map(|_| {
            let techniques: Vec<Lobe> = (0..n).map(|_| random_lobe(rng)).collect();
            let samples = (0..n)
                .map(|_| uniform_sphere([rng.random(), rng.random()]))
                .collect();
            let values = (0..n).map(|_| rng.random::<f32>()).collect();
            SmisInput {
                techniques,
                samples,
                values,
            }
        })
        .collect()
}

/// Baseline: the double loop a renderer author would write.
fn naive_loop(t: &[Lobe], xs: &[[f32; 3]], fs: &[f32]) -> f32 {
    let mut sum = 0.0;
    for i in 0..xs.len() {
        let mut d = 0.0;
        for tj in t {
            d += tj.pdf(&xs[i]);
        }
        if d > 0.0 {
            sum += fs[i] / d;
        }
    }
    sum
}

/// Baseline: single-technique importance sampling, Σᵢ f(xᵢ)/p(xᵢ | tᵢ).
fn single_is(t: &[Lobe], xs: &[[f32; 3]], fs: &[f32]) -> f32 {
    t.iter()
        .zip(xs)
        .zip(fs)
        .map(|((t, x), f)| {
            let p = t.pdf(x);
            if p > 0.0 { f / p } else { 0.0 }
        })
        .sum()
}

fn bench_smis(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(11);
    for n in [2_usize, 4, 8, 16, 32] {
        let inputs = smis_inputs(n, &mut rng);
        let mut g = c.benchmark_group(format!("smis_n/{n}"));
        g.throughput(Throughput::Elements(BATCH as u64));
        g.bench_function("single_is_baseline", |b| {
            b.iter(|| {
                black_box(&inputs)
                    .iter()
                    .map(|i| single_is(&i.techniques, &i.samples, &i.values))
                    .sum::<f32>()
            })
        });
        g.bench_function("naive_loop_baseline", |b| {
            b.iter(|| {
                black_box(&inputs)
                    .iter()
                    .map(|i| naive_loop(&i.techniques, &i.samples, &i.values))
                    .sum::<f32>()
            })
        });
        g.bench_function("smis", |b| {
            b.iter(|| {
                black_box(&inputs)
                    .iter()
                    .map(|i| smis(&i.techniques, &i.samples, &i.values))
                    .sum::<f32>()
            })
        });
        g.finish();
    }
}

/// Techniques per path vertex in `path/{k}`.
const SET: usize = 4;

/// One path input: a technique set per vertex and the vertices.
type PathInput = (Vec<[Lobe; SET]>, Vec<[f32; 3]>);

fn bench_path(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(12);
    for k in 1..=6_usize {
        let inputs: Vec<PathInput> = (0..BATCH)
            .map(|_| {
                let sets = (0..k)
                    .map(|_| std::array::from_fn(|_| random_lobe(&mut rng)))
                    .collect();
                let xs = (0..k)
                    .map(|_| uniform_sphere([rng.random(), rng.random()]))
                    .collect();
                (sets, xs)
            })
            .collect();
        let mut g = c.benchmark_group(format!("path/{k}"));
        g.throughput(Throughput::Elements(BATCH as u64));
        g.bench_function("naive_baseline", |b| {
            b.iter(|| {
                black_box(&inputs)
                    .iter()
                    .map(|(sets, xs)| {
                        let refs: [&[Lobe]; 6] =
                            std::array::from_fn(|v| sets.get(v).map_or(&[][..], |s| &s[..]));
                        path_pdf_naive(&refs[..k], xs)
                    })
                    .sum::<f32>()
            })
        });
        g.bench_function("linear", |b| {
            b.iter(|| {
                black_box(&inputs)
                    .iter()
                    .map(|(sets, xs)| {
                        let refs: [&[Lobe]; 6] =
                            std::array::from_fn(|v| sets.get(v).map_or(&[][..], |s| &s[..]));
                        path_pdf(&refs[..k], xs)
                    })
                    .sum::<f32>()
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench_smis, bench_path);
criterion_main!(benches);
