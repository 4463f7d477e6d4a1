//! Statistical suite of `VmfMixture`: samples against the mixture pdf on the sphere, the pdf
//! returned with a sample, and the component choice with a zero weight.
//!
//! The mixture has four distinct lobes with unequal weights, one of them zero:
//! (normalize(0.3, −0.5, 0.8), κ 20, weight 5), (−x, κ 3, weight 3),
//! (normalize(0, 1, −1), κ 80, weight 0) and (normalize(−1, −1, −0.5), κ 0.5, weight 2).
//! The zero-weight lobe points where the others have little mass, so sampling it would show.

use glam::{Vec2, Vec3};
use mcg_tests::{SphereBins, assert_sphere_chi_square, seeded_rng, uniform_vec2};
use mcg_vmf::{Vmf, VmfMixture};

fn mixture() -> VmfMixture<4> {
    VmfMixture::new(
        [
            Vmf::new(Vec3::new(0.3, -0.5, 0.8), 20.0).unwrap(),
            Vmf::new(-Vec3::X, 3.0).unwrap(),
            Vmf::new(Vec3::new(0.0, 1.0, -1.0), 80.0).unwrap(),
            Vmf::new(Vec3::new(-1.0, -1.0, -0.5), 0.5).unwrap(),
        ],
        [5.0, 3.0, 0.0, 2.0],
    )
    .unwrap()
}

/// H₀: `VmfMixture::sample` has the density `VmfMixture::pdf`. Chi-square over 32 × 64
/// equal-area bins (expected counts from the f32 pdf integrated per bin; bins below 5 expected
/// merged), n = 10⁶, α = 0.001, seed 0x313_0000. Where the zero-weight lobe (κ = 80) points,
/// the mixture density is under 2 % of its peak: a sampler that picked that lobe for a
/// fraction 10⁻³ of the samples would pile ~10³ samples into ~15 bins expecting ~120 each,
/// adding ~500 to X² on ~2000 degrees of freedom.
#[test]
fn mixture_chi_square() {
    const N: usize = 1_000_000;
    let mixture = mixture();
    let mut rng = seeded_rng(0x313_0000);
    assert_sphere_chi_square(
        "4-lobe mixture on sphere bins",
        &SphereBins::new(32, 64),
        3,
        |w| f64::from(mixture.pdf(w.as_vec3())),
        (0..N).map(|_| mixture.sample(uniform_vec2(&mut rng)).as_dvec3()),
        0.001,
    );
}

/// `sample_with_pdf` returns `sample(u)` and exactly `pdf(w)` (same f32 operations), and a
/// finite positive density, for 10⁵ uniforms (seed 0x313_0001) plus the corners of [0, 1)².
#[test]
fn sample_with_pdf_returns_the_pdf() {
    let mixture = mixture();
    let mut rng = seeded_rng(0x313_0001);
    let corners = [
        Vec2::ZERO,
        Vec2::new(1.0 - f32::EPSILON / 2.0, 0.0),
        Vec2::splat(1.0 - f32::EPSILON / 2.0),
    ];
    for u in (0..100_000).map(|_| uniform_vec2(&mut rng)).chain(corners) {
        let (w, pdf) = mixture.sample_with_pdf(u);
        assert_eq!(w, mixture.sample(u), "u {u}");
        assert_eq!(pdf, mixture.pdf(w), "u {u}");
        assert!(pdf.is_finite() && pdf > 0.0, "u {u}: {pdf}");
    }
}

/// The component choice never picks the zero-weight lobe, picks each live lobe with its
/// weight's share of u.x (checked exactly on a grid of 10⁵ + 1 values of u.x) and rescales u.x
/// into [0, 1). Deterministic.
#[test]
fn selection_follows_the_weights() {
    let mixture = mixture();
    assert_eq!(mixture.weights(), &[0.5, 0.3, 0.0, 0.2]);
    let steps = 100_000;
    let mut counts = [0_u32; 4];
    for i in 0..=steps {
        let u = (i as f32 / steps as f32).min(1.0 - f32::EPSILON / 2.0);
        let (index, rescaled) = mixture.select(u);
        assert_ne!(index, 2, "zero-weight lobe selected at u = {u}");
        assert!((0.0..1.0).contains(&rescaled), "u {u}: rescaled {rescaled}");
        counts[index] += 1;
    }
    for (count, weight) in counts.iter().zip(mixture.weights()) {
        let share = f64::from(*count) / f64::from(steps + 1);
        mcg_tests::assert_close!(share, f64::from(*weight), 1e-4, "{counts:?}");
    }
}
