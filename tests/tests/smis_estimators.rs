//! Every estimator of mcg-smis is unbiased: the mean of many independent estimates matches the
//! closed-form integral of twelve functions on [0, 1) and eleven on S² (smooth, peaky,
//! multi-modal, discontinuous; see `mcg_tests::line_integrands` / `sphere_integrands`).
//!
//! Estimators (one test each, both domains):
//! - `mis_balance` over three classical techniques drawn (1, 2, 2) times (MMIS eq. 1-4);
//! - `smis`, 4-sample SMIS over lobes drawn from a guided p(t) (MCMM eq. 8);
//! - `smis_one_sample` over 8 such lobes with uniform selection (MCMM eq. 9);
//! - `Mmis` over two technique spaces (guided lobes, 2 pairs; compact caps or boxes, 2 pairs)
//!   and a classical uniform technique drawn once (MMIS eq. 6, sec. 3.1);
//! - `Defensive`: a classical uniform technique with p = 0.2 beside 4 pure lobes;
//! - `path_estimate` over 3-vertex paths (sets of 8, 2 and 4 techniques; the second and third
//!   sets depend on the previous vertex)
//!   (MCPG eq. 6), f(x̄) = g(x₁) h(x₂) h(x₃) with ∫h = 1.
//!
//! Each check: 100 000 independent estimates, f32 estimator outputs accumulated in f64, z-test
//! of the mean against the exact integral at 5σ (two-sided α ≈ 5.7·10⁻⁷ per check, 138
//! checks), and the standard error must be below 5 % of the integral so that the test can see
//! a bias of that size. Seeds are fixed per estimator and domain.

use std::f64::consts::PI;

use mcg_smis::{
    Defensive, Mmis, Technique, mis_balance, path_estimate, sample_uniform_mixture, smis,
    smis_one_sample,
};
use mcg_tests::{
    LineIntegrand, LineTechnique, Pcg64Mcg, RunningStats, SphereIntegrand, SphereTechnique,
    assert_z_test, draw_line_boxcar, draw_line_lobe, draw_sphere_cap, draw_sphere_lobe,
    line_integrands, seeded_rng, sphere_integrands, uniform2,
};
use mcg_vmf::Vmf;
use mcg_vmf::glam::Vec3;
use rand::RngExt;

const RUNS: usize = 100_000;

fn check(label: &str, integral: f64, seed: u64, mut estimate: impl FnMut(&mut Pcg64Mcg) -> f64) {
    let mut rng = seeded_rng(seed);
    let stats: RunningStats = (0..RUNS).map(|_| estimate(&mut rng)).collect();
    let r = assert_z_test(label, &stats, integral, 5.0);
    assert!(
        r.standard_error < 0.05 * integral.abs(),
        "`{label}`: standard error {:.3e} too large to detect a 5 % bias (integral {integral:.4e})",
        r.standard_error
    );
}

// --- [0, 1) ----------------------------------------------------------------------------------

fn fl(g: &LineIntegrand, x: f32) -> f32 {
    (g.f)(f64::from(x)) as f32
}

fn for_line(seed: u64, estimator: &str, mut run: impl FnMut(&LineIntegrand, &mut Pcg64Mcg) -> f64) {
    for (k, g) in line_integrands().iter().enumerate() {
        let label = format!("{estimator} on [0,1): {}", g.name);
        check(&label, g.integral, seed + k as u64, |rng| run(g, rng));
    }
}

fn pure_line_lobe(rng: &mut Pcg64Mcg, features: &[f64]) -> LineTechnique {
    match draw_line_lobe(rng, features) {
        LineTechnique::Laplace { c, s, .. } => LineTechnique::Laplace { c, s, eps: 0.0 },
        other => other,
    }
}

#[test]
fn mis_balance_on_line() {
    let techniques = [
        LineTechnique::Uniform,
        LineTechnique::Laplace {
            c: 0.25,
            s: 0.1,
            eps: 0.0,
        },
        LineTechnique::Laplace {
            c: 0.7,
            s: 0.05,
            eps: 0.0,
        },
    ];
    let counts = [1_u32, 2, 2];
    for_line(0x5317_0100, "mis_balance", |g, rng| {
        let mut xs = [0.0_f32; 5];
        let mut s = 0;
        for (t, &n) in techniques.iter().zip(&counts) {
            for _ in 0..n {
                xs[s] = t.sample(rng.random());
                s += 1;
            }
        }
        let f = xs.map(|x| fl(g, x));
        f64::from(mis_balance(&techniques, &counts, &xs, &f))
    });
}

#[test]
fn smis_on_line() {
    for_line(0x5317_0200, "smis n=4", |g, rng| {
        let t: [LineTechnique; 4] = std::array::from_fn(|_| draw_line_lobe(rng, g.features));
        let xs = t.map(|t| t.sample(rng.random()));
        let f = xs.map(|x| fl(g, x));
        f64::from(smis(&t, &xs, &f))
    });
}

#[test]
fn smis_one_sample_on_line() {
    for_line(0x5317_0300, "smis_one_sample n=8", |g, rng| {
        let t: [LineTechnique; 8] = std::array::from_fn(|_| draw_line_lobe(rng, g.features));
        let (_, x) = sample_uniform_mixture(&t, rng.random(), rng.random());
        f64::from(smis_one_sample(&t, &x, fl(g, x)))
    });
}

#[test]
fn mmis_on_line() {
    for_line(0x5317_0400, "mmis", |g, rng| {
        let lobes: [LineTechnique; 2] = std::array::from_fn(|_| draw_line_lobe(rng, g.features));
        let boxes: [LineTechnique; 2] = std::array::from_fn(|_| draw_line_boxcar(rng));
        let spaces: [&[LineTechnique]; 2] = [&lobes, &boxes];
        let classical = [LineTechnique::Uniform];
        let mmis = Mmis::new(&spaces).with_classical(&classical, &[1]).unwrap();
        let xs = [
            lobes[0].sample(rng.random()),
            lobes[1].sample(rng.random()),
            boxes[0].sample(rng.random()),
            boxes[1].sample(rng.random()),
            classical[0].sample(rng.random()),
        ];
        let f = xs.map(|x| fl(g, x));
        f64::from(mmis.estimate(&xs, &f))
    });
}

#[test]
fn defensive_on_line() {
    for_line(0x5317_0500, "defensive p=0.2", |g, rng| {
        let set: [LineTechnique; 4] = std::array::from_fn(|_| pure_line_lobe(rng, g.features));
        let mix = Defensive::new(LineTechnique::Uniform, 0.2, &set).unwrap();
        let x = mix.sample((rng.random(), rng.random()));
        f64::from(mix.estimate(&x, fl(g, x)))
    });
}

#[test]
fn path_on_line() {
    let h = |x: f32| 0.5 + f64::from(x);
    for_line(0x5317_0600, "path k=3", |g, rng| {
        let v1: [LineTechnique; 8] = std::array::from_fn(|_| draw_line_lobe(rng, g.features));
        let (_, x1) = sample_uniform_mixture(&v1, rng.random(), rng.random());
        // The next vertex's lobes are placed relative to the previous vertex.
        let near = |x: f32, rng: &mut Pcg64Mcg| LineTechnique::Laplace {
            c: (x + 0.3 * (rng.random::<f32>() - 0.5)).clamp(0.0, 1.0),
            s: 0.1 + 0.3 * rng.random::<f32>(),
            eps: 0.3,
        };
        let v2: [LineTechnique; 2] = std::array::from_fn(|_| near(x1, rng));
        let (_, x2) = sample_uniform_mixture(&v2, rng.random(), rng.random());
        let v3: [LineTechnique; 4] = std::array::from_fn(|_| near(x2, rng));
        let (_, x3) = sample_uniform_mixture(&v3, rng.random(), rng.random());
        let f = (g.f)(f64::from(x1)) * h(x2) * h(x3);
        let sets: [&[LineTechnique]; 3] = [&v1, &v2, &v3];
        f64::from(path_estimate(f as f32, &sets, &[x1, x2, x3]))
    });
}

// --- S² --------------------------------------------------------------------------------------

fn fs(g: &SphereIntegrand, w: Vec3) -> f32 {
    (g.f)(w.as_dvec3()) as f32
}

fn for_sphere(
    seed: u64,
    estimator: &str,
    mut run: impl FnMut(&SphereIntegrand, &mut Pcg64Mcg) -> f64,
) {
    for (k, g) in sphere_integrands().iter().enumerate() {
        let label = format!("{estimator} on S2: {}", g.name);
        check(&label, g.integral, seed + k as u64, |rng| run(g, rng));
    }
}

fn pure_sphere_lobe(rng: &mut Pcg64Mcg, features: &[[f64; 3]]) -> SphereTechnique {
    match draw_sphere_lobe(rng, features) {
        SphereTechnique::Lobe { vmf, .. } => SphereTechnique::Lobe { vmf, eps: 0.0 },
        other => other,
    }
}

#[test]
fn mis_balance_on_sphere() {
    let techniques = [
        SphereTechnique::Uniform,
        SphereTechnique::Lobe {
            vmf: Vmf::new(Vec3::new(1.0, 2.0, 2.0), 10.0).unwrap(),
            eps: 0.0,
        },
        SphereTechnique::Lobe {
            vmf: Vmf::new(Vec3::new(-2.0, 1.0, -0.5), 100.0).unwrap(),
            eps: 0.0,
        },
    ];
    let counts = [1_u32, 2, 2];
    for_sphere(0x5317_0700, "mis_balance", |g, rng| {
        let mut xs = [Vec3::ZERO; 5];
        let mut s = 0;
        for (t, &n) in techniques.iter().zip(&counts) {
            for _ in 0..n {
                xs[s] = t.sample(uniform2(rng));
                s += 1;
            }
        }
        let f = xs.map(|x| fs(g, x));
        f64::from(mis_balance(&techniques, &counts, &xs, &f))
    });
}

#[test]
fn smis_on_sphere() {
    for_sphere(0x5317_0800, "smis n=4", |g, rng| {
        let t: [SphereTechnique; 4] = std::array::from_fn(|_| draw_sphere_lobe(rng, g.features));
        let xs = t.map(|t| t.sample(uniform2(rng)));
        let f = xs.map(|x| fs(g, x));
        f64::from(smis(&t, &xs, &f))
    });
}

#[test]
fn smis_one_sample_on_sphere() {
    for_sphere(0x5317_0900, "smis_one_sample n=8", |g, rng| {
        let t: [SphereTechnique; 8] = std::array::from_fn(|_| draw_sphere_lobe(rng, g.features));
        let (_, x) = sample_uniform_mixture(&t, rng.random(), uniform2(rng));
        f64::from(smis_one_sample(&t, &x, fs(g, x)))
    });
}

#[test]
fn mmis_on_sphere() {
    for_sphere(0x5317_0a00, "mmis", |g, rng| {
        let lobes: [SphereTechnique; 2] =
            std::array::from_fn(|_| draw_sphere_lobe(rng, g.features));
        let caps: [SphereTechnique; 2] = std::array::from_fn(|_| draw_sphere_cap(rng));
        let spaces: [&[SphereTechnique]; 2] = [&lobes, &caps];
        let classical = [SphereTechnique::Uniform];
        let mmis = Mmis::new(&spaces).with_classical(&classical, &[1]).unwrap();
        let xs = [
            lobes[0].sample(uniform2(rng)),
            lobes[1].sample(uniform2(rng)),
            caps[0].sample(uniform2(rng)),
            caps[1].sample(uniform2(rng)),
            classical[0].sample(uniform2(rng)),
        ];
        let f = xs.map(|x| fs(g, x));
        f64::from(mmis.estimate(&xs, &f))
    });
}

#[test]
fn defensive_on_sphere() {
    for_sphere(0x5317_0b00, "defensive p=0.2", |g, rng| {
        let set: [SphereTechnique; 4] = std::array::from_fn(|_| pure_sphere_lobe(rng, g.features));
        let mix = Defensive::new(SphereTechnique::Uniform, 0.2, &set).unwrap();
        let x = mix.sample((rng.random(), uniform2(rng)));
        f64::from(mix.estimate(&x, fs(g, x)))
    });
}

#[test]
fn path_on_sphere() {
    // h(ω) = 3 (1 + z²) / (16π) integrates to 1.
    let h = |w: Vec3| 3.0 * (1.0 + f64::from(w.z).powi(2)) / (16.0 * PI);
    for_sphere(0x5317_0c00, "path k=3", |g, rng| {
        let v1: [SphereTechnique; 8] = std::array::from_fn(|_| draw_sphere_lobe(rng, g.features));
        let (_, x1) = sample_uniform_mixture(&v1, rng.random(), uniform2(rng));
        // The next vertex's lobes point near the previous vertex's direction.
        let near = |w: Vec3, rng: &mut Pcg64Mcg| SphereTechnique::Lobe {
            vmf: Vmf::new(
                Vmf::new(w, 5.0).unwrap().sample(uniform2(rng)),
                1.0 + 4.0 * rng.random::<f32>(),
            )
            .unwrap(),
            eps: 0.5,
        };
        let v2: [SphereTechnique; 2] = std::array::from_fn(|_| near(x1, rng));
        let (_, x2) = sample_uniform_mixture(&v2, rng.random(), uniform2(rng));
        let v3: [SphereTechnique; 4] = std::array::from_fn(|_| near(x2, rng));
        let (_, x3) = sample_uniform_mixture(&v3, rng.random(), uniform2(rng));
        let f = (g.f)(x1.as_dvec3()) * h(x2) * h(x3);
        let sets: [&[SphereTechnique]; 3] = [&v1, &v2, &v3];
        f64::from(path_estimate(f as f32, &sets, &[x1, x2, x3]))
    });
}
