//! Criterion benchmarks of mcg-vmf, each group with its baseline in the same group so that
//! results read as ratios:
//!
//! - `sample`: [`Vmf::sample`] vs uniform-sphere sampling from two uniforms (the floor any
//!   direction sampler pays: one `sin_cos`, one `sqrt`) and vs the textbook vMF sampler; lobes
//!   of mixed κ ∈ {0.5, 2, 10, 50, 80}, and `vmf_concentrated` with κ ∈ {20, …, 10⁴}.
//! - `pdf`: [`Vmf::pdf`] vs the textbook density κ/(4π sinh κ)·e^{κ μ·ω}.
//! - `sample_with_pdf`: ours vs uniform sampling (with its constant pdf) and the textbook pair.
//! - `mixture_pdf/K`, `mixture_sample/K` for K = 8, 32: [`VmfMixture`] vs a straightforward
//!   mixture over the textbook formulas.
//!
//! Every iteration processes a batch of [`BATCH`] inputs so the loop overhead is amortised.

use core::f32::consts::{PI, TAU};
use std::hint::black_box;

use core::iter::Sum;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion, Throughput, criterion_group, criterion_main};
use mcg_vmf::glam::{Vec2, Vec3};
use mcg_vmf::{Vmf, VmfMixture, sample_batch, uniform_sphere};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 1024;

/// Inputs shared by all groups: uniforms, unit directions and lobes of mixed κ.
struct Inputs {
    uniforms: Vec<Vec2>,
    directions: Vec<Vec3>,
    lobes: Vec<Vmf>,
}

impl Inputs {
    fn lobe_uniform_pairs(&self) -> Vec<(Vmf, Vec2)> {
        self.lobes
            .iter()
            .copied()
            .zip(self.uniforms.iter().copied())
            .collect()
    }
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

/// Registers `name` in `group`: one iteration maps `f` over the whole batch `inputs` and sums
/// the results, so nothing is optimised away.
fn bench_batch<I: Copy, O: Sum<O>>(
    group: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    inputs: &[I],
    f: impl Fn(I) -> O,
) {
    group.bench_function(name, |b| {
        b.iter(|| black_box(inputs).iter().map(|&i| f(i)).sum::<O>())
    });
}

fn group<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(BATCH as u64));
    g
}

fn bench_sample(c: &mut Criterion) {
    let inp = inputs();
    let pairs = inp.lobe_uniform_pairs();
    let mut g = group(c, "sample");
    bench_batch(
        &mut g,
        "uniform_sphere_baseline",
        &inp.uniforms,
        uniform_sphere,
    );
    bench_batch(&mut g, "textbook", &pairs, |(l, u)| textbook_sample(&l, u));
    bench_batch(&mut g, "vmf", &pairs, |(l, u)| l.sample(u));
    // The same draws through the slice API, which vectorises; summed like the others.
    let (lobes, uniforms): (Vec<Vmf>, Vec<Vec2>) = pairs.iter().copied().unzip();
    let mut out = vec![Vec3::ZERO; lobes.len()];
    g.bench_function("vmf_batch", |b| {
        b.iter(|| {
            sample_batch(black_box(&lobes), black_box(&uniforms), &mut out);
            out.iter().copied().sum::<Vec3>()
        })
    });
    // The same lobes made concentrated (κ ∈ {20, 50, 200, 10³, 10⁴}, typical of fitted guiding
    // lobes): above κ = 17 the sampler needs no `exp`, so this is its fast path.
    let concentrated: Vec<(Vmf, Vec2)> = pairs
        .iter()
        .enumerate()
        .map(|(i, (l, u))| {
            (
                Vmf::new(l.mu(), [20.0, 50.0, 200.0, 1e3, 1e4][i % 5]).unwrap(),
                *u,
            )
        })
        .collect();
    bench_batch(&mut g, "vmf_concentrated", &concentrated, |(l, u)| {
        l.sample(u)
    });
    g.finish();
}

fn bench_pdf(c: &mut Criterion) {
    let inp = inputs();
    let pairs: Vec<(Vmf, Vec3)> = inp
        .lobes
        .iter()
        .copied()
        .zip(inp.directions.iter().copied())
        .collect();
    let mut g = group(c, "pdf");
    bench_batch(&mut g, "textbook_baseline", &pairs, |(l, w)| {
        textbook_pdf(&l, w)
    });
    bench_batch(&mut g, "vmf", &pairs, |(l, w)| l.pdf(w));
    g.finish();
}

/// `sample_with_pdf` results are folded as `w · pdf` so that both outputs are used.
fn bench_sample_with_pdf(c: &mut Criterion) {
    let inp = inputs();
    let pairs = inp.lobe_uniform_pairs();
    let mut g = group(c, "sample_with_pdf");
    bench_batch(&mut g, "uniform_sphere_baseline", &inp.uniforms, |u| {
        uniform_sphere(u) * (0.25 / PI)
    });
    bench_batch(&mut g, "textbook", &pairs, |(l, u)| {
        let w = textbook_sample(&l, u);
        w * textbook_pdf(&l, w)
    });
    bench_batch(&mut g, "vmf", &pairs, |(l, u)| {
        let (w, p) = l.sample_with_pdf(u);
        w * p
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
    let mut g = group(c, &format!("mixture_pdf/{K}"));
    bench_batch(&mut g, "textbook_baseline", &inp.directions, |w| {
        theirs.pdf(w)
    });
    bench_batch(&mut g, "vmf_mixture", &inp.directions, |w| ours.pdf(w));
    g.finish();

    let mut g = group(c, &format!("mixture_sample/{K}"));
    bench_batch(
        &mut g,
        "uniform_sphere_baseline",
        &inp.uniforms,
        uniform_sphere,
    );
    bench_batch(&mut g, "textbook_baseline", &inp.uniforms, |u| {
        theirs.sample(u)
    });
    bench_batch(&mut g, "vmf_mixture", &inp.uniforms, |u| ours.sample(u));
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
