//! Bucket hashes and the checksum of a [`CellKey`].
//!
//! A table slot is found from a 32-bit *bucket hash* reduced to the capacity
//! ([`SlotIndexer`](crate::SlotIndexer)); a separate 32-bit *checksum* stored in the slot tells
//! whether the slot holds this key or another one that hashed to the same place (MCPG sec. 4:
//! "we store the grid position, hashed with a separate hash function, to detect collisions",
//! after Binder et al. 2018). All functions hash the four words `[x, y, z, meta]` of the key,
//! so the level and the normal class are part of both.
//!
//! The default bucket hash [`hash_fold`] and the [`checksum`] come from one short pass
//! ([`fold_and_checksum`]: three independent multiplies and one finishing multiply); the
//! paper's [`pcg4d`] (Jarzynski and Olano 2020) stays available as [`BucketHash::Mix`].
//! Everything is wrapping `u32` arithmetic, which WGSL has, so the GPU twin reproduces every
//! value bit for bit.

use crate::constants::{
    COHERENT_RUN_BITS, FIRST_CHECKSUM, FOLD_FINISH, FOLD_META_ROTATE, FOLD_X, FOLD_Y, FOLD_Z,
    MIX_WORD, PCG_INC, PCG_MUL, PRIME_META, PRIME_X, PRIME_Y, PRIME_Z,
};
use crate::key::CellKey;

/// Which bucket hash a table uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BucketHash {
    /// `x·π₁ ⊕ y·π₂ ⊕ z·π₃ ⊕ meta·π₄` (wrapping u32 products, ⊕ = xor) with Instant-NGP's
    /// primes π = (1, 2654435761, 805459861) and MCPG's 723850877 for the meta word
    /// (MCPG sec. 4, "Hash Grid"; Müller et al. 2022, eq. 4). Three multiplies, but poor low
    /// bits on structured keys: [`hash_xor_primes`].
    XorPrimes,
    /// Word [`MIX_WORD`] of [`pcg4d`] of the four words
    /// ([`hash_mix`]): every output bit depends on every input bit; uniform bucket occupancy
    /// on structured keys. 12 multiplies in two dependent rounds, plus the [`checksum`]'s
    /// fold: a lookup hashes in ≈ 3× the instructions of [`BucketHash::Fold`].
    Mix,
    /// [`pcg4d`] of the key with `x` divided by 4, xor'ed with the low 2 bits of `x`
    /// ([`hash_mix_coherent`]): runs of 4 vertices along x land in 4 neighbouring slots (one
    /// cache line of checksums), as π₁ = 1 does for Instant-NGP, while the runs themselves
    /// are spread like [`BucketHash::Mix`]. Runs of four occupied slots make linear-probing
    /// clusters grow faster (the demo measures the failed inserts), and the checksum needs a
    /// second permutation (of the full key), so lookups cost more; on the bench's renderer
    /// streams (stochastic trilinear corners of neighbouring pixels) the locality did not pay
    /// for that.
    MixCoherent,
    /// Two multiply–add folds of the words, xor'ed and finished by one multiply–xorshift
    /// ([`hash_fold`]); the [`checksum`] is the fold of `z, meta` plus this hash, so one short
    /// pass gives both ([`fold_and_checksum`]: 4 multiplies, none dependent on another
    /// multiply of the key). Passes the same occupancy and checksum suites as
    /// [`BucketHash::Mix`]. The default.
    #[default]
    Fold,
}

impl BucketHash {
    /// Every variant, for sweeps.
    pub const ALL: [BucketHash; 4] = [
        BucketHash::XorPrimes,
        BucketHash::Mix,
        BucketHash::MixCoherent,
        BucketHash::Fold,
    ];

    /// The bucket hash of `key`.
    #[inline]
    #[must_use]
    pub fn hash(self, key: &CellKey) -> u32 {
        match self {
            BucketHash::XorPrimes => hash_xor_primes(key),
            BucketHash::Mix => hash_mix(key),
            BucketHash::MixCoherent => hash_mix_coherent(key),
            BucketHash::Fold => hash_fold(key),
        }
    }

    /// `(self.hash(key), checksum(key))`, in one pass for [`BucketHash::Fold`]
    /// ([`fold_and_checksum`]): what the tables compute per lookup. Always inlined, so that a
    /// caller that knows the variant (the tables dispatch once per call) gets straight-line
    /// code: out of line, the call and the `match` cost a cache-resident `get` ≈ 35 %.
    #[inline(always)]
    #[must_use]
    pub fn hash_and_checksum(self, key: &CellKey) -> (u32, u32) {
        match self {
            BucketHash::XorPrimes => (hash_xor_primes(key), checksum(key)),
            BucketHash::Mix => mix_and_checksum(key),
            BucketHash::MixCoherent => (hash_mix_coherent(key), checksum(key)),
            BucketHash::Fold => fold_and_checksum(key),
        }
    }

    /// A short lowercase name (`"xor-primes"`, `"mix"`, `"mix-coherent"`, `"fold"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            BucketHash::XorPrimes => "xor-primes",
            BucketHash::Mix => "mix",
            BucketHash::MixCoherent => "mix-coherent",
            BucketHash::Fold => "fold",
        }
    }
}

/// The xor-of-primes bucket hash of MCPG and Instant-NGP,
/// `hash(x) = ⊕ᵢ πᵢ xᵢ` (MCPG sec. 4; the `mod B` is the table's [`SlotIndexer`](crate::SlotIndexer)),
/// over `[x, y, z, meta]` with the primes in [`constants`](crate::constants).
///
/// Because π₁ = 1, the low bits of the result are the low bits of `x` xor'ed with a few low
/// bits of the other products: with a power-of-two table (mask) whole planes of keys fall
/// into a fraction of the buckets. Use it for compatibility with MCPG's shaders; prefer
/// [`hash_mix`] otherwise.
#[inline]
#[must_use]
pub const fn hash_xor_primes(key: &CellKey) -> u32 {
    let [x, y, z, meta] = key.words();
    x.wrapping_mul(PRIME_X)
        ^ y.wrapping_mul(PRIME_Y)
        ^ z.wrapping_mul(PRIME_Z)
        ^ meta.wrapping_mul(PRIME_META)
}

/// `pcg4d` (Jarzynski and Olano 2020, "Hash Functions for GPU Rendering", JCGT 9(3), sec. 4
/// and listing "pcg4d"): a permutation of four `u32` words built from a PCG-style LCG step
/// `vᵢ ← vᵢ·1664525 + 1013904223`, two rounds of multiply–add between the words
/// (`x += y·w; y += z·x; z += x·y; w += y·z`, in that order) with a xorshift `vᵢ ^= vᵢ >> 16`
/// between them.
///
/// Every step is invertible (odd multipliers; each round updates one word from the others),
/// so distinct keys give distinct 128-bit outputs. The paper's tests rate it among the best
/// GPU hashes of multi-dimensional input at its cost (12 multiplies, no loops), which is what
/// grid keys are.
#[inline]
#[must_use]
pub const fn pcg4d(words: [u32; 4]) -> [u32; 4] {
    let [mut x, mut y, mut z, mut w] = words;
    x = x.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
    y = y.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
    z = z.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
    w = w.wrapping_mul(PCG_MUL).wrapping_add(PCG_INC);
    x = x.wrapping_add(y.wrapping_mul(w));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    w = w.wrapping_add(y.wrapping_mul(z));
    x ^= x >> 16;
    y ^= y >> 16;
    z ^= z >> 16;
    w ^= w >> 16;
    x = x.wrapping_add(y.wrapping_mul(w));
    y = y.wrapping_add(z.wrapping_mul(x));
    z = z.wrapping_add(x.wrapping_mul(y));
    w = w.wrapping_add(y.wrapping_mul(z));
    [x, y, z, w]
}

/// The mixing bucket hash: word [`MIX_WORD`] (= 3, `w`) of [`pcg4d`]`([x, y, z, meta])`.
///
/// The last word of the second round: it depends on all four words after the xorshift, so
/// even its low bits (all a power-of-two mask reads) are uniform on structured keys; the
/// `hashgrid_occupancy` suite checks it (word 1, `y`, fails it on a line along z).
#[inline]
#[must_use]
pub const fn hash_mix(key: &CellKey) -> u32 {
    pcg4d(key.words())[MIX_WORD]
}

/// `(hash_mix(key), checksum(key))`: what a [`BucketHash::Mix`] table computes per lookup.
#[inline]
#[must_use]
pub const fn mix_and_checksum(key: &CellKey) -> (u32, u32) {
    (hash_mix(key), checksum(key))
}

/// The two folds of [`hash_fold`]: `(x·FOLD_X + y·FOLD_Y, z·FOLD_Z + rotl(meta, 16))`.
#[inline(always)]
const fn folds(key: &CellKey) -> (u32, u32) {
    let [x, y, z, meta] = key.words();
    (
        x.wrapping_mul(FOLD_X).wrapping_add(y.wrapping_mul(FOLD_Y)),
        z.wrapping_mul(FOLD_Z)
            .wrapping_add(meta.rotate_left(FOLD_META_ROTATE)),
    )
}

/// The finisher of [`hash_fold`]: `t ^= t >> 16; t ·= FOLD_FINISH; t ^= t >> 15` (the first
/// half of Wellons' `lowbias32`), a bijection whose low output bits depend on every input bit.
#[inline(always)]
const fn finish(t: u32) -> u32 {
    let t = (t ^ (t >> 16)).wrapping_mul(FOLD_FINISH);
    t ^ (t >> 15)
}

/// The fold bucket hash (the default, [`BucketHash::Fold`]):
///
/// ```text
/// a = x·FOLD_X + y·FOLD_Y,   b = z·FOLD_Z + rotl(meta, 16)   (wrapping u32)
/// t = a ⊕ b;   t ⊕= t >> 16;   t ·= FOLD_FINISH;   hash = t ⊕ (t >> 15)
/// ```
///
/// Each fold is injective on every box of keys of sides below ≈ 44 000 cells (see
/// [`FOLD_X`] and [`FOLD_Z`]; the meta
/// word, whose level and class are small, is rotated into the high half instead of
/// multiplied); xor'ing two folds is not linear mod 2³², and the multiply–xorshift finisher
/// (Wellons' `lowbias32`, first round) carries every bit into the low bits that a power-of-two
/// mask reads. Four multiplies, the first three independent: under a third of the
/// instructions of [`hash_mix`], which the `hashgrid_occupancy` suite shows no better on
/// planes, lines, spheres and a renderer's multi-level stream. (Leaving x unmultiplied as
/// well, `x + y·FOLD_Y`, failed that suite on a plane with a power-of-two capacity:
/// X²/df = 1.094, p = 1.8·10⁻⁵.)
#[inline]
#[must_use]
pub const fn hash_fold(key: &CellKey) -> u32 {
    let (a, b) = folds(key);
    finish(a ^ b)
}

/// `(hash_fold(key), checksum(key))` in one pass: the checksum is the second fold plus the
/// hash, `b + hash_fold(key)`, remapped off the reserved words.
///
/// `(a, b) ↦ (hash, b + hash)` is a bijection (the finisher is one, and `a = (t ⊕ b)` is
/// recovered from `t` and `b`), so two distinct keys share both the bucket hash and the
/// checksum only if they share both folds, which no two keys within ≈ 44 000 of each other
/// in every coordinate (and with equal extra bits) do. Keys sharing a checksum have different bucket hashes.
#[inline]
#[must_use]
pub const fn fold_and_checksum(key: &CellKey) -> (u32, u32) {
    let (h, raw) = fold_and_raw_checksum(key);
    (h, reserve(raw))
}

/// [`fold_and_checksum`] with the checksum before [`reserve`] (`b + hash`, possibly 0 or 1):
/// [`HashTable::get`](crate::HashTable::get) compares it with the home slot's word first and
/// remaps it only off its fast path.
#[inline(always)]
pub(crate) const fn fold_and_raw_checksum(key: &CellKey) -> (u32, u32) {
    let (a, b) = folds(key);
    let h = finish(a ^ b);
    (h, b.wrapping_add(h))
}

/// The coherent mixing bucket hash: [`hash_mix`] of `[x >> 2, y, z, meta]`, xor'ed with
/// `x & 3` ([`COHERENT_RUN_BITS`] = 2).
///
/// The four vertices `4k..4k+3` along x share the mixed value `m` and get `m ⊕ 0..3`: four
/// slots in one aligned group of four with a power-of-two capacity, or within a window of four
/// consecutive slots with a modulo. `x >> 2` is an arithmetic shift (floor division), so runs
/// are aligned for negative x too.
#[inline]
#[must_use]
pub const fn hash_mix_coherent(key: &CellKey) -> u32 {
    let [x, y, z, meta] = key.words();
    let run = ((x as i32) >> COHERENT_RUN_BITS) as u32;
    pcg4d([run, y, z, meta])[MIX_WORD] ^ (x & ((1 << COHERENT_RUN_BITS) - 1))
}

/// The checksum stored in a slot, for every [`BucketHash`]: `b + hash_fold(key)` with the
/// second fold `b = z·FOLD_Z + rotl(meta, 16)` ([`fold_and_checksum`]), never
/// [`EMPTY`](crate::constants::EMPTY) (0) or [`TOMBSTONE`](crate::constants::TOMBSTONE) (1): a
/// raw value below [`FIRST_CHECKSUM`] is or'ed with 2.
///
/// Two distinct keys share a checksum with probability ≈ 2⁻³² (exactly 2⁻³² · (1 + 2⁻³¹) for
/// an ideal hash, because of the remap). Unlike MCPG's 16-bit checksum (≈ 1/65 536 false
/// matches) all 32 bits are kept; the `hashgrid_checksum` suite measures the rate, and that
/// keys sharing a checksum share neither the [`hash_fold`] nor the [`hash_mix`] word.
#[inline]
#[must_use]
pub const fn checksum(key: &CellKey) -> u32 {
    fold_and_checksum(key).1
}

/// Moves raw values 0 and 1 (the reserved words) to 2 and 3.
#[inline]
pub(crate) const fn reserve(h: u32) -> u32 {
    if h < FIRST_CHECKSUM {
        h | FIRST_CHECKSUM
    } else {
        h
    }
}

#[cfg(test)]
mod tests {
    use glam::IVec3;

    use super::*;

    /// pcg4d as printed in Jarzynski and Olano (2020), on `[u32; 4]` with the constants
    /// written out, as the reference for [`pcg4d`].
    fn pcg4d_reference(mut v: [u32; 4]) -> [u32; 4] {
        for c in &mut v {
            *c = c.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        }
        let round = |v: &mut [u32; 4]| {
            v[0] = v[0].wrapping_add(v[1].wrapping_mul(v[3]));
            v[1] = v[1].wrapping_add(v[2].wrapping_mul(v[0]));
            v[2] = v[2].wrapping_add(v[0].wrapping_mul(v[1]));
            v[3] = v[3].wrapping_add(v[1].wrapping_mul(v[2]));
        };
        round(&mut v);
        for c in &mut v {
            *c ^= *c >> 16;
        }
        round(&mut v);
        v
    }

    #[test]
    fn pcg4d_matches_the_reference_and_is_a_permutation_locally() {
        let mut seen = std::collections::HashSet::new();
        for x in -8..8 {
            for meta in 0..64 {
                let w = [x as u32, 5, 0xFFFF_FFF0, meta];
                let v = pcg4d(w);
                assert_eq!(v, pcg4d_reference(w));
                assert!(seen.insert(v));
            }
        }
    }

    #[test]
    fn one_pass_equals_the_separate_functions() {
        for i in -300..300 {
            let key = CellKey::new(IVec3::new(i, 3 * i, -7), (i & 15) as u8, (i & 7) as u8);
            assert_eq!(mix_and_checksum(&key), (hash_mix(&key), checksum(&key)));
            assert_eq!(fold_and_checksum(&key), (hash_fold(&key), checksum(&key)));
            for hash in BucketHash::ALL {
                assert_eq!(
                    hash.hash_and_checksum(&key),
                    (hash.hash(&key), checksum(&key))
                );
            }
        }
    }

    #[test]
    fn level_and_class_change_every_hash() {
        let a = CellKey::new(IVec3::new(10, -4, 7), 3, 2);
        for b in [
            CellKey { level: 4, ..a },
            CellKey { class: 3, ..a },
            a.with_extra(1),
        ] {
            assert_ne!(hash_xor_primes(&a), hash_xor_primes(&b));
            assert_ne!(hash_mix(&a), hash_mix(&b));
            assert_ne!(hash_mix_coherent(&a), hash_mix_coherent(&b));
            assert_ne!(hash_fold(&a), hash_fold(&b));
            assert_ne!(checksum(&a), checksum(&b));
        }
    }

    #[test]
    fn checksum_is_never_reserved() {
        // Search keys whose raw checksum word is 0 or 1 would take 2³¹ tries; check the remap
        // rule directly instead, and a run of keys.
        for h in [0_u32, 1, 2, 3, u32::MAX] {
            assert!(reserve(h) >= FIRST_CHECKSUM);
            assert_eq!(reserve(h) == h, h >= FIRST_CHECKSUM);
        }
        assert_eq!((reserve(0), reserve(1)), (2, 3));
        for i in -500..500 {
            let key = CellKey::new(IVec3::new(i, i * 7, -i), 0, 0);
            assert!(checksum(&key) >= FIRST_CHECKSUM);
        }
    }

    #[test]
    fn value_stability() {
        let key = CellKey::new(IVec3::new(1, -2, 3), 7, 3);
        assert_eq!(
            hash_xor_primes(&key),
            1 ^ 0xFFFF_FFFE_u32.wrapping_mul(2_654_435_761)
                ^ 3_u32.wrapping_mul(805_459_861)
                ^ 0x0000_0307_u32.wrapping_mul(723_850_877)
        );
        let pinned = [
            hash_xor_primes(&key),
            hash_mix(&key),
            hash_fold(&key),
            checksum(&key),
        ];
        let run: [u32; 5] = [-5, -4, -1, 0, 3].map(|x| {
            hash_mix_coherent(&CellKey {
                cell: IVec3::new(x, -2, 3),
                ..key
            })
        });
        // −4..−1 is one run, 0..3 another: members differ in the low two bits only.
        assert_eq!((run[1] ^ run[2], run[3] ^ run[4]), (3, 3));
        assert_ne!(run[0] ^ 3, run[1]);
        // pcg4d([1, 0xFFFFFFFE, 3, 0x307]) = [0x090f2888, 0x16f386d9, 0x0140a1c4, 0x9a869f9e],
        // also from an independent Python transcription of the paper's listing.
        assert_eq!(pcg4d(key.words())[1], 0x16f3_86d9);
        // The fold pair, also from an independent Python transcription of the formulas:
        // a = 0x9e3779b1 − 2·0x27d4eb2f = 0x4e8da353,
        // b = 3·0x85ebca77 + rotl(0x307, 16) = 0x94ca5f65 (mod 2³²).
        assert_eq!(pinned, [0xced1_1e4b, 0x9a86_9f9e, 0x7232_c2b9, 0x06fd_221e]);
    }
}
