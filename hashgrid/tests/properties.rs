//! Proptest properties of keys, hashes, vertex choice, levels and the tables.

use std::collections::HashMap;

use mcg_hashgrid::glam::{IVec3, Vec3};
use mcg_hashgrid::{
    AdaptiveGrid, BucketHash, CellKey, HashTable, Insert, SlotIndexer, checksum, hash_mix,
    hash_xor_primes, jittered_vertex, mix_and_checksum, normal_class, pcg4d, stochastic_trilinear,
};
use proptest::prelude::*;

fn any_key() -> impl Strategy<Value = CellKey> {
    (any::<[i32; 3]>(), any::<u8>(), any::<u8>(), any::<u16>()).prop_map(
        |(c, level, class, extra)| {
            CellKey::new(IVec3::from_array(c), level, class).with_extra(extra)
        },
    )
}

/// Small keys, as a scene produces them (many share coordinates).
fn small_key() -> impl Strategy<Value = CellKey> {
    (-8..8_i32, -8..8_i32, -8..8_i32, 0..3_u8, 0..6_u8)
        .prop_map(|(x, y, z, level, class)| CellKey::new(IVec3::new(x, y, z), level, class))
}

proptest! {
    #![proptest_config(mcg_test_support::proptest_config(512, 0x7E57_0006))]

    #[test]
    fn words_round_trip(key in any_key()) {
        prop_assert_eq!(CellKey::from_words(key.words()), key);
        prop_assert_eq!(mcg_hashgrid::bytemuck::bytes_of(&key).len(), 16);
    }

    #[test]
    fn hashes_are_deterministic_and_checksums_never_reserved(key in any_key()) {
        let copy = CellKey::from_words(key.words());
        prop_assert_eq!(hash_mix(&key), hash_mix(&copy));
        prop_assert_eq!(hash_xor_primes(&key), hash_xor_primes(&copy));
        prop_assert_eq!(checksum(&key), checksum(&copy));
        prop_assert!(checksum(&key) >= 2);
    }

    /// The xor hash is a bijection of the meta word when the others are fixed (odd
    /// multiplier), and `pcg4d` is a bijection of all four words, so keys that differ only in
    /// level, class or extra bits never share the xor hash, and share the pair (mix hash,
    /// checksum), 64 bits of the permutation, with probability 2⁻⁶⁴ per case (≈ 3·10⁻¹⁷
    /// for the run): levels cannot alias. A hash that ignored the meta word fails at once.
    #[test]
    fn keys_differing_in_meta_never_share_a_hash(key in any_key(), level in any::<u8>(), class in any::<u8>()) {
        let other = CellKey { level, class, ..key };
        prop_assume!(other != key);
        prop_assert_ne!(mix_and_checksum(&key), mix_and_checksum(&other));
        prop_assert_ne!(pcg4d(key.words()), pcg4d(other.words()));
        prop_assert_ne!(hash_xor_primes(&key), hash_xor_primes(&other));
    }

    #[test]
    fn slot_index_is_modulo(h in any::<u32>(), cap in 1..u32::MAX) {
        let ix = SlotIndexer::new(cap).unwrap();
        prop_assert_eq!(ix.index(h), h % cap);
    }

    #[test]
    fn vertices_are_corners_of_the_enclosing_cell(
        q in prop::array::uniform3(-1e4_f32..1e4),
        u in 0.0_f32..1.0,
        v in prop::array::uniform3(0.0_f32..1.0),
    ) {
        let q = Vec3::from_array(q);
        let base = q.floor().as_ivec3();
        for vertex in [stochastic_trilinear(q, u), jittered_vertex(q, Vec3::from_array(v))] {
            let d = vertex - base;
            prop_assert!(d.cmpge(IVec3::ZERO).all() && d.cmple(IVec3::ONE).all(), "{vertex} from {q}");
        }
    }

    #[test]
    fn levels_grow_with_distance_and_jitter_only_coarsens(
        d1 in 0.0_f32..1e5, d2 in 0.0_f32..1e5, xi in 0.0_f32..1.0,
    ) {
        let g = AdaptiveGrid::mcpg();
        let (near, far) = if d1 <= d2 { (d1, d2) } else { (d2, d1) };
        prop_assert!(g.target_level(near) <= g.target_level(far));
        prop_assert!(g.level(near, xi) >= g.target_level(near));
    }

    #[test]
    fn normal_class_picks_the_dominant_axis(n in prop::array::uniform3(-10.0_f32..10.0)) {
        let n = Vec3::from_array(n);
        let c = normal_class(n);
        prop_assert!(c < 6);
        let axis = usize::from(c / 2);
        prop_assert_eq!(n.abs().max_element(), n.abs()[axis]);
        prop_assert_eq!(c % 2 == 1, n[axis] < 0.0);
    }

    /// A sequence of inserts, removals and lookups on a small table agrees with a HashMap
    /// model: every key the table accepted is found with its value, rejected keys only when
    /// the table reports Full, and the occupied slots hold distinct checksums.
    #[test]
    fn table_agrees_with_a_model(
        ops in prop::collection::vec((small_key(), 0..4_u8), 1..300),
        cap in 16..64_u32,
        probes in 1..8_u32,
        xor in any::<bool>(),
    ) {
        let hash = if xor { BucketHash::XorPrimes } else { BucketHash::Mix };
        let mut table = HashTable::<u32>::new(cap, probes, hash).unwrap();
        let mut model: HashMap<CellKey, u32> = HashMap::new();
        for (step, (key, op)) in ops.iter().enumerate() {
            match op {
                0 => {
                    prop_assert_eq!(table.remove(key), model.remove(key).is_some());
                }
                _ => match table.insert_or_get(key) {
                    Insert::Inserted(slot) => {
                        prop_assert!(!model.contains_key(key));
                        prop_assert_eq!(table.values()[slot as usize], 0);
                        table.values_mut()[slot as usize] = step as u32 + 1;
                        model.insert(*key, step as u32 + 1);
                    }
                    Insert::Found(slot) => {
                        prop_assert_eq!(model.get(key), Some(&table.values()[slot as usize]));
                    }
                    Insert::Full => {
                        prop_assert!(!model.contains_key(key));
                        // Full means every probed slot holds another key.
                        let mut s = table.home_slot(key);
                        for _ in 0..probes {
                            prop_assert!(table.checksums()[s as usize] >= 2);
                            s = (s + 1) % cap;
                        }
                    }
                },
            }
            prop_assert_eq!(table.len() as usize, model.len());
        }
        for (key, value) in &model {
            prop_assert_eq!(table.get(key), Some(value));
        }
        let mut words: Vec<u32> = table.checksums().iter().copied().filter(|&w| w >= 2).collect();
        words.sort_unstable();
        let n = words.len();
        words.dedup();
        prop_assert_eq!(words.len(), n);
        prop_assert_eq!(n, model.len());
    }
}
