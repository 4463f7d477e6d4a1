//! Bounded linear probing, written once for the plain and the concurrent table (and mirrored
//! by the WGSL twin in the GPU backend).

use crate::capacity::SlotIndexer;
use crate::constants::{EMPTY, TOMBSTONE};
use crate::hash::{BucketHash, fold_and_checksum, fold_and_checksum_words, mix_and_checksum};
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
/// plain table pipelines its batches instead, [`find_ahead`], with prefetches.)
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

/// Keys hashed ahead of the key decided by [`find_ahead`] (a power of two). 8 and 32
/// measured no different at 2¹⁶ and 2¹⁹ slots.
pub(crate) const AHEAD: usize = 16;

/// [`find`] for a stream of keys on a plain table, software-pipelined: key `i + AHEAD` is
/// hashed, and the cache lines of its home checksum word and (through `prefetch(home)`) of
/// its value are prefetched, before key `i` is decided and handed to `emit(i, slot)`.
///
/// By the time a key is decided its lines have had [`AHEAD`] keys' work to arrive, so the
/// decision reads the L1 cache: the home word (a well-predicted branch at low load), then
/// [`find_plain`]'s group compare for the keys not in their home slot. A mispredicted branch
/// then costs a pipeline refill, not a wait for memory: the lines of the next [`AHEAD`] keys
/// are already on their way. (Deciding every key by the branch-free group compare measured
/// slower: 4.3 against 3.5 ns per key at 2¹⁶ slots, 21 % more instructions.) Compiled once
/// per hash and kind of capacity like [`find_many`].
#[inline(always)]
#[allow(clippy::too_many_arguments)] // a table's fields, passed apart like `find_many`'s
pub(crate) fn find_ahead(
    words: &[u32],
    hash: BucketHash,
    indexer: &SlotIndexer,
    max_probes: u32,
    keys: &[CellKey],
    prefetch: impl Fn(u32),
    emit: impl FnMut(usize, Option<u32>),
) {
    let ix = *indexer;
    let prefetch = &prefetch;
    macro_rules! ahead {
        ($words:expr, $hash_and_checksum:expr, $index:expr, $in_bounds:expr) => {
            find_ahead_with(
                $words,
                &ix,
                max_probes,
                keys,
                $hash_and_checksum,
                $index,
                $in_bounds,
                prefetch,
                emit,
            )
        };
    }
    match (hash, ix.is_mask()) {
        (BucketHash::Fold, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            ahead!(cut, fold_and_checksum, |h| h & mask, |s| s & mask)
        }
        (BucketHash::Fold, false) => ahead!(words, fold_and_checksum, |h| ix.modulo(h), |s| s),
        (BucketHash::Mix, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            ahead!(cut, mix_and_checksum, |h| h & mask, |s| s & mask)
        }
        (BucketHash::Mix, false) => ahead!(words, mix_and_checksum, |h| ix.modulo(h), |s| s),
        (hash, _) => ahead!(
            words,
            |k: &CellKey| hash.hash_and_checksum(k),
            |h| ix.index(h),
            |s| s
        ),
    }
}

/// The loop of [`find_ahead`] with the hash and the slot index given.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // as `find_ahead`, plus the hash, the index and its re-mask
fn find_ahead_with(
    words: &[u32],
    indexer: &SlotIndexer,
    max_probes: u32,
    keys: &[CellKey],
    hash_and_checksum: impl Fn(&CellKey) -> (u32, u32),
    index: impl Fn(u32) -> u32,
    in_bounds: impl Fn(u32) -> u32,
    prefetch_value: impl Fn(u32),
    mut emit: impl FnMut(usize, Option<u32>),
) {
    // `(home, checksum)` of the keys hashed but not decided yet, key `i` at `i % AHEAD`.
    let mut ring = [(0_u32, 0_u32); AHEAD];
    let start = |key: &CellKey| {
        let (h, c) = hash_and_checksum(key);
        let home = index(h);
        prefetch(words.as_ptr().wrapping_add(home as usize));
        prefetch_value(home);
        (home, c)
    };
    let decide = |(home, c): (u32, u32)| {
        // A no-op on a home slot (an `& mask` again, or nothing), which shows the compiler
        // that the home slot from the ring is in bounds of the words cut to the capacity.
        let home = in_bounds(home);
        match words.get(home as usize) {
            Some(&w) if w == c => Some(home),
            Some(&EMPTY) => None,
            _ => find_plain(words, indexer, max_probes, home, c),
        }
    };
    for (r, key) in ring.iter_mut().zip(keys) {
        *r = start(key);
    }
    // Key `i + AHEAD` started as key `i` is decided, then the last `AHEAD` keys decided. (One
    // loop with a test for a key to start measured 12 % slower in `find_many` at 2¹⁶ slots.)
    let ahead = keys.get(AHEAD..).unwrap_or_default();
    for (i, key) in ahead.iter().enumerate() {
        let r = &mut ring[i % AHEAD];
        let current = *r;
        *r = start(key);
        emit(i, decide(current));
    }
    for i in ahead.len()..keys.len() {
        emit(i, decide(ring[i % AHEAD]));
    }
}

/// Keys per step of [`find_chunked`]: each step hashes (and prefetches the lines of) the next
/// `CHUNK` keys, then decides the current `CHUNK` ([`AHEAD`]: 8 measured slower, 32 no faster).
pub(crate) const CHUNK: usize = AHEAD;

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
    let fold_words = |k: &CellKey| fold_and_checksum_words(k.load_words());
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
            chunked!(cut, fold_words, move |h| h & mask, move |s| s & mask)
        }
        (BucketHash::Fold, false) => chunked!(words, fold_words, move |h| ix.modulo(h), |s| s),
        (BucketHash::Mix, true) => {
            let mask = ix.capacity() - 1;
            let cut = &words[..=mask as usize]; // all of them: the capacity is `mask + 1`
            chunked!(cut, mix_and_checksum, move |h| h & mask, move |s| s & mask)
        }
        (BucketHash::Mix, false) => chunked!(words, mix_and_checksum, move |h| ix.modulo(h), |s| s),
        (hash, _) => chunked!(
            words,
            |k: &CellKey| hash.hash_and_checksum(k),
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
    hash_and_checksum: impl Fn(&CellKey) -> (u32, u32),
    index: impl Fn(u32) -> u32,
    in_bounds: impl Fn(u32) -> u32,
    prefetch_value: impl Fn(u32),
    sink: &mut impl ChunkSink,
) {
    let start = |hashed: &mut Hashed, keys: &[CellKey]| {
        hash_chunk(hashed, keys, &hash_and_checksum, &index);
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
        match words.get(home as usize) {
            Some(&w) if w == c => Some(home),
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

/// The home slots and checksums of a chunk of keys (up to [`CHUNK`]), key by key: written
/// lane by lane, so that the compiler vectorises a full chunk (LLVM does for
/// [`BucketHash::Fold`] with baseline x86-64's SSE2, four keys at a time).
#[inline(always)]
fn hash_chunk(
    (homes, checks): &mut Hashed,
    keys: &[CellKey],
    hash_and_checksum: &impl Fn(&CellKey) -> (u32, u32),
    index: &impl Fn(u32) -> u32,
) {
    if let Ok(full) = <&[CellKey; CHUNK]>::try_from(keys) {
        for ((h, c), key) in homes.iter_mut().zip(checks.iter_mut()).zip(full) {
            let (hash, checksum) = hash_and_checksum(key);
            (*h, *c) = (index(hash), checksum);
        }
    } else {
        for ((h, c), key) in homes.iter_mut().zip(checks.iter_mut()).zip(keys) {
            let (hash, checksum) = hash_and_checksum(key);
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
