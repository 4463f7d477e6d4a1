//! CPU/GPU parity of `mcg::vmf` and `mcg::vmf_mixture`: pdf, sampling, reconstruction, products,
//! statistics update, convolution and mixtures.
//!
//! Runs on whatever wgpu adapter exists (lavapipe in CI); every test skips with a printed
//! reason when there is no adapter, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).
//! Hashes, checksums, table outcomes, packed words and integers must match bit for bit; the
//! vMF lobes go through `exp` and `log`, which WGSL only bounds loosely, so they are compared
//! within tolerances derived from WGSL's precision rules (see `common::tolerance`).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::types::{
    VmfQuery, VmfStatsQuery, VmfUpdate, mixture_stride_floats, pack_mixtures,
};
use mcg_gpu_backend::{VmfKernels, VmfMixtureKernel};
use mcg_test_support::assert_close;
use mcg_vmf::{FitParams, MapPrior, PriorDecay, SufficientStats, Vmf, VmfMixture};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

mod common;
use common::{EPS, KAPPAS, gpu_and_rng, random_unit, tolerance};

/// vMF pdf and `sample_with_pdf` on 22 × 512 lobes, queries and uniform pairs (fixed seed),
/// incl. uniforms 0 and 1 − ε: every GPU value within the [`tolerance`] of the CPU's.
/// Reports the largest error as a fraction of its tolerance. Broken once on purpose (the
/// WGSL pdf used `exp(-lobe.kappa * distance_squared)`, dropping the ½): failed.
#[test]
fn vmf_pdf_and_samples_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_pdf_and_samples_match_the_cpu", 7) else {
        return;
    };
    let mut lobes = Vec::new();
    let mut queries = Vec::new();
    for &kappa in &KAPPAS {
        for j in 0..512 {
            let lobe = Vmf::new(random_unit(&mut rng), kappa).unwrap();
            // Directions near the mean (where the pdf is large) and anywhere.
            let w = if j % 2 == 0 {
                lobe.sample(Vec2::new(rng.random(), rng.random()))
            } else {
                random_unit(&mut rng)
            };
            let u = match j {
                0 => Vec2::ZERO,
                1 => Vec2::splat(1.0 - f32::EPSILON / 2.0),
                _ => Vec2::new(rng.random(), rng.random()),
            };
            lobes.push(lobe);
            queries.push(VmfQuery::new(w, u));
        }
    }
    let kernels = VmfKernels::new();
    let (pdfs, samples) = kernels.pdf_and_sample(ctx, &lobes, &queries).unwrap();
    let (mut worst_pdf, mut worst_dir, mut worst_spdf) = (0.0_f64, 0.0_f64, 0.0_f64);
    for i in 0..lobes.len() {
        let (lobe, q) = (lobes[i], queries[i]);
        let kappa = f64::from(lobe.kappa());
        // pdf
        let cpu = f64::from(lobe.pdf(q.direction));
        let exponent = 0.5 * kappa * f64::from((q.direction - lobe.mu()).length_squared());
        // WGSL may flush subnormals: exp(·) below f32::MIN_POSITIVE may become 0 before the
        // multiplication by C(κ).
        let flush = f64::from(lobe.normalization()) * 2.0 * f64::from(f32::MIN_POSITIVE);
        let tol = tolerance::pdf(kappa, exponent) * cpu + flush;
        let err = (f64::from(pdfs[i]) - cpu).abs();
        assert!(
            err <= tol,
            "pdf κ = {kappa}, ω = {}: GPU {} CPU {cpu}, tolerance {tol}",
            q.direction,
            pdfs[i]
        );
        worst_pdf = worst_pdf.max(err / tol);
        // sample
        let (w, p) = lobe.sample_with_pdf(q.uniforms);
        let r = f64::from(lobe.mu().dot(w)) - 1.0;
        let dr = tolerance::cos_theta_minus_one(kappa, f64::from(q.uniforms.y), r);
        let tol_dir = tolerance::direction(dr);
        let g = samples[i];
        let err_dir = f64::from((g.direction - w).length());
        assert!(
            err_dir <= tol_dir,
            "sample κ = {kappa}, u = {}: GPU {} CPU {w}, |Δ| {err_dir} > {tol_dir}",
            q.uniforms,
            g.direction
        );
        worst_dir = worst_dir.max(err_dir / tol_dir);
        let tol_p =
            (tolerance::normalization(kappa) + tolerance::exp_of_product(kappa * r) + kappa * dr)
                * f64::from(p)
                + flush;
        let err_p = (f64::from(g.pdf) - f64::from(p)).abs();
        assert!(
            err_p <= tol_p,
            "sample pdf κ = {kappa}, u = {}: GPU {} CPU {p}, tolerance {tol_p}",
            q.uniforms,
            g.pdf
        );
        worst_spdf = worst_spdf.max(err_p / tol_p);
    }
    println!(
        "vMF parity on {} ({} lobes): largest error / tolerance: pdf {worst_pdf:.3}, \
         sample direction {worst_dir:.3}, sample pdf {worst_spdf:.3}",
        ctx.adapter_info().name,
        lobes.len()
    );
}

/// Reconstruction from sufficient statistics (MCMM/MCPG Alg. 2), products and the mean
/// cosine round trip on 2 000 fits (fixed seed): μ within 64 ε, κ within 64 ε relative (no
/// exp/log on that path: only +, −, ×, ÷ and sqrt), "no lobe" exactly where the CPU says
/// `None`; product scale within the tolerance of its three C(κ) and one exp; A₃(κ) within
/// the error of its expm1. Includes NaN statistics weights (no lobe), prior mean cosines of
/// NaN, 1.5 and −0.5 (clamped to [0, 1], NaN as 0, as on the CPU: the WGSL used r_p as given,
/// and the NaN case failed) and NaN κs (A₃ = 0; with `kappa <= 0.0`, what a driver may make of
/// `!(kappa > 0.0)`, it failed; so did w̄ ≤ 0 for the weight's guard). Broken once on purpose
/// (N instead of N² in the WGSL posterior):
/// failed.
#[test]
fn vmf_reconstruction_and_products_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_reconstruction_and_products_match_the_cpu", 11)
    else {
        return;
    };
    let mut stats = Vec::new();
    let mut queries = Vec::new();
    for i in 0..2000 {
        let x = Vec3::new(rng.random(), rng.random(), rng.random());
        let mut s = SufficientStats::EMPTY;
        let light = Vec3::new(
            rng.random_range(-5.0..5.0),
            4.0,
            rng.random_range(-5.0..5.0),
        );
        let spread = [0.01_f32, 0.3, 3.0][i % 3];
        let params = if i % 2 == 0 {
            FitParams::MCMM
        } else {
            FitParams::MCPG
        };
        for _ in 0..(i % 40) {
            let y = light + random_unit(&mut rng) * spread * rng.random::<f32>();
            s.update(x, y, rng.random_range(0.0..2.0), &params);
        }
        if i % 97 == 0 {
            s.mean_target = x; // ȳ = x: no lobe.
        }
        if i % 89 == 1 {
            s.weight_sum = f32::NAN; // Not valid: no lobe.
        }
        let prior = MapPrior {
            // Out of range and NaN: clamped to [0, 1], NaN as 0.
            mean_cosine: match i % 61 {
                0 => f32::NAN,
                1 => 1.5,
                2 => -0.5,
                _ => [0.0, 0.3][i % 2],
            },
            weight: [0.0, 0.2, 1.0, f32::INFINITY][i % 4],
            decay: if i % 5 == 0 {
                PriorDecay::Count
            } else {
                PriorDecay::SquaredCount
            },
        };
        let other = Vmf::new(random_unit(&mut rng), KAPPAS[i % KAPPAS.len()]).unwrap();
        let kappa = if i % 53 == 0 {
            f32::NAN
        } else {
            KAPPAS[(i / 3) % KAPPAS.len()]
        };
        stats.push(s);
        queries.push(VmfStatsQuery::new(x, prior, other, kappa));
    }
    let results = VmfKernels::new().stats(ctx, &stats, &queries).unwrap();
    let mut lobes = 0;
    for (i, (s, q)) in stats.iter().zip(&queries).enumerate() {
        let prior = MapPrior {
            mean_cosine: q.prior_mean_cosine,
            weight: q.prior_weight,
            decay: if q.prior_decay == 1 {
                PriorDecay::Count
            } else {
                PriorDecay::SquaredCount
            },
        };
        let g = results[i];
        match s.to_vmf(q.shading_point, prior) {
            None => assert_eq!(g.reconstructed[3], -1.0, "{i}: GPU found a lobe, CPU none"),
            Some(lobe) => {
                lobes += 1;
                let mu = Vec3::from_slice(&g.reconstructed[..3]);
                assert!(
                    (mu - lobe.mu()).length() <= 64.0 * f32::EPSILON,
                    "{i}: μ {mu} vs {}",
                    lobe.mu()
                );
                let k = f64::from(lobe.kappa());
                assert_close!(f64::from(g.reconstructed[3]), k, 64.0 * EPS * k, "{i}: κ");
                // Product with `other`, from the CPU's lobe.
                let (p, scale) = lobe.product(&q.other);
                let pk = f64::from(p.kappa());
                assert_close!(
                    f64::from(g.product[3]),
                    pk,
                    64.0 * EPS * pk.max(1.0),
                    "{i}: product κ"
                );
                let pmu = Vec3::from_slice(&g.product[..3]);
                assert!(
                    (pmu - p.mu()).length() <= 1e-4,
                    "{i}: product μ {pmu} vs {}",
                    p.mu()
                );
                let exponent = pk - k - f64::from(q.other.kappa());
                let tol = tolerance::normalization(k)
                    + tolerance::normalization(f64::from(q.other.kappa()))
                    + tolerance::normalization(pk)
                    + tolerance::exp_of_product(exponent.min(0.0))
                    // κ' − κ₀ − κ₁ cancels: its absolute error is a few ε of the κs.
                    + 64.0 * EPS * (k + pk)
                    + 8.0 * EPS;
                let err = (f64::from(g.product_scale) - f64::from(scale)).abs();
                assert!(
                    err <= tol * f64::from(scale) + 1e-30,
                    "{i}: scale {} vs {scale}",
                    g.product_scale
                );
            }
        }
        let kappa = q.kappa;
        let a = mcg_vmf::mean_cosine_from_kappa(kappa);
        // NaN: A₃ = 0 exactly.
        let tol = tolerance::mean_cosine(f64::from(kappa).max(0.0));
        assert_close!(f64::from(g.mean_cosine), f64::from(a), tol, "A₃({kappa})");
        // Banerjee's κ of the GPU's own A₃ (arithmetic only) matches the CPU's of the same r.
        let kb = mcg_vmf::kappa_from_mean_cosine(g.mean_cosine);
        assert_close!(
            f64::from(g.kappa_back),
            f64::from(kb),
            64.0 * EPS * f64::from(kb).max(1.0),
            "κ(A₃)"
        );
    }
    assert!(lobes > 1500, "{lobes} lobes");
}

/// One `SufficientStats::update` (MCMM Alg. 3, MCPG Alg. 3) from 4 096 states (fits of
/// 0..40 samples, both mean-cosine updates, incl. rejected negative and infinite weights,
/// y = x, and targets so far that |y − x|² overflows or so near that it is subnormal, which
/// `normalize_robust` rescales first: a WGSL normalisation without the rescaling fails those,
/// 1 − r̄ 0.33 against 0.60): N exact; w̄ within 8 ε relative (three roundings of positive terms and the 2.5-ULP
/// division 1/N); ȳ within 16 ε (|ȳ| + |y|); 1 − r̄ within 32 ε (√(2t) + e + t) + 400 ε²,
/// where t = 1 − d·μ: the normalisations of d and μ (sqrt and division, ≤ 5 ULP each)
/// perturb |d − μ| by ≤ 16 ε, and the remaining products and the final division add a few ε
/// of e and t. Broken once on purpose (β = α instead of αf/w̄'): failed.
#[test]
fn vmf_stats_update_matches_the_cpu() {
    let Some(ctx) = gpu_or_skip("vmf_stats_update_matches_the_cpu") else {
        return;
    };
    let kernels = VmfKernels::new();
    for params in [FitParams::MCMM, FitParams::MCPG] {
        let mut rng = Pcg64::seed_from_u64(23);
        let mut stats = Vec::new();
        let mut updates = Vec::new();
        for i in 0..4096 {
            let x = Vec3::new(rng.random(), rng.random(), rng.random());
            let light = Vec3::new(
                rng.random_range(-5.0..5.0),
                6.0,
                rng.random_range(-5.0..5.0),
            );
            let spread = [0.001_f32, 0.1, 2.0][i % 3];
            let mut s = SufficientStats::EMPTY;
            for _ in 0..(i % 40) {
                s.update(
                    x,
                    light + random_unit(&mut rng) * spread,
                    rng.random_range(0.0..2.0),
                    &params,
                );
            }
            // Targets so far that |y − x|² overflows, and so near that it is subnormal:
            // `normalize_robust` rescales both first.
            let (x, y) = match (i % 50, i % 89) {
                (0, _) => (x, x),
                (_, 3) => (Vec3::ZERO, Vec3::new(3e19, -2e19, 1e19)),
                (_, 4) => (Vec3::ZERO, Vec3::new(1e-20, -2e-20, 3e-21)),
                _ => (x, light + random_unit(&mut rng) * spread),
            };
            let weight = match i % 97 {
                0 => -1.0,
                1 => f32::INFINITY,
                2 => 0.0,
                _ => rng.random_range(0.0..2.0),
            };
            stats.push(s);
            updates.push(VmfUpdate::new(x, y, weight));
        }
        let gpu = kernels
            .update_stats(ctx, &stats, &updates, &params)
            .unwrap();
        for i in 0..stats.len() {
            let before = stats[i];
            let u = updates[i];
            let mut cpu = before;
            cpu.update(u.x, u.y, u.weight, &params);
            let g = gpu[i];
            assert_eq!(g.sample_count, cpu.sample_count, "{i}");
            let w = f64::from(cpu.weight_sum);
            assert_close!(f64::from(g.weight_sum), w, 8.0 * EPS * w, "{i}: w̄");
            let scale = f64::from(before.mean_target.length() + u.y.length());
            assert!(
                f64::from((g.mean_target - cpu.mean_target).length()) <= 16.0 * EPS * scale,
                "{i}: ȳ {} vs {}",
                g.mean_target,
                cpu.mean_target
            );
            let d = (u.y - u.x).normalize_or_zero();
            let mu = if before.weight_sum > 0.0 {
                (before.mean_target - u.x).try_normalize().unwrap_or(d)
            } else {
                d
            };
            let t = 0.5 * f64::from((d - mu).length_squared());
            let e = f64::from(before.one_minus_mean_cosine);
            let c = f64::from(cpu.one_minus_mean_cosine);
            // Plus the update's division, within 2.5 ULP in WGSL (an NVIDIA H200 gave
            // 0.99999994 for a fresh state's 1).
            let tol = 32.0 * EPS * ((2.0 * t).sqrt() + e + t) + 400.0 * EPS * EPS + 4.0 * EPS * c;
            assert_close!(f64::from(g.one_minus_mean_cosine), c, tol, "{i}: 1 − r̄");
        }
    }
}

/// `VmfMixture<4>` pdf, component choice and `sample_with_pdf` on 8 192 mixtures (fixed seed;
/// κ from the switch-point list, weights with zeros, uniforms incl. 0 and 1 − ε/2).
/// Hypotheses: the component index is exact and the rescaled uniform within 4 ULP
/// (`rescaled_uniform_matches`: +, −, comparisons and one division); the pdf is within
/// Σ wᵢ Vᵢ(ω) tolᵢ + 4ε of the CPU's, tolᵢ = `tolerance::pdf` of each lobe; the sampled
/// direction within `tolerance::direction` of the CPU's sample of the chosen lobe with the
/// same uniforms; the sample's pdf within the pdf tolerance of the CPU's mixture pdf at the
/// GPU's direction. Broken once on purpose (the WGSL select rescaled with `u / weight`
/// instead of `(u − start)/weight`): failed.
#[test]
fn vmf_mixture_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_mixture_matches_the_cpu", 29) else {
        return;
    };
    let n = 8192;
    let mut mixtures = Vec::with_capacity(n);
    let mut queries = Vec::with_capacity(n);
    for i in 0..n {
        let lobes = [0; 4].map(|_| {
            Vmf::new(
                random_unit(&mut rng),
                KAPPAS[rng.random_range(0..KAPPAS.len())],
            )
            .unwrap()
        });
        let mut weights = [0; 4].map(|_| rng.random_range(0.0..3.0_f32));
        if i % 3 == 0 {
            weights[rng.random_range(0..4)] = 0.0;
        }
        weights[i % 4] += 0.1;
        mixtures.push(VmfMixture::new(lobes, weights).unwrap());
        let u = match i % 64 {
            0 => Vec2::ZERO,
            1 => Vec2::splat(1.0 - f32::EPSILON / 2.0),
            _ => Vec2::new(rng.random(), rng.random()),
        };
        queries.push(VmfQuery::new(random_unit(&mut rng), u));
    }
    let evals = VmfMixtureKernel::<4>::new()
        .eval(ctx, &mixtures, &queries)
        .unwrap();
    // The pdf tolerance of the mixture at `w`: each lobe's tolerance, weighted.
    let pdf_tolerance = |m: &VmfMixture<4>, w: Vec3| -> f64 {
        let mut tol = 0.0;
        for (lobe, &weight) in m.lobes().iter().zip(m.weights()) {
            let kappa = f64::from(lobe.kappa());
            let exponent = 0.5 * kappa * f64::from((w - lobe.mu()).length_squared());
            let flush = f64::from(lobe.normalization()) * 2.0 * f64::from(f32::MIN_POSITIVE);
            tol += f64::from(weight)
                * (tolerance::pdf(kappa, exponent) * f64::from(lobe.pdf(w)) + flush);
        }
        tol + 4.0 * EPS * f64::from(m.pdf(w))
    };
    let (mut worst_pdf, mut worst_dir) = (0.0_f64, 0.0_f64);
    for i in 0..n {
        let (m, q) = (&mixtures[i], queries[i]);
        let (index, u) = m.select(q.uniforms.x);
        let e = evals[i];
        assert_eq!(
            e.component, index,
            "{i}: component choice of u = {}",
            q.uniforms.x
        );
        assert!(
            rescaled_uniform_matches(e.u, u),
            "{i}: rescaled uniform of u = {}: GPU {} CPU {u}",
            q.uniforms.x,
            e.u
        );
        let cpu = f64::from(m.pdf(q.direction));
        let tol = pdf_tolerance(m, q.direction);
        let gpu_pdf = e.pdf;
        let err = (f64::from(gpu_pdf) - cpu).abs();
        assert!(err <= tol, "{i}: pdf GPU {gpu_pdf} CPU {cpu} (tol {tol})");
        worst_pdf = worst_pdf.max(err / tol);
        let lobe = m.lobes()[index];
        let w = lobe.sample(Vec2::new(u, q.uniforms.y));
        assert_eq!(w, m.sample(q.uniforms), "the CPU reuses the uniform");
        let kappa = f64::from(lobe.kappa());
        let r = f64::from(lobe.mu().dot(w)) - 1.0;
        let dr = tolerance::cos_theta_minus_one(kappa, f64::from(q.uniforms.y), r);
        let tol_dir = tolerance::direction(dr);
        let g = e.sample;
        let err_dir = f64::from((g.direction - w).length());
        assert!(
            err_dir <= tol_dir,
            "{i}: sample GPU {} CPU {w} (tol {tol_dir})",
            g.direction
        );
        worst_dir = worst_dir.max(err_dir / tol_dir);
        let at = f64::from(m.pdf(g.direction));
        let tol_p = pdf_tolerance(m, g.direction);
        assert_close!(f64::from(g.pdf), at, tol_p, "{i}: sample pdf, GPU vs CPU");
    }
    println!(
        "mixture parity ({n} mixtures of 4): choices exact; largest error / tolerance: \
         pdf {worst_pdf:.3}, direction {worst_dir:.3}"
    );
}

/// `Vmf::convolve` and `kappa_from_mean_cosine_exact` on 4 096 lobes × kernels and 4 096 mean
/// cosines in (0, 1) (fixed seed, κ from the switch-point list, r dense near 0 and 1).
/// Hypothesis: μ is copied bit for bit and κ' agrees within the propagated error of the
/// inputs' A₃ on the GPU: |Δκ'| ≤ (ΔA(κ) A(κ_k) + A(κ) ΔA(κ_k) + ΔA(κ') + 4ε)/A₃'(κ') +
/// 4·10⁻⁷ κ' (the two Newton stops), ΔA = `tolerance::mean_cosine`, and the same for the
/// inverse alone (ΔA(κ') + 2ε over the slope). NaN kernel κs and NaN mean cosines give κ' = 0
/// as on the CPU: the guards test NaN from the bits. Written as a driver may rewrite them
/// under WGSL's no-NaN assumption (`kappa <= 0.0` for `!(kappa > 0.0)`; `r <= 0.0` with the
/// Newton loop's `next <= 0.0`), the NaN cases failed. Broken once on purpose (the WGSL inverse
/// returned Banerjee's approximation without Newton steps): failed.
#[test]
fn vmf_convolution_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_convolution_matches_the_cpu", 31) else {
        return;
    };
    let n = 4096;
    let lobes: Vec<Vmf> = (0..n)
        .map(|i| Vmf::new(random_unit(&mut rng), KAPPAS[i % KAPPAS.len()]).unwrap())
        .collect();
    let params: Vec<[f32; 2]> = (0..n)
        .map(|i| {
            let kernel = match i % 5 {
                0 if i % 10 == 0 => f32::NAN,
                0 => -1.0,
                1 => KAPPAS[(i / 5) % KAPPAS.len()],
                _ => 10f32.powf(rng.random_range(-3.0..5.0)),
            };
            let r = match i % 3 {
                0 if i % 33 == 0 => f32::NAN,
                0 => rng.random::<f32>(),
                1 => 1.0 - 10f32.powf(rng.random_range(-7.0..0.0)),
                _ => 10f32.powf(rng.random_range(-8.0..0.0)),
            };
            [kernel, r]
        })
        .collect();
    let (kernel_kappas, mean_cosines): (Vec<f32>, Vec<f32>) =
        params.iter().map(|&[k, r]| (k, r)).unzip();
    let (convolved, kappas) = VmfKernels::new()
        .convolve(ctx, &lobes, &kernel_kappas, &mean_cosines)
        .unwrap();
    let a = |k: f64| f64::from(mcg_vmf::mean_cosine_from_kappa(k as f32));
    // dA₃/dκ in f64: 1/κ² − 1/sinh²κ (series near 0).
    let slope = |k: f64| {
        if k < 1e-3 {
            1.0 / 3.0 - k * k / 15.0
        } else {
            1.0 / (k * k) - 1.0 / k.sinh().powi(2)
        }
    };
    let (mut worst_conv, mut worst_inv) = (0.0_f64, 0.0_f64);
    for i in 0..n {
        let [kk, r] = params[i];
        let cpu = lobes[i].convolve(kk);
        let g = convolved[i];
        assert_eq!(g.mu(), cpu.mu(), "{i}: μ");
        let (k, kk, k2) = (
            f64::from(lobes[i].kappa()),
            f64::from(kk.max(0.0)),
            f64::from(cpu.kappa()),
        );
        let da = tolerance::mean_cosine(k) * a(kk)
            + a(k) * tolerance::mean_cosine(kk)
            + tolerance::mean_cosine(k2)
            + 4.0 * EPS;
        let tol = (da / slope(k2).max(1e-300)).min(1e7) + 4e-7 * k2 + 1e-30;
        let err = (f64::from(g.kappa()) - k2).abs();
        assert!(
            err <= tol,
            "{i}: κ {k} ⊛ {kk}: GPU {} CPU {k2} (tol {tol})",
            g.kappa()
        );
        worst_conv = worst_conv.max(err / tol);
        let cpu = f64::from(mcg_vmf::kappa_from_mean_cosine_exact(r));
        let tol = ((tolerance::mean_cosine(cpu) + 2.0 * EPS) / slope(cpu).max(1e-300)).min(1e7)
            + 4e-7 * cpu
            + 1e-30;
        let err = (f64::from(kappas[i]) - cpu).abs();
        assert!(
            err <= tol,
            "{i}: κ(r = {r}): GPU {} CPU {cpu} (tol {tol})",
            kappas[i]
        );
        worst_inv = worst_inv.max(err / tol);
    }
    println!(
        "convolution parity ({n}): largest error / tolerance: convolved κ {worst_conv:.3}, \
         exact inverse {worst_inv:.3}"
    );
}

/// `VmfMixtureKernel::<K>` for K = 1 and 3 (the kernel's `VMF_MIXTURE_K` replaced on the
/// host): on 512 mixtures each (fixed seed, κ in [0.5, 50], weights in (0.1, 3)), the
/// component equals the CPU's, the rescaled uniform is within 4 ULP of it and the pdf is within
/// 10⁻⁴ relative (κ ≤ 50 keeps `tolerance::pdf` below 10⁻⁴, see the K = 4 test). A wrong K
/// misreads the packed layout and fails. Broken once on purpose (the host left K at 4):
/// failed.
#[test]
fn vmf_mixture_kernel_takes_any_k() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_mixture_kernel_takes_any_k", 53) else {
        return;
    };
    fn check<const K: usize>(ctx: &mcg_gpu_backend::GpuContext, rng: &mut impl rand::Rng) {
        let mixtures: Vec<VmfMixture<K>> = (0..512)
            .map(|_| {
                let lobes = [0; K]
                    .map(|_| Vmf::new(random_unit(rng), rng.random_range(0.5..50.0)).unwrap());
                VmfMixture::new(lobes, [0; K].map(|_| rng.random_range(0.1..3.0))).unwrap()
            })
            .collect();
        let queries: Vec<VmfQuery> = (0..512)
            .map(|_| VmfQuery::new(random_unit(rng), Vec2::new(rng.random(), rng.random())))
            .collect();
        let evals = VmfMixtureKernel::<K>::new()
            .eval(ctx, &mixtures, &queries)
            .unwrap();
        for ((m, q), e) in mixtures.iter().zip(&queries).zip(&evals) {
            let (index, u) = m.select(q.uniforms.x);
            assert_eq!(e.component, index, "K = {K}");
            assert!(
                rescaled_uniform_matches(e.u, u),
                "K = {K}: GPU {} CPU {u}",
                e.u
            );
            let cpu = m.pdf(q.direction);
            assert_close!(e.pdf, cpu, 1e-4 * cpu + 1e-30, "K = {K}: pdf, GPU vs CPU");
        }
    }
    check::<1>(ctx, &mut rng);
    check::<3>(ctx, &mut rng);
}

/// The rescaled uniform (u − start)/w of a mixture's component choice: within 4 ULP of the
/// CPU's, WGSL's division being within 2.5 ULP (lavapipe's is correctly rounded and matched
/// bit for bit; an NVIDIA H200's was 1 ULP off).
fn rescaled_uniform_matches(gpu: f32, cpu: f32) -> bool {
    common::ulps(gpu, cpu) <= 4
}

/// `pack_mixtures` writes the layout the WGSL struct has for K = 4 (checked against naga in
/// `tests/modules.rs` for K = 1..=5): lobes, then weights, then padding.
#[test]
fn packed_mixtures_have_the_wgsl_layout() {
    let m = VmfMixture::new(
        [
            Vmf::new(Vec3::X, 1.0).unwrap(),
            Vmf::new(Vec3::Y, 2.0).unwrap(),
        ],
        [1.0, 3.0],
    )
    .unwrap();
    let packed = pack_mixtures(&[m, m]);
    assert_eq!(mixture_stride_floats(2), 12);
    assert_eq!(packed.len(), 24);
    assert_eq!(
        packed[..12],
        [1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.25, 0.75, 0.0, 0.0]
    );
}
