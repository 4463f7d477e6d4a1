//! Every hash constant and default of the crate, defined once.
//!
//! The GPU backend emits [`U32_CONSTANTS`] and [`F32_CONSTANTS`] into a WGSL prelude
//! (`const HASHGRID_PRIME_X: u32 = 1u;` …), so the shaders hash bit for bit like the CPU; the
//! typed `pub const` items below are what the Rust code uses. A unit test checks that the two
//! tables and the typed constants agree.

/// Multiplier of x in the xor-of-primes bucket hash: 1, as in Instant-NGP (Müller et al. 2022,
/// eq. 4) and MCPG sec. 4 "Hash Grid" ("π₁ = 1 for better cache coherency").
///
/// The MCPG authors later noted that the factor 1 on x causes artifacts; the occupancy suites
/// (`tests/tests/hashgrid_occupancy.rs`) show why: on structured key streams the low bits of
/// the hash are the low bits of x. [`BucketHash::Mix`](crate::BucketHash::Mix) avoids it.
pub const PRIME_X: u32 = 1;
/// Multiplier of y in the xor-of-primes bucket hash (Instant-NGP π₂, MCPG static grid).
pub const PRIME_Y: u32 = 2_654_435_761;
/// Multiplier of z in the xor-of-primes bucket hash (Instant-NGP π₃, MCPG static grid).
pub const PRIME_Z: u32 = 805_459_861;
/// Multiplier of the key's meta word (level, class, extra bits) in the xor-of-primes bucket
/// hash; the MCPG adaptive grid folds `((level << 16) | cube) · 723850877` the same way.
pub const PRIME_META: u32 = 723_850_877;

/// Multiplier of the LCG step of [`pcg4d`](crate::pcg4d) (Jarzynski and Olano 2020; the
/// Numerical Recipes LCG multiplier).
pub const PCG_MUL: u32 = 1_664_525;
/// Increment of the LCG step of [`pcg4d`](crate::pcg4d).
pub const PCG_INC: u32 = 1_013_904_223;
/// Which word of [`pcg4d`](crate::pcg4d)`([x, y, z, meta])` is the mixing bucket hash
/// ([`hash_mix`](crate::hash_mix)): 3, the last word of the second round.
pub const MIX_WORD: usize = 3;

/// Multiplier of x in the first fold of [`hash_fold`](crate::hash_fold) (⌊2³²/φ⌋ rounded to
/// odd). With [`FOLD_Y`], the fold `x·FOLD_X + y·FOLD_Y` is injective on every box of
/// (x, y) whose sides are below ≈ 44 700: the shortest nonzero (Δx, Δy) it maps to 0 mod 2³²
/// has length ≈ 63 200 (Gauss lattice reduction).
pub const FOLD_X: u32 = 0x9E37_79B1;
/// Multiplier of y in the first fold of [`hash_fold`](crate::hash_fold) (xxHash's 4th prime).
pub const FOLD_Y: u32 = 0x27D4_EB2F;
/// Multiplier of z in the second fold of [`hash_fold`](crate::hash_fold),
/// `z·FOLD_Z + rotl(meta, FOLD_META_ROTATE)` (xxHash's 2nd prime). For keys with equal extra
/// bits (meta bits 16..32) the rotated meta words differ by a multiple of 2¹⁶, which
/// `Δz·FOLD_Z` (FOLD_Z odd) matches only when 2¹⁶ divides Δz: the fold is injective on every
/// range of z shorter than 65 536.
pub const FOLD_Z: u32 = 0x85EB_CA77;
/// Left rotation of the meta word in the second fold of [`hash_fold`](crate::hash_fold)
/// (in place of a multiply): the level and class (meta bits 0..16) move to the high half,
/// which the finisher's `t ⊕ (t >> 16)` brings back down before its multiply.
pub const FOLD_META_ROTATE: u32 = 16;
/// Multiplier of the finisher of [`hash_fold`](crate::hash_fold) (the first multiplier of
/// Wellons' `lowbias32`).
pub const FOLD_FINISH: u32 = 0x7FEB_352D;

/// log₂ of the run length of [`BucketHash::MixCoherent`](crate::BucketHash::MixCoherent):
/// runs of 2² = 4 vertices consecutive in x hash to 4 neighbouring slots.
pub const COHERENT_RUN_BITS: u32 = 2;

/// Checksum word of an empty slot. [`checksum`](crate::checksum) never returns it.
pub const EMPTY: u32 = 0;
/// Checksum word of an evicted slot (a tombstone: probing walks past it, inserts reuse it).
/// [`checksum`](crate::checksum) never returns it.
pub const TOMBSTONE: u32 = 1;
/// Checksums below this value are reserved ([`EMPTY`], [`TOMBSTONE`]); a raw hash `h < 2` is
/// returned as `h | 2` (so the checksums 2 and 3 are twice as likely as any other: a false-match
/// probability of 2⁻³¹ instead of 2⁻³² for those two values, 2⁻³² · (1 + 2⁻³¹) on average).
pub const FIRST_CHECKSUM: u32 = 2;

/// Default probe limit of the tables: a key is looked for in at most this many consecutive
/// slots (wrapping at the end). Bevy Solari probes 3. With 8 and the mixing hash, the demo's
/// section `hashgrid` measures failed inserts of ≲ 6·10⁻⁴ at load factor 0.25 and ≈ 3 % at
/// 0.5 on a renderer's key stream — the same as random keys (ideal hashing), because linear
/// probing clusters. Size tables for α ≲ 0.25 or raise the limit.
pub const DEFAULT_MAX_PROBES: u32 = 8;

/// Number of bits of the level in the key's meta word (bits 0..8).
///
/// Level and class sit in the *low* bits of the meta word: the xor-of-primes hash multiplies
/// the meta word by [`PRIME_META`], and a product's low bits depend only on the factor's low
/// bits, so high-placed level bits would never reach the bucket index of a power-of-two table
/// (MCPG's `(level << 16) | cube` has that problem for tables under 2¹⁶ slots).
pub const LEVEL_BITS: u32 = 8;
/// Number of bits of the class in the key's meta word (bits 8..16).
pub const CLASS_BITS: u32 = 8;
/// Number of free extra bits in the key's meta word (bits 16..32).
pub const EXTRA_BITS: u32 = 16;
/// Bit position of the level in the meta word.
pub const LEVEL_SHIFT: u32 = 0;
/// Bit position of the class in the meta word.
pub const CLASS_SHIFT: u32 = 8;
/// Bit position of the extra bits in the meta word.
pub const EXTRA_SHIFT: u32 = 16;
/// The class of a key that carries no normal (the static grid): 6, after the six normal
/// classes 0..5.
pub const CLASS_NONE: u8 = 6;

/// MCPG's adaptive-grid angular resolution: 0.6° (MCPG sec. 6, "a grid resolution of 0.6° and
/// a buffer size of 10⁶"), as tan(α/2) = tan(0.3°).
pub const DEFAULT_TAN_HALF_ANGLE: f32 = 0.005_236_035_7;
/// Finest cell width of the adaptive grid, in scene units (merian-quake: 0.01).
pub const DEFAULT_MIN_WIDTH: f32 = 0.01;
/// Width ratio over [`DEFAULT_LEVEL_STEPS`] levels (merian-quake uses 4 or √3).
pub const DEFAULT_LEVEL_POWER: f32 = 4.0;
/// Levels per factor [`DEFAULT_LEVEL_POWER`] in width (merian-quake uses 1 to 6): with 4 and
/// 4, consecutive levels differ by √2 in width.
pub const DEFAULT_LEVEL_STEPS: u32 = 4;
/// Highest level a key can carry ([`LEVEL_BITS`] = 8 bits).
pub const MAX_LEVEL: u32 = (1 << LEVEL_BITS) - 1;
/// Cell width of MCPG's static grid (merian-quake: about 25 scene units).
pub const DEFAULT_STATIC_WIDTH: f32 = 25.0;
/// MCPG's probability of loading from the adaptive rather than the static grid (sec. 4, Step 1).
pub const DEFAULT_P_ADAPTIVE: f32 = 0.7;

/// Every `u32` constant by its WGSL name, for the GPU backend's generated prelude.
pub const U32_CONSTANTS: &[(&str, u32)] = &[
    ("HASHGRID_PRIME_X", PRIME_X),
    ("HASHGRID_PRIME_Y", PRIME_Y),
    ("HASHGRID_PRIME_Z", PRIME_Z),
    ("HASHGRID_PRIME_META", PRIME_META),
    ("HASHGRID_PCG_MUL", PCG_MUL),
    ("HASHGRID_PCG_INC", PCG_INC),
    ("HASHGRID_MIX_WORD", MIX_WORD as u32),
    ("HASHGRID_COHERENT_RUN_BITS", COHERENT_RUN_BITS),
    ("HASHGRID_FOLD_X", FOLD_X),
    ("HASHGRID_FOLD_Y", FOLD_Y),
    ("HASHGRID_FOLD_Z", FOLD_Z),
    ("HASHGRID_FOLD_META_ROTATE", FOLD_META_ROTATE),
    ("HASHGRID_FOLD_FINISH", FOLD_FINISH),
    ("HASHGRID_EMPTY", EMPTY),
    ("HASHGRID_TOMBSTONE", TOMBSTONE),
    ("HASHGRID_FIRST_CHECKSUM", FIRST_CHECKSUM),
    ("HASHGRID_DEFAULT_MAX_PROBES", DEFAULT_MAX_PROBES),
    ("HASHGRID_LEVEL_BITS", LEVEL_BITS),
    ("HASHGRID_CLASS_BITS", CLASS_BITS),
    ("HASHGRID_EXTRA_BITS", EXTRA_BITS),
    ("HASHGRID_LEVEL_SHIFT", LEVEL_SHIFT),
    ("HASHGRID_CLASS_SHIFT", CLASS_SHIFT),
    ("HASHGRID_EXTRA_SHIFT", EXTRA_SHIFT),
    ("HASHGRID_CLASS_NONE", CLASS_NONE as u32),
    ("HASHGRID_DEFAULT_LEVEL_STEPS", DEFAULT_LEVEL_STEPS),
    ("HASHGRID_MAX_LEVEL", MAX_LEVEL),
];

/// Every `f32` default by its WGSL name, for the GPU backend's generated prelude.
pub const F32_CONSTANTS: &[(&str, f32)] = &[
    ("HASHGRID_DEFAULT_TAN_HALF_ANGLE", DEFAULT_TAN_HALF_ANGLE),
    ("HASHGRID_DEFAULT_MIN_WIDTH", DEFAULT_MIN_WIDTH),
    ("HASHGRID_DEFAULT_LEVEL_POWER", DEFAULT_LEVEL_POWER),
    ("HASHGRID_DEFAULT_STATIC_WIDTH", DEFAULT_STATIC_WIDTH),
    ("HASHGRID_DEFAULT_P_ADAPTIVE", DEFAULT_P_ADAPTIVE),
];

#[cfg(test)]
mod tests {
    use super::*;

    fn u32_named(name: &str) -> u32 {
        U32_CONSTANTS.iter().find(|(n, _)| *n == name).unwrap().1
    }

    #[test]
    fn tables_are_unique_and_match_the_typed_constants() {
        for (i, (a, _)) in U32_CONSTANTS.iter().enumerate() {
            assert!(a.starts_with("HASHGRID_"));
            for (b, _) in &U32_CONSTANTS[i + 1..] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(u32_named("HASHGRID_PRIME_Y"), 2_654_435_761);
        assert_eq!(u32_named("HASHGRID_PCG_INC"), PCG_INC);
        assert_eq!(u32_named("HASHGRID_MAX_LEVEL"), 255);
        const { assert!(MIX_WORD < 4) };
        assert_eq!(LEVEL_BITS + CLASS_BITS + EXTRA_BITS, 32);
        assert_eq!(CLASS_SHIFT, LEVEL_SHIFT + LEVEL_BITS);
        assert_eq!(EXTRA_SHIFT, CLASS_SHIFT + CLASS_BITS);
        let tan = (0.3_f64.to_radians()).tan() as f32;
        assert_eq!(DEFAULT_TAN_HALF_ANGLE, tan);
        assert!(
            F32_CONSTANTS
                .iter()
                .all(|(n, v)| n.starts_with("HASHGRID_") && v.is_finite())
        );
    }
}
