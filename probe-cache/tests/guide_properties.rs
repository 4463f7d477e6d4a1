//! Properties of ADGI's heuristics and guiding function (mcg-probe-cache): h is non-negative
//! and finite for any input, the heuristics are in [0, 1], and the heuristics word round-trips.

use mcg_probe_cache::glam::{UVec3, Vec3};
use mcg_probe_cache::heuristics::{
    self, camera_distance, dynamic_heuristic, incoming_radiance, probe_visibility, static_heuristic,
};
use mcg_probe_cache::mcg_color_codec::Heuristics;
use mcg_probe_cache::probe_chains::{direction_from_chain, fold_direction};
use mcg_probe_cache::{GuideParams, GuidingFunction, ProbeGrid, ProxyGrid};
use proptest::prelude::*;

/// Any f32, special values included.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -10.0f32..10.0,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN_POSITIVE),
        2 => any::<u32>().prop_map(f32::from_bits),
    ]
}

fn any_vec3() -> impl Strategy<Value = Vec3> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn unit_interval(x: f32) -> bool {
    (0.0..=1.0).contains(&x)
}

proptest! {
    #![proptest_config(mcg_test_support::proptest_config(256, 0x7E57_0007))]

    #[test]
    fn h_is_non_negative_and_finite(
        f in any_f32(),
        g in any_f32(),
        alpha in 0.0f32..1e6,
        cap in 0.0f32..=64.0,
    ) {
        for params in [GuideParams::STATIC, GuideParams::DYNAMIC, GuideParams::new(alpha, cap).unwrap()] {
            let h = params.guiding_value(f, g);
            prop_assert!(h >= 0.0 && h.is_finite(), "h({f}, {g}) = {h} with {params:?}");
            // f is clamped to [0, 1], so h ≤ e^cap.
            prop_assert!(h <= params.exponent_cap().exp() * (1.0 + 1e-6));
        }
    }

    #[test]
    fn tabulated_h_is_non_negative_and_finite(
        table in proptest::collection::vec(any_f32(), 16),
        feedback in proptest::collection::vec(any_f32(), 16),
        p in any_vec3(),
        d in any_vec3(),
    ) {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(2, 1, 1)).unwrap();
        let guide = GuidingFunction::new(ProxyGrid::probes(grid), &table, Some(&feedback), GuideParams::STATIC).unwrap();
        let h = guide.guiding_value(p, d);
        prop_assert!(h >= 0.0 && h.is_finite());
    }

    #[test]
    fn heuristics_are_in_the_unit_interval(
        p in any_vec3(), c in any_vec3(), k in any_f32(),
        t in any_f32(), s in any_f32(), r in any_f32(), beta in any_f32(),
        a in any_f32(), b in any_f32(), mu in any_f32(),
    ) {
        prop_assert!(unit_interval(camera_distance(p, c, k)));
        prop_assert!(unit_interval(probe_visibility(t, s)));
        prop_assert!(unit_interval(incoming_radiance(r, beta)));
        prop_assert!(unit_interval(static_heuristic(a, b)));
        prop_assert!(unit_interval(dynamic_heuristic(a, b, t, r, mu)));
    }

    #[test]
    fn heuristics_word_round_trips(
        f_v in 0.0f32..=1.0, f_s in 0.0f32..=1.0, f_d in 0.0f32..=1.0, flags in 0u32..64,
    ) {
        let h = Heuristics { f_v, f_s, f_d, flags };
        let back = heuristics::decode(heuristics::encode(h));
        prop_assert!((back.f_v - f_v).abs() <= 0.5 / 63.0 + 1e-6);
        prop_assert!((back.f_s - f_s).abs() <= 0.5 / 1023.0 + 1e-6);
        prop_assert!((back.f_d - f_d).abs() <= 0.5 / 1023.0 + 1e-6);
        prop_assert_eq!(back.flags, flags);
        // Decoding is a fixed point after one trip.
        prop_assert_eq!(heuristics::encode(back), heuristics::encode(h));
    }

    #[test]
    fn folded_directions_are_unit_and_preserve_the_direction(z in -50.0f32..50.0, phi in -100.0f32..100.0) {
        let [zf, pf] = fold_direction(z, phi);
        prop_assert!((-1.0..=1.0).contains(&zf) && (0.0..core::f32::consts::TAU).contains(&pf));
        let d = direction_from_chain(zf, pf);
        prop_assert!((d.length() - 1.0).abs() < 1e-5);
        // φ wraps: the same azimuth (compare cos and sin).
        prop_assert!((pf.cos() - phi.cos()).abs() < 1e-3 && (pf.sin() - phi.sin()).abs() < 1e-3);
    }
}
