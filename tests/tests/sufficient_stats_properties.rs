//! Property tests of `SufficientStats`: no sequence of updates, however bad its weights, leaves
//! the statistics non-finite or out of range, and rejected samples change nothing.
//!
//! Deterministic: 512 cases from the fixed seed 0x7E57_0002 (`support::proptest_config`), no
//! regression files.

use glam::Vec3;
use mcg_vmf::{FitParams, KAPPA_MAX, MapPrior, MeanCosineUpdate, SufficientStats};
use proptest::prelude::*;

mod support;

/// 512 cases per property (each a sequence of up to 64 updates) from the fixed seed
/// 0x7E57_0002, no failure persistence.
fn config() -> ProptestConfig {
    support::proptest_config(512, 0x7E57_0002)
}

/// Any weight: every f32 class (NaN, ±∞, ±0, subnormal, negative, up to f32::MAX), and
/// ordinary values.
fn weight() -> impl Strategy<Value = f32> {
    prop_oneof![
        proptest::num::f32::ANY,
        0.0_f32..10.0,
        Just(f32::MAX),
        Just(0.0_f32),
    ]
}

/// A finite coordinate of a scene point: ordinary scene scales, huge ones and ones up to the
/// end of the f32 range (where differences of two points overflow).
fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        -100.0_f32..100.0,
        -1e18_f32..1e18,
        -f32::MAX..f32::MAX,
        Just(f32::MAX),
        Just(0.0_f32)
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Any parameters: any N_max, any α_min (NaN and out-of-range values included), either update.
fn params() -> impl Strategy<Value = FitParams> {
    (
        prop_oneof![
            Just(u32::MAX),
            Just(0_u32),
            Just(1_u32),
            1_u32..2048,
            proptest::num::u32::ANY
        ],
        prop_oneof![proptest::num::f32::ANY, 0.0_f32..=1.0],
        prop_oneof![
            Just(MeanCosineUpdate::Resultant),
            Just(MeanCosineUpdate::Projected)
        ],
    )
        .prop_map(|(max_count, alpha_min, mean_cosine_update)| FitParams {
            max_count,
            alpha_min,
            mean_cosine_update,
        })
}

fn assert_in_range(stats: &SufficientStats, params: &FitParams) -> Result<(), TestCaseError> {
    prop_assert!(stats.mean_target.is_finite(), "{stats:?}");
    prop_assert!(
        stats.weight_sum.is_finite() && stats.weight_sum >= 0.0,
        "{stats:?}"
    );
    prop_assert!(
        stats.mean_cosine().is_finite() && (-1.0..=1.0).contains(&stats.mean_cosine()),
        "{stats:?}"
    );
    prop_assert!(
        stats.sample_count <= params.max_count.max(1),
        "{stats:?} {params:?}"
    );
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    /// After every update of any sequence (finite points, any weights, any parameters) all
    /// fields are finite, w̄ ≥ 0, r̄ ∈ [−1, 1] and N ≤ max(N_max, 1). An update returns false
    /// exactly for a negative, NaN or infinite weight, and then leaves the statistics
    /// unchanged. A lobe rebuilt at any finite point, with or without a prior, has a unit mean
    /// and κ ∈ [0, KAPPA_MAX].
    #[test]
    fn updates_keep_statistics_finite(
        params in params(),
        samples in prop::collection::vec((point(), point(), weight()), 1..64),
        at in point(),
        prior_weight in prop_oneof![0.0_f32..10.0, proptest::num::f32::ANY],
    ) {
        let mut stats = SufficientStats::EMPTY;
        for (x, y, weight) in samples {
            let before = stats;
            let absorbed = stats.update(x, y, weight, &params);
            let valid = weight >= 0.0 && weight.is_finite();
            prop_assert_eq!(absorbed, valid, "weight {}", weight);
            if !absorbed {
                prop_assert_eq!(stats, before);
            }
            assert_in_range(&stats, &params)?;
        }
        for prior in [MapPrior::NONE, MapPrior::uninformed(prior_weight)] {
            let r = stats.posterior_mean_cosine(prior);
            prop_assert!(r.is_finite() || prior_weight.is_nan(), "posterior {r} with {prior:?}");
            if let Some(lobe) = stats.to_vmf(at, prior) {
                prop_assert!(lobe.mu().is_normalized(), "{lobe:?}");
                prop_assert!((0.0..=KAPPA_MAX).contains(&lobe.kappa()), "{lobe:?} with {prior:?}");
            }
        }
    }

    /// Non-finite points are rejected (return false, no change), whatever the weight.
    #[test]
    fn non_finite_points_are_rejected(
        params in params(),
        x in point(),
        y in point(),
        weight in 0.0_f32..10.0,
        axis in 0_usize..3,
        bad in prop::sample::select(vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY]),
    ) {
        let mut stats = SufficientStats::EMPTY;
        stats.update(x, y, weight, &params);
        let before = stats;
        let mut bad_y = y;
        bad_y[axis] = bad;
        prop_assert!(!stats.update(x, bad_y, weight, &params));
        let mut bad_x = x;
        bad_x[axis] = bad;
        prop_assert!(!stats.update(bad_x, y, weight, &params));
        prop_assert_eq!(stats, before);
    }
}

/// Finite points near ±f32::MAX should leave ȳ finite (ȳ stays in the convex hull of the
/// targets). Regression test: an earlier `update` formed y − ȳ, which overflowed to
/// [+∞, 0, 0] after `update(0, (−3·10³⁸, 0, 0), 1)` then `update(0, (3·10³⁸, 0, 0), 1)` with
/// `FitParams::RUNNING_MEAN`; the blend (1 − β)ȳ + βy cannot overflow.
#[test]
fn points_near_f32_max_keep_mean_target_finite() {
    let mut stats = SufficientStats::EMPTY;
    let params = FitParams::RUNNING_MEAN;
    stats.update(Vec3::ZERO, Vec3::new(-3e38, 0.0, 0.0), 1.0, &params);
    stats.update(Vec3::ZERO, Vec3::new(3e38, 0.0, 0.0), 1.0, &params);
    assert!(stats.mean_target.is_finite(), "{stats:?}");
}

/// Finite weights near f32::MAX should leave w̄ finite (w̄ is a blend of finite weights).
/// Regression test: with α = 1 (N_max ≤ 1 or α_min ≥ 1), an earlier `update` with weight
/// 5.263978·10³⁷ and then f32::MAX gave `weight_sum = inf`, because w̄ + α(f − w̄) rounded above
/// f32::MAX (found by `updates_keep_statistics_finite`); the blend is now clamped to max(w̄, f).
#[test]
fn weights_near_f32_max_keep_weight_sum_finite() {
    let params = FitParams {
        max_count: 1,
        alpha_min: 0.0,
        mean_cosine_update: MeanCosineUpdate::Resultant,
    };
    let mut stats = SufficientStats::EMPTY;
    stats.update(Vec3::ZERO, Vec3::ZERO, 5.263_978e37, &params);
    stats.update(Vec3::ZERO, Vec3::ZERO, f32::MAX, &params);
    assert!(stats.weight_sum.is_finite(), "{stats:?}");
}
