//! Property tests of `Vmf`, `VmfMixture` and the mean-cosine functions: finiteness and ranges
//! for every valid input, agreement of `sample_with_pdf` with `pdf`, the κ ↔ mean cosine round
//! trip, and the error each invalid input gets.
//!
//! Deterministic: every property runs 1024 cases from the fixed seed 0x7E57_0001
//! (`support::proptest_config`) and writes no regression files.

use glam::{Vec2, Vec3};
use mcg_vmf::{
    KAPPA_MAX, MixtureError, Vmf, VmfError, VmfMixture, kappa_from_mean_cosine,
    kappa_from_mean_cosine_exact, mean_cosine_from_kappa,
};
use proptest::prelude::*;

mod support;

/// 1024 cases per property from the fixed seed 0x7E57_0001, no failure persistence.
fn config() -> ProptestConfig {
    support::proptest_config(1024, 0x7E57_0001)
}

/// κ in [0, 10⁶]: exactly 0, log-uniform over [10⁻⁸, 10⁶), uniform over [0, 10⁶], or 10⁶.
fn kappa() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0_f32),
        Just(KAPPA_MAX),
        (-8.0_f32..6.0).prop_map(|e| 10.0_f32.powf(e).min(KAPPA_MAX)),
        0.0_f32..=KAPPA_MAX,
    ]
}

/// A nonzero finite mean: a direction in the cube [−1, 1]³ (length ≥ 10⁻³) scaled by
/// 10^s, s ∈ [−15, 15].
///
/// The scale is bounded because `Vmf::new` normalises with `try_normalize`, whose squared
/// length leaves f32 range outside about 10^±19: a mean of length 10²⁰ (or 10⁻²³) is rejected
/// with `MeanZeroLength` (see `long_means_are_normalised`).
fn mean() -> impl Strategy<Value = Vec3> {
    (-1.0_f32..1.0, -1.0_f32..1.0, -1.0_f32..1.0, -15.0_f32..15.0)
        .prop_filter("length at least 1e-3", |(x, y, z, _)| {
            Vec3::new(*x, *y, *z).length() >= 1e-3
        })
        .prop_map(|(x, y, z, s)| Vec3::new(x, y, z) * 10.0_f32.powf(s))
}

fn lobe() -> impl Strategy<Value = Vmf> {
    (mean(), kappa()).prop_map(|(mu, kappa)| Vmf::new(mu, kappa).unwrap())
}

/// A unit direction from z uniform in [−1, 1] and φ uniform in [0, 2π), plus the axes.
fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        prop::sample::select(vec![
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::X,
            -Vec3::Y,
            -Vec3::Z
        ]),
        (-1.0_f64..=1.0, 0.0_f64..std::f64::consts::TAU).prop_map(|(z, phi)| {
            let s = (1.0 - z * z).sqrt();
            glam::DVec3::new(s * phi.cos(), s * phi.sin(), z).as_vec3()
        }),
    ]
}

/// Uniforms in [0, 1)², including the extremes 0 and 1 − 2⁻²⁴ (the largest f32 below 1).
fn uniforms() -> impl Strategy<Value = Vec2> {
    let coordinate = prop_oneof![Just(0.0_f32), Just(1.0 - f32::EPSILON / 2.0), 0.0_f32..1.0];
    (coordinate.clone(), coordinate).prop_map(|(x, y)| Vec2::new(x, y))
}

/// Any f32 that is not finite.
fn non_finite() -> impl Strategy<Value = f32> {
    prop::sample::select(vec![f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY])
}

/// Relative tolerance of `sample_with_pdf`'s density against `pdf(w)`: 10⁻⁵ + 10⁻⁶ √κ.
///
/// The two differ by how the exponent is formed: from the sampled cos θ − 1 (exact to f32
/// relative precision) or from |w − μ|² of the rounded f32 direction, whose components carry
/// absolute errors ~10⁻⁷. The exponent κ|w − μ|²/2 ≈ κθ²/2 then errs by ~κθ·10⁻⁷, and θ reaches
/// √(2·16.6/κ) in the tail (u.y = 1 − 2⁻²⁴), so the error grows like √κ: measured worst
/// 2.4·10⁻⁵ at κ = 10⁴ and 2.4·10⁻⁴ at κ = 10⁶, where the tolerance allows 1.1·10⁻⁴ and 10⁻³.
fn sample_pdf_tolerance(kappa: f32) -> f32 {
    1e-5 + 1e-6 * kappa.sqrt()
}

proptest! {
    #![proptest_config(config())]

    /// `pdf` is finite and ≥ 0 for every valid lobe and unit direction.
    #[test]
    fn pdf_is_finite_and_non_negative(lobe in lobe(), w in direction()) {
        let pdf = lobe.pdf(w);
        prop_assert!(pdf.is_finite() && pdf >= 0.0, "{lobe:?} {w}: {pdf}");
    }

    /// `sample` returns a finite unit vector (|len − 1| < 10⁻⁵) for every u in [0, 1)².
    #[test]
    fn samples_are_unit(lobe in lobe(), u in uniforms()) {
        let w = lobe.sample(u);
        prop_assert!(w.is_finite() && (w.as_dvec3().length() - 1.0).abs() < 1e-5, "{lobe:?} {u}: {w}");
    }

    /// `sample_with_pdf` returns `sample(u)` with a finite, non-negative density equal to
    /// `pdf(w)` to relative [`sample_pdf_tolerance`] (at most 1.01·10⁻³ at κ = 10⁶).
    #[test]
    fn sample_with_pdf_matches_pdf(lobe in lobe(), u in uniforms()) {
        let (w, pdf) = lobe.sample_with_pdf(u);
        prop_assert_eq!(w, lobe.sample(u));
        prop_assert!(pdf.is_finite() && pdf >= 0.0, "{lobe:?} {u}: {pdf}");
        let reference = lobe.pdf(w);
        let tolerance = sample_pdf_tolerance(lobe.kappa());
        prop_assert!(
            (pdf - reference).abs() <= tolerance * reference,
            "{lobe:?} {u}: sample_with_pdf {pdf} vs pdf {reference} (tolerance {tolerance})"
        );
    }

    /// `kappa_from_mean_cosine_exact(mean_cosine_from_kappa(κ))` returns κ to relative
    /// max(10⁻³, 2⁻²⁴·κ) for κ log-uniform in [10⁻⁴, 10⁵].
    ///
    /// Above κ ≈ 1.7·10⁴ the f32 mean cosine r ≈ 1 − 1/κ itself is the limit: its spacing 2⁻²⁴
    /// is a relative step of 2⁻²⁴·κ in 1 − r and so in κ (6·10⁻³ at κ = 10⁵), whatever the
    /// inverse does.
    #[test]
    fn mean_cosine_round_trip(e in -4.0_f32..=5.0) {
        let kappa = 10.0_f32.powf(e);
        let back = kappa_from_mean_cosine_exact(mean_cosine_from_kappa(kappa));
        let tolerance = 1e-3_f32.max(kappa * f32::EPSILON / 2.0);
        prop_assert!((back / kappa - 1.0).abs() <= tolerance, "{kappa} -> {back} (tolerance {tolerance})");
    }

    /// For any f32 r (NaN and ±∞ included) both inverses return κ in [0, KAPPA_MAX], and the
    /// mean cosine of any f32 κ is in [0, 1].
    #[test]
    fn inverses_stay_in_range(r in proptest::num::f32::ANY) {
        let banerjee = kappa_from_mean_cosine(r);
        prop_assert!((0.0..=KAPPA_MAX).contains(&banerjee), "banerjee({r}) = {banerjee}");
        let exact = kappa_from_mean_cosine_exact(r);
        prop_assert!((0.0..=KAPPA_MAX).contains(&exact), "exact({r}) = {exact}");
        let mean_cosine = mean_cosine_from_kappa(r);
        prop_assert!((0.0..=1.0).contains(&mean_cosine), "mean_cosine({r}) = {mean_cosine}");
    }

    /// A mean with a NaN or infinite component is `MeanNotFinite`, whatever κ (the mean is
    /// checked first).
    #[test]
    fn non_finite_mean_is_rejected(
        mu in mean(), bad in non_finite(), axis in 0_usize..3, kappa in proptest::num::f32::ANY
    ) {
        let mut mu = mu;
        mu[axis] = bad;
        let e = Vmf::new(mu, kappa);
        prop_assert!(matches!(e, Err(VmfError::MeanNotFinite { mean }) if mean.to_array()[axis].to_bits() == bad.to_bits()), "{:?}", e);
    }

    /// With a valid mean, a NaN or infinite κ is `KappaNotFinite` and a negative finite κ is
    /// `KappaNegative`; −0 is accepted as 0.
    #[test]
    fn bad_kappa_is_rejected(mu in mean(), bad in non_finite(), magnitude in proptest::num::f32::POSITIVE) {
        let e = Vmf::new(mu, bad);
        prop_assert!(matches!(e, Err(VmfError::KappaNotFinite { kappa }) if kappa.to_bits() == bad.to_bits()), "{:?}", e);
        let negative = -magnitude;
        if negative.is_finite() {
            prop_assert_eq!(Vmf::new(mu, negative), Err(VmfError::KappaNegative { kappa: negative }));
        }
        prop_assert_eq!(Vmf::new(mu, -0.0).map(|v| v.kappa()), Ok(0.0));
    }

    /// A zero mean (any signs of zero) is `MeanZeroLength` for any valid κ. κ is checked
    /// before the length, so a zero mean with a bad κ reports the κ error.
    #[test]
    fn zero_mean_is_rejected(signs in 0_u8..8, kappa in kappa(), bad in non_finite()) {
        let zero = |bit: u8| if signs & bit != 0 { -0.0 } else { 0.0 };
        let mu = Vec3::new(zero(1), zero(2), zero(4));
        prop_assert_eq!(Vmf::new(mu, kappa), Err(VmfError::MeanZeroLength { mean: mu }));
        let e = Vmf::new(mu, bad);
        prop_assert!(matches!(e, Err(VmfError::KappaNotFinite { .. })), "{:?}", e);
        prop_assert_eq!(Vmf::new(mu, -1.0), Err(VmfError::KappaNegative { kappa: -1.0 }));
    }

    /// Mixture weights: any NaN or infinite weight (others valid) is `WeightNotFinite`, any
    /// negative finite weight (others valid) is `WeightNegative`, all zeros is
    /// `WeightsSumToZero`, and valid weights are normalised to sum to 1.
    #[test]
    fn mixture_weights_are_validated(
        weights in prop::array::uniform3(0.0_f32..1e30),
        bad in non_finite(),
        negative in proptest::num::f32::POSITIVE,
        index in 0_usize..3,
    ) {
        let lobes = [Vmf::uniform(); 3];
        let mut with_bad = weights;
        with_bad[index] = bad;
        let e = VmfMixture::new(lobes, with_bad);
        prop_assert!(matches!(e, Err(MixtureError::WeightNotFinite { index: i, weight }) if i == index && weight.to_bits() == bad.to_bits()), "{:?}", e);
        let mut with_negative = weights;
        with_negative[index] = -negative;
        prop_assert_eq!(VmfMixture::new(lobes, with_negative), Err(MixtureError::WeightNegative { index, weight: -negative }));
        prop_assert_eq!(VmfMixture::new(lobes, [0.0, -0.0, 0.0]), Err(MixtureError::WeightsSumToZero));
        if weights.iter().sum::<f32>() > 0.0 {
            let mixture = VmfMixture::new(lobes, weights).unwrap();
            let sum: f32 = mixture.weights().iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-6, "{weights:?} -> {:?}", mixture.weights());
        }
    }

    /// A mixture of valid lobes samples unit vectors and has a finite, non-negative pdf.
    #[test]
    fn mixture_is_finite(
        lobes in prop::array::uniform3(lobe()),
        weights in prop::array::uniform3(0.0_f32..10.0),
        u in uniforms(),
        w in direction(),
    ) {
        prop_assume!(weights.iter().sum::<f32>() > 0.0);
        let mixture = VmfMixture::new(lobes, weights).unwrap();
        let (sample, pdf) = mixture.sample_with_pdf(u);
        prop_assert!((sample.as_dvec3().length() - 1.0).abs() < 1e-5, "{sample}");
        prop_assert!(pdf.is_finite() && pdf >= 0.0);
        let at_w = mixture.pdf(w);
        prop_assert!(at_w.is_finite() && at_w >= 0.0);
    }
}

/// A finite, nonzero mean should be normalised whatever its length. Regression test: an
/// earlier `Vmf::new` used `try_normalize` directly, whose squared length overflows f32 above
/// |μ| ≈ 1.8·10¹⁹ (and underflows below ≈ 3.7·10⁻²³), so `Vmf::new((1e20, 0, 0), 1)` was
/// `Err(MeanZeroLength)`. It now divides by the largest |component| first.
#[test]
fn long_means_are_normalised() {
    assert!(Vmf::new(Vec3::new(1e15, -2e15, 3e15), 1.0).is_ok());
    let lobe = Vmf::new(Vec3::new(1e20, 0.0, 0.0), 1.0);
    assert_eq!(lobe.map(|v| v.mu()), Ok(Vec3::X));
    let lobe = Vmf::new(Vec3::new(0.0, -1e-30, 0.0), 1.0);
    assert_eq!(lobe.map(|v| v.mu()), Ok(-Vec3::Y));
}
