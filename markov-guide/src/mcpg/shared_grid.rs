//! A hash grid of [`GridState`]s that many threads read and write through `&self`.

use std::boxed::Box;
use std::vec::Vec;

use core::sync::atomic::{AtomicU32, Ordering, fence};

use mcg_hashgrid::{BucketHash, CellKey, ConcurrentTable, Located, TableError};

use super::GridState;

/// The words of one [`GridState`] (32 bytes = 8 words) stored as atomics.
const WORDS: usize = 8;

/// One slot: the state's words and its sequence word in one 64-byte cache line, so that a
/// load touches one line besides the checksum.
#[repr(C, align(64))]
#[derive(Debug)]
struct Slot {
    words: [AtomicU32; WORDS],
    sequence: AtomicU32,
}

impl Slot {
    fn empty() -> Self {
        Self {
            words: core::array::from_fn(|_| AtomicU32::new(0)),
            sequence: AtomicU32::new(0),
        }
    }
}

/// Per-slot [`GridState`]s that many threads load and store at once, each state as eight
/// [`AtomicU32`] words behind a sequence word (a seqlock).
///
/// # The rule that makes torn writes harmless
/// - A writer first moves the slot's sequence word from an even value s to s + 1 by
///   compare-and-swap. When the word is odd (another writer is inside) or the swap fails, the
///   store is **dropped**: MCPG's stores are overwrites at a randomly chosen vertex anyway (the
///   GPU's racing writes lose one of two states the same way). Then the eight words, then the
///   sequence word s + 2 with release ordering.
/// - A reader loads the sequence word (acquire), the eight words, an acquire fence and the
///   sequence word again. Unless both are the same even value, the read was torn and counts as
///   a miss: the empty state, w̄ = 0, exactly as a hash collision reads in MCPG Alg. 1 line 7.
///
/// So a reader sees either a state some writer wrote whole, or nothing. With one thread no
/// store is ever dropped and no read ever misses: single-threaded runs are deterministic bit
/// for bit. The states keep [`GridState`]'s `#[repr(C)]` layout word for word
/// ([`SharedStates::snapshot`] copies them out for upload); on the CPU each state and its
/// sequence word share one 64-byte cache line (64 bytes per slot).
#[derive(Debug)]
pub struct SharedStates {
    slots: Box<[Slot]>,
}

impl SharedStates {
    /// `len` empty states.
    #[must_use]
    pub fn new(len: usize) -> Self {
        Self {
            slots: (0..len).map(|_| Slot::empty()).collect(),
        }
    }

    /// The number of slots.
    #[must_use]
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// `true` when there are no slots.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// The state at `slot`, or `None` when a writer was inside (a torn read) or `slot` is out
    /// of range.
    #[inline]
    #[must_use]
    pub fn load(&self, slot: u32) -> Option<GridState> {
        let Slot { words, sequence } = self.slots.get(slot as usize)?;
        let before = sequence.load(Ordering::Acquire);
        if before & 1 == 1 {
            return None;
        }
        let raw: [u32; WORDS] = core::array::from_fn(|k| words[k].load(Ordering::Relaxed));
        fence(Ordering::Acquire);
        if sequence.load(Ordering::Relaxed) != before {
            return None;
        }
        Some(bytemuck::cast(raw))
    }

    /// [`load`](Self::load) into `out`: `false`, with `out` unchanged, for a torn read or a
    /// slot out of range.
    #[inline]
    pub(crate) fn load_into(&self, slot: u32, out: &mut GridState) -> bool {
        match self.load(slot) {
            Some(state) => {
                *out = state;
                true
            }
            None => false,
        }
    }

    /// Asks for the cache line of the state at `slot` (a prefetch hint; nothing for a slot
    /// out of range).
    #[inline]
    pub fn prefetch(&self, slot: u32) {
        if let Some(s) = self.slots.get(slot as usize) {
            mcg_hashgrid::prefetch_line(s);
        }
    }

    /// Writes `state` at `slot` (all eight words) unless another writer is inside; returns
    /// whether it was written.
    #[inline]
    pub fn store(&self, slot: u32, state: &GridState) -> bool {
        let raw: [u32; WORDS] = bytemuck::cast(*state);
        self.write(slot, |words| {
            for (w, v) in words.iter().zip(raw) {
                w.store(v, Ordering::Relaxed);
            }
        })
    }

    /// Sets w̄ of the state at `slot` to 0 (the discard heuristic's action, MCPG sec. 5),
    /// unless another writer is inside; returns whether it was written.
    #[inline]
    pub fn clear_weight(&self, slot: u32) -> bool {
        self.write(slot, |words| words[3].store(0, Ordering::Relaxed))
    }

    #[inline]
    fn write(&self, slot: u32, body: impl FnOnce(&[AtomicU32; WORDS])) -> bool {
        let Some(Slot { words, sequence }) = self.slots.get(slot as usize) else {
            return false;
        };
        let s = sequence.load(Ordering::Relaxed);
        if s & 1 == 1
            || sequence
                .compare_exchange(s, s.wrapping_add(1), Ordering::Relaxed, Ordering::Relaxed)
                .is_err()
        {
            return false;
        }
        fence(Ordering::Release);
        body(words);
        sequence.store(s.wrapping_add(2), Ordering::Release);
        true
    }

    /// Empties `slot` (exclusive access, no sequence protocol needed).
    pub fn reset(&mut self, slot: u32) {
        if let Some(Slot { words, .. }) = self.slots.get_mut(slot as usize) {
            for w in words.iter_mut() {
                *w.get_mut() = 0;
            }
        }
    }

    /// Every state, copied in slot order: the `#[repr(C)]` array to upload to the GPU
    /// (`bytemuck::cast_slice` gives its bytes). Takes `&mut self`, so no writer is inside.
    #[must_use]
    pub fn snapshot(&mut self) -> Vec<GridState> {
        self.slots
            .iter_mut()
            .map(|s| bytemuck::cast(s.words.each_mut().map(|a| *a.get_mut())))
            .collect()
    }
}

/// One grid's slot index ([`ConcurrentTable`]) and its states ([`SharedStates`]): MCPG's
/// `grid.load` and `grid.store` through `&self` from many threads, without locks or replay.
#[derive(Debug)]
pub struct SharedGrid {
    table: ConcurrentTable,
    states: SharedStates,
}

impl SharedGrid {
    /// An empty grid of `capacity` slots, probing at most 8, with the mixing hash.
    ///
    /// # Errors
    /// A [`TableError`] for a capacity below 8.
    pub fn new(capacity: u32) -> Result<Self, TableError> {
        Ok(Self {
            table: ConcurrentTable::new(capacity, 8, BucketHash::default())?,
            states: SharedStates::new(capacity as usize),
        })
    }

    /// The same grid with an age per slot (each lookup and store marks its slot as used),
    /// so that [`evict_older_than`](Self::evict_older_than) can free slots of vertices that
    /// are no longer visited.
    #[must_use]
    pub fn with_age_tracking(mut self) -> Self {
        self.table = self.table.with_age_tracking();
        self
    }

    /// Moves the age counter to the next frame and empties every slot not used in the last
    /// `max_age` frames (the table then takes new keys there); returns how many. Without age
    /// tracking it only returns 0.
    pub fn evict_older_than(&mut self, max_age: u32) -> u32 {
        self.table.advance_frame();
        let states = &mut self.states;
        self.table
            .evict_older_than(max_age, |slot| states.reset(slot))
    }

    /// The slot index.
    #[must_use]
    pub const fn table(&self) -> &ConcurrentTable {
        &self.table
    }

    /// The state at `key` and its slot; `None` for a key the table does not hold and for a
    /// torn read (both count as MCPG's collision, Alg. 1 line 6).
    #[inline]
    #[must_use]
    pub fn load(&self, key: &CellKey) -> Option<(GridState, u32)> {
        let slot = self.table.find(key)?;
        Some((self.states.load(slot)?, slot))
    }

    /// The slot holding `key`, if any (the first half of [`load`](Self::load), for loading
    /// several candidates in one batch: all lookups first, then all states).
    #[inline]
    #[must_use]
    pub fn find(&self, key: &CellKey) -> Option<u32> {
        self.table.find(key)
    }

    /// Where the lookup of `key` starts ([`ConcurrentTable::locate`]), with the cache lines it
    /// will read asked for: the home slot's checksum word and its state (at a low load most
    /// keys sit in their home slot). Locate a vertex's candidates first, then
    /// [`find_located`](Self::find_located) them: their cache misses overlap.
    #[inline]
    #[must_use]
    pub fn locate(&self, key: &CellKey) -> Located {
        let at = self.table.locate(key);
        self.states.prefetch(at.home());
        at
    }

    /// The slot of the key `at` was [`locate`](Self::locate)d for, if any: the same as
    /// [`find`](Self::find) of that key.
    #[inline]
    #[must_use]
    pub fn find_located(&self, at: Located) -> Option<u32> {
        self.table.find_located(at)
    }

    /// The state at `slot`; `None` for a torn read (the second half of [`load`](Self::load)).
    #[inline]
    #[must_use]
    pub fn state(&self, slot: u32) -> Option<GridState> {
        self.states.load(slot)
    }

    /// The state at `slot` written into `out`; `false` (and `out` unchanged) for a torn read.
    #[inline]
    pub(crate) fn load_into(&self, slot: u32, out: &mut GridState) -> bool {
        self.states.load_into(slot, out)
    }

    /// Writes `state` at `key` (claiming a slot if needed). `false` when the probe
    /// neighbourhood is full or another writer holds the slot: the state is dropped.
    #[inline]
    pub fn store(&self, key: &CellKey, state: &GridState) -> bool {
        match self.table.insert_or_get(key).slot() {
            Some(slot) => self.states.store(slot, state),
            None => false,
        }
    }

    /// Zeroes w̄ at `slot` (the discard heuristic).
    #[inline]
    pub fn discard(&self, slot: u32) -> bool {
        self.states.clear_weight(slot)
    }

    /// The states in slot order, for upload beside [`ConcurrentTable::checksums`].
    #[must_use]
    pub fn snapshot(&mut self) -> Vec<GridState> {
        self.states.snapshot()
    }

    /// Number of occupied slots.
    #[must_use]
    pub fn occupied(&self) -> u32 {
        self.table.count_occupied()
    }

    /// Empties every slot.
    pub fn clear(&mut self) {
        self.table.clear();
        for slot in 0..self.states.len() as u32 {
            self.states.reset(slot);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcpg::resampling::tests::state_towards;
    use mcg_hashgrid::glam::{IVec3, Vec3};

    #[test]
    fn states_round_trip_and_discard_clears_the_weight() {
        let grid = SharedGrid::new(64).unwrap();
        let key = CellKey::new(IVec3::new(1, 2, 3), 4, 5);
        assert_eq!(grid.load(&key), None);
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 3.0);
        assert!(grid.store(&key, &s));
        let (back, slot) = grid.load(&key).unwrap();
        assert_eq!(back, s);
        assert!(grid.discard(slot));
        let (cleared, _) = grid.load(&key).unwrap();
        assert_eq!(cleared.weight_sum, 0.0);
        assert_eq!(cleared.mean_target, s.mean_target);
    }

    /// Hypothesis: under concurrent stores of whole states a reader sees only states some
    /// writer wrote (each writer writes states whose eight words all derive from one number),
    /// never a mixture. 4 threads × 20 000 stores and loads on 4 slots; any mixed read fails.
    #[test]
    fn idle_slots_are_evicted_and_reused() {
        let mut grid = SharedGrid::new(8).unwrap().with_age_tracking();
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 3.0);
        let keys: Vec<CellKey> = (0..4)
            .map(|i| CellKey::new(IVec3::new(i, 0, 0), 0, 0))
            .collect();
        assert!(keys.iter().all(|k| grid.store(k, &s)));
        assert_eq!(grid.evict_older_than(4), 0);
        // Key 0 stays in use; the others go idle and are evicted after more than 4 frames.
        for _ in 0..5 {
            assert!(grid.load(&keys[0]).is_some());
            grid.evict_older_than(4);
        }
        assert_eq!(grid.occupied(), 1);
        assert_eq!(grid.load(&keys[1]), None);
        assert!(grid.store(&keys[1], &s));
        assert_eq!(grid.load(&keys[1]).unwrap().0, s);
    }

    #[test]
    fn readers_never_see_torn_states() {
        let grid = SharedGrid::new(16).unwrap();
        let keys: Vec<CellKey> = (0..4)
            .map(|i| CellKey::new(IVec3::new(i, 0, 0), 0, 0))
            .collect();
        let state_of = |v: u32| -> GridState {
            let f = v as f32 + 1.0;
            let mut s = GridState::EMPTY;
            s.mean_target = Vec3::splat(f);
            s.weight_sum = f;
            s.one_minus_mean_cosine = f;
            s.time = f;
            s
        };
        let (mut mixed, mut seen) = (0u32, 0u32);
        std::thread::scope(|scope| {
            let handles: Vec<_> = (0..4u32)
                .map(|t| {
                    let (grid, keys) = (&grid, &keys);
                    scope.spawn(move || {
                        let (mut mixed, mut seen) = (0u32, 0u32);
                        for i in 0..20_000u32 {
                            let key = &keys[(i % 4) as usize];
                            grid.store(key, &state_of(t * 100_000 + i));
                            if let Some((s, _)) = grid.load(&keys[((i + t) % 4) as usize]) {
                                seen += 1;
                                let f = s.weight_sum;
                                if s.mean_target != Vec3::splat(f)
                                    || s.time != f
                                    || s.one_minus_mean_cosine != f
                                {
                                    mixed += 1;
                                }
                            }
                        }
                        (mixed, seen)
                    })
                })
                .collect();
            for h in handles {
                let (m, s) = h.join().unwrap();
                mixed += m;
                seen += s;
            }
        });
        assert_eq!(mixed, 0);
        assert!(seen > 0);
    }
}
