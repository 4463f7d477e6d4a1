//! Bounded linear probing, written once for the plain and the concurrent table (and mirrored
//! by the WGSL twin in the GPU backend).

use crate::capacity::SlotIndexer;
use crate::constants::{EMPTY, TOMBSTONE};
use crate::hash::{BucketHash, fold_and_checksum, mix_and_checksum};
use crate::key::CellKey;

/// What [`insert_or_get`](crate::HashTable::insert_or_get) did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Insert {
    /// The key was already in the table, in this slot.
    Found(u32),
    /// The key was not in the table and now owns this slot (its value is fresh).
    Inserted(u32),
    /// The key is not in the table and none of the `max_probes` slots from its home slot was
    /// free: the table is full there. Nothing was changed.
    Full,
}

impl Insert {
    /// The slot of the key, or `None` when the table was full.
    #[inline]
    #[must_use]
    pub const fn slot(self) -> Option<u32> {
        match self {
            Insert::Found(s) | Insert::Inserted(s) => Some(s),
            Insert::Full => None,
        }
    }

    /// `true` for [`Insert::Inserted`].
    #[inline]
    #[must_use]
    pub const fn is_inserted(self) -> bool {
        matches!(self, Insert::Inserted(_))
    }
}

/// Access to the checksum words of a table.
pub(crate) trait Slots {
    /// The checksum word of `slot`.
    fn load(&mut self, slot: u32) -> u32;
    /// Replaces `current` (EMPTY or TOMBSTONE) by `checksum` in `slot`; on failure returns the
    /// word found there instead.
    fn claim(&mut self, slot: u32, current: u32, checksum: u32) -> Result<(), u32>;
}

/// Looks for `checksum` in at most `max_probes` slots of `words` from `home` (wrapping),
/// stopping at the first empty slot; tombstones are walked past. `load` reads one word.
///
/// When the probe window `home..home + max_probes` ends before the last slot (all home slots
/// but the last `max_probes − 1`), it is taken as one sub-slice: one bounds check instead of
/// one per probe, and no wrap test per step, without `unsafe`. Otherwise the walk wraps from
/// the last slot to slot 0. (Comparing a group of four slots at once into bit masks, to avoid
/// the loop branch, measured slower here: ≈ 2× on cache-resident lookups.)
#[inline]
pub(crate) fn find<E>(
    words: &[E],
    load: impl Fn(&E) -> u32,
    indexer: &SlotIndexer,
    max_probes: u32,
    home: u32,
    checksum: u32,
) -> Option<u32> {
    let start = home as usize;
    if let Some(window) = words.get(start..start + max_probes as usize) {
        for (i, w) in window.iter().enumerate() {
            let v = load(w);
            if v == checksum {
                return Some(home + i as u32);
            }
            if v == EMPTY {
                return None;
            }
        }
        return None;
    }
    let mut slot = home;
    for _ in 0..max_probes {
        let v = load(words.get(slot as usize)?);
        if v == checksum {
            return Some(slot);
        }
        if v == EMPTY {
            return None;
        }
        slot = indexer.next(slot);
    }
    None
}

/// [`find`] for a batch of keys on the concurrent table: `emit(first, slots)` receives,
/// batch after batch, the slots of `keys[first..first + slots.len()]` in `words` (read by
/// `load`). `walk(home, checksum)` decides a key whose home slot holds another key. (The
/// plain table pipelines its batches instead, [`find_chunked`], with prefetches.)
///
/// Per step of `BATCH` keys: (1) every key hashed (pure arithmetic); (2) the home word of
/// every key read (independent loads with no branch on their values, so their cache misses
/// overlap); (3) each key decided from its home word, walking on only where needed; (4) the
/// batch's slots handed to `emit`. The loop is compiled once per hash and kind of capacity,
/// so that it branches on neither per key; with a power-of-two capacity the words are cut to
/// `..=mask`.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // a table's fields, passed apart so that both tables share it
pub(crate) fn find_many<E, const BATCH: usize>(
    words: &[E],
    load: impl Fn(&E) -> u32,
    hash: BucketHash,
    indexer: &SlotIndexer,
    keys: &[CellKey],
    walk: impl Fn(u32, u32) -> Option<u32>,
    emit: impl FnMut(usize, &[Option<u32>]),
) {
    let ix = *indexer;
    let (load, walk) = (&load, &walk);
    // One monomorphic copy of the loop per arm (the hash and index closures are its type
    // parameters).
    macro_rules! batch {
        ($words:expr, $hash_and_checksum:expr, $index:expr) => {
            find_many_with::<E, BATCH>($words, load, walk, keys, $hash_and_checksum, $index, emit)
        };
    }
    match (hash, ix.is_mask()) {
        (BucketHash::Fold, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            batch!(cut, fold_and_checksum, |h| h & mask)
        }
        (BucketHash::Fold, false) => batch!(words, fold_and_checksum, |h| ix.modulo(h)),
        (BucketHash::Mix, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            batch!(cut, mix_and_checksum, |h| h & mask)
        }
        (BucketHash::Mix, false) => batch!(words, mix_and_checksum, |h| ix.modulo(h)),
        (hash, _) => batch!(words, |k: &CellKey| hash.hash_and_checksum(k), |h| ix
            .index(h)),
    }
}

/// The loop of [`find_many`] with the hash (`(bucket hash, checksum)`) and the slot index of
/// a bucket hash given.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // as `find_many`, plus the hash and the index
fn find_many_with<E, const BATCH: usize>(
    words: &[E],
    load: impl Fn(&E) -> u32,
    walk: impl Fn(u32, u32) -> Option<u32>,
    keys: &[CellKey],
    hash_and_checksum: impl Fn(&CellKey) -> (u32, u32),
    index: impl Fn(u32) -> u32,
    mut emit: impl FnMut(usize, &[Option<u32>]),
) {
    let mut homes = [(0_u32, 0_u32); BATCH];
    let mut first = [0_u32; BATCH];
    let mut slots = [None; BATCH];
    for (b, keys) in keys.chunks(BATCH).enumerate() {
        for (hc, key) in homes.iter_mut().zip(keys) {
            let (h, c) = hash_and_checksum(key);
            *hc = (index(h), c);
        }
        for (f, &(home, _)) in first.iter_mut().zip(&homes[..keys.len()]) {
            *f = words.get(home as usize).map_or(EMPTY, &load);
        }
        let n = keys.len();
        for ((o, &(home, c)), &f) in slots[..n].iter_mut().zip(&homes).zip(&first) {
            *o = if f == c {
                Some(home)
            } else if f == EMPTY {
                None
            } else {
                walk(home, c)
            };
        }
        emit(b * BATCH, &slots[..n]);
    }
}

/// Keys per step of [`find_chunked`] (a power of two): each step hashes (and prefetches the
/// lines of) the next `CHUNK` keys, then decides the current `CHUNK` (8 measured slower, 32
/// no faster).
pub(crate) const CHUNK: usize = 16;

/// Where [`find_chunked`] hands the decided keys, a chunk at a time: `decide(home, checksum)`
/// gives the slot of one key of the chunk (its home slot and checksum in `homes` and
/// `checks`), and the keys are `keys[first..first + homes.len()]`. A trait rather than a
/// closure, so that `decide` (one type per hash and kind of capacity) is a generic parameter
/// and inlined.
pub(crate) trait ChunkSink {
    /// Decides and hands on the keys of one chunk.
    fn chunk(
        &mut self,
        first: usize,
        homes: &[u32],
        checks: &[u32],
        decide: &impl Fn(u32, u32) -> Option<u32>,
    );
}

/// The home slots and checksums of a chunk of keys.
type Hashed = ([u32; CHUNK], [u32; CHUNK]);

/// [`find`] for a stream of keys on a plain table, software-pipelined by chunks of [`CHUNK`]
/// keys: chunk `k + 1` is hashed, and the cache lines of its keys' home checksum words and
/// (through `prefetch(home)`) values are prefetched, before chunk `k` is decided from the L1
/// cache by `sink`. Compiled once per hash and kind of capacity like [`find_many`].
#[inline(always)]
#[allow(clippy::too_many_arguments)] // a table's fields, passed apart like `find_many`'s
pub(crate) fn find_chunked(
    words: &[u32],
    hash: BucketHash,
    indexer: &SlotIndexer,
    max_probes: u32,
    keys: &[CellKey],
    prefetch: impl Fn(u32),
    sink: &mut impl ChunkSink,
) {
    let ix = *indexer;
    let prefetch = &prefetch;
    macro_rules! chunked {
        ($words:expr, $hash_and_checksum:expr, $index:expr, $in_bounds:expr) => {
            find_chunked_with(
                $words,
                &ix,
                max_probes,
                keys,
                $hash_and_checksum,
                $index,
                $in_bounds,
                prefetch,
                sink,
            )
        };
    }
    match (hash, ix.is_mask()) {
        (BucketHash::Fold, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            chunked!(cut, Fold, move |h| h & mask, move |s| s & mask)
        }
        (BucketHash::Fold, false) => chunked!(words, Fold, move |h| ix.modulo(h), |s| s),
        (BucketHash::Mix, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            chunked!(cut, PerKey(mix_and_checksum), move |h| h & mask, move |s| s
                & mask)
        }
        (BucketHash::Mix, false) => {
            chunked!(
                words,
                PerKey(mix_and_checksum),
                move |h| ix.modulo(h),
                |s| s
            )
        }
        (hash, _) => chunked!(
            words,
            PerKey(|k: &CellKey| hash.hash_and_checksum(k)),
            |h| ix.index(h),
            |s| s
        ),
    }
}

/// The loop of [`find_chunked`] with the hash and the slot index given.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // as `find_chunked`, plus the hash, the index and its re-mask
fn find_chunked_with(
    words: &[u32],
    indexer: &SlotIndexer,
    max_probes: u32,
    keys: &[CellKey],
    hash: impl LaneHash,
    index: impl Fn(u32) -> u32,
    in_bounds: impl Fn(u32) -> u32,
    prefetch_value: impl Fn(u32),
    sink: &mut impl ChunkSink,
) {
    let start = |hashed: &mut Hashed, keys: &[CellKey]| {
        hash_chunk(hashed, keys, &hash, &index);
        let prefetch_one = |home: u32| {
            prefetch(words.as_ptr().wrapping_add(home as usize));
            prefetch_value(home);
        };
        if keys.len() == CHUNK {
            hashed.0.iter().copied().for_each(prefetch_one);
        } else {
            hashed.0[..keys.len()]
                .iter()
                .copied()
                .for_each(prefetch_one);
        }
    };
    let decide = |home: u32, c: u32| {
        // A no-op on a home slot (an `& mask` again, or nothing), which shows the compiler
        // that the home slot from the stack is in bounds of the words cut to the capacity.
        let home = in_bounds(home);
        // The next slot: `(home + 1) & mask`, or `home + 1` (past the last slot with a modulo
        // capacity, where `words.get` answers `None` and `past_home` wraps).
        let next = in_bounds(home + 1);
        match words.get(home as usize) {
            Some(&w) if w == c => Some(home),
            // Most keys not in their home slot are in the next one.
            Some(&w) if w != EMPTY && max_probes > 1 && words.get(next as usize) == Some(&c) => {
                Some(next)
            }
            _ => past_home(words, indexer, max_probes, home, c),
        }
    };
    let (mut a, mut b): (Hashed, Hashed) = Default::default();
    let (mut current, mut next) = (&mut a, &mut b);
    let mut chunks = keys.chunks(CHUNK);
    let Some(first) = chunks.next() else {
        return;
    };
    start(current, first);
    let mut n = first.len();
    let mut at = 0;
    for chunk in chunks {
        start(next, chunk);
        sink.chunk(at, &current.0[..n], &current.1[..n], &decide);
        core::mem::swap(&mut current, &mut next);
        at += n;
        n = chunk.len();
    }
    sink.chunk(at, &current.0[..n], &current.1[..n], &decide);
}

/// [`find_plain`] for a key that is not in its home slot (an empty home slot answers `None`):
/// out of line, so that the chunked loop's home-slot hit (≈ 88 % of hits at load 1/4) is
/// straight-line code.
#[inline(never)]
fn past_home(
    words: &[u32],
    indexer: &SlotIndexer,
    max_probes: u32,
    home: u32,
    checksum: u32,
) -> Option<u32> {
    match words.get(home as usize) {
        Some(&EMPTY) => None,
        _ => find_plain(words, indexer, max_probes, home, checksum),
    }
}

/// The bucket hash and checksum of keys, one at a time or four at once: what
/// [`find_chunked`] hashes a chunk with.
pub(crate) trait LaneHash {
    /// `(bucket hash, checksum)` of one key.
    fn one(&self, key: &CellKey) -> (u32, u32);
    /// `(bucket hashes, checksums)` of four keys.
    #[inline(always)]
    fn four(&self, keys: &[CellKey; 4]) -> ([u32; 4], [u32; 4]) {
        let mut out = ([0; 4], [0; 4]);
        for (i, key) in keys.iter().enumerate() {
            (out.0[i], out.1[i]) = self.one(key);
        }
        out
    }
    /// The home slots (`index` of the bucket hashes) and checksums of a full chunk: four keys
    /// at a time.
    #[inline(always)]
    fn chunk(&self, keys: &[CellKey; CHUNK], index: &impl Fn(u32) -> u32, hashed: &mut Hashed) {
        by_fours(self, keys, index, hashed);
    }
}

/// [`LaneHash::chunk`] four keys at a time ([`LaneHash::four`]).
#[inline(always)]
fn by_fours(
    hash: &(impl LaneHash + ?Sized),
    keys: &[CellKey; CHUNK],
    index: &impl Fn(u32) -> u32,
    (homes, checks): &mut Hashed,
) {
    let groups = keys.as_chunks::<4>().0;
    let (hs, cs) = (homes.as_chunks_mut::<4>().0, checks.as_chunks_mut::<4>().0);
    for ((h, c), group) in hs.iter_mut().zip(cs.iter_mut()).zip(groups) {
        let (h4, c4) = hash.four(group);
        *h = h4.map(index);
        *c = c4;
    }
}

/// Any `(bucket hash, checksum)` function, four keys as four single ones.
pub(crate) struct PerKey<F>(pub(crate) F);

impl<F: Fn(&CellKey) -> (u32, u32)> LaneHash for PerKey<F> {
    #[inline(always)]
    fn one(&self, key: &CellKey) -> (u32, u32) {
        (self.0)(key)
    }
}

/// [`fold_and_checksum`], four keys at once with SSE2 where the target has it (baseline
/// x86-64: [`fold4_sse2`]); a full chunk eight keys at once where the CPU has AVX2 (detected
/// at run time, with the `std` feature: [`fold16_avx2`]).
pub(crate) struct Fold;

impl LaneHash for Fold {
    #[inline(always)]
    fn one(&self, key: &CellKey) -> (u32, u32) {
        fold_and_checksum(key)
    }
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    #[inline(always)]
    fn four(&self, keys: &[CellKey; 4]) -> ([u32; 4], [u32; 4]) {
        fold4_sse2(keys)
    }
    /// Eight keys at a time with AVX2 where the CPU has it (detected at run time, with `std`),
    /// otherwise four at a time.
    #[inline(always)]
    #[allow(unsafe_code)]
    fn chunk(&self, keys: &[CellKey; CHUNK], index: &impl Fn(u32) -> u32, hashed: &mut Hashed) {
        #[cfg(all(target_arch = "x86_64", feature = "std"))]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: `fold16_avx2` is safe code that needs AVX2, which the CPU running this
            // has (detected just above); it takes no pointers.
            unsafe { fold16_avx2(keys, index, hashed) };
            return;
        }
        by_fours(self, keys, index, hashed);
    }
}

/// [`fold_and_checksum`] of a chunk, eight keys at once in the lanes of AVX2 registers: as
/// [`fold4_sse2`] with each 32-bit multiply one `vpmulld`. Keys `i` and `i + 4` of a group of
/// eight share a register (one per 128-bit half), so that the in-half transposition leaves the
/// lanes in key order.
#[cfg(all(target_arch = "x86_64", feature = "std"))]
#[target_feature(enable = "avx2")]
fn fold16_avx2(keys: &[CellKey; CHUNK], index: &impl Fn(u32) -> u32, (homes, checks): &mut Hashed) {
    use crate::constants::{FIRST_CHECKSUM, FOLD_FINISH, FOLD_X, FOLD_Y, FOLD_Z};
    use core::arch::x86_64::{
        __m128i, __m256i, _mm256_add_epi32, _mm256_and_si256, _mm256_cmpeq_epi32,
        _mm256_mullo_epi32, _mm256_or_si256, _mm256_set_m128i, _mm256_set1_epi32,
        _mm256_setzero_si256, _mm256_slli_epi32, _mm256_srli_epi32, _mm256_unpackhi_epi32,
        _mm256_unpackhi_epi64, _mm256_unpacklo_epi32, _mm256_unpacklo_epi64, _mm256_xor_si256,
    };
    const _: () = assert!(crate::constants::FOLD_META_ROTATE == 16 && FIRST_CHECKSUM == 2);
    let k: [__m128i; CHUNK] = bytemuck::cast(*keys);
    let mul = |v: __m256i, c: u32| _mm256_mullo_epi32(v, _mm256_set1_epi32(c as i32));
    let groups = k.as_chunks::<8>().0;
    let (hs, cs) = (homes.as_chunks_mut::<8>().0, checks.as_chunks_mut::<8>().0);
    for ((hs, cs), g) in hs.iter_mut().zip(cs.iter_mut()).zip(groups) {
        let r = |i: usize| _mm256_set_m128i(g[i + 4], g[i]);
        let (k0, k1, k2, k3) = (r(0), r(1), r(2), r(3));
        let t0 = _mm256_unpacklo_epi32(k0, k1); // x0 x1 y0 y1 | x4 x5 y4 y5
        let t1 = _mm256_unpacklo_epi32(k2, k3); // x2 x3 y2 y3 | x6 x7 y6 y7
        let t2 = _mm256_unpackhi_epi32(k0, k1); // z0 z1 m0 m1 | z4 z5 m4 m5
        let t3 = _mm256_unpackhi_epi32(k2, k3); // z2 z3 m2 m3 | z6 z7 m6 m7
        let (x, y) = (_mm256_unpacklo_epi64(t0, t1), _mm256_unpackhi_epi64(t0, t1));
        let (z, m) = (_mm256_unpacklo_epi64(t2, t3), _mm256_unpackhi_epi64(t2, t3));
        let rot = _mm256_or_si256(_mm256_slli_epi32::<16>(m), _mm256_srli_epi32::<16>(m));
        let a = _mm256_add_epi32(mul(x, FOLD_X), mul(y, FOLD_Y));
        let b = _mm256_add_epi32(mul(z, FOLD_Z), rot);
        let t = _mm256_xor_si256(a, b);
        let t = mul(_mm256_xor_si256(t, _mm256_srli_epi32::<16>(t)), FOLD_FINISH);
        let h = _mm256_xor_si256(t, _mm256_srli_epi32::<15>(t));
        let c = _mm256_add_epi32(b, h);
        let low = _mm256_cmpeq_epi32(_mm256_srli_epi32::<1>(c), _mm256_setzero_si256());
        let c = _mm256_or_si256(
            c,
            _mm256_and_si256(low, _mm256_set1_epi32(FIRST_CHECKSUM as i32)),
        );
        let h: [u32; 8] = bytemuck::cast(h);
        *hs = h.map(index);
        *cs = bytemuck::cast(c);
    }
}

/// [`fold_and_checksum`] of four keys in the four lanes of SSE2 registers: the keys' words
/// transposed by 8 unpacks (a key's 16 bytes are its [`words`](CellKey::words) on this
/// little-endian target), each 32-bit multiply as two `pmuludq` and three shuffles (SSE2 has
/// no 32-bit lane multiply), the rotation of the meta word as two shifts and an or. ≈ 17
/// instructions per key, where LLVM's own vectorisation of the scalar hash took ≈ 20 (it
/// gathers the words one `movd` at a time) and the scalar hash 20.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
#[allow(unsafe_code)]
fn fold4_sse2(keys: &[CellKey; 4]) -> ([u32; 4], [u32; 4]) {
    use crate::constants::{FIRST_CHECKSUM, FOLD_FINISH, FOLD_X, FOLD_Y, FOLD_Z};
    use core::arch::x86_64::{
        __m128i, _mm_add_epi32, _mm_and_si128, _mm_cmpeq_epi32, _mm_mul_epu32, _mm_or_si128,
        _mm_set1_epi32, _mm_setzero_si128, _mm_shuffle_epi32, _mm_slli_epi32, _mm_srli_epi32,
        _mm_srli_epi64, _mm_unpackhi_epi32, _mm_unpackhi_epi64, _mm_unpacklo_epi32,
        _mm_unpacklo_epi64, _mm_xor_si128,
    };
    const _: () = assert!(crate::constants::FOLD_META_ROTATE == 16 && FIRST_CHECKSUM == 2);
    let [k0, k1, k2, k3]: [__m128i; 4] = bytemuck::cast(*keys);
    // SAFETY: these intrinsics only need SSE2, which this build enables (the `cfg` above; part
    // of the x86-64 baseline). They take no pointers: values in registers only.
    let (h, c) = unsafe {
        // Lane-wise wrapping product by a constant: the even lanes' 64-bit products and the
        // odd lanes', their low words put back in place.
        let mul = |v: __m128i, k: u32| {
            let k = _mm_set1_epi32(k as i32);
            let even = _mm_mul_epu32(v, k);
            let odd = _mm_mul_epu32(_mm_srli_epi64::<32>(v), k);
            _mm_unpacklo_epi32(
                _mm_shuffle_epi32::<0b10_00_10_00>(even),
                _mm_shuffle_epi32::<0b10_00_10_00>(odd),
            )
        };
        let t0 = _mm_unpacklo_epi32(k0, k1); // x0 x1 y0 y1
        let t1 = _mm_unpacklo_epi32(k2, k3); // x2 x3 y2 y3
        let t2 = _mm_unpackhi_epi32(k0, k1); // z0 z1 m0 m1
        let t3 = _mm_unpackhi_epi32(k2, k3); // z2 z3 m2 m3
        let (x, y) = (_mm_unpacklo_epi64(t0, t1), _mm_unpackhi_epi64(t0, t1));
        let (z, m) = (_mm_unpacklo_epi64(t2, t3), _mm_unpackhi_epi64(t2, t3));
        // rotl(m, 16): the two 16-bit halves of every lane swapped.
        let rot = _mm_or_si128(_mm_slli_epi32::<16>(m), _mm_srli_epi32::<16>(m));
        let a = _mm_add_epi32(mul(x, FOLD_X), mul(y, FOLD_Y));
        let b = _mm_add_epi32(mul(z, FOLD_Z), rot);
        let t = _mm_xor_si128(a, b);
        let t = mul(_mm_xor_si128(t, _mm_srli_epi32::<16>(t)), FOLD_FINISH);
        let h = _mm_xor_si128(t, _mm_srli_epi32::<15>(t));
        // The checksum `b + h`, or'ed with 2 where it is 0 or 1 (`reserve`).
        let c = _mm_add_epi32(b, h);
        let low = _mm_cmpeq_epi32(_mm_srli_epi32::<1>(c), _mm_setzero_si128());
        let c = _mm_or_si128(c, _mm_and_si128(low, _mm_set1_epi32(FIRST_CHECKSUM as i32)));
        (h, c)
    };
    (bytemuck::cast(h), bytemuck::cast(c))
}

/// The home slots and checksums of a chunk of keys (up to [`CHUNK`]): a full chunk four keys
/// at a time ([`LaneHash::four`]), a partial one key by key.
#[inline(always)]
fn hash_chunk(
    hashed: &mut Hashed,
    keys: &[CellKey],
    hash: &impl LaneHash,
    index: &impl Fn(u32) -> u32,
) {
    if let Ok(full) = <&[CellKey; CHUNK]>::try_from(keys) {
        hash.chunk(full, index, hashed);
    } else {
        let (homes, checks) = hashed;
        for ((h, c), key) in homes.iter_mut().zip(checks.iter_mut()).zip(keys) {
            let (hash, checksum) = hash.one(key);
            (*h, *c) = (index(hash), checksum);
        }
    }
}

/// Starts loading the cache line at `address` into every cache level (`prefetcht0`), without
/// waiting for it and without a load that the CPU must retire: a hint, which reads nothing,
/// never faults (any address, even one outside the program's memory, is allowed) and changes
/// no result. A no-op where SSE is not enabled (not x86-64).
#[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
#[inline(always)]
#[allow(unsafe_code)]
pub(crate) fn prefetch<T>(address: *const T) {
    use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
    // SAFETY: `_mm_prefetch` only needs SSE, which this build enables (the `cfg` above; part
    // of the x86-64 baseline). A prefetch is a hint: it does not access memory
    // architecturally and never faults, whatever the address.
    unsafe { _mm_prefetch::<_MM_HINT_T0>(address.cast::<i8>()) }
}

/// Starts loading the cache line at `address`: a no-op on this target.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
#[inline(always)]
pub(crate) fn prefetch<T>(address: *const T) {
    let _ = address;
}

/// Asks the CPU to start loading the cache line that holds `value`, so that a later read of
/// it waits less: `_mm_prefetch` on x86-64 (a hint that reads nothing architecturally and
/// changes no result), nothing on other targets. For values a caller indexes by the slots of
/// a table ([`ConcurrentTable::locate`](crate::ConcurrentTable::locate) does the same for the
/// table's own words).
#[inline(always)]
pub fn prefetch_line<T>(value: &T) {
    prefetch(core::ptr::from_ref(value));
}

/// Slots compared at once by [`group`].
pub(crate) const GROUP: u32 = 4;

/// The [`GROUP`] words from `home` compared at once, as bit masks (bit i: slot `home + i`):
/// `(equal to checksum, EMPTY)`. `None` when the group would run past the last slot (then the
/// caller walks slot by slot, wrapping).
///
/// Branch-free: a key that sits a few slots past its home slot costs no misprediction (a walk
/// slot by slot mispredicts its loop exit on the ≈ α/2 of keys not in their home slot, and
/// each misprediction discards the work the CPU had started on the following lookups). Only
/// [`HashTable::find_many`](crate::HashTable::find_many) uses it: in a per-key `get` the
/// value's address would then wait for the checksum words, where a predicted walk lets the
/// CPU load the value at once (measured: `get` 9.9 → 14 ns on a 19 MB table).
#[inline(always)]
pub(crate) fn group(words: &[u32], home: u32, checksum: u32) -> Option<(u32, u32)> {
    let start = home as usize;
    let w: &[u32; GROUP as usize] = words.get(start..start + GROUP as usize)?.try_into().ok()?;
    Some(group_masks(*w, checksum))
}

/// The two masks of [`group`] with SSE2 (baseline x86-64): one unaligned 16-byte load, two
/// `pcmpeqd` + `movmskps` (LLVM turns the portable loop below into ≈ 25 scalar instructions).
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
#[inline(always)]
#[allow(unsafe_code)]
fn group_masks(w: [u32; 4], checksum: u32) -> (u32, u32) {
    use core::arch::x86_64::{
        __m128i, _mm_castsi128_ps, _mm_cmpeq_epi32, _mm_movemask_ps, _mm_set1_epi32,
    };
    let v: __m128i = bytemuck::cast(w);
    let mask = |x: u32| {
        // SAFETY: these intrinsics only need SSE and SSE2, which this build enables (the
        // `cfg` above; both are part of the x86-64 baseline). They take no pointers.
        unsafe {
            _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(
                v,
                _mm_set1_epi32(x as i32),
            ))) as u32
        }
    };
    (mask(checksum), mask(EMPTY))
}

/// The two masks of [`group`], portable.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
#[inline(always)]
fn group_masks(w: [u32; 4], checksum: u32) -> (u32, u32) {
    let (mut hit, mut empty) = (0, 0);
    for (i, &v) in w.iter().enumerate() {
        hit |= u32::from(v == checksum) << i;
        empty |= u32::from(v == EMPTY) << i;
    }
    (hit, empty)
}

/// [`find`] on plain words, deciding from one [`group`] first: the first slot holding the
/// checksum or empty ends the search, whichever comes first. Only when neither is among the
/// first [`GROUP`] slots (or the group would wrap, or `max_probes` < [`GROUP`]: the group
/// would read past the probe limit) does it walk on slot by slot.
#[inline(always)]
pub(crate) fn find_plain(
    words: &[u32],
    indexer: &SlotIndexer,
    max_probes: u32,
    home: u32,
    checksum: u32,
) -> Option<u32> {
    if max_probes >= GROUP
        && let Some((hit, empty)) = group(words, home, checksum)
    {
        let stop = hit | empty;
        if stop != 0 {
            let i = stop.trailing_zeros();
            return ((hit >> i) & 1 != 0).then_some(home + i);
        }
        if max_probes <= GROUP {
            return None;
        }
    }
    find(words, |&w| w, indexer, max_probes, home, checksum)
}

/// Insert-or-get with bounded linear probing, safe under concurrent inserts.
///
/// One walk from `home`: until the checksum (found), an empty slot or the probe limit,
/// remembering the first free slot (empty or tombstone) and the word read there. Then claim
/// that slot by compare-and-swap against the word read, without reading it again; a failed
/// CAS gives the word another thread put there: this checksum means found, another one means
/// move on to the next slot and try again (reading it).
///
/// Every thread inserting the same key tries the same first free slot, and slots only go from
/// free to taken while inserts run (evictions need exclusive access), so the key ends in
/// exactly one slot. Never loops more than `max_probes` slots (plus one retry per lost CAS).
/// (The first version walked to the first free slot and then read it again in a second loop:
/// with the plain table, ≈ 15 % more time per insert.)
#[inline]
pub(crate) fn insert_or_get<S: Slots>(
    slots: &mut S,
    indexer: &SlotIndexer,
    max_probes: u32,
    home: u32,
    checksum: u32,
) -> Insert {
    let mut slot = home;
    let mut first_free = None;
    for i in 0..max_probes {
        let v = slots.load(slot);
        if v == checksum {
            return Insert::Found(slot);
        }
        if v == EMPTY || v == TOMBSTONE {
            if first_free.is_none() {
                first_free = Some((i, slot, v));
            }
            if v == EMPTY {
                break;
            }
        }
        slot = indexer.next(slot);
    }
    let Some((mut i, mut slot, mut v)) = first_free else {
        return Insert::Full;
    };
    loop {
        if v == checksum {
            return Insert::Found(slot);
        }
        if v == EMPTY || v == TOMBSTONE {
            match slots.claim(slot, v, checksum) {
                Ok(()) => return Insert::Inserted(slot),
                // Another thread took the slot: look at what it wrote.
                Err(actual) => {
                    v = actual;
                    continue;
                }
            }
        }
        i += 1;
        if i >= max_probes {
            return Insert::Full;
        }
        slot = indexer.next(slot);
        v = slots.load(slot);
    }
}

#[cfg(test)]
mod tests {
    use glam::IVec3;
    use std::vec::Vec;

    use super::*;
    use crate::constants::{FOLD_FINISH, FOLD_X, FOLD_Z};

    /// The multiplicative inverse of an odd `k` mod 2³² (Newton's iteration).
    fn inverse(k: u32) -> u32 {
        let mut x = k; // correct to 3 bits for odd k
        for _ in 0..5 {
            x = x.wrapping_mul(2_u32.wrapping_sub(k.wrapping_mul(x)));
        }
        assert_eq!(k.wrapping_mul(x), 1);
        x
    }

    /// A key whose raw checksum `b + hash_fold` is `raw` (before the remap off 0 and 1): with
    /// `y = 0`, `z` and the meta word given, `x` follows from inverting the finisher and the
    /// first fold.
    fn key_with_raw_checksum(raw: u32, z: i32, level: u8) -> CellKey {
        let base = CellKey::new(IVec3::new(0, 0, z), level, 3);
        let meta = base.meta();
        let b = (z as u32)
            .wrapping_mul(FOLD_Z)
            .wrapping_add(meta.rotate_left(16));
        let h = raw.wrapping_sub(b);
        // Undo `t ^= t >> 15`, `t *= FOLD_FINISH`, `t ^= t >> 16`.
        let t = h ^ (h >> 15) ^ (h >> 30);
        let t = t.wrapping_mul(inverse(FOLD_FINISH));
        let t = t ^ (t >> 16);
        let x = (t ^ b).wrapping_mul(inverse(FOLD_X));
        CellKey::new(IVec3::new(x as i32, 0, z), level, 3)
    }

    #[cfg(feature = "alloc")]
    #[test]
    fn keys_whose_raw_checksum_is_empty_or_tombstone() {
        // `get` compares the raw checksum first: a key whose raw checksum is 0 must not match
        // an empty home slot, one whose raw checksum is 1 not a tombstone there.
        use crate::{BucketHash, HashTable};
        let mut t = HashTable::<u32>::new(64, 8, BucketHash::Fold).unwrap();
        let k0 = key_with_raw_checksum(0, 5, 1);
        let k1 = key_with_raw_checksum(1, -9, 2);
        assert_eq!(t.get(&k0), None);
        assert_eq!(t.get(&k1), None);
        // A tombstone in k1's home slot, k1 in the next one.
        let home = t.home_slot(&k1);
        let other = (0..)
            .map(|i| CellKey::new(IVec3::new(i, 3, 4), 0, 0))
            .find(|k| t.home_slot(k) == home)
            .unwrap();
        *t.entry(&other).unwrap().0 = 7;
        *t.entry(&k1).unwrap().0 = 11;
        assert!(t.remove(&other));
        assert_eq!(t.checksums()[home as usize], crate::constants::TOMBSTONE);
        assert_eq!(t.find(&k1), Some((home + 1) % 64));
        assert_eq!(t.get(&k1), Some(&11));
        assert_eq!(t.get(&k0), None);
        *t.entry(&k0).unwrap().0 = 10;
        assert_eq!(t.get(&k0), Some(&10));
        assert_eq!(t.get(&other), None);
        let keys = [k0, k1, other, k0, k1];
        let mut out = [None; 5];
        t.find_many(&keys, &mut out);
        assert_eq!(out, keys.map(|k| t.find(&k)));
    }

    #[test]
    fn four_keys_at_once_equal_one_at_a_time() {
        // Keys whose raw checksum is 0 or 1 (remapped to 2 and 3) in every lane, among others
        // with negative coordinates and every meta field set.
        let reserved: Vec<CellKey> = (0..8)
            .map(|i| key_with_raw_checksum(i % 2, 17 * i as i32 - 50, i as u8))
            .collect();
        for (i, k) in reserved.iter().enumerate() {
            let raw = fold_and_checksum(k).1;
            assert_eq!(raw, 2 + i as u32 % 2, "{k:?}");
        }
        let others = (0..400).map(|i: i32| {
            CellKey::new(
                IVec3::new(i * 7919 - 1_000_000, -i, i * i),
                i as u8,
                (i % 7) as u8,
            )
            .with_extra((i * 331) as u16)
        });
        let keys: Vec<CellKey> = reserved.iter().copied().chain(others).collect();
        for start in 0..4 {
            for group in keys[start..].as_chunks::<4>().0 {
                let (h, c) = Fold.four(group);
                assert_eq!((h, c), PerKey(fold_and_checksum).four(group));
                for (i, key) in group.iter().enumerate() {
                    assert_eq!((h[i], c[i]), fold_and_checksum(key), "{key:?}");
                    assert_eq!((h[i], c[i]), Fold.one(key));
                }
            }
        }
    }

    #[test]
    fn a_chunk_at_once_equals_one_key_at_a_time() {
        // `Fold::chunk` as dispatched on this CPU (eight keys at once with AVX2 where it has
        // it, four with SSE2 otherwise) against the scalar hash, at every offset, with a mask
        // and a modulo for the slot index; the keys with raw checksums 0 and 1 in every lane.
        let reserved = (0..32).map(|i| key_with_raw_checksum(i % 2, 13 * i as i32 - 200, i as u8));
        let others = (0..2000).map(|i: i32| {
            CellKey::new(
                IVec3::new(i * 104_729 - 7_000_000, 3 - i * 31, i * i - 5000),
                (i % 17) as u8,
                (i % 7) as u8,
            )
            .with_extra((i * 977) as u16)
        });
        let keys: Vec<CellKey> = reserved.chain(others).collect();
        let indices: [&dyn Fn(u32) -> u32; 3] = [&|h| h, &|h| h & 1023, &|h| h % 1_000_003];
        #[cfg(all(target_arch = "x86_64", feature = "std"))]
        std::println!("avx2: {}", std::is_x86_feature_detected!("avx2"));
        for index in indices {
            for start in 0..CHUNK {
                for chunk in keys[start..].as_chunks::<CHUNK>().0 {
                    let mut hashed: Hashed = Default::default();
                    Fold.chunk(chunk, &index, &mut hashed);
                    let mut by_fours_out: Hashed = Default::default();
                    by_fours(&Fold, chunk, &index, &mut by_fours_out);
                    assert_eq!(hashed, by_fours_out);
                    for (i, key) in chunk.iter().enumerate() {
                        let (h, c) = fold_and_checksum(key);
                        assert_eq!((hashed.0[i], hashed.1[i]), (index(h), c), "{key:?}");
                    }
                }
            }
        }
    }
}
