//! Suite of `Vmf::pdf`: normalisation by f64 quadrature and pointwise agreement with the f64
//! reference density, for κ from 0 to 10⁶ (= `KAPPA_MAX`).
//!
//! The f32 pdf is always evaluated at f32 directions (built in f64 and converted), and its
//! values are accumulated in f64.

use glam::Vec3;
use mcg_tests::{
    graded_theta_breaks, integrate_sphere, one_minus_cos, seeded_rng, uniform_sphere_direction,
    uniform_vec2, vmf_normalization, vmf_pdf,
};
use mcg_vmf::Vmf;

const KAPPAS: [f32; 10] = [0.0, 1e-6, 0.01, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6];

fn lobe(kappa: f32) -> Vmf {
    Vmf::new(Vec3::new(0.3, -0.5, 0.8), kappa).unwrap()
}

/// ∫ pdf dω = 1 for κ ∈ {0, 10⁻⁶, 0.01, 1, 10, 100, 10³, 10⁴, 10⁵, 10⁶}, within 10⁻⁵.
///
/// Deterministic (no sampling). The integral runs over the lobe's own polar angle with
/// 16-point Gauss-Legendre panels graded around the peak width 1/√κ (0, w/8, w/4, …, π) and
/// 16 azimuths; the quadrature itself is exact to ~10⁻¹⁰ for the f64 density. Measured errors
/// are ≤ 7·10⁻⁸ (f32 rounding of the normalisation and of exp); the tolerance 10⁻⁵ is 100
/// times tighter than the 10⁻³ a renderer would notice, and still 100 times the f32 noise.
#[test]
fn pdf_integrates_to_one() {
    let mut report = String::new();
    for kappa in KAPPAS {
        let lobe = lobe(kappa);
        let width = if kappa > 0.0 {
            1.0 / f64::from(kappa).sqrt()
        } else {
            std::f64::consts::PI
        };
        let integral =
            integrate_sphere(lobe.mu().as_dvec3(), &graded_theta_breaks(width), 16, |w| {
                f64::from(lobe.pdf(w.as_vec3()))
            });
        let normalised = (integral - 1.0).abs() < 1e-5;
        if !normalised {
            report += &format!("\n  kappa {kappa}: integral {integral:.9}");
        }
    }
    assert!(report.is_empty(), "pdf does not integrate to 1:{report}");
}

/// `Vmf::pdf(ω)` equals the f64 density C(κ) e^{−κ(1 − μ·ω)} (with 1 − μ·ω taken from the angle
/// and the lobe's own f32 μ) to relative 10⁻⁶ · (1 + κ(1 − μ·ω)), wherever the reference
/// exceeds 10⁻³⁰.
///
/// The tolerance is the f32 error budget: a few ulps on C(κ), plus the relative error of the
/// exponent x = κ(1 − μ·ω), which exp turns into an absolute error proportional to x; measured
/// worst is 3.1·10⁻⁷ · (1 + x). Directions: 10⁵ samples of the lobe (the peak) and 10⁵
/// uniform directions (the tails) per κ ∈ {0, 10⁻⁶, 0.01, 1, 10, 100, 10³, 10⁴, 10⁵, 10⁶},
/// seed 0x9D_0000.
#[test]
fn pdf_matches_f64_reference() {
    let mut report = String::new();
    let mut rng = seeded_rng(0x9D_0000);
    for kappa in KAPPAS {
        let lobe = lobe(kappa);
        let mu = lobe.mu().as_dvec3();
        let k = f64::from(kappa);
        for i in 0..200_000 {
            let w = if i % 2 == 0 {
                lobe.sample(uniform_vec2(&mut rng))
            } else {
                uniform_sphere_direction(&mut rng).as_vec3()
            };
            let reference = vmf_pdf(mu, k, w.as_dvec3());
            if reference < 1e-30 {
                continue;
            }
            let got = f64::from(lobe.pdf(w));
            let x = k * one_minus_cos(mu, w.as_dvec3());
            let error = (got / reference - 1.0).abs() / (1.0 + x);
            let accurate = error <= 1e-6;
            if !accurate {
                report += &format!("\n  kappa {kappa}, w {w}: pdf {got:e} vs {reference:e}");
            }
        }
    }
    assert!(
        report.is_empty(),
        "pdf differs from the f64 reference:{report}"
    );
}

/// The pdf peaks at μ with the value C(κ) and is exactly 1/(4π) for κ = 0 at any direction.
/// Deterministic.
#[test]
fn peak_value_is_the_normalization() {
    for kappa in KAPPAS {
        let lobe = lobe(kappa);
        let peak = f64::from(lobe.pdf(lobe.mu()));
        let want = vmf_normalization(f64::from(kappa));
        mcg_tests::assert_close!(peak / want, 1.0, 1e-6, "kappa {kappa}: {peak} vs {want}");
        mcg_tests::assert_close!(
            f64::from(lobe.normalization()) / want,
            1.0,
            1e-6,
            "kappa {kappa}"
        );
    }
    let uniform = lobe(0.0);
    for w in [Vec3::X, -Vec3::Z, Vec3::new(0.6, 0.0, -0.8)] {
        assert_eq!(uniform.pdf(w), mcg_vmf::UNIFORM_SPHERE_PDF);
    }
}
