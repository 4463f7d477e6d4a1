//! Bucket hashes and the checksum of a [`CellKey`].
//!
//! A table slot is found from a 32-bit *bucket hash* reduced to the capacity
//! ([`SlotIndexer`](crate::SlotIndexer)); a separate 32-bit *checksum* stored in the slot tells
//! whether the slot holds this key or another one that hashed to the same place (MCPG sec. 4:
//! "we store the grid position, hashed with a separate hash function, to detect collisions",
//! after Binder et al. 2018). All functions hash the four words `[x, y, z, meta]` of the key,
//! so the level and the normal class are part of both.

use crate::constants::{
    BUCKET_SEED, CHECKSUM_SEED, COHERENT_RUN_BITS, FIRST_CHECKSUM, FMIX_M1, FMIX_M2, MURMUR_C1,
    MURMUR_C2, MURMUR_N, PRIME_META, PRIME_X, PRIME_Y, PRIME_Z,
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
    /// Murmur3 over the four words ([`hash_mix`]): every output bit depends on every input bit;
    /// uniform bucket occupancy on structured keys. The default.
    #[default]
    Mix,
    /// Murmur3 of the key with `x` divided by 4, xor'ed with the low 2 bits of `x`
    /// ([`hash_mix_coherent`]): runs of 4 vertices along x land in 4 neighbouring slots (one
    /// cache line of checksums), as π₁ = 1 does for Instant-NGP, while the runs themselves
    /// are spread like [`BucketHash::Mix`]. Faster on coherent query streams, but runs of
    /// four occupied slots make linear-probing clusters grow faster: the demo measures ≈ 1 %
    /// failed inserts at load 0.25 and 12 % at 0.5 with 8 probes (`Mix`: 0.03 % and 2.5 %).
    MixCoherent,
}

impl BucketHash {
    /// Every variant, for sweeps.
    pub const ALL: [BucketHash; 3] = [
        BucketHash::XorPrimes,
        BucketHash::Mix,
        BucketHash::MixCoherent,
    ];

    /// The bucket hash of `key`.
    #[inline]
    #[must_use]
    pub fn hash(self, key: &CellKey) -> u32 {
        match self {
            BucketHash::XorPrimes => hash_xor_primes(key),
            BucketHash::Mix => hash_mix(key),
            BucketHash::MixCoherent => hash_mix_coherent(key),
        }
    }

    /// A short lowercase name (`"xor-primes"`, `"mix"`, `"mix-coherent"`).
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            BucketHash::XorPrimes => "xor-primes",
            BucketHash::Mix => "mix",
            BucketHash::MixCoherent => "mix-coherent",
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

/// Murmur3's 32-bit finaliser (Appleby): an invertible map in which every output bit depends
/// on every input bit.
#[inline]
#[must_use]
pub const fn fmix32(mut h: u32) -> u32 {
    h ^= h >> 16;
    h = h.wrapping_mul(FMIX_M1);
    h ^= h >> 13;
    h = h.wrapping_mul(FMIX_M2);
    h ^= h >> 16;
    h
}

/// `MurmurHash3_x86_32` (Appleby) of four little-endian 32-bit words with `seed`: four block
/// rounds `k = rotl(w·c₁, 15)·c₂; h = rotl(h ⊕ k, 13)·5 + n`, then `h ⊕= 16` (the byte length)
/// and [`fmix32`]. Identical to the reference implementation on the 16 bytes of the words.
#[inline]
#[must_use]
pub const fn murmur3_words(words: [u32; 4], seed: u32) -> u32 {
    let mut h = seed;
    let mut i = 0;
    while i < 4 {
        let k = words[i]
            .wrapping_mul(MURMUR_C1)
            .rotate_left(15)
            .wrapping_mul(MURMUR_C2);
        h = (h ^ k)
            .rotate_left(13)
            .wrapping_mul(5)
            .wrapping_add(MURMUR_N);
        i += 1;
    }
    fmix32(h ^ 16)
}

/// The mixing bucket hash: [`murmur3_words`] of `[x, y, z, meta]` with [`BUCKET_SEED`].
#[inline]
#[must_use]
pub const fn hash_mix(key: &CellKey) -> u32 {
    murmur3_words(key.words(), BUCKET_SEED)
}

/// The coherent mixing bucket hash: [`murmur3_words`] of `[x >> 2, y, z, meta]` with
/// [`BUCKET_SEED`], xor'ed with `x & 3` ([`COHERENT_RUN_BITS`] = 2).
///
/// The four vertices `4k..4k+3` along x share the murmur value `m` and get `m ⊕ 0..3`: four
/// slots in one aligned group of four with a power-of-two capacity, or within a window of four
/// consecutive slots with a modulo. A renderer's neighbouring pixels touch neighbouring
/// vertices, so their lookups share cache lines. `x >> 2` is an arithmetic shift (floor
/// division), so runs are aligned for negative x too.
#[inline]
#[must_use]
pub const fn hash_mix_coherent(key: &CellKey) -> u32 {
    let [x, y, z, meta] = key.words();
    let run = ((x as i32) >> COHERENT_RUN_BITS) as u32;
    murmur3_words([run, y, z, meta], BUCKET_SEED) ^ (x & ((1 << COHERENT_RUN_BITS) - 1))
}

/// The checksum stored in a slot: [`murmur3_words`] of `[x, y, z, meta]` with
/// [`CHECKSUM_SEED`], never [`EMPTY`](crate::constants::EMPTY) (0) or
/// [`TOMBSTONE`](crate::constants::TOMBSTONE) (1): a raw value below
/// [`FIRST_CHECKSUM`] is or'ed with 2.
///
/// Two distinct keys share a checksum with probability ≈ 2⁻³² (exactly 2⁻³² · (1 + 2⁻³¹) for
/// an ideal hash, because of the remap). Unlike MCPG's 16-bit checksum (≈ 1/65 536 false
/// matches) all 32 bits are kept; the `hashgrid_checksum` suite measures the rate.
#[inline]
#[must_use]
pub const fn checksum(key: &CellKey) -> u32 {
    let h = murmur3_words(key.words(), CHECKSUM_SEED);
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

    /// Byte-wise reference `MurmurHash3_x86_32`, written from Appleby's description.
    fn murmur3_reference(data: &[u8], seed: u32) -> u32 {
        let mut h = seed;
        let blocks = data.chunks_exact(4);
        let tail = blocks.remainder();
        for b in blocks {
            let mut k = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            k = k
                .wrapping_mul(0xcc9e_2d51)
                .rotate_left(15)
                .wrapping_mul(0x1b87_3593);
            h ^= k;
            h = h.rotate_left(13).wrapping_mul(5).wrapping_add(0xe654_6b64);
        }
        let mut k = 0_u32;
        for (i, &byte) in tail.iter().enumerate() {
            k ^= u32::from(byte) << (8 * i);
        }
        if !tail.is_empty() {
            h ^= k
                .wrapping_mul(0xcc9e_2d51)
                .rotate_left(15)
                .wrapping_mul(0x1b87_3593);
        }
        h ^= data.len() as u32;
        fmix32(h)
    }

    #[test]
    fn reference_murmur3_matches_published_vectors() {
        assert_eq!(murmur3_reference(b"", 0), 0);
        assert_eq!(murmur3_reference(b"", 1), 0x514e_28b7);
        assert_eq!(murmur3_reference(b"Hello, world!", 1234), 0xfaf6_cdb3);
        assert_eq!(
            murmur3_reference(b"The quick brown fox jumps over the lazy dog", 0x9747_b28c),
            0x2fa8_26cd
        );
    }

    #[test]
    fn murmur3_words_is_murmur3_of_the_bytes() {
        for key in [
            CellKey::new(IVec3::new(1, 2, 3), 4, 5),
            CellKey::new(IVec3::new(-1, i32::MAX, i32::MIN), 255, 0).with_extra(77),
        ] {
            let mut bytes = [0_u8; 16];
            for (chunk, w) in bytes.chunks_exact_mut(4).zip(key.words()) {
                chunk.copy_from_slice(&w.to_le_bytes());
            }
            for seed in [0, BUCKET_SEED, CHECKSUM_SEED] {
                assert_eq!(
                    murmur3_words(key.words(), seed),
                    murmur3_reference(&bytes, seed)
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
            assert_ne!(checksum(&a), checksum(&b));
        }
    }

    #[test]
    fn checksum_is_never_reserved() {
        // Search keys whose raw checksum hash is 0 or 1 would take 2³¹ tries; check the remap
        // rule directly instead, and a run of keys.
        for h in [0_u32, 1, 2, 3, u32::MAX] {
            let mapped = if h < FIRST_CHECKSUM {
                h | FIRST_CHECKSUM
            } else {
                h
            };
            assert!(mapped >= FIRST_CHECKSUM);
        }
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
        assert_eq!(fmix32(0), 0);
        assert_eq!(fmix32(1), 0x514e_28b7);
        let pinned = [hash_xor_primes(&key), hash_mix(&key), checksum(&key)];
        let run: [u32; 5] = [-5, -4, -1, 0, 3].map(|x| {
            hash_mix_coherent(&CellKey {
                cell: IVec3::new(x, -2, 3),
                ..key
            })
        });
        // −4..−1 is one run, 0..3 another: members differ in the low two bits only.
        assert_eq!((run[1] ^ run[2], run[3] ^ run[4]), (3, 3));
        assert_ne!(run[0] ^ 3, run[1]);
        assert_eq!(pinned, [0xced1_1e4b, 0x66d3_6f99, 0x8403_c0ec]);
    }
}
