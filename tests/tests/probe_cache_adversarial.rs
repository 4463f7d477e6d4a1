//! Adversarial properties of mcg-probe-cache (the functions of issue 14's rows 13-19 and the
//! texel store around them): grids, proxies, texel maps, the direction maps, the temporal
//! gradient, the heuristics and the texel updates, called with NaN, ±∞, ±0, subnormals,
//! `f32::MAX`, `u32::MAX` counts, radii and block sizes, and out-of-range texel coordinates.
//!
//! Asserted: constructors reject what later calls could not handle; no panic except the
//! documented ones (out-of-range probe indices of `ProbeTexels`, never provoked here); finite
//! input gives finite output; no update stores a texel or detector state that decodes to NaN
//! or ∞; a failed `ChangeDetector::detect` changes nothing. CI runs this with overflow checks
//! and debug assertions on (`--profile ci`).
//!
//! Deterministic: 256 cases from the fixed seed 0x7E57_00A6 (`support::proptest_config`).

use glam::{UVec2, UVec3, Vec2, Vec3};
use mcg_probe_cache::temporal_gradient::{spatial_smoothing, temporal_gradient};
use mcg_probe_cache::{
    ChangeDetector, ControlError, GridError, HeuristicParams, MapKind, ProbeGrid, ProbeTexels,
    ProxyGrid, SmoothingKernel, TemporalTrigger, TexelConfig, TexelMap, equal_area_decode,
    equal_area_encode, equal_area_solid_angle, octahedral_decode, octahedral_encode,
    octahedral_solid_angle,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform, any_vec3, finite_vec3};

fn finite_non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

fn counts() -> impl Strategy<Value = UVec3> {
    prop_oneof![
        Just(UVec3::new(1 << 31, 1 << 31, 4)),
        Just(UVec3::splat(u32::MAX)),
        Just(UVec3::new(u32::MAX, 1, 1)),
        (any_u32(), any_u32(), any_u32()).prop_map(|(x, y, z)| UVec3::new(x, y, z)),
        (1u32..6, 1u32..6, 1u32..6).prop_map(|(x, y, z)| UVec3::new(x, y, z)),
    ]
}

/// A small valid grid (the tables below have one entry per probe and octant).
fn small_grid() -> impl Strategy<Value = ProbeGrid> {
    (1u32..5, 1u32..4, 1u32..4).prop_map(|(x, y, z)| {
        ProbeGrid::new(
            Vec3::new(-1.0, 0.0, 2.0),
            Vec3::new(0.5, 1.0, 0.25),
            UVec3::new(x, y, z),
        )
        .unwrap()
    })
}

proptest! {
    #![proptest_config(support::proptest_config(256, 0x7E57_00A6))]

    #[test]
    fn grids_and_proxies_validate_and_stay_in_range(
        origin in any_vec3(), spacing in any_vec3(), counts in counts(), block in any_u32(),
        point in any_vec3(), corner in 0u32..8,
    ) {
        let grid = match ProbeGrid::new(origin, spacing, counts) {
            Ok(g) => g,
            Err(e) => {
                let total = u128::from(counts.x) * u128::from(counts.y) * u128::from(counts.z);
                { let expected = match e {
                    GridError::OriginNotFinite { origin: o } => !origin.is_finite() && format!("{o:?}") == format!("{origin:?}"),
                    GridError::SpacingNotPositive { spacing: s } => {
                        origin.is_finite() && !(spacing.min_element() > 0.0 && spacing.is_finite())
                            && format!("{s:?}") == format!("{spacing:?}")
                    }
                    GridError::CountsOutOfRange { counts: c } => {
                        c == counts && (counts.min_element() == 0 || total > u128::from(u32::MAX))
                    }
                    _ => false,
                }; prop_assert!(expected, "{e:?}"); };
                return Ok(());
            }
        };
        prop_assert_eq!(grid.probe_count() as u128, u128::from(counts.x) * u128::from(counts.y) * u128::from(counts.z));
        let cell = grid.cell(point);
        prop_assert!(cell.alpha.cmpge(Vec3::ZERO).all() && cell.alpha.cmple(Vec3::ONE).all());
        let (coords, w) = grid.corner(cell, corner);
        prop_assert!(coords.cmplt(grid.counts()).all() && (0.0..=1.0).contains(&w));
        let p = grid.probe_position(coords);
        prop_assert!(!p.is_nan());
        match ProxyGrid::new(grid, block) {
            Ok(proxies) => {
                let c = proxies.counts();
                prop_assert!(c.cmpge(UVec3::ONE).all() && c.cmple(grid.counts()).all());
                prop_assert!(proxies.proxy_count() >= 1);
                if let Some(i) = proxies.proxy_at(point) {
                    prop_assert!(i < proxies.proxy_count(), "{i} of {}", proxies.proxy_count());
                    prop_assert!(proxies.probes_in(i) >= 1);
                }
                if let Some(probe) = proxies.nearest_probe(point) {
                    prop_assert!(probe.cmplt(grid.counts()).all());
                }
            }
            Err(e) => prop_assert!(block == 0 && e == GridError::ProxyBlockZero),
        }
    }

    #[test]
    fn maps_and_solid_angles_are_finite(
        d in any_vec3(), p in (any_f32(), any_f32()), n in any_u32(), x in any_u32(), y in any_u32(),
        side in 0u32..40, border in any::<bool>(), texel in (any_u32(), any_u32()),
    ) {
        let p = Vec2::new(p.0, p.1);
        for e in [octahedral_encode(d), equal_area_encode(d)] {
            prop_assert!(e.is_finite() && e.abs().cmple(Vec2::ONE).all(), "{d}: {e}");
        }
        if p.is_finite() {
            for w in [octahedral_decode(p), equal_area_decode(p)] {
                prop_assert!(w.is_finite() && (w.length() - 1.0).abs() < 1e-5, "{p}: {w}");
            }
        }
        prop_assert!(finite_non_negative(equal_area_solid_angle(n)));
        let a = octahedral_solid_angle(n.min(4096), x, y);
        prop_assert!(finite_non_negative(a), "{n} {x} {y}: {a}");
        for kind in [MapKind::Octahedral, MapKind::EqualArea] {
            let Ok(map) = TexelMap::new(kind, side, border) else {
                prop_assert!(side < 1 + 2 * u32::from(border));
                continue;
            };
            let t = UVec2::new(texel.0, texel.1);
            prop_assert!(map.index(t) < map.texel_count());
            let s = map.source(t);
            prop_assert!(s.x < map.side() && s.y < map.side() && !map.is_border(s));
            prop_assert!(finite_non_negative(map.solid_angle(t)));
            let w = map.direction(t);
            prop_assert!(w.is_finite() && (w.length() - 1.0).abs() < 1e-5);
            let hit = map.texel(d);
            prop_assert!(hit.x < map.side() && hit.y < map.side());
            for (i, weight) in map.bilinear(d) {
                prop_assert!(i < map.texel_count() && (0.0..=1.0).contains(&weight));
            }
        }
    }

    #[test]
    fn change_detection_is_finite_and_atomic(
        grid in small_grid(),
        frames in proptest::collection::vec((any_f32(), any_f32(), 0usize..8), 1..6),
        decay in any_f32(), radius in any_u32(), directional in any::<bool>(),
        short in any::<bool>(),
    ) {
        let trigger = match TemporalTrigger::new(decay) {
            Ok(t) => t,
            Err(e) => {
                let carries_decay = matches!(e, ControlError::TriggerDecayOutOfRange { decay: d } if d.to_bits() == decay.to_bits());
                prop_assert!(!(0.0..1.0).contains(&decay) && carries_decay, "{e:?}");
                TemporalTrigger::DEFAULT
            }
        };
        let kernel = SmoothingKernel { spatial_radius: radius, directional };
        let n = grid.probe_count() * 8;
        let mut detector = ChangeDetector::new(grid, trigger, kernel);
        for (v, r, stride) in frames {
            // An adversarial value in every `stride + 1`-th entry, ordinary values elsewhere.
            let table = |bad: f32| -> Vec<f32> {
                (0..n).map(|i| if i % (stride + 1) == 0 { bad } else { (i % 5) as f32 * 0.2 }).collect()
            };
            let (f_v, f_r) = (table(v), table(r));
            let before = (
                detector.delta_visibility().to_vec(),
                detector.delta_radiance().to_vec(),
                detector.trigger_states().0.to_vec(),
            );
            if short {
                prop_assert!(detector.detect(&f_v, &f_r[1..]).is_err());
                prop_assert_eq!(&before.0, &detector.delta_visibility().to_vec());
                prop_assert_eq!(&before.2, &detector.trigger_states().0.to_vec());
            }
            let (dv, dr) = detector.detect(&f_v, &f_r).unwrap();
            prop_assert!(dv.iter().chain(dr).all(|&x| finite_non_negative(x)), "{dv:?} {dr:?}");
            let (sv, sr) = detector.trigger_states();
            prop_assert!(sv.iter().chain(sr).all(|&x| finite_non_negative(x)));
            let mut g = vec![0.0; n];
            temporal_gradient(&f_v, &f_r, &mut g).unwrap();
            prop_assert!(g.iter().all(|x| x.is_finite()));
            let (mut out, mut scratch) = (vec![0.0; n], vec![0.0; n]);
            spatial_smoothing(&grid, kernel, &f_v, &mut out, &mut scratch).unwrap();
            prop_assert!(out.iter().all(|x| x.is_finite()), "{out:?}");
        }
    }

    #[test]
    fn heuristics_are_unit_values(
        k in any_f32(), s in any_f32(), probe in any_vec3(), camera in any_vec3(),
        t in any_f32(), r in any_f32(), f in (any_f32(), any_f32(), any_f32(), any_f32(), any_f32()),
    ) {
        let _ = f;
        let Ok(h) = HeuristicParams::new(k, s) else { return Ok(()) };
        for x in [h.camera_distance(probe, camera), h.probe_visibility(t), h.incoming_radiance(r)] {
            prop_assert!((0.0..=1.0).contains(&x), "{x}");
        }
    }

    #[test]
    fn texel_updates_store_finite_words(
        grid in small_grid(), values in proptest::collection::vec((finite_vec3(), any_vec3(), any_f32(), any_uniform(), 0usize..64), 1..12),
        count in any_u32(), distance in any_f32(),
    ) {
        let texels = ProbeTexels::new(grid, TexelConfig::default());
        let probes = grid.probe_count();
        let (ni, nv) = (
            texels.config().irradiance_map.texel_count(),
            texels.config().visibility_map.texel_count(),
        );
        texels.fill_visibility(distance, count);
        for (finite, any, t, u, i) in values {
            let (probe, it, vt) = (i % probes, i % ni, (i * 7) % nv);
            for v in [finite, any] {
                let _ = texels.update_irradiance(probe, it, v, u);
                texels.set_irradiance(probe, (it + 1) % ni, v, count);
            }
            if let Some(d) = texels.normalise_distance(t) {
                prop_assert!(finite_non_negative(d));
                let _ = texels.update_visibility(probe, vt, Vec2::new(d, d * d), u);
            }
            let _ = texels.update_visibility(probe, vt, Vec2::new(t, t), u);
            texels.cap_counts(probe, count);
            prop_assert!(texels.irradiance(probe, it).is_finite());
            prop_assert!(texels.visibility(probe, vt).is_finite());
        }
        texels.refresh_borders();
        for probe in 0..probes {
            for t in 0..ni {
                let c = texels.irradiance(probe, t);
                prop_assert!(c.is_finite() && c.cmpge(Vec3::ZERO).all());
            }
        }
    }
}
