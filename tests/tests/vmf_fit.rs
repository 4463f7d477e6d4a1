//! Statistical suite of the parallax-aware fit (`SufficientStats`): samples of a known lobe
//! vMF(μ, κ) seen from a shading point x, turned into target points y = x + d·ω with weights
//! f, must give back μ and κ.
//!
//! Setting: x at the origin, μ = normalize(0.3, −0.5, 0.8), n = 20 000 samples per fit,
//! κ ∈ {1, 3, 10, 30, 100, 300}, every fit with its own fixed seed; κ = 1000 is in
//! [`kappa_1000_running_mean`], which also guards against the f32 drift of a stored r̄ (see
//! that test). The statistics use `FitParams::RUNNING_MEAN` (α = 1/N: the plain weighted
//! mean) unless stated, and the lobe is read back without a prior (`MapPrior::NONE`).
//!
//! Each fit is checked three ways:
//! 1. κ̂ = `kappa_from_mean_cosine_exact(posterior_mean_cosine)` is within 5 % of κ **and**
//!    within 5σ_κ, with σ_κ = sd(μ·ω) · √(Σf²)/Σf / A₃'(κ) by the delta method (σ_κ/κ is 1.3 %
//!    at κ = 1 and 0.7 % for large κ at n = 20 000, so 5 % is 3.7σ at κ = 1 and 7σ above).
//! 2. The mean direction (ȳ − x)/|ȳ − x|: its two angular components orthogonal to μ, divided
//!    by their standard deviation σ_a = √(A₃/κ · Σf²d²)/(A₃ Σfd), give a χ²₂ statistic that must
//!    stay below 13.8 (α = 0.001).
//! 3. Banerjee's approximation, `to_vmf(x, MapPrior::NONE).kappa()`, is within 5 % of
//!    `kappa_from_mean_cosine(mean_cosine_from_kappa(κ))` (its own bias, up to 4.9 %, is not
//!    the fit's error, so it is compared with the approximation of the true value).

use glam::{DVec3, Vec3};
use mcg_tests::{
    orthonormal_basis, seeded_rng, uniform_vec2, vmf_cos_theta_variance, vmf_mean_cosine,
    vmf_mean_cosine_derivative,
};
use mcg_vmf::{
    FitParams, MapPrior, MeanCosineUpdate, SufficientStats, Vmf, kappa_from_mean_cosine,
    kappa_from_mean_cosine_exact, mean_cosine_from_kappa,
};
use rand::RngExt;

const KAPPAS: [f32; 6] = [1.0, 3.0, 10.0, 30.0, 100.0, 300.0];
const N: usize = 20_000;
/// χ²₂ quantile at 1 − 0.001: −2 ln 0.001.
const CHI2_2DOF_999: f64 = 13.815_510_557_964_274;

/// The MCPG projected update with a plain running mean (α_min = 0, N uncapped).
const PROJECTED_RUNNING_MEAN: FitParams = FitParams {
    max_count: u32::MAX,
    alpha_min: 0.0,
    mean_cosine_update: MeanCosineUpdate::Projected,
};

#[derive(Clone, Copy, Debug)]
enum Distance {
    Fixed(f32),
    Uniform(f32, f32),
}

#[derive(Clone, Copy, Debug)]
enum Weights {
    One,
    /// f = 2(1 − u), uniform on (0, 2], independent of the direction.
    Uniform,
}

/// One fit and what it is checked against.
#[derive(Debug)]
struct Fit {
    kappa: f32,
    kappa_exact: f32,
    kappa_banerjee: f32,
    banerjee_expected: f32,
    sigma_kappa: f64,
    direction_chi2: f64,
}

impl Fit {
    fn failures(&self) -> Vec<String> {
        let k = f64::from(self.kappa);
        let deviation = f64::from(self.kappa_exact) - k;
        let mut failures = Vec::new();
        let within_five_percent = deviation.abs() < 0.05 * k;
        if !within_five_percent {
            failures.push(format!(
                "exact kappa {} is not within 5 % of {}",
                self.kappa_exact, self.kappa
            ));
        }
        let within_five_sigma = deviation.abs() < 5.0 * self.sigma_kappa;
        if !within_five_sigma {
            failures.push(format!(
                "exact kappa {} is {:.2} sigma from {}",
                self.kappa_exact,
                deviation / self.sigma_kappa,
                self.kappa
            ));
        }
        let direction_accepted = self.direction_chi2 < CHI2_2DOF_999;
        if !direction_accepted {
            failures.push(format!(
                "mean direction chi2 {:.2} >= {CHI2_2DOF_999:.2}",
                self.direction_chi2
            ));
        }
        let banerjee = f64::from(self.kappa_banerjee) / f64::from(self.banerjee_expected) - 1.0;
        let banerjee_within = banerjee.abs() < 0.05;
        if !banerjee_within {
            failures.push(format!(
                "Banerjee kappa {} is not within 5 % of {}",
                self.kappa_banerjee, self.banerjee_expected
            ));
        }
        failures
    }
}

/// Fits `n` samples of vMF(μ, κ) seen from the origin with the given target distances,
/// weights and update rule.
fn fit(kappa: f32, seed: u64, distance: Distance, weights: Weights, params: &FitParams) -> Fit {
    let lobe = Vmf::new(Vec3::new(0.3, -0.5, 0.8), kappa).unwrap();
    let x = Vec3::ZERO;
    let mut rng = seeded_rng(seed);
    let mut stats = SufficientStats::EMPTY;
    // Σf, Σf², Σfd, Σf²d² in f64, for the standard deviations.
    let (mut sf, mut sf2, mut sfd, mut sf2d2) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for _ in 0..N {
        let w = lobe.sample(uniform_vec2(&mut rng));
        let d = match distance {
            Distance::Fixed(d) => d,
            Distance::Uniform(lo, hi) => lo + (hi - lo) * rng.random::<f32>(),
        };
        let f = match weights {
            Weights::One => 1.0,
            Weights::Uniform => 2.0 * (1.0 - rng.random::<f32>()),
        };
        assert!(stats.update(x, x + w * d, f, params));
        let (f, d) = (f64::from(f), f64::from(d));
        sf += f;
        sf2 += f * f;
        sfd += f * d;
        sf2d2 += f * f * d * d;
    }
    let k = f64::from(kappa);
    let a3 = vmf_mean_cosine(k);
    let sigma_r = vmf_cos_theta_variance(k).sqrt() * sf2.sqrt() / sf;
    let sigma_kappa = sigma_r / vmf_mean_cosine_derivative(k);

    let mu = lobe.mu().as_dvec3();
    let (e1, e2) = orthonormal_basis(mu);
    let m: DVec3 = (stats.mean_target - x).as_dvec3();
    let (a1, a2) = (m.dot(e1) / m.dot(mu), m.dot(e2) / m.dot(mu));
    let sigma_a = (a3 / k * sf2d2).sqrt() / (a3 * sfd);
    let direction_chi2 = (a1 * a1 + a2 * a2) / (sigma_a * sigma_a);

    let fitted = stats
        .to_vmf(x, MapPrior::NONE)
        .expect("statistics are valid");
    assert_eq!(Some(fitted.mu()), stats.mean_direction(x));
    Fit {
        kappa,
        kappa_exact: kappa_from_mean_cosine_exact(stats.posterior_mean_cosine(MapPrior::NONE)),
        kappa_banerjee: fitted.kappa(),
        banerjee_expected: kappa_from_mean_cosine(mean_cosine_from_kappa(kappa)),
        sigma_kappa,
        direction_chi2,
    }
}

/// Runs the fit for every κ and panics with the whole table if any check fails.
fn check_all(
    label: &str,
    seed: u64,
    distance: Distance,
    weights: Weights,
    params: &FitParams,
) -> Vec<Fit> {
    check_kappas(&KAPPAS, label, seed, distance, weights, params)
}

/// [`check_all`] for the given concentrations.
fn check_kappas(
    kappas: &[f32],
    label: &str,
    seed: u64,
    distance: Distance,
    weights: Weights,
    params: &FitParams,
) -> Vec<Fit> {
    let fits: Vec<Fit> = kappas
        .iter()
        .enumerate()
        .map(|(i, &kappa)| fit(kappa, seed + i as u64, distance, weights, params))
        .collect();
    let mut report = String::new();
    for fit in &fits {
        let failures = fit.failures();
        report += &format!(
            "\n  kappa {:>6}: exact {:>9.3} ({:+.2} sigma), Banerjee {:>9.3} vs {:>9.3}, direction chi2 {:>5.2} {}",
            fit.kappa,
            fit.kappa_exact,
            (f64::from(fit.kappa_exact) - f64::from(fit.kappa)) / fit.sigma_kappa,
            fit.kappa_banerjee,
            fit.banerjee_expected,
            fit.direction_chi2,
            if failures.is_empty() {
                String::new()
            } else {
                format!("FAILED: {}", failures.join("; "))
            },
        );
    }
    eprintln!("{label}:{report}");
    assert!(
        fits.iter().all(|fit| fit.failures().is_empty()),
        "fit `{label}` failed:{report}"
    );
    fits
}

/// H₀: the running-mean fit recovers μ and κ from targets at a fixed distance d = 5 with unit
/// weights. n = 20 000 per κ, thresholds as in the module docs (5 % and 5σ_κ on κ, χ²₂ at
/// α = 0.001 on the direction, 5 % for Banerjee), seeds 0xF1_0000 + i.
#[test]
fn fixed_distance_unit_weights() {
    check_all(
        "d = 5, f = 1",
        0xF1_0000,
        Distance::Fixed(5.0),
        Weights::One,
        &FitParams::RUNNING_MEAN,
    );
}

/// H₀: as [`fixed_distance_unit_weights`] with each target at a random distance d ~ U[2, 10)
/// independent of ω. The mean target ȳ is then on none of the sample rays, but
/// E[ȳ − x] = E[d]·A₃(κ)·μ by independence, so its direction is still μ (with an angular
/// spread larger by √E[d²]/E[d] ≈ 1.07, which σ_a accounts for). r̄ is the resultant length
/// re-projected onto the ȳ direction at each step; the difference from |Σω|/n is second order.
/// n = 20 000, seeds 0xF2_0000 + i.
#[test]
fn random_distance_unit_weights() {
    check_all(
        "d ~ U[2, 10), f = 1",
        0xF2_0000,
        Distance::Uniform(2.0, 10.0),
        Weights::One,
        &FitParams::RUNNING_MEAN,
    );
}

/// H₀: as [`fixed_distance_unit_weights`] with random weights f ~ U(0, 2] independent of ω
/// (effective sample size (Σf)²/Σf² ≈ 0.75 n, accounted for in σ_κ and σ_a).
/// n = 20 000, seeds 0xF3_0000 + i.
#[test]
fn fixed_distance_random_weights() {
    check_all(
        "d = 5, f ~ U(0, 2]",
        0xF3_0000,
        Distance::Fixed(5.0),
        Weights::Uniform,
        &FitParams::RUNNING_MEAN,
    );
}

/// H₀: random distances and random weights together. n = 20 000, seeds 0xF4_0000 + i.
#[test]
fn random_distance_random_weights() {
    check_all(
        "d ~ U[2, 10), f ~ U(0, 2]",
        0xF4_0000,
        Distance::Uniform(2.0, 10.0),
        Weights::Uniform,
        &FitParams::RUNNING_MEAN,
    );
}

/// H₀: MCPG's projected update r̄ ← mix(r̄, d·μ̂, β) (MCPG Alg. 3 line 9), run as a plain running
/// mean (α_min = 0, N uncapped), passes the same checks as the resultant update.
///
/// The projected r̄ averages ω_k·μ̂_{k−1} against the mean direction *before* sample k, so
/// early samples are projected onto a poor μ̂ (the first one onto itself, cos = 1). Both
/// effects are O(ln n / n) relative in 1 − r̄, i.e. ~5·10⁻⁴ at n = 20 000, far below the
/// statistical error. Measured on identical samples (seeds 0xF5_0000 + i, d = 5, f = 1), the
/// two estimates of κ differ by 0.05–0.3 % (largest at κ = 300, where f32 rounding of r̄
/// starts to show), at most 0.4σ_κ: the projected update is as good as the resultant one
/// for a stationary lobe. The assertion allows 1 %. (With `FitParams::MCPG`'s α_min = 0.01
/// the fit is an exponential moving average over (2 − α)/α ≈ 200 effective samples, so κ̂
/// scatters by ~1/√200 ≈ 7 %: a tracking setting, not an estimator of a fixed lobe.)
#[test]
fn projected_update_matches_resultant() {
    let resultant = check_all(
        "resultant",
        0xF5_0000,
        Distance::Fixed(5.0),
        Weights::One,
        &FitParams::RUNNING_MEAN,
    );
    let projected = check_all(
        "projected",
        0xF5_0000,
        Distance::Fixed(5.0),
        Weights::One,
        &PROJECTED_RUNNING_MEAN,
    );
    for (r, p) in resultant.iter().zip(&projected) {
        let difference = f64::from(p.kappa_exact) / f64::from(r.kappa_exact) - 1.0;
        assert!(
            difference.abs() < 0.01,
            "kappa {}: projected {} vs resultant {}",
            r.kappa,
            p.kappa_exact,
            r.kappa_exact
        );
    }
}

/// H₀: the four settings above also hold at κ = 1000 (n = 20 000, same thresholds, seeds
/// 0xF6_0000, 0xF7_0000, 0xF8_0000, 0xF9_0000).
///
/// Also a regression test of the f32 precision of r̄. An earlier `SufficientStats` kept r̄ in f32
/// next to 1, where its spacing is 2⁻²⁴ ≈ 6·10⁻⁸, while the per-sample change β(μ·ω − r̄) of a
/// running mean is ~1/(κN), 5·10⁻⁸ at κ = 10³ and N = 2·10⁴: increments below half an ulp
/// rounded away and, since μ·ω − r̄ is skewed, r̄ drifted (1033.7 (+4.8σ) and 961.8 (−5.4σ) in
/// the first two settings here; 510 instead of 1000 at N = 10⁵). It now stores e = 1 − r̄ and
/// updates it without cancellation, which passes. With the papers' α_min ≥ 0.01 the steps
/// are ≥ 0.01/κ and the drift did not occur.
#[test]
fn kappa_1000_running_mean() {
    let k = [1000.0];
    let p = &FitParams::RUNNING_MEAN;
    check_kappas(
        &k,
        "kappa 1000, d = 5, f = 1",
        0xF6_0000,
        Distance::Fixed(5.0),
        Weights::One,
        p,
    );
    check_kappas(
        &k,
        "kappa 1000, d ~ U[2, 10)",
        0xF7_0000,
        Distance::Uniform(2.0, 10.0),
        Weights::One,
        p,
    );
    check_kappas(
        &k,
        "kappa 1000, f ~ U(0, 2]",
        0xF8_0000,
        Distance::Fixed(5.0),
        Weights::Uniform,
        p,
    );
    check_kappas(
        &k,
        "kappa 1000, projected",
        0xF9_0000,
        Distance::Fixed(5.0),
        Weights::One,
        &PROJECTED_RUNNING_MEAN,
    );
}
