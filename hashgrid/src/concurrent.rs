//! The lock-free table: many threads insert and look up through `&self`.

use alloc::boxed::Box;
use alloc::vec::Vec;
use core::sync::atomic::{AtomicU32, Ordering};

use crate::capacity::SlotIndexer;
use crate::constants::{EMPTY, TOMBSTONE};
use crate::error::TableError;
use crate::hash::BucketHash;
use crate::key::CellKey;
use crate::probe::{self, Insert, Slots};
use crate::table::{trim_tombstones_in, validate};

/// The atomic checksum words of a lock-free table, wherever they live (`word` finds a slot's
/// word in an element of the slice), as the probe reads and claims them.
pub(crate) struct AtomicSlots<'a, E, F>(pub(crate) &'a [E], pub(crate) F);

impl<E, F: Fn(&E) -> &AtomicU32> Slots for AtomicSlots<'_, E, F> {
    #[inline(always)]
    fn load(&mut self, slot: u32) -> u32 {
        (self.1)(&self.0[slot as usize]).load(Ordering::Acquire)
    }
    #[inline(always)]
    fn claim(&mut self, slot: u32, current: u32, checksum: u32) -> Result<(), u32> {
        (self.1)(&self.0[slot as usize])
            .compare_exchange(current, checksum, Ordering::AcqRel, Ordering::Acquire)
            .map(|_| ())
    }
}

/// A key's probe start in a [`ConcurrentTable`]: its home slot and checksum
/// ([`ConcurrentTable::locate`]). The default locates no key: [`ConcurrentTable::find_located`]
/// of it is `None` (a placeholder for arrays of them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Located {
    home: u32,
    checksum: u32,
}

impl Located {
    /// The home slot, where probing starts (also the slot a value array is best prefetched
    /// at: at a low load most keys sit there).
    #[inline]
    #[must_use]
    pub const fn home(self) -> u32 {
        self.home
    }

    /// `key`'s home slot and checksum under `hash` and `indexer` (the hash, once).
    #[inline]
    pub(crate) fn of(key: &CellKey, hash: BucketHash, indexer: &SlotIndexer) -> Self {
        let (h, checksum) = hash.hash_and_checksum(key);
        Self {
            home: indexer.index(h),
            checksum,
        }
    }

    /// The slot of the located key among `slots`, whose atomic checksum words `word` gives:
    /// both lock-free tables' lookup, before they touch the slot's age.
    #[inline]
    pub(crate) fn find_in<E>(
        self,
        slots: &[E],
        word: impl Fn(&E) -> &AtomicU32,
        indexer: &SlotIndexer,
        max_probes: u32,
    ) -> Option<u32> {
        // A real key's checksum is never EMPTY or TOMBSTONE; the default `Located` has EMPTY,
        // which the probe would otherwise "find" in an empty slot.
        if self.checksum <= TOMBSTONE {
            return None;
        }
        probe::find(
            slots,
            |s| word(s).load(Ordering::Acquire),
            indexer,
            max_probes,
            self.home,
            self.checksum,
        )
    }

    /// Finds or claims the located key's slot among `slots` ([`probe::insert_or_get`] on the
    /// atomic checksum words `word` gives): both lock-free tables' insert, before the touch.
    #[inline]
    pub(crate) fn insert_in<E>(
        self,
        slots: &[E],
        word: impl Fn(&E) -> &AtomicU32,
        indexer: &SlotIndexer,
        max_probes: u32,
    ) -> Insert {
        probe::insert_or_get(
            &mut AtomicSlots(slots, word),
            indexer,
            max_probes,
            self.home,
            self.checksum,
        )
    }
}

/// Eviction's test of one slot: a key idle for more than `max_age` frames at `frame` becomes a
/// tombstone (`true`). Both lock-free tables evict with it.
#[inline]
pub(crate) fn evict_idle(checksum: &mut u32, age: u32, frame: u32, max_age: u32) -> bool {
    let idle = *checksum > TOMBSTONE && frame.wrapping_sub(age) > max_age;
    if idle {
        *checksum = TOMBSTONE;
    }
    idle
}

/// The slot index of a hash grid that many threads fill at once: checksums are
/// [`AtomicU32`]s and a key is inserted by compare-and-swap on its checksum word, exactly as
/// the GPU does with `atomicCompareExchangeWeak` (MCPG sec. 4; Bevy Solari).
///
/// The table owns only the checksum words (and optional ages); the *values* are yours, in any
/// array you index by the returned slot — typically per-slot atomics that threads accumulate
/// into, or the state array of the GPU buffer. That is what a renderer needs: the slot is
/// known after one CAS, values are written with whatever atomics or ownership rule the
/// renderer already uses, and nothing here locks.
///
/// - [`insert_or_get`](Self::insert_or_get) (`&self`): the same key inserted from several
///   threads at once ends in exactly one slot; the thread that gets [`Insert::Inserted`] is
///   the one that initialises the value.
/// - [`find`](Self::find) (`&self`): lock-free lookup.
/// - Eviction ([`evict_older_than`](Self::evict_older_than)) and the plain `&[u32]` view for
///   upload ([`checksums`](Self::checksums)) take `&mut self`: no insert can run meanwhile.
///
/// Probing is the same bounded linear probing with wrap-around as [`HashTable`](crate::HashTable),
/// with [`Insert::Full`] at the probe limit.
///
/// # Example
/// ```
/// use std::sync::atomic::{AtomicU32, Ordering};
/// use mcg_hashgrid::{BucketHash, CellKey, ConcurrentTable, glam::IVec3};
///
/// let table = ConcurrentTable::new(1024, 8, BucketHash::Mix)?;
/// let hits: Vec<AtomicU32> = (0..1024).map(|_| AtomicU32::new(0)).collect();
/// std::thread::scope(|s| {
///     for _ in 0..4 {
///         s.spawn(|| {
///             for i in 0..100 {
///                 let key = CellKey::new(IVec3::new(i % 10, 0, 0), 0, 4);
///                 if let Some(slot) = table.insert_or_get(&key).slot() {
///                     hits[slot as usize].fetch_add(1, Ordering::Relaxed);
///                 }
///             }
///         });
///     }
/// });
/// let slot = table.find(&CellKey::new(IVec3::new(3, 0, 0), 0, 4)).unwrap();
/// assert_eq!(hits[slot as usize].load(Ordering::Relaxed), 40);
/// # Ok::<(), mcg_hashgrid::TableError>(())
/// ```
#[derive(Debug)]
pub struct ConcurrentTable {
    indexer: SlotIndexer,
    hash: BucketHash,
    max_probes: u32,
    checksums: Box<[AtomicU32]>,
    ages: Box<[AtomicU32]>,
    frame: u32,
}

impl ConcurrentTable {
    /// An empty table of `capacity` slots probing at most `max_probes` slots per key
    /// (see [`HashTable::new`](crate::HashTable::new) for the rules).
    pub fn new(capacity: u32, max_probes: u32, hash: BucketHash) -> Result<Self, TableError> {
        let indexer = validate(capacity, max_probes)?;
        Ok(Self {
            indexer,
            hash,
            max_probes,
            checksums: (0..capacity).map(|_| AtomicU32::new(EMPTY)).collect(),
            ages: Box::new([]),
            frame: 0,
        })
    }

    /// The same table with an age array (all slots at the current frame).
    #[must_use]
    pub fn with_age_tracking(mut self) -> Self {
        self.ages = (0..self.capacity())
            .map(|_| AtomicU32::new(self.frame))
            .collect();
        self
    }

    /// The number of slots.
    #[inline]
    #[must_use]
    pub fn capacity(&self) -> u32 {
        self.indexer.capacity()
    }

    /// The probe limit.
    #[inline]
    #[must_use]
    pub fn max_probes(&self) -> u32 {
        self.max_probes
    }

    /// The bucket hash.
    #[inline]
    #[must_use]
    pub fn bucket_hash(&self) -> BucketHash {
        self.hash
    }

    /// The home slot of `key`, where probing starts.
    #[inline]
    #[must_use]
    pub fn home_slot(&self, key: &CellKey) -> u32 {
        self.indexer.index(self.hash.hash(key))
    }

    /// The slot holding `key`, if any; touches its age.
    #[inline]
    #[must_use]
    pub fn find(&self, key: &CellKey) -> Option<u32> {
        self.find_located(self.located(key))
    }

    /// `key`'s home slot and checksum (the hash, once), nothing asked for.
    #[inline]
    fn located(&self, key: &CellKey) -> Located {
        Located::of(key, self.hash, &self.indexer)
    }

    /// Where the probe for `key` starts (its home slot and checksum, hashed once), with the
    /// cache line of its home checksum word asked for: a prefetch hint, which changes
    /// nothing. [`find_located`](Self::find_located) then decides the key:
    /// `find_located(locate(key)) == find(key)`.
    ///
    /// For a few keys wanted at once that are not a stream for
    /// [`find_many`](Self::find_many) — a guide's candidates at one vertex: locate them all,
    /// then find them, and their cache misses overlap instead of waiting on each other.
    #[inline]
    #[must_use]
    pub fn locate(&self, key: &CellKey) -> Located {
        let at = self.located(key);
        probe::prefetch(self.checksums.as_ptr().wrapping_add(at.home as usize));
        at
    }

    /// The slot holding the key `at` was [`locate`](Self::locate)d for, if any; touches its
    /// age. The same slot as [`find`](Self::find) of that key.
    #[inline]
    #[must_use]
    pub fn find_located(&self, at: Located) -> Option<u32> {
        let slot = at.find_in(&self.checksums, |w| w, &self.indexer, self.max_probes)?;
        self.touch(slot);
        Some(slot)
    }

    /// Keys hashed per step of [`find_many`](Self::find_many).
    pub const BATCH: usize = 64;

    /// [`find`](Self::find) for a batch of keys: `out[i] = find(&keys[i])`, ages touched the
    /// same way. Safe to call from many threads at once, like `find`.
    ///
    /// The same slots as `find`. Per step of [`BATCH`](Self::BATCH) keys: (1) every key
    /// hashed (pure arithmetic, compiled once per hash and kind of capacity, so no per-key
    /// branch on either); (2) the home slot's checksum word of every key read (independent
    /// loads with no branch on their values, so their cache misses overlap); (3) each key
    /// decided from its home word, walking on only for keys whose home slot holds another
    /// key. [`HashTable::find_many`](crate::HashTable::find_many) does the same on plain
    /// words; this is its twin for the lock-free table (a guide's candidates of several
    /// vertices looked up at once).
    ///
    /// # Panics
    /// When `keys` and `out` differ in length.
    pub fn find_many(&self, keys: &[CellKey], out: &mut [Option<u32>]) {
        assert_eq!(
            keys.len(),
            out.len(),
            "find_many: keys and out differ in length"
        );
        let load = |w: &AtomicU32| w.load(Ordering::Acquire);
        probe::find_many::<AtomicU32, { Self::BATCH }>(
            &self.checksums,
            load,
            self.hash,
            &self.indexer,
            keys,
            |home, c| {
                probe::find(
                    &self.checksums,
                    load,
                    &self.indexer,
                    self.max_probes,
                    home,
                    c,
                )
            },
            |first, slots| {
                out[first..first + slots.len()].copy_from_slice(slots);
                for &slot in slots.iter().flatten() {
                    self.touch(slot);
                }
            },
        );
    }

    /// Finds `key` or claims a slot for it by compare-and-swap; touches its age. Safe to call
    /// from many threads at once. [`Insert::Full`] when the probe limit is reached.
    #[inline]
    pub fn insert_or_get(&self, key: &CellKey) -> Insert {
        let r = self
            .located(key)
            .insert_in(&self.checksums, |w| w, &self.indexer, self.max_probes);
        if let Some(slot) = r.slot() {
            self.touch(slot);
        }
        r
    }

    /// Marks `slot` as used in the current frame (a relaxed store; no-op without ages). The
    /// age is only written when it changes, so that threads reading the same slots in one
    /// frame do not take the cache line from each other.
    #[inline]
    pub fn touch(&self, slot: u32) {
        if let Some(age) = self.ages.get(slot as usize)
            && age.load(Ordering::Relaxed) != self.frame
        {
            age.store(self.frame, Ordering::Relaxed);
        }
    }

    /// Number of slots holding a key (counts the whole array).
    #[must_use]
    pub fn count_occupied(&self) -> u32 {
        self.checksums
            .iter()
            .filter(|w| w.load(Ordering::Relaxed) > TOMBSTONE)
            .count() as u32
    }

    /// The current frame of the age counter.
    #[must_use]
    pub fn frame(&self) -> u32 {
        self.frame
    }

    /// Moves the age counter to the next frame (wrapping).
    pub fn advance_frame(&mut self) {
        self.frame = self.frame.wrapping_add(1);
    }

    /// Evicts every key not inserted or found in the last `max_age` frames and calls
    /// `on_evict(slot)` for each (to reset your value), returning how many. Needs ages.
    pub fn evict_older_than(&mut self, max_age: u32, mut on_evict: impl FnMut(u32)) -> u32 {
        if self.ages.is_empty() {
            return 0;
        }
        let frame = self.frame;
        let mut evicted = 0;
        for (slot, (word, age)) in self
            .checksums
            .iter_mut()
            .zip(self.ages.iter_mut())
            .enumerate()
        {
            if evict_idle(word.get_mut(), *age.get_mut(), frame, max_age) {
                evicted += 1;
                on_evict(slot as u32);
            }
        }
        // Only an eviction makes tombstones, and only `trim_tombstones` and `clear` make
        // empty slots: with nothing evicted, the last trim left nothing to trim.
        if evicted > 0 {
            trim_tombstones_in(&mut self.checksums, AtomicU32::get_mut);
        }
        evicted
    }

    /// Empties every slot.
    pub fn clear(&mut self) {
        for w in self.checksums.iter_mut() {
            *w.get_mut() = EMPTY;
        }
    }

    /// The checksum words as plain `u32`s, to upload to the GPU without a copy.
    ///
    /// Takes `&mut self`, so no thread can be inserting while the view lives.
    #[allow(unsafe_code)]
    #[must_use]
    pub fn checksums(&mut self) -> &[u32] {
        let len = self.checksums.len();
        let ptr = self.checksums.as_ptr().cast::<u32>();
        // SAFETY: `AtomicU32` "has the same size and bit validity as the underlying integer
        // type, u32" and an alignment of 4 (std docs), at least that of `u32`, so the pointer
        // is valid and aligned for `len` `u32`s. The `&mut self` borrow that the returned slice
        // keeps alive excludes every other access to the atomics, so reading them non-atomically
        // cannot race.
        unsafe { core::slice::from_raw_parts(ptr, len) }
    }

    /// The age words (empty without age tracking), copied.
    #[must_use]
    pub fn ages(&self) -> Vec<u32> {
        self.ages
            .iter()
            .map(|a| a.load(Ordering::Relaxed))
            .collect()
    }

    /// The checksum words, consuming the table (no `unsafe` involved).
    #[must_use]
    pub fn into_checksums(self) -> Vec<u32> {
        self.checksums
            .into_vec()
            .into_iter()
            .map(AtomicU32::into_inner)
            .collect()
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use glam::IVec3;

    use super::*;
    use crate::hash::checksum;

    #[test]
    fn same_key_from_many_threads_ends_in_one_slot() {
        for round in 0..20 {
            let table = ConcurrentTable::new(64, 8, BucketHash::Mix).unwrap();
            let key = CellKey::new(IVec3::new(round, 1, 2), 0, 0);
            let results: Vec<Insert> = std::thread::scope(|s| {
                let handles: Vec<_> = (0..4)
                    .map(|_| s.spawn(|| table.insert_or_get(&key)))
                    .collect();
                handles.into_iter().map(|h| h.join().unwrap()).collect()
            });
            let slots: Vec<u32> = results.iter().map(|r| r.slot().unwrap()).collect();
            assert!(slots.iter().all(|&s| s == slots[0]), "{results:?}");
            assert_eq!(results.iter().filter(|r| r.is_inserted()).count(), 1);
            assert_eq!(table.count_occupied(), 1);
        }
    }

    /// `find_many` gives `find`'s slot for every key: 3 000 keys in a 1 000-slot table
    /// probing 8 (a full table, so many keys sit past their home slot or are missing), with a
    /// power-of-two and a prime capacity and every hash, in batches that straddle
    /// [`ConcurrentTable::BATCH`]; and it touches the ages of the slots it finds.
    #[test]
    fn find_many_equals_find() {
        for capacity in [1024, 1009] {
            for hash in BucketHash::ALL {
                let mut t = ConcurrentTable::new(capacity, 8, hash)
                    .unwrap()
                    .with_age_tracking();
                let keys: Vec<CellKey> = (0..3000)
                    .map(|i| CellKey::new(IVec3::new(i % 17, i / 17, -i), (i % 3) as u8, 1))
                    .collect();
                for k in keys.iter().step_by(2) {
                    t.insert_or_get(k);
                }
                t.advance_frame();
                let want: Vec<Option<u32>> = keys.iter().map(|k| t.find(k)).collect();
                assert!(want.iter().any(Option::is_some) && want.iter().any(Option::is_none));
                t.advance_frame();
                let mut got = alloc::vec![None; keys.len()];
                t.find_many(&keys, &mut got);
                assert_eq!(got, want, "{hash:?} capacity {capacity}");
                let ages = t.ages();
                for s in want.iter().flatten() {
                    assert_eq!(ages[*s as usize], t.frame());
                }
            }
        }
    }

    #[test]
    fn upload_view_and_eviction() {
        let mut t = ConcurrentTable::new(32, 4, BucketHash::Mix)
            .unwrap()
            .with_age_tracking();
        let a = CellKey::new(IVec3::ONE, 2, 3);
        let b = CellKey::new(IVec3::NEG_ONE, 2, 3);
        let sa = t.insert_or_get(&a).slot().unwrap();
        t.advance_frame();
        let sb = t.insert_or_get(&b).slot().unwrap();
        assert_eq!(t.checksums()[sa as usize], checksum(&a));
        assert_eq!(t.checksums().iter().filter(|&&w| w > TOMBSTONE).count(), 2);
        let mut evicted = Vec::new();
        assert_eq!(t.evict_older_than(0, |s| evicted.push(s)), 1);
        assert_eq!(evicted, [sa]);
        assert_eq!(t.find(&a), None);
        assert_eq!(t.find(&b), Some(sb));
        assert_eq!(t.ages().len(), 32);
        t.clear();
        assert_eq!(t.count_occupied(), 0);
        assert_eq!(t.into_checksums(), [EMPTY; 32]);
    }
}
