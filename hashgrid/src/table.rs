//! A fixed-capacity hash table of `Pod` values keyed by [`CellKey`], laid out for the GPU.

use alloc::vec;
use alloc::vec::Vec;

use bytemuck::Pod;

use crate::capacity::SlotIndexer;
use crate::constants::{EMPTY, FIRST_CHECKSUM, TOMBSTONE};
use crate::error::TableError;
use crate::hash::{BucketHash, fold_and_checksum, fold_and_raw_checksum, reserve};
use crate::key::CellKey;
use crate::probe::{self, Insert, Slots};

/// Checks the parameters shared by both tables.
pub(crate) fn validate(capacity: u32, max_probes: u32) -> Result<SlotIndexer, TableError> {
    let indexer = SlotIndexer::new(capacity).ok_or(TableError::CapacityZero)?;
    if max_probes == 0 {
        return Err(TableError::MaxProbesZero);
    }
    if max_probes > capacity {
        return Err(TableError::MaxProbesAboveCapacity {
            max_probes,
            capacity,
        });
    }
    Ok(indexer)
}

/// Clears tombstones that are followed (in probe order) by an empty slot: no key can sit
/// behind them, so lookups and inserts may stop there. Returns how many were cleared.
pub(crate) fn trim_tombstones(words: &mut [u32]) -> u32 {
    trim_tombstones_in(words, |w| w)
}

/// [`trim_tombstones`] over slots whose checksum word `word` gives (exclusive access): the
/// lock-free tables' atomic words, in place.
pub(crate) fn trim_tombstones_in<E>(
    slots: &mut [E],
    mut word: impl FnMut(&mut E) -> &mut u32,
) -> u32 {
    let n = slots.len();
    let Some(empty) = slots.iter_mut().position(|s| *word(s) == EMPTY) else {
        return 0;
    };
    let mut cleared = 0;
    let mut next_is_empty = true;
    for step in 1..n {
        let w = word(&mut slots[(empty + n - step) % n]);
        if *w == TOMBSTONE && next_is_empty {
            *w = EMPTY;
            cleared += 1;
        } else {
            next_is_empty = *w == EMPTY;
        }
    }
    cleared
}

/// A fixed-capacity hash table from [`CellKey`] to a `Pod` value `T`: MCPG's hash-grid buffer
/// (sec. 4, "Hash Grid", Table 1) on the CPU.
///
/// Two arrays of `capacity` entries, side by side:
///
/// - `checksums: [u32]`: [`checksum`](crate::checksum) of the key in the slot, [`EMPTY`] (0) or
///   [`TOMBSTONE`] (1);
/// - `values: [T]`: the state of the slot (zeroed when the slot is taken).
///
/// Both upload to the GPU as they are ([`checksums`](Self::checksums),
/// [`values`](Self::values); `bytemuck::cast_slice` gives the bytes), and the GPU twin finds
/// the same slots: the home slot is `hash(key) mod capacity` ([`SlotIndexer`]), then bounded
/// linear probing over at most `max_probes` slots that wraps from the last slot to slot 0.
/// A key that finds no free slot within the limit gets [`Insert::Full`], never an endless loop.
///
/// A lookup compares checksums only, so two keys that share a home region *and* a checksum
/// are confused (probability ≈ 2⁻³² per pair, measured by the `hashgrid_checksum` suite).
///
/// **Ages (optional).** With [`with_age_tracking`](Self::with_age_tracking) a third array
/// stores for each slot the frame it was last inserted or touched in; [`advance_frame`] and
/// [`evict_older_than`] then free stale cells (as tombstones, which probes walk past and
/// inserts reuse; tombstones that end a probe run are cleared).
///
/// [`advance_frame`]: Self::advance_frame
/// [`evict_older_than`]: Self::evict_older_than
#[derive(Clone, Debug)]
pub struct HashTable<T> {
    indexer: SlotIndexer,
    /// `Some(capacity − 1)` for [`BucketHash::Fold`] with a power-of-two capacity: the
    /// default case, which lookups and inserts take without dispatch (see [`find`](Self::find)).
    fold_mask: Option<u32>,
    hash: BucketHash,
    max_probes: u32,
    checksums: Vec<u32>,
    values: Vec<T>,
    ages: Vec<u32>,
    frame: u32,
    occupied: u32,
    tombstones: u32,
}

impl<T: Pod> HashTable<T> {
    /// An empty table of `capacity` slots (any size ≥ 1; a power of two makes the slot index
    /// a mask, anything else a modulo, see [`SlotIndexer`]) that probes at most `max_probes`
    /// slots per key (1 ≤ `max_probes` ≤ `capacity`) and finds home slots with `hash`.
    pub fn new(capacity: u32, max_probes: u32, hash: BucketHash) -> Result<Self, TableError> {
        let indexer = validate(capacity, max_probes)?;
        Ok(Self {
            indexer,
            fold_mask: (hash == BucketHash::Fold && indexer.is_mask()).then(|| capacity - 1),
            hash,
            max_probes,
            checksums: vec![EMPTY; capacity as usize],
            values: vec![T::zeroed(); capacity as usize],
            ages: Vec::new(),
            frame: 0,
            occupied: 0,
            tombstones: 0,
        })
    }

    /// The same table with an age array (all slots at frame 0), enabling
    /// [`evict_older_than`](Self::evict_older_than).
    #[must_use]
    pub fn with_age_tracking(mut self) -> Self {
        self.ages = vec![self.frame; self.checksums.len()];
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

    /// Number of slots holding a key.
    #[inline]
    #[must_use]
    pub fn len(&self) -> u32 {
        self.occupied
    }

    /// `true` when no slot holds a key.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.occupied == 0
    }

    /// Number of tombstones (evicted or removed slots not yet reused or cleared).
    #[inline]
    #[must_use]
    pub fn tombstones(&self) -> u32 {
        self.tombstones
    }

    /// `len / capacity`.
    #[must_use]
    pub fn load_factor(&self) -> f64 {
        f64::from(self.occupied) / f64::from(self.capacity())
    }

    /// The home slot of `key`: `hash(key) mod capacity`, where probing starts. The probe
    /// length of a key found in slot `s` is `(s − home) mod capacity + 1`.
    #[inline]
    #[must_use]
    pub fn home_slot(&self, key: &CellKey) -> u32 {
        self.indexer.index(self.hash.hash(key))
    }

    /// The slot holding `key`, if any.
    #[inline]
    #[must_use]
    pub fn find(&self, key: &CellKey) -> Option<u32> {
        // The default (`Fold`, power-of-two capacity) inline and without dispatch; every other
        // hash and capacity out of line. The inline path then needs no callee-saved registers
        // (the `Mix` variants' did), and the home slot decides ≈ 85 % of lookups at load 1/4
        // in a few instructions (no probe window to set up), with a well-predicted branch.
        match self.fold_mask {
            Some(mask) => self.lookup(mask, key, Some),
            None => self.find_general(key),
        }
    }

    /// [`find`](Self::find) in the default case (`Fold`, capacity `mask + 1`), handing the
    /// slot found to `hit`. The checksums are cut to `..=mask` (all of them), so the compiler
    /// sees the home slot `h & mask` in bounds; each path calls `hit` on its own, so where `hit`
    /// indexes an array cut the same way, the home slot needs no bounds check there either:
    /// [`get`](Self::get)'s home-slot hit is the hash, one load, one compare and the value's
    /// load (28 instructions per lookup in the benches' loop, was 37 with the two bounds
    /// checks and the register they held).
    #[inline(always)]
    fn lookup<R>(&self, mask: u32, key: &CellKey, hit: impl FnOnce(u32) -> Option<R>) -> Option<R> {
        let (h, raw) = fold_and_raw_checksum(key);
        let home = h & mask;
        let words = self.checksums.get(..=mask as usize)?;
        match words.get(home as usize) {
            // The raw checksum equals the stored one unless it is 0 or 1 (EMPTY, TOMBSTONE),
            // which `reserve` remaps: one compare on the fast path instead of the remap.
            Some(&w) if w == raw && raw >= FIRST_CHECKSUM => hit(home),
            Some(&EMPTY) => None,
            Some(&w) if w == reserve(raw) => hit(home),
            _ => {
                let c = reserve(raw);
                // Most keys not in their home slot are in the next one (wrapping): one compare
                // there before the general walk, which starts over from the home slot.
                let next = (home + 1) & mask;
                match words.get(next as usize) {
                    Some(&w) if w == c && self.max_probes > 1 => hit(next),
                    _ => hit(self.walk(home, c)?),
                }
            }
        }
    }

    /// [`find`](Self::find) for any hash and capacity.
    #[inline(never)]
    fn find_general(&self, key: &CellKey) -> Option<u32> {
        let (h, c) = self.hash.hash_and_checksum(key);
        let home = self.indexer.index(h);
        match self.checksums.get(home as usize) {
            Some(&w) if w == c => Some(home),
            Some(&EMPTY) => None,
            _ => self.walk(home, c),
        }
    }

    /// The probe walk of [`find`](Self::find) past a home slot that holds another key.
    #[inline(never)]
    fn walk(&self, home: u32, checksum: u32) -> Option<u32> {
        probe::find(
            &self.checksums,
            |&w| w,
            &self.indexer,
            self.max_probes,
            home,
            checksum,
        )
    }

    /// [`find`](Self::find) for a batch of keys: `out[i] = find(&keys[i])`.
    ///
    /// The same slots as `find`, faster on large tables: software-pipelined by chunks of
    /// [`BATCH`](Self::BATCH) keys. Before it decides a chunk it has already hashed the next
    /// one and prefetched the cache lines of those keys' home checksum words, so every
    /// decision reads the L1 cache and up to 2 × [`BATCH`](Self::BATCH) keys' misses are in
    /// flight at once, whatever the branches do. A per-key `find` instead mispredicts on the
    /// ≈ α/2 of keys (at load α) not in their home slot, and each misprediction that waits on a
    /// missed checksum line stalls the loads of the following keys. With the default
    /// [`BucketHash::Fold`] a chunk is hashed four keys at a time (SSE2 on x86-64); a key not
    /// in its home slot is looked for in the next slot, then decided out of line from one
    /// compare of 4 slots at once. The loop is compiled once per hash and kind of capacity
    /// (no per-key branch on either). Measured (`benches/README.md`, seventh session, 2¹⁶ /
    /// 2¹⁹ slots, load 1/4, fastest passes, then the value reads): 2.9 / 4.6 ns per key with
    /// warm caches (0.87–0.88 / 0.88–0.94 of hashbrown's `get` speed), 5.6 / 13.2–13.7 ns with
    /// the table flushed from the caches (1.15–1.16 / 1.25–1.29). To read the values right
    /// away, [`get_many`](Self::get_many) is faster from memory.
    ///
    /// # Panics
    /// When `keys` and `out` differ in length.
    pub fn find_many(&self, keys: &[CellKey], out: &mut [Option<u32>]) {
        assert_eq!(
            keys.len(),
            out.len(),
            "find_many: keys and out differ in length"
        );
        let mut sink = OutSink {
            out: out.chunks_mut(probe::CHUNK),
        };
        probe::find_chunked(
            &self.checksums,
            self.hash,
            &self.indexer,
            self.max_probes,
            keys,
            |_| {},
            &mut sink,
        );
    }

    /// The values of a batch of keys: `f(i, self.get(&keys[i]))` for every `i`, in order.
    ///
    /// [`find_many`](Self::find_many) with the value reads inside: with the home checksum
    /// word's line it also prefetches the home slot's value line, and it calls `f` for each
    /// key right after deciding it, a chunk of [`BATCH`](Self::BATCH) keys after both lines
    /// were asked for; a `find_many` over a long stream followed by a pass over the values
    /// fetches every value line a second time, after the stream has evicted it. Use it for a wavefront of
    /// hit points whose states are read (or accumulated) right away, `find_many` where the
    /// slots themselves are wanted. Measured against hashbrown's `get` per key
    /// (`benches/README.md`, seventh session, 2¹⁶ / 2¹⁹ slots at load 1/4, fastest passes):
    /// 0.84–0.85 / 0.68–0.72 of its speed with warm caches, 1.09–1.11 / 1.34–1.35 with the
    /// structures flushed from the caches (`get`: 0.75–0.77 / 0.79–0.83). With warm caches on
    /// a table well above the L2 cache, `find_many` followed by a value pass measured faster
    /// (0.88–0.94 at 2¹⁹): two prefetched lines per key in flight, where `find_many` has one.
    ///
    /// The prefetch is `_mm_prefetch` on x86-64 (a hint, which never faults and changes no
    /// result) and nothing elsewhere.
    #[inline]
    pub fn get_many<'a>(&'a self, keys: &[CellKey], mut f: impl FnMut(usize, Option<&'a T>)) {
        // Cut to the capacity like the checksums, so that a home slot (`h & mask` on the
        // default path) indexes the values without a bounds check.
        let values = &self.values[..self.checksums.len()];
        probe::find_chunked(
            &self.checksums,
            self.hash,
            &self.indexer,
            self.max_probes,
            keys,
            |home| probe::prefetch(values.as_ptr().wrapping_add(home as usize)),
            &mut ValueSink { values, f: &mut f },
        );
    }

    /// Keys per step of [`find_many`](Self::find_many) and [`get_many`](Self::get_many):
    /// each hashes (and prefetches the lines of) a chunk of this many keys one chunk ahead of
    /// the chunk it decides. (Before they were pipelined, the batch of keys hashed per step:
    /// 256; from the fifth session to the seventh, the distance of a ring of 16 keys.)
    pub const BATCH: usize = probe::CHUNK;

    /// The value of `key`, if the table holds it.
    #[inline]
    #[must_use]
    pub fn get(&self, key: &CellKey) -> Option<&T> {
        match self.fold_mask {
            Some(mask) => {
                let values = self.values.get(..=mask as usize)?;
                self.lookup(mask, key, |slot| values.get(slot as usize))
            }
            None => self.values.get(self.find_general(key)? as usize),
        }
    }

    /// The value of `key` for writing, if the table holds it; touches its age.
    #[inline]
    pub fn get_mut(&mut self, key: &CellKey) -> Option<&mut T> {
        let slot = self.find(key)?;
        self.touch(slot);
        Some(&mut self.values[slot as usize])
    }

    /// Finds `key` or gives it a slot (with a zeroed value); touches its age. Returns
    /// [`Insert::Full`] and changes nothing when the `max_probes` slots from its home slot are
    /// all taken by other keys.
    #[inline]
    pub fn insert_or_get(&mut self, key: &CellKey) -> Insert {
        let (h, c) = match self.fold_mask {
            Some(mask) => {
                let (h, c) = fold_and_checksum(key);
                (h & mask, c)
            }
            None => self.hash_general(key),
        };
        let home = h;
        // The home slot first (most inserts and repeats end there): this key, or an empty slot
        // that it takes (no key sits past an empty slot). Otherwise the general walk, which
        // remembers whether the claimed slot was a tombstone for the counters.
        let outcome = match self.checksums.get_mut(home as usize) {
            Some(w) if *w == c => (Insert::Found(home), false),
            Some(w) if *w == EMPTY => {
                *w = c;
                (Insert::Inserted(home), false)
            }
            _ => {
                let mut slots = TrackingSlots {
                    words: &mut self.checksums,
                    claimed_tombstone: false,
                };
                let r = probe::insert_or_get(&mut slots, &self.indexer, self.max_probes, home, c);
                (r, slots.claimed_tombstone)
            }
        };
        match outcome {
            (Insert::Inserted(slot), was_tombstone) => {
                self.values[slot as usize] = T::zeroed();
                self.occupied += 1;
                if was_tombstone {
                    self.tombstones -= 1;
                }
                self.touch(slot);
                Insert::Inserted(slot)
            }
            (Insert::Found(slot), _) => {
                self.touch(slot);
                Insert::Found(slot)
            }
            (Insert::Full, _) => Insert::Full,
        }
    }

    /// `(home slot, checksum)` of `key` for any hash and capacity.
    #[inline(never)]
    fn hash_general(&self, key: &CellKey) -> (u32, u32) {
        let (h, c) = self.hash.hash_and_checksum(key);
        (self.indexer.index(h), c)
    }

    /// [`insert_or_get`](Self::insert_or_get) returning the value for writing and whether it
    /// is fresh; `None` when the table is full there.
    #[inline]
    pub fn entry(&mut self, key: &CellKey) -> Option<(&mut T, bool)> {
        let r = self.insert_or_get(key);
        let slot = r.slot()?;
        Some((&mut self.values[slot as usize], r.is_inserted()))
    }

    /// Removes `key` (its slot becomes a tombstone); returns whether it was there.
    pub fn remove(&mut self, key: &CellKey) -> bool {
        match self.find(key) {
            Some(slot) => {
                self.checksums[slot as usize] = TOMBSTONE;
                self.occupied -= 1;
                self.tombstones += 1;
                true
            }
            None => false,
        }
    }

    /// Empties every slot (values are zeroed when slots are taken again).
    pub fn clear(&mut self) {
        self.checksums.fill(EMPTY);
        self.occupied = 0;
        self.tombstones = 0;
    }

    /// The current frame of the age counter.
    #[inline]
    #[must_use]
    pub fn frame(&self) -> u32 {
        self.frame
    }

    /// Moves the age counter to the next frame (wrapping).
    pub fn advance_frame(&mut self) {
        self.frame = self.frame.wrapping_add(1);
    }

    /// Marks `slot` as used in the current frame (no-op without age tracking).
    #[inline]
    pub fn touch(&mut self, slot: u32) {
        if let Some(age) = self.ages.get_mut(slot as usize) {
            *age = self.frame;
        }
    }

    /// Evicts every key not inserted or touched in the last `max_age` frames
    /// (`frame − age > max_age`, wrapping) and returns how many. Without age tracking nothing
    /// is evicted.
    pub fn evict_older_than(&mut self, max_age: u32) -> u32 {
        if self.ages.is_empty() {
            return 0;
        }
        let mut evicted = 0;
        for (word, &age) in self.checksums.iter_mut().zip(&self.ages) {
            if *word > TOMBSTONE && self.frame.wrapping_sub(age) > max_age {
                *word = TOMBSTONE;
                evicted += 1;
            }
        }
        self.occupied -= evicted;
        self.tombstones += evicted;
        self.tombstones -= trim_tombstones(&mut self.checksums);
        evicted
    }

    /// The checksum array (upload it as is: `bytemuck::cast_slice::<u32, u8>`).
    #[inline]
    #[must_use]
    pub fn checksums(&self) -> &[u32] {
        &self.checksums
    }

    /// The value array (upload it as is).
    #[inline]
    #[must_use]
    pub fn values(&self) -> &[T] {
        &self.values
    }

    /// The value array for writing (e.g. after reading back the GPU's copy). Writing a value
    /// does not change which keys the table holds.
    #[inline]
    #[must_use]
    pub fn values_mut(&mut self) -> &mut [T] {
        &mut self.values
    }

    /// The age array (empty without age tracking).
    #[inline]
    #[must_use]
    pub fn ages(&self) -> &[u32] {
        &self.ages
    }

    /// The occupied slots and their values.
    pub fn iter(&self) -> impl Iterator<Item = (u32, &T)> {
        self.checksums
            .iter()
            .zip(&self.values)
            .enumerate()
            .filter(|(_, (w, _))| **w > TOMBSTONE)
            .map(|(i, (_, v))| (i as u32, v))
    }
}

/// [`HashTable::find_many`]'s output, a chunk of `out` per chunk of keys.
struct OutSink<'a> {
    out: core::slice::ChunksMut<'a, Option<u32>>,
}

impl probe::ChunkSink for OutSink<'_> {
    #[inline(always)]
    fn chunk(
        &mut self,
        _first: usize,
        homes: &[u32],
        checks: &[u32],
        decide: &impl Fn(u32, u32) -> Option<u32>,
    ) {
        if let Some(out) = self.out.next() {
            for ((o, &home), &c) in out.iter_mut().zip(homes).zip(checks) {
                *o = decide(home, c);
            }
        }
    }
}

/// [`HashTable::get_many`]'s output: `f(i, value)` for every key `i`, in order.
struct ValueSink<'a, 'f, T, F> {
    values: &'a [T],
    f: &'f mut F,
}

impl<'a, T, F: FnMut(usize, Option<&'a T>)> probe::ChunkSink for ValueSink<'a, '_, T, F> {
    #[inline(always)]
    fn chunk(
        &mut self,
        first: usize,
        homes: &[u32],
        checks: &[u32],
        decide: &impl Fn(u32, u32) -> Option<u32>,
    ) {
        for (i, (&home, &c)) in (first..).zip(homes.iter().zip(checks)) {
            (self.f)(i, decide(home, c).and_then(|s| self.values.get(s as usize)));
        }
    }
}

/// Plain slots that remember whether the claimed slot was a tombstone.
struct TrackingSlots<'a> {
    words: &'a mut [u32],
    claimed_tombstone: bool,
}

impl Slots for TrackingSlots<'_> {
    #[inline(always)]
    fn load(&mut self, slot: u32) -> u32 {
        self.words[slot as usize]
    }
    #[inline(always)]
    fn claim(&mut self, slot: u32, current: u32, checksum: u32) -> Result<(), u32> {
        self.claimed_tombstone = current == TOMBSTONE;
        self.words[slot as usize] = checksum;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use glam::IVec3;

    use super::*;

    fn key(i: i32) -> CellKey {
        CellKey::new(IVec3::new(i, 2 * i, -i), 3, 1)
    }

    /// Each key's index and value, if any.
    type Values = Vec<(usize, Option<[u32; 8]>)>;

    /// `keys`' values as `get_many` hands them on, and as `get` finds them one by one.
    fn get_many_and_get(t: &HashTable<[u32; 8]>, keys: &[CellKey]) -> (Values, Values) {
        let mut got = Vec::new();
        t.get_many(keys, |i, v| got.push((i, v.copied())));
        let want = keys
            .iter()
            .enumerate()
            .map(|(i, k)| (i, t.get(k).copied()))
            .collect();
        (got, want)
    }

    /// A key whose home slot in `table` is `home` (searched).
    fn key_at_home<T: Pod>(table: &HashTable<T>, home: u32, skip: usize) -> CellKey {
        (0..)
            .map(key)
            .filter(|k| table.home_slot(k) == home)
            .nth(skip)
            .unwrap()
    }

    #[test]
    fn constructor_validates() {
        assert_eq!(
            HashTable::<u32>::new(0, 1, BucketHash::Mix).unwrap_err(),
            TableError::CapacityZero
        );
        assert_eq!(
            HashTable::<u32>::new(8, 0, BucketHash::Mix).unwrap_err(),
            TableError::MaxProbesZero
        );
        assert_eq!(
            HashTable::<u32>::new(8, 9, BucketHash::Mix).unwrap_err(),
            TableError::MaxProbesAboveCapacity {
                max_probes: 9,
                capacity: 8
            }
        );
    }

    #[test]
    fn insert_get_remove() {
        let mut t = HashTable::<[f32; 2]>::new(211, 8, BucketHash::Mix).unwrap();
        for i in 0..50 {
            let (v, fresh) = t.entry(&key(i)).unwrap();
            assert!(fresh);
            *v = [i as f32, 1.0];
        }
        assert_eq!(t.len(), 50);
        for i in 0..50 {
            assert_eq!(t.get(&key(i)), Some(&[i as f32, 1.0]));
            assert!(matches!(t.insert_or_get(&key(i)), Insert::Found(_)));
        }
        assert_eq!(t.get(&key(1000)), None);
        assert!(t.remove(&key(7)));
        assert!(!t.remove(&key(7)));
        assert_eq!(t.get(&key(7)), None);
        assert_eq!((t.len(), t.tombstones()), (49, 1));
        for i in (0..50).filter(|&i| i != 7) {
            assert!(t.get(&key(i)).is_some(), "key {i} lost behind a tombstone");
        }
        let (v, fresh) = t.entry(&key(7)).unwrap();
        assert!(fresh && *v == [0.0, 0.0]);
        assert_eq!(t.iter().count(), 50);
        t.clear();
        assert!(t.is_empty() && t.get(&key(3)).is_none());
    }

    #[test]
    fn find_many_equals_find() {
        // Every hash with a modulo (97) and a mask (128) capacity: each has its own copy of
        // the pipelined loop.
        for (hash, cap) in BucketHash::ALL
            .into_iter()
            .flat_map(|h| [(h, 97), (h, 128)])
        {
            let mut t = HashTable::<u32>::new(cap, 8, hash).unwrap();
            for i in 0..40 {
                t.insert_or_get(&key(i));
            }
            // 0..40 are (mostly) in, the rest not. Streams shorter than, as long as and longer
            // than a chunk, up to several chunks plus a partial one (whose stack arrays still
            // hold an earlier chunk's homes past its length); a small capacity puts some
            // windows across the wrap-around.
            let b = HashTable::<u32>::BATCH;
            for n in [0, 1, b - 1, b, b + 1, 2 * b + 75] {
                let keys: Vec<CellKey> = (0..n as i32).map(key).collect();
                let mut out = vec![Some(u32::MAX); keys.len()];
                t.find_many(&keys, &mut out);
                let want: Vec<Option<u32>> = keys.iter().map(|k| t.find(k)).collect();
                assert_eq!(out, want, "{hash:?} {cap} {n} keys");
                if n > 40 {
                    assert!(want[..40].iter().filter(|s| s.is_some()).count() > 30);
                }
            }
        }
    }

    #[test]
    fn get_many_equals_get() {
        // As `find_many_equals_find`, for the values: each key's value is its index, every
        // key is handed to `f` once, in order.
        for (hash, cap) in BucketHash::ALL
            .into_iter()
            .flat_map(|h| [(h, 97), (h, 128)])
        {
            let mut t = HashTable::<[u32; 8]>::new(cap, 8, hash).unwrap();
            for i in 0..60 {
                if let Some((v, _)) = t.entry(&key(i)) {
                    v[3] = i as u32;
                }
            }
            let b = HashTable::<u32>::BATCH;
            for n in [0, 1, b - 1, b, b + 1, 3 * b + 75] {
                let keys: Vec<CellKey> = (0..n as i32).map(key).collect();
                let (got, want) = get_many_and_get(&t, &keys);
                assert_eq!(got, want, "{hash:?} {cap} {n} keys");
                if n > 60 {
                    assert!(want[..60].iter().filter(|(_, v)| v.is_some()).count() > 45);
                    assert!(want[60..].iter().any(|(_, v)| v.is_none()));
                }
            }
        }
    }

    #[test]
    fn find_many_on_a_full_table_and_at_the_last_slot() {
        // Every slot taken: hits are found wherever they sit, misses walk `max_probes` slots
        // (wrapping) and answer None.
        let mut t = HashTable::<u32>::new(16, 16, BucketHash::Mix).unwrap();
        let mut i = 0;
        while t.len() < 16 {
            t.insert_or_get(&key(i));
            i += 1;
        }
        let keys: Vec<CellKey> = (0..i + 20).map(key).collect();
        let mut out = vec![None; keys.len()];
        t.find_many(&keys, &mut out);
        let want: Vec<Option<u32>> = keys.iter().map(|k| t.find(k)).collect();
        assert_eq!(out, want);
        assert_eq!(out.iter().filter(|s| s.is_some()).count(), 16);
        // Keys whose home is the last slot: the second one wraps to slot 0.
        let mut t = HashTable::<u32>::new(16, 4, BucketHash::Mix).unwrap();
        let keys: Vec<CellKey> = (0..2).map(|s| key_at_home(&t, 15, s)).collect();
        for k in &keys {
            t.insert_or_get(k);
        }
        let mut out = [None; 2];
        t.find_many(&keys, &mut out);
        assert_eq!(out, [Some(15), Some(0)]);
        t.find_many(&[], &mut []);
    }

    #[test]
    fn find_many_equals_find_on_a_long_stream() {
        // The chunked loop hashes a full chunk of keys lane by lane (vectorised for `Fold`) and
        // a partial one key by key: a long stream of random keys (negative coordinates, every
        // meta field set), half of them in the table, at load 1/4 and 3/4, with a mask and a
        // modulo capacity, must give `find`'s slots, and `get_many` `get`'s values.
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(21);
        let mut random_key = || {
            CellKey::new(
                IVec3::new(
                    rng.random_range(-3000..3000),
                    rng.random_range(-40..40),
                    rng.random_range(-3000..3000),
                ),
                rng.random_range(0..20),
                rng.random_range(0..7),
            )
            .with_extra(rng.random())
        };
        for hash in BucketHash::ALL {
            for (cap, stored) in [(4096_u32, 1024), (4096, 3072), (4093, 1023)] {
                let mut t = HashTable::<[u32; 8]>::new(cap, 16, hash).unwrap();
                let inserted: Vec<CellKey> = (0..stored).map(|_| random_key()).collect();
                for (i, k) in inserted.iter().enumerate() {
                    if let Some((v, _)) = t.entry(k) {
                        v[5] = i as u32;
                    }
                }
                // Tombstones: every fifth key removed again.
                for k in inserted.iter().step_by(5) {
                    t.remove(k);
                }
                assert!(t.tombstones() > 0);
                // Hits and misses interleaved, 5 003 keys (not a multiple of the chunk).
                let keys: Vec<CellKey> = (0..5003)
                    .map(|i| {
                        if i % 2 == 0 {
                            inserted[(i * 7) % inserted.len()]
                        } else {
                            random_key()
                        }
                    })
                    .collect();
                let mut out = vec![Some(u32::MAX); keys.len()];
                t.find_many(&keys, &mut out);
                let want: Vec<Option<u32>> = keys.iter().map(|k| t.find(k)).collect();
                assert_eq!(out, want, "{hash:?} {cap} {stored}");
                // `find` (inline fast paths for `Fold` with a mask) against the plain walk from
                // the home slot.
                for (k, &slot) in keys.iter().zip(&want) {
                    let (h, c) = hash.hash_and_checksum(k);
                    let walk = probe::find(
                        t.checksums(),
                        |&w| w,
                        &t.indexer,
                        t.max_probes(),
                        t.indexer.index(h),
                        c,
                    );
                    assert_eq!(slot, walk, "{hash:?} {cap} {stored} {k:?}");
                }
                let hits = want.iter().filter(|s| s.is_some()).count();
                assert!(hits > keys.len() / 4 && hits < keys.len() * 2 / 3, "{hits}");
                let (got, want) = get_many_and_get(&t, &keys);
                assert_eq!(got, want, "{hash:?} {cap} {stored}");
            }
        }
    }

    #[test]
    fn find_many_with_fewer_probes_than_a_group() {
        // max_probes 1..=3, below the 4-slot group: `find_many` must not look past the
        // probe limit. Tables nearly full, so keys sit past their home slots and windows wrap.
        for probes in 1..=3 {
            for cap in [13_u32, 16] {
                let mut t = HashTable::<u32>::new(cap, probes, BucketHash::Fold).unwrap();
                for i in 0..200 {
                    t.insert_or_get(&key(i));
                }
                let keys: Vec<CellKey> = (0..300).map(key).collect();
                let mut out = vec![None; keys.len()];
                t.find_many(&keys, &mut out);
                let want: Vec<Option<u32>> = keys.iter().map(|k| t.find(k)).collect();
                assert_eq!(out, want, "{probes} probes, {cap} slots");
                assert!(want.iter().filter(|s| s.is_some()).count() >= cap as usize / 2);
            }
        }
    }

    #[test]
    fn get_on_the_default_path() {
        // `Fold` with a power-of-two capacity: `get`'s inline path without bounds checks. A
        // nearly full table, so keys sit past their home slots and windows wrap past the
        // last slot; every key's value is its own index.
        let mut t = HashTable::<u32>::new(64, 8, BucketHash::Fold).unwrap();
        let keys: Vec<CellKey> = (0..56).map(key).collect();
        let mut stored = Vec::new();
        for (i, k) in keys.iter().enumerate() {
            if let Some((v, _)) = t.entry(k) {
                *v = i as u32;
                stored.push(i);
            }
        }
        assert!(stored.len() > 48);
        let displaced = stored
            .iter()
            .filter(|&&i| t.find(&keys[i]) != Some(t.home_slot(&keys[i])))
            .count();
        assert!(displaced > 10, "{displaced}");
        let wrapped = (0..2)
            .map(|s| key_at_home(&t, 63, s + 100))
            .collect::<Vec<_>>();
        for &i in &stored {
            assert_eq!(t.get(&keys[i]), Some(&(i as u32)), "key {i}");
        }
        for k in (1000..1100).map(key).chain(wrapped) {
            assert_eq!(t.get(&k), t.find(&k).map(|s| &t.values()[s as usize]));
        }
    }

    #[test]
    fn next_slot_behind_a_tombstone() {
        // Two keys with home slot 63 (the last): the first there, the second wrapped to slot 0.
        // With the first removed (a tombstone at home), `get`, `find_many` and `get_many` still
        // find the second through the next-slot compare, and the first is gone.
        let mut t = HashTable::<u32>::new(64, 8, BucketHash::Fold).unwrap();
        let keys: Vec<CellKey> = (0..3).map(|s| key_at_home(&t, 63, s)).collect();
        for (i, k) in keys[..2].iter().enumerate() {
            *t.entry(k).unwrap().0 = i as u32 + 10;
        }
        assert_eq!(t.find(&keys[1]), Some(0));
        assert!(t.remove(&keys[0]));
        assert_eq!(t.get(&keys[1]), Some(&11));
        assert_eq!(t.get(&keys[0]), None);
        assert_eq!(t.get(&keys[2]), None);
        let stream: Vec<CellKey> = keys.iter().copied().cycle().take(40).collect();
        let mut out = vec![None; stream.len()];
        t.find_many(&stream, &mut out);
        let want: Vec<Option<u32>> = stream.iter().map(|k| t.find(k)).collect();
        assert_eq!(out, want);
        assert_eq!(&out[..3], [None, Some(0), None]);
        let mut got = Vec::new();
        t.get_many(&stream, |_, v| got.push(v.copied()));
        assert_eq!(&got[..3], [None, Some(11), None]);
    }

    #[test]
    #[should_panic(expected = "differ in length")]
    fn find_many_checks_lengths() {
        let t = HashTable::<u32>::new(16, 4, BucketHash::Mix).unwrap();
        t.find_many(&[key(1)], &mut []);
    }

    #[test]
    fn full_and_wrap_around() {
        let mut t = HashTable::<u32>::new(16, 4, BucketHash::Mix).unwrap();
        // Five keys with home slot 15: the first takes 15, the next wrap to 0, 1, 2; the fifth
        // finds its four probes taken.
        let keys: Vec<CellKey> = (0..5).map(|s| key_at_home(&t, 15, s)).collect();
        let slots: Vec<Insert> = keys.iter().map(|k| t.insert_or_get(k)).collect();
        assert_eq!(
            slots,
            [
                Insert::Inserted(15),
                Insert::Inserted(0),
                Insert::Inserted(1),
                Insert::Inserted(2),
                Insert::Full
            ]
        );
        assert_eq!(t.find(&keys[3]), Some(2));
        assert_eq!(t.find(&keys[4]), None);
        assert_eq!(t.len(), 4);
        // A table whose every slot is taken answers Full for a new key and Found for old ones.
        let mut t = HashTable::<u32>::new(3, 3, BucketHash::XorPrimes).unwrap();
        let mut inserted = Vec::new();
        let mut i = 0;
        while t.len() < 3 {
            if t.insert_or_get(&key(i)).is_inserted() {
                inserted.push(key(i));
            }
            i += 1;
        }
        assert_eq!(t.insert_or_get(&key(i + 1)), Insert::Full);
        for k in &inserted {
            assert!(matches!(t.insert_or_get(k), Insert::Found(_)));
        }
    }

    #[test]
    fn ages_evict_stale_cells() {
        let mut t = HashTable::<u32>::new(64, 8, BucketHash::Mix)
            .unwrap()
            .with_age_tracking();
        for i in 0..20 {
            t.insert_or_get(&key(i));
        }
        t.advance_frame();
        t.advance_frame();
        for i in 0..5 {
            assert!(t.get_mut(&key(i)).is_some());
        }
        assert_eq!(t.evict_older_than(1), 15);
        assert_eq!(t.len(), 5);
        for i in 0..5 {
            assert!(t.get(&key(i)).is_some());
        }
        for i in 5..20 {
            assert!(t.get(&key(i)).is_none());
        }
        // Without age tracking nothing is evicted.
        let mut plain = HashTable::<u32>::new(8, 8, BucketHash::Mix).unwrap();
        plain.insert_or_get(&key(1));
        plain.advance_frame();
        assert_eq!(plain.evict_older_than(0), 0);
    }

    #[test]
    fn trailing_tombstones_are_trimmed() {
        let mut w = [5, TOMBSTONE, TOMBSTONE, EMPTY, TOMBSTONE, 9, TOMBSTONE];
        // Slot 6 wraps to slot 0 (occupied): kept. Slots 1, 2 precede the empty slot 3: cleared.
        assert_eq!(trim_tombstones(&mut w), 2);
        assert_eq!(w, [5, EMPTY, EMPTY, EMPTY, TOMBSTONE, 9, TOMBSTONE]);
        let mut w = [TOMBSTONE, 4, TOMBSTONE];
        assert_eq!(trim_tombstones(&mut w), 0);
        let mut w = [TOMBSTONE, EMPTY, TOMBSTONE];
        assert_eq!(trim_tombstones(&mut w), 2);
    }
}
