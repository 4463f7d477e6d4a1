//! Reducing a 32-bit hash to a slot index: modulo for any capacity, a mask for powers of two.

/// Maps a 32-bit bucket hash to a slot in `0..capacity`, for any capacity ≥ 1, as `h mod B`
/// (MCPG sec. 4: `hash(x) mod B`).
///
/// - **Any capacity (e.g. a prime):** `h mod B`. Every bit of the hash matters, so a prime `B`
///   rescues a weak hash such as [`hash_xor_primes`](crate::hash_xor_primes). (merian-quake's
///   sizes 32 777 259 = 3 · 10 925 753 and 800 009 = 7 · 23 · 4969 are odd but not prime; odd
///   already keeps the high bits in play, a prime keeps every residue class.) On the CPU the division is replaced by Lemire's
///   exact `fastmod` (Lemire, Kaser, Kurz 2019, "Faster remainder by direct computation"):
///   a precomputed 64-bit magic `M = ⌊(2⁶⁴ − 1)/B⌋ + 1` and `((M·h mod 2⁶⁴)·B) >> 64`, which
///   equals `h % B` for every 32-bit `h` and `B`. The GPU computes `h % B` (WGSL has no 64-bit
///   integers); the results are the same.
/// - **Power-of-two capacity:** `h & (B − 1)`, which is what `h % B` is then; it only reads the
///   low bits of the hash, so it needs a hash whose low bits are good ([`BucketHash::Mix`]).
///
/// [`BucketHash::Mix`]: crate::BucketHash::Mix
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SlotIndexer {
    capacity: u32,
    /// `capacity − 1` when the capacity is a power of two, else 0 (and `magic` is used).
    mask: u32,
    magic: u64,
}

impl SlotIndexer {
    /// An indexer for `capacity` slots; `None` when `capacity` is 0.
    #[must_use]
    pub const fn new(capacity: u32) -> Option<Self> {
        if capacity == 0 {
            return None;
        }
        let is_power_of_two = capacity.is_power_of_two();
        Some(Self {
            capacity,
            mask: if is_power_of_two { capacity - 1 } else { 0 },
            magic: if is_power_of_two {
                0
            } else {
                u64::MAX / capacity as u64 + 1
            },
        })
    }

    /// The number of slots.
    #[inline]
    #[must_use]
    pub const fn capacity(&self) -> u32 {
        self.capacity
    }

    /// `true` when the capacity is a power of two and [`index`](Self::index) is a mask.
    #[inline]
    #[must_use]
    pub const fn is_mask(&self) -> bool {
        self.magic == 0
    }

    /// `h mod capacity`.
    #[inline]
    #[must_use]
    pub const fn index(&self, h: u32) -> u32 {
        if self.magic == 0 {
            h & self.mask
        } else {
            self.modulo(h)
        }
    }

    /// `h mod capacity` by the fast modulo alone, for a capacity that is not a power of two
    /// (the table's batch loop calls it after checking [`is_mask`](Self::is_mask) once).
    #[inline]
    #[must_use]
    pub(crate) const fn modulo(&self, h: u32) -> u32 {
        let low = self.magic.wrapping_mul(h as u64);
        ((low as u128 * self.capacity as u128) >> 64) as u32
    }

    /// The slot after `slot`, wrapping from the last slot to slot 0 (linear probing). A `slot`
    /// outside `0..capacity` also gives slot 0.
    #[inline]
    #[must_use]
    pub const fn next(&self, slot: u32) -> u32 {
        // `capacity ≥ 1`; comparing before adding cannot overflow, even for u32::MAX.
        if slot >= self.capacity - 1 {
            0
        } else {
            slot + 1
        }
    }
}

/// The smallest prime ≥ `n` (by trial division; fine for table sizes up to 2³²), or `None`
/// when there is none below 2³². Handy for choosing a prime capacity like MCPG's.
#[must_use]
pub fn next_prime(n: u32) -> Option<u32> {
    let mut c = n.max(2);
    loop {
        if is_prime(c) {
            return Some(c);
        }
        c = c.checked_add(1)?;
    }
}

fn is_prime(n: u32) -> bool {
    if n < 4 {
        return n >= 2;
    }
    if n.is_multiple_of(2) {
        return false;
    }
    let n = u64::from(n);
    let mut d = 3_u64;
    while d * d <= n {
        if n.is_multiple_of(d) {
            return false;
        }
        d += 2;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_is_exactly_modulo() {
        let hashes = [
            0_u32,
            1,
            2,
            12345,
            0x7FFF_FFFF,
            0x8000_0000,
            u32::MAX - 1,
            u32::MAX,
        ];
        for cap in [
            1_u32,
            2,
            3,
            7,
            1000,
            1024,
            800_009,
            1 << 20,
            32_777_259,
            u32::MAX,
        ] {
            let ix = SlotIndexer::new(cap).unwrap();
            assert_eq!(ix.is_mask(), cap.is_power_of_two());
            for &h in &hashes {
                assert_eq!(ix.index(h), h % cap, "h = {h}, cap = {cap}");
            }
            let mut h = 0x1234_5678_u32;
            for _ in 0..10_000 {
                h = h.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
                assert_eq!(ix.index(h), h % cap);
            }
        }
        assert_eq!(SlotIndexer::new(0), None);
    }

    #[test]
    fn next_wraps_at_the_last_slot() {
        let ix = SlotIndexer::new(5).unwrap();
        assert_eq!(ix.next(3), 4);
        assert_eq!(ix.next(4), 0);
        assert_eq!(SlotIndexer::new(1).unwrap().next(0), 0);
        // Issue 14: `next(u32::MAX)` overflowed (debug panic); out-of-range slots give 0.
        assert_eq!(SlotIndexer::new(1).unwrap().next(u32::MAX), 0);
        assert_eq!(ix.next(5), 0);
        assert_eq!(ix.next(u32::MAX), 0);
        assert_eq!(SlotIndexer::new(u32::MAX).unwrap().next(u32::MAX - 1), 0);
        assert_eq!(SlotIndexer::new(u32::MAX).unwrap().next(u32::MAX), 0);
    }

    #[test]
    fn primes() {
        assert_eq!(next_prime(0), Some(2));
        assert_eq!(next_prime(1_000_000), Some(1_000_003));
        assert_eq!(next_prime(800_000), Some(800_011));
        assert!(!is_prime(800_009) && !is_prime(32_777_259) && is_prime(10_925_753));
        assert_eq!(next_prime(u32::MAX), None);
        assert_eq!(next_prime(4_294_967_291), Some(4_294_967_291));
    }
}
