//! The lock-free table whose slots hold their values: a slot's checksum, age and value share
//! one cache line.

use alloc::boxed::Box;
use alloc::vec::Vec;
use core::sync::atomic::{AtomicU32, Ordering};

use crate::capacity::SlotIndexer;
use crate::concurrent::{Located, evict_idle};
use crate::constants::{EMPTY, TOMBSTONE};
use crate::error::TableError;
use crate::hash::BucketHash;
use crate::key::CellKey;
use crate::probe::{self, Insert};
use crate::table::{trim_tombstones_in, validate};

/// One slot: its checksum word, its age word and the value, from the start of a cache line.
#[repr(C, align(64))]
#[derive(Debug, Default)]
struct Slot<V> {
    checksum: AtomicU32,
    age: AtomicU32,
    value: V,
}

/// A lock-free hash table whose every slot is one 64-byte-aligned record: the key's checksum,
/// the slot's age and your value `V`, so that a lookup that finds its key in the home slot
/// reads one cache line — where [`ConcurrentTable`](crate::ConcurrentTable) reads its checksum
/// word, its age word and your value array's entry, three lines.
///
/// The same slots as [`ConcurrentTable`](crate::ConcurrentTable) for the same keys, capacity,
/// probe limit and hash, inserted in the same order: the same probing ([`Insert::Full`] at the
/// limit), insert by compare-and-swap on the checksum word (the same key inserted from several
/// threads at once ends in exactly one slot, and the thread that gets [`Insert::Inserted`]
/// initialises the value), ages and eviction. `V` holds whatever atomics your values need (a
/// seqlocked record, counters to add into); the table never writes it through `&self`.
///
/// Which to choose: [`ConcurrentTable`](crate::ConcurrentTable) keeps its checksums dense
/// (16 per cache line, the fastest scan, and an upload view without a copy) and leaves the
/// values' layout to you; `ConcurrentSlots` spends a line per slot (64 bytes for values up to
/// 56 bytes) for one line per lookup, which pays when the table is larger than the caches and
/// each lookup reads its value. MCPG's CPU guide keeps its chain states in one
/// (`mcg-markov-guide`'s `SharedGrid`): a guided frame of its renderer took 2-8 % less time
/// than with the three arrays, with a third fewer first-level cache misses. What it costs: a
/// scan of the whole table (eviction, [`count_occupied`](Self::count_occupied)) reads every
/// slot's line, 16 times the bytes of a dense checksum array, and filling a large table is
/// slower (2 threads inserting 2¹⁷ keys into 2¹⁹ slots and adding to each value: 19-32 % more
/// time than `ConcurrentTable` with a value array, still less than `DashMap`; the `peers`
/// bench). For upload, [`checksums`](Self::checksums) and
/// [`ages`](Self::ages) copy the words out in the GPU's separate-array layout.
///
/// # Example
/// ```
/// use std::sync::atomic::{AtomicU32, Ordering};
/// use mcg_hashgrid::{BucketHash, CellKey, ConcurrentSlots, glam::IVec3};
///
/// let table = ConcurrentSlots::<AtomicU32>::new(1024, 8, BucketHash::Fold)?;
/// std::thread::scope(|s| {
///     for _ in 0..4 {
///         s.spawn(|| {
///             for i in 0..100 {
///                 let key = CellKey::new(IVec3::new(i % 10, 0, 0), 0, 4);
///                 if let Some(slot) = table.insert_or_get(&key).slot() {
///                     table.value(slot).unwrap().fetch_add(1, Ordering::Relaxed);
///                 }
///             }
///         });
///     }
/// });
/// let slot = table.find(&CellKey::new(IVec3::new(3, 0, 0), 0, 4)).unwrap();
/// assert_eq!(table.value(slot).unwrap().load(Ordering::Relaxed), 40);
/// # Ok::<(), mcg_hashgrid::TableError>(())
/// ```
#[derive(Debug)]
pub struct ConcurrentSlots<V> {
    indexer: SlotIndexer,
    hash: BucketHash,
    max_probes: u32,
    slots: Box<[Slot<V>]>,
    aged: bool,
    frame: u32,
}

impl<V: Default> ConcurrentSlots<V> {
    /// An empty table of `capacity` slots, each holding `V::default()`, probing at most
    /// `max_probes` slots per key (see [`HashTable::new`](crate::HashTable::new) for the rules).
    ///
    /// # Errors
    /// [`TableError`] for a capacity below 8 or a probe limit of 0 or above the capacity.
    pub fn new(capacity: u32, max_probes: u32, hash: BucketHash) -> Result<Self, TableError> {
        let indexer = validate(capacity, max_probes)?;
        Ok(Self {
            indexer,
            hash,
            max_probes,
            slots: (0..capacity).map(|_| Slot::default()).collect(),
            aged: false,
            frame: 0,
        })
    }

    /// Empties every slot and resets its value to `V::default()`.
    pub fn clear(&mut self) {
        for s in &mut self.slots {
            *s.checksum.get_mut() = EMPTY;
            s.value = V::default();
        }
    }
}

impl<V> ConcurrentSlots<V> {
    /// The same table with ages: every lookup that finds a key and every insert marks its
    /// slot with the current frame (all slots start at the current frame), so that
    /// [`evict_older_than`](Self::evict_older_than) can free the idle ones.
    #[must_use]
    pub fn with_age_tracking(mut self) -> Self {
        self.aged = true;
        let frame = self.frame;
        for s in &mut self.slots {
            *s.age.get_mut() = frame;
        }
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

    /// `key`'s home slot and checksum (the hash, once), nothing asked for.
    #[inline]
    fn located(&self, key: &CellKey) -> Located {
        Located::of(key, self.hash, &self.indexer)
    }

    /// Where the probe for `key` starts, with the cache line of its home slot asked for (a
    /// prefetch hint, which changes nothing): the line holds the checksum, the age and the
    /// value a lookup that ends there reads. Locate the keys you want at once (a guide's
    /// candidates at one vertex), then [`find_located`](Self::find_located) them: their
    /// cache misses overlap.
    #[inline]
    #[must_use]
    pub fn locate(&self, key: &CellKey) -> Located {
        let at = self.located(key);
        probe::prefetch(self.slots.as_ptr().wrapping_add(at.home() as usize));
        at
    }

    /// The slot holding the key `at` was [`locate`](Self::locate)d for, if any; touches its
    /// age. The same slot as [`find`](Self::find) of that key.
    #[inline]
    #[must_use]
    pub fn find_located(&self, at: Located) -> Option<u32> {
        let slot = at.find_in(&self.slots, |s| &s.checksum, &self.indexer, self.max_probes)?;
        self.touch(slot);
        Some(slot)
    }

    /// The slot holding `key`, if any; touches its age.
    #[inline]
    #[must_use]
    pub fn find(&self, key: &CellKey) -> Option<u32> {
        self.find_located(self.located(key))
    }

    /// Finds `key` or claims a slot for it by compare-and-swap; touches its age. Safe to call
    /// from many threads at once. [`Insert::Full`] when the probe limit is reached. A claimed
    /// slot's value is what the last owner of the slot left (`V::default()` in a slot never
    /// used, whatever [`evict_older_than`](Self::evict_older_than)'s `on_evict` left in an
    /// evicted one).
    #[inline]
    pub fn insert_or_get(&self, key: &CellKey) -> Insert {
        let r = self.located(key).insert_in(
            &self.slots,
            |s| &s.checksum,
            &self.indexer,
            self.max_probes,
        );
        if let Some(slot) = r.slot() {
            self.touch(slot);
        }
        r
    }

    /// The value of `slot` (`None` out of range), whether or not a key holds the slot.
    #[inline]
    #[must_use]
    pub fn value(&self, slot: u32) -> Option<&V> {
        self.slots.get(slot as usize).map(|s| &s.value)
    }

    /// The values in slot order, mutably (exclusive access: for snapshots and resets).
    pub fn values_mut(&mut self) -> impl ExactSizeIterator<Item = &mut V> {
        self.slots.iter_mut().map(|s| &mut s.value)
    }

    /// Marks `slot` as used in the current frame (no-op without ages). The age is only
    /// written when it changes, so that threads reading the same slots in one frame do not
    /// take the cache line from each other.
    #[inline]
    pub fn touch(&self, slot: u32) {
        if self.aged
            && let Some(s) = self.slots.get(slot as usize)
            && s.age.load(Ordering::Relaxed) != self.frame
        {
            s.age.store(self.frame, Ordering::Relaxed);
        }
    }

    /// Number of slots holding a key (counts the whole table).
    #[must_use]
    pub fn count_occupied(&self) -> u32 {
        self.slots
            .iter()
            .filter(|s| s.checksum.load(Ordering::Relaxed) > TOMBSTONE)
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

    /// Evicts every key not inserted or found in the last `max_age` frames, calling
    /// `on_evict(slot, value)` for each (to reset the value), and returns how many. Tombstones
    /// that end a probe run are cleared, as in [`ConcurrentTable`](crate::ConcurrentTable). 0
    /// without ages.
    pub fn evict_older_than(&mut self, max_age: u32, mut on_evict: impl FnMut(u32, &mut V)) -> u32 {
        if !self.aged {
            return 0;
        }
        let frame = self.frame;
        let mut evicted = 0;
        for (slot, s) in self.slots.iter_mut().enumerate() {
            if evict_idle(s.checksum.get_mut(), *s.age.get_mut(), frame, max_age) {
                evicted += 1;
                on_evict(slot as u32, &mut s.value);
            }
        }
        if evicted > 0 {
            trim_tombstones_in(&mut self.slots, |s| s.checksum.get_mut());
        }
        evicted
    }

    /// The checksum words in slot order, copied (the GPU's checksum array).
    #[must_use]
    pub fn checksums(&self) -> Vec<u32> {
        self.slots
            .iter()
            .map(|s| s.checksum.load(Ordering::Relaxed))
            .collect()
    }

    /// The age words in slot order, copied (empty without ages).
    #[must_use]
    pub fn ages(&self) -> Vec<u32> {
        if !self.aged {
            return Vec::new();
        }
        self.slots
            .iter()
            .map(|s| s.age.load(Ordering::Relaxed))
            .collect()
    }
}

#[cfg(all(test, feature = "std"))]
mod tests {
    use glam::IVec3;

    use super::*;
    use crate::ConcurrentTable;

    fn keys(n: i32) -> Vec<CellKey> {
        (0..n)
            .map(|i| CellKey::new(IVec3::new(i % 17, i / 17, -i), (i % 3) as u8, 1))
            .collect()
    }

    /// Hypothesis: for the same keys, capacity, probe limit and hash, inserted, found and
    /// evicted in the same order, the slots, checksums and ages equal `ConcurrentTable`'s.
    /// 3 000 keys in a 1 000-slot table probing 8 (full, so keys sit past their home slot,
    /// inserts fail and tombstones are reused), power-of-two and prime capacities, every hash.
    #[test]
    fn same_slots_as_the_concurrent_table() {
        for capacity in [1024, 1009] {
            for hash in BucketHash::ALL {
                let mut a = ConcurrentTable::new(capacity, 8, hash)
                    .unwrap()
                    .with_age_tracking();
                let mut b = ConcurrentSlots::<u32>::new(capacity, 8, hash)
                    .unwrap()
                    .with_age_tracking();
                let keys = keys(3000);
                for (round, chunk) in keys.chunks(700).enumerate() {
                    for k in chunk {
                        assert_eq!(a.insert_or_get(k), b.insert_or_get(k), "{hash:?}");
                    }
                    for k in keys.iter().step_by(3) {
                        assert_eq!(a.find(k), b.find(k));
                        assert_eq!(a.find_located(a.locate(k)), b.find_located(b.locate(k)));
                    }
                    a.advance_frame();
                    b.advance_frame();
                    let mut evicted_a = Vec::new();
                    let mut evicted_b = Vec::new();
                    let na = a.evict_older_than(1, |s| evicted_a.push(s));
                    let nb = b.evict_older_than(1, |s, _| evicted_b.push(s));
                    assert_eq!((na, &evicted_a), (nb, &evicted_b), "round {round}");
                    assert_eq!(a.checksums(), b.checksums().as_slice());
                    assert_eq!(a.ages(), b.ages());
                    assert_eq!(a.count_occupied(), b.count_occupied());
                }
            }
        }
    }

    #[test]
    fn same_key_from_many_threads_ends_in_one_slot() {
        for round in 0..20 {
            let table = ConcurrentSlots::<AtomicU32>::new(64, 8, BucketHash::Fold).unwrap();
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

    #[test]
    fn values_ages_eviction_and_clear() {
        let mut t = ConcurrentSlots::<u32>::new(32, 4, BucketHash::Mix)
            .unwrap()
            .with_age_tracking();
        assert_eq!(core::mem::size_of::<Slot<[u32; 14]>>(), 64);
        let a = CellKey::new(IVec3::ONE, 2, 3);
        let b = CellKey::new(IVec3::NEG_ONE, 2, 3);
        let sa = t.insert_or_get(&a).slot().unwrap();
        *t.values_mut().nth(sa as usize).unwrap() = 7;
        t.advance_frame();
        let sb = t.insert_or_get(&b).slot().unwrap();
        assert_eq!(t.value(sa), Some(&7));
        assert_eq!(t.value(32), None);
        assert_eq!(t.checksums()[sa as usize], crate::checksum(&a));
        assert_eq!(t.ages()[sb as usize], 1);
        let mut evicted = Vec::new();
        let n = t.evict_older_than(0, |s, v| {
            evicted.push((s, *v));
            *v = 0;
        });
        assert_eq!((n, evicted), (1, alloc::vec![(sa, 7)]));
        assert_eq!(t.value(sa), Some(&0));
        assert_eq!(t.find(&a), None);
        assert_eq!(t.find(&b), Some(sb));
        assert_eq!(t.find_located(Located::default()), None);
        t.clear();
        assert_eq!(t.count_occupied(), 0);
        assert_eq!(t.checksums(), [EMPTY; 32]);
        let plain = ConcurrentSlots::<u32>::new(32, 4, BucketHash::Mix).unwrap();
        assert!(plain.ages().is_empty());
    }
}
