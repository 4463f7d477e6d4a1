//! Adversarial properties of mcg-vmf: every public function called with NaN, ±∞, ±0,
//! subnormals, `f32::MAX`, huge κ, zero vectors and out-of-range uniforms.
//!
//! Asserted: constructors reject what later calls could not handle (with the variant named
//! for the broken condition); no panic (none of these functions documents one, except
//! `sample_batch` on mismatched lengths, which is not called so); finite input gives finite
//! output; no update ever stores NaN or ∞ in [`SufficientStats`]. `Frame` is only built
//! around unit normals, its documented precondition. CI runs this with overflow checks and
//! debug assertions on (`--profile ci`).
//!
//! Deterministic: 1024 cases from the fixed seed 0x7E57_00A1 (`support::proptest_config`).

use glam::{Vec2, Vec3};
use mcg_vmf::{
    FitParams, Frame, KAPPA_MAX, MapPrior, MeanCosineUpdate, MixtureError, PriorDecay,
    SufficientStats, Vmf, VmfError, VmfMixture, kappa_from_mean_cosine,
    kappa_from_mean_cosine_exact, mean_cosine_from_kappa, sample_batch,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform, any_uniform2, any_vec3, finite_f32, finite_vec3};

/// κ values: the valid range with its edges, and beyond.
fn any_kappa() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(f32::from_bits(1)),
        Just(KAPPA_MAX),
        Just(1e20f32),
        Just(f32::MAX),
        0.0f32..100.0,
        any_f32(),
    ]
}

/// A lobe from `new`, or the uniform lobe where `new` rejects the parameters.
fn lobe(mu: Vec3, kappa: f32) -> Vmf {
    Vmf::new(mu, kappa).unwrap_or_default()
}

fn finite_unit(w: Vec3) -> bool {
    w.is_finite() && (w.length() - 1.0).abs() < 1e-5
}

fn finite_non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

fn assert_finite_stats(s: &SufficientStats) {
    assert!(
        s.mean_target.is_finite()
            && finite_non_negative(s.weight_sum)
            && s.one_minus_mean_cosine.is_finite()
            && (0.0..=2.0).contains(&s.one_minus_mean_cosine),
        "{s:?}"
    );
}

proptest! {
    #![proptest_config(support::proptest_config(1024, 0x7E57_00A1))]

    #[test]
    fn new_validates_and_lobes_stay_finite(
        mu in any_vec3(), kappa in any_kappa(), w in any_vec3(), u in any_uniform2(),
    ) {
        match Vmf::new(mu, kappa) {
            Ok(v) => {
                prop_assert!(mu.is_finite() && (0.0..=KAPPA_MAX).contains(&kappa));
                prop_assert!(v.mu().is_normalized() && v.kappa() == kappa);
                prop_assert!(finite_non_negative(v.normalization()));
                prop_assert!((0.0..=1.0).contains(&v.mean_cosine()));
                let (s, p) = v.sample_with_pdf(u);
                prop_assert!(finite_unit(s) && finite_non_negative(p), "{v:?} {u}: {s} {p}");
                prop_assert!(finite_unit(v.sample(u)));
                if w.is_finite() {
                    let q = v.pdf(w);
                    prop_assert!(finite_non_negative(q), "{v:?} pdf({w}) = {q}");
                }
                let mut out = [Vec3::ZERO; 2];
                sample_batch(&[v, v], &[u, Vec2::new(u.y, u.x)], &mut out);
                prop_assert!(out.iter().all(|&w| finite_unit(w)), "{v:?} {u}: {out:?}");
                let c = v.convolve(kappa);
                prop_assert!(c.kappa().is_finite() && c.mu() == v.mu());
            }
            Err(e) => {
                let same = |a: f32, b: f32| a.to_bits() == b.to_bits();
                let same3 = |a: Vec3, b: Vec3| (0..3).all(|i| same(a[i], b[i]));
                let expected = match e {
                    VmfError::MeanNotFinite { mean } => !mu.is_finite() && same3(mean, mu),
                    VmfError::KappaNotFinite { kappa: k } => {
                        mu.is_finite() && !kappa.is_finite() && same(k, kappa)
                    }
                    VmfError::KappaNegative { kappa: k } => {
                        mu.is_finite() && kappa.is_finite() && kappa < 0.0 && same(k, kappa)
                    }
                    VmfError::KappaAboveMax { kappa: k, maximum } => {
                        mu.is_finite() && kappa.is_finite() && kappa > KAPPA_MAX
                            && same(k, kappa) && maximum == KAPPA_MAX
                    }
                    VmfError::MeanZeroLength { mean } => {
                        (0.0..=KAPPA_MAX).contains(&kappa) && mu == Vec3::ZERO && same3(mean, mu)
                    }
                    _ => false,
                };
                prop_assert!(expected, "{:?} for {} {}", e, mu, kappa);
            }
        }
        if let Ok(c) = Vmf::clamped_cosine(mu) {
            prop_assert!(c.mu().is_normalized());
        }
    }

    #[test]
    fn products_are_finite(
        a in (any_vec3(), any_kappa()), b in (any_vec3(), any_kappa()), u in any_uniform2(),
    ) {
        let (a, b) = (lobe(a.0, a.1), lobe(b.0, b.1));
        let (c, scale) = a.product(&b);
        prop_assert!(c.mu().is_normalized(), "{a:?} {b:?}: {c:?}");
        prop_assert!(c.kappa().is_finite() && c.kappa() <= a.kappa() + b.kappa() + 1.0);
        prop_assert!(finite_non_negative(scale), "{a:?} {b:?}: {scale}");
        let (w, p) = c.sample_with_pdf(u);
        prop_assert!(finite_unit(w) && finite_non_negative(p));
        prop_assert!(finite_non_negative(c.pdf(w)));
    }

    #[test]
    fn mean_cosine_functions_are_finite(x in any_f32()) {
        let r = mean_cosine_from_kappa(x);
        if !x.is_nan() {
            prop_assert!(r.is_finite() && (-1.0..=1.0).contains(&r), "A3({x}) = {r}");
        }
        for k in [kappa_from_mean_cosine(x), kappa_from_mean_cosine_exact(x)] {
            prop_assert!((0.0..=KAPPA_MAX).contains(&k), "kappa({x}) = {k}");
        }
    }

    #[test]
    fn mixtures_validate_and_stay_finite(
        lobes in [(any_vec3(), any_kappa()), (any_vec3(), any_kappa()), (any_vec3(), any_kappa())],
        weights in [any_f32(), any_f32(), any_f32()],
        u in any_uniform2(), w in finite_vec3(),
    ) {
        let lobes = lobes.map(|(mu, k)| lobe(mu, k));
        match VmfMixture::new(lobes, weights) {
            Ok(m) => {
                let ws = m.weights();
                prop_assert!(ws.iter().all(|&x| finite_non_negative(x)));
                let (i, rescaled) = m.select(u.x);
                prop_assert!(i < 3 && ws[i] > 0.0 && (0.0..1.0).contains(&rescaled));
                let (s, p) = m.sample_with_pdf(u);
                prop_assert!(finite_unit(s) && finite_non_negative(p), "{s} {p}");
                prop_assert!(finite_non_negative(m.pdf(w)), "{}", m.pdf(w));
            }
            Err(e) => {
                let bad = weights.iter().any(|w| !w.is_finite());
                let negative = weights.iter().any(|&w| w < 0.0);
                { let expected = match e {
                    MixtureError::WeightNotFinite { index, weight } => {
                        bad && !weights[index].is_finite() && weight.to_bits() == weights[index].to_bits()
                    }
                    MixtureError::WeightSumNotFinite => !bad && !negative && weights.iter().sum::<f32>().is_infinite(),
                    MixtureError::WeightNegative { index, weight } => negative && weights[index] < 0.0 && weight == weights[index],
                    MixtureError::WeightsSumToZero => weights.iter().all(|&w| w == 0.0),
                    _ => false,
                }; prop_assert!(expected, "{e:?} for {weights:?}"); };
            }
        }
    }

    #[test]
    fn frames_of_unit_normals_are_orthonormal(n in any_vec3(), local in finite_vec3()) {
        // The documented precondition: `normal` is unit length (scaled first, so that tiny and
        // huge vectors normalise to f32 precision).
        let largest = n.abs().max_element();
        if !(largest > 0.0 && largest.is_finite()) {
            return Ok(());
        }
        let Some(n) = (n / largest).try_normalize() else { return Ok(()) };
        let f = Frame::from_normal(n);
        for axis in [f.tangent, f.bitangent, f.normal] {
            prop_assert!(finite_unit(axis), "{n}: {f:?}");
        }
        let local = local.clamp(Vec3::splat(-1e30), Vec3::splat(1e30));
        prop_assert!(f.to_world(local).is_finite() && f.to_local(local).is_finite());
    }

    #[test]
    fn statistics_never_store_non_finite_values(
        steps in proptest::collection::vec((any_vec3(), any_vec3(), any_f32()), 1..24),
        max_count in any_u32(), alpha_min in any_f32(), projected in any::<bool>(),
        x in any_vec3(), prior in (any_f32(), any_f32(), any::<bool>()),
    ) {
        let params = FitParams {
            max_count,
            alpha_min,
            mean_cosine_update: if projected {
                MeanCosineUpdate::Projected
            } else {
                MeanCosineUpdate::Resultant
            },
        };
        let prior = MapPrior {
            mean_cosine: prior.0,
            weight: prior.1,
            decay: if prior.2 { PriorDecay::Count } else { PriorDecay::SquaredCount },
        };
        let mut s = SufficientStats::EMPTY;
        for (x, y, f) in steps {
            let before = s;
            let absorbed = s.update(x, y, f, &params);
            if !absorbed {
                prop_assert_eq!(s, before, "a rejected sample changed the statistics");
            }
            assert_finite_stats(&s);
        }
        prop_assert!(s.mean_cosine().is_finite());
        if x.is_finite() {
            let d = s.target_distance(x);
            prop_assert!(finite_non_negative(d), "{s:?} {x}: {d}");
            if let Some(mu) = s.mean_direction(x) {
                prop_assert!(mu.is_normalized(), "{s:?} {x}: {mu}");
            }
            let r = s.posterior_mean_cosine(prior);
            prop_assert!(r.is_finite(), "{s:?} {prior:?}: {r}");
            if let Some(v) = s.to_vmf(x, prior) {
                prop_assert!(v.mu().is_normalized() && (0.0..=KAPPA_MAX).contains(&v.kappa()));
            }
        }
    }

    #[test]
    fn priors_are_finite_for_finite_input(
        scale in finite_f32(), min_weight in finite_f32(), distance in finite_f32(), w in any_f32(),
    ) {
        prop_assert_eq!(MapPrior::uninformed(w).weight.to_bits(), w.to_bits());
        let p = MapPrior::inverse_square_distance(scale, min_weight, distance);
        // A zero distance (or one whose square underflows) gives an infinite weight by
        // design ("prior only", documented); anything else is finite.
        if distance * distance != 0.0 && scale.is_finite() {
            prop_assert!(!p.weight.is_nan() && p.weight < f32::INFINITY, "{p:?}");
        }
    }

    #[test]
    fn uniforms_are_clamped_not_nan(kappa in any_kappa(), u in any_uniform(), v in any_uniform()) {
        let l = lobe(Vec3::new(0.3, -0.2, 0.9), kappa);
        prop_assert!(finite_unit(l.sample(Vec2::new(u, v))));
    }
}
