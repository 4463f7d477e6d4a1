//! Adversarial properties of mcg-hashgrid: every public function called with NaN, ±∞, ±0,
//! subnormals, `f32::MAX` positions and distances, keys at the ends of the `i32` range,
//! `u32::MAX` capacities, slots, levels and frames, and out-of-range uniforms.
//!
//! Asserted: constructors reject what later calls could not handle (with the variant named
//! for the broken condition); no panic (`find_many`, which documents one on mismatched
//! lengths, gets matching slices); widths and weights are finite; chosen vertices never wrap
//! to the opposite end of the grid; slots stay below the capacity; tables keep their counts.
//! CI runs this with overflow checks and debug assertions on (`--profile ci`). The
//! concurrency promises have their own suite (`hashgrid_concurrency`).
//!
//! Deterministic: 512 cases from the fixed seed 0x7E57_00A4 (`support::proptest_config`).

use glam::{IVec3, Vec3};
use mcg_hashgrid::{
    AdaptiveGrid, BucketHash, CellKey, ConcurrentTable, GridError, HashTable, LevelParams,
    SlotIndexer, StaticGrid, TableError, cell_and_fraction, checksum, floor_ivec3,
    geometric_jitter, geometric_jitter_probability, hash_mix, hash_mix_coherent, hash_xor_primes,
    jittered_vertex, mix_and_checksum, next_prime, normal_class, pcg4d, stochastic_corner,
    stochastic_trilinear, trilinear_weights,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform, any_vec3};

fn any_key() -> impl Strategy<Value = CellKey> {
    let coordinate = prop_oneof![Just(i32::MIN), Just(i32::MAX), Just(0), -4..4, any::<i32>()];
    (
        [coordinate.clone(), coordinate.clone(), coordinate],
        any::<u8>(),
        any::<u8>(),
        any::<u16>(),
    )
        .prop_map(|(c, level, class, extra)| {
            CellKey::new(IVec3::from_array(c), level, class).with_extra(extra)
        })
}

fn hashes() -> [BucketHash; 3] {
    [
        BucketHash::XorPrimes,
        BucketHash::Mix,
        BucketHash::MixCoherent,
    ]
}

/// The vertex `v` is one of the corners of the cell `⌊q⌋` (saturated at the i32 range) — in
/// particular never on the opposite side of the grid.
fn is_corner_of(v: IVec3, q: Vec3) -> bool {
    let base = floor_ivec3(q);
    (0..3).all(|a| {
        let d = i64::from(v[a]) - i64::from(base[a]);
        d == 0 || d == 1
    })
}

proptest! {
    #![proptest_config(support::proptest_config(512, 0x7E57_00A4))]

    #[test]
    fn vertex_choice_stays_in_the_cell(q in any_vec3(), u in any_f32(), u3 in (any_f32(), any_f32(), any_f32())) {
        let (base, f) = cell_and_fraction(q);
        prop_assert!(base == floor_ivec3(q));
        prop_assert!(f.cmpge(Vec3::ZERO).all() && f.cmple(Vec3::ONE).all(), "{q}: {f}");
        let w = trilinear_weights(f);
        prop_assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)));
        prop_assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        prop_assert!(stochastic_corner(f, u) < 8);
        let v = stochastic_trilinear(q, u);
        prop_assert!(is_corner_of(v, q), "{q} {u}: {v}");
        let j = jittered_vertex(q, Vec3::new(u3.0, u3.1, u3.2));
        prop_assert!(is_corner_of(j, q), "{q} {u3:?}: {j}");
    }

    #[test]
    fn grids_validate_and_give_finite_widths_and_keys(
        params in (any_f32(), any_f32(), any_f32(), any_u32(), 0u32..300),
        position in any_vec3(), normal in any_vec3(), camera in any_vec3(),
        xi in any_f32(), u in any_f32(), level in any_u32(), width in any_f32(),
    ) {
        let p = LevelParams {
            tan_half_angle: params.0,
            min_width: params.1,
            power: params.2,
            steps: params.3,
            max_level: params.4,
        };
        match AdaptiveGrid::new(p) {
            Ok(g) => {
                let w = g.width(level);
                prop_assert!(w.is_finite() && w > 0.0, "{p:?} width({level}) = {w}");
                let d = camera.distance(position);
                let l = g.level(d, xi);
                prop_assert!(l <= p.max_level && g.target_level(d) <= l);
                prop_assert!(g.width(l).is_finite());
                if d.is_finite() {
                    prop_assert!(!g.target_width(d).is_nan());
                }
                let key = g.vertex_key(position, normal, camera, xi, u);
                prop_assert!(u32::from(key.level) <= p.max_level);
            }
            Err(e) => {
                let want = if !(p.tan_half_angle > 0.0 && p.tan_half_angle.is_finite()) {
                    GridError::TanHalfAngleNotPositive { tan_half_angle: p.tan_half_angle }
                } else if !(p.min_width > 0.0 && p.min_width.is_finite()) {
                    GridError::WidthNotPositive { width: p.min_width }
                } else if !(p.power > 1.0 && p.power.is_finite()) {
                    GridError::PowerNotAboveOne { power: p.power }
                } else if p.steps == 0 {
                    GridError::StepsZero
                } else if p.max_level > 255 {
                    GridError::MaxLevelTooLarge { max_level: p.max_level, maximum: 255 }
                } else {
                    GridError::CoarsestWidthNotFinite { params: p }
                };
                // Compared through `Debug` so that a NaN carried by the error compares equal.
                prop_assert_eq!(format!("{e:?}"), format!("{want:?}"));
            }
        }
        let g = AdaptiveGrid::mcpg();
        let _ = g.vertex_key(position, normal, camera, xi, u);
        match StaticGrid::new(width) {
            Ok(s) => {
                let v = s.vertex_key(position, u);
                prop_assert!(is_corner_of(v.cell, position / width) || !(position / width).is_finite());
                let _ = s.cell(position);
            }
            Err(e) => {
                let carries_width = matches!(e, GridError::WidthNotPositive { width: w } if w.to_bits() == width.to_bits());
                prop_assert!(carries_width && !(width > 0.0 && width.is_finite()), "{e:?}");
            }
        }
        let _ = StaticGrid::mcpg().vertex_key(position, u);
        prop_assert!(geometric_jitter(xi) <= 24);
        prop_assert!((0.0..=0.5).contains(&geometric_jitter_probability(level)));
        prop_assert!(normal_class(normal) < 6);
    }

    #[test]
    fn hashes_and_indexers_stay_in_range(key in any_key(), capacity in any_u32(), h in any_u32(), slot in any_u32(), n in any_u32()) {
        for hash in hashes() {
            let (a, c) = hash.hash_and_checksum(&key);
            prop_assert_eq!(a, hash.hash(&key));
            let _ = (c, hash.name());
        }
        let _ = (hash_xor_primes(&key), hash_mix(&key), hash_mix_coherent(&key), checksum(&key));
        let _ = (mix_and_checksum(&key), pcg4d(key.words()));
        prop_assert_eq!(CellKey::from_words(key.words()), key);
        match SlotIndexer::new(capacity) {
            Some(ix) => {
                prop_assert!(ix.index(h) < capacity);
                prop_assert!(ix.next(slot) < capacity);
                prop_assert_eq!(ix.index(h), h % capacity);
            }
            None => prop_assert_eq!(capacity, 0),
        }
        // Small n, or n near the top where the search ends quickly (trial division is slow in
        // between).
        if !(1 << 20..=u32::MAX - 64).contains(&n)
            && let Some(p) = next_prime(n)
        {
            prop_assert!(p >= n);
        }
    }

    #[test]
    fn tables_keep_their_counts_with_any_keys_and_slots(
        capacity in prop_oneof![Just(0u32), Just(1u32), 1u32..64],
        max_probes in any_u32(),
        keys in proptest::collection::vec(any_key(), 0..40),
        slots in proptest::collection::vec(any_u32(), 4),
        frames in 0u32..4, max_age in any_u32(), u in any_uniform(),
    ) {
        let _ = u;
        for hash in hashes() {
            let table = HashTable::<u32>::new(capacity, max_probes, hash);
            let concurrent = ConcurrentTable::new(capacity, max_probes, hash);
            let (mut table, mut concurrent) = match (table, concurrent) {
                (Ok(t), Ok(c)) => (t.with_age_tracking(), c.with_age_tracking()),
                (Err(e), Err(f)) => {
                    prop_assert_eq!(e, f);
                    { let expected = match e {
                        TableError::CapacityZero => capacity == 0,
                        TableError::MaxProbesZero => max_probes == 0,
                        TableError::MaxProbesAboveCapacity { max_probes: m, capacity: c } => {
                            max_probes > capacity && (m, c) == (max_probes, capacity)
                        }
                        _ => false,
                    }; prop_assert!(expected); };
                    continue;
                }
                _ => return Err(TestCaseError::fail("the two tables validate differently")),
            };
            for key in &keys {
                let a = table.insert_or_get(key);
                let b = concurrent.insert_or_get(key);
                prop_assert_eq!(a.slot().is_some(), b.slot().is_some());
                if let Some(s) = a.slot() {
                    prop_assert!(s < capacity);
                    if let Some(v) = table.get_mut(key) {
                        *v = v.wrapping_add(1);
                    }
                }
                prop_assert!(table.home_slot(key) < capacity && concurrent.home_slot(key) < capacity);
            }
            let mut found = vec![None; keys.len()];
            table.find_many(&keys, &mut found);
            for (key, f) in keys.iter().zip(&found) {
                prop_assert_eq!(*f, table.find(key));
                prop_assert_eq!(f.is_some(), concurrent.find(key).is_some());
            }
            for &slot in &slots {
                table.touch(slot);
                concurrent.touch(slot);
            }
            for _ in 0..frames {
                table.advance_frame();
                concurrent.advance_frame();
            }
            let e1 = table.evict_older_than(max_age);
            let e2 = concurrent.evict_older_than(max_age, |s| assert!(s < capacity));
            prop_assert_eq!(e1, e2);
            prop_assert_eq!(table.len(), concurrent.count_occupied());
            prop_assert!(table.len() + table.tombstones() <= capacity);
            prop_assert!((0.0..=1.0).contains(&table.load_factor()));
            if let Some(key) = keys.first() {
                let _ = table.remove(key);
                let _ = table.entry(key);
            }
            prop_assert!(table.iter().all(|(s, _)| s < capacity));
            table.clear();
            concurrent.clear();
            prop_assert!(table.is_empty() && concurrent.count_occupied() == 0);
        }
    }
}
