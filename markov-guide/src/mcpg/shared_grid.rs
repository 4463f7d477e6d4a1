//! A hash grid of [`GridState`]s that many threads read and write through `&self`.

use std::vec::Vec;

use core::sync::atomic::{AtomicU32, Ordering, fence};

use mcg_hashgrid::{BucketHash, CellKey, ConcurrentSlots, Located, TableError};

use super::GridState;

/// The words of one [`GridState`] (32 bytes = 8 words) stored as atomics.
const WORDS: usize = 8;

/// One [`GridState`] that many threads load and store at once: its eight words as
/// [`AtomicU32`]s behind a sequence word (a seqlock), 36 bytes.
///
/// # The rule that makes torn writes harmless
/// - A writer first moves the sequence word from an even value s to s + 1 by
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
/// for bit. The words keep [`GridState`]'s `#[repr(C)]` layout word for word
/// ([`SharedGrid::snapshot`] copies them out for upload).
#[derive(Debug, Default)]
pub struct SharedState {
    sequence: AtomicU32,
    words: [AtomicU32; WORDS],
}

impl SharedState {
    /// The state, or `None` when a writer was inside (a torn read).
    #[inline]
    #[must_use]
    pub fn load(&self) -> Option<GridState> {
        let before = self.sequence.load(Ordering::Acquire);
        if before & 1 == 1 {
            return None;
        }
        let raw: [u32; WORDS] = core::array::from_fn(|k| self.words[k].load(Ordering::Relaxed));
        fence(Ordering::Acquire);
        if self.sequence.load(Ordering::Relaxed) != before {
            return None;
        }
        Some(bytemuck::cast(raw))
    }

    /// Writes `state` (all eight words) unless another writer is inside; returns whether it
    /// was written.
    #[inline]
    pub fn store(&self, state: &GridState) -> bool {
        let raw: [u32; WORDS] = bytemuck::cast(*state);
        self.write(|words| {
            for (w, v) in words.iter().zip(raw) {
                w.store(v, Ordering::Relaxed);
            }
        })
    }

    /// Sets w̄ to 0 (the discard heuristic's action, MCPG sec. 5) unless another writer is
    /// inside; returns whether it was written.
    #[inline]
    pub fn clear_weight(&self) -> bool {
        self.write(|words| words[3].store(0, Ordering::Relaxed))
    }

    #[inline]
    fn write(&self, body: impl FnOnce(&[AtomicU32; WORDS])) -> bool {
        let s = self.sequence.load(Ordering::Relaxed);
        if s & 1 == 1
            || self
                .sequence
                .compare_exchange(s, s.wrapping_add(1), Ordering::Relaxed, Ordering::Relaxed)
                .is_err()
        {
            return false;
        }
        fence(Ordering::Release);
        body(&self.words);
        self.sequence.store(s.wrapping_add(2), Ordering::Release);
        true
    }

    /// The state, read with exclusive access (no sequence protocol needed).
    #[must_use]
    pub fn get_mut(&mut self) -> GridState {
        bytemuck::cast(self.words.each_mut().map(|a| *a.get_mut()))
    }

    /// Empties the state (exclusive access).
    pub fn reset(&mut self) {
        for w in &mut self.words {
            *w.get_mut() = 0;
        }
    }
}

/// One grid's states in a lock-free table ([`ConcurrentSlots`] of [`SharedState`]s): MCPG's
/// `grid.load` and `grid.store` through `&self` from many threads, without locks or replay.
///
/// Each slot's checksum, age and state share one 64-byte cache line, so a candidate found in
/// its home slot costs one line: with the checksums, ages and states in three arrays (the
/// GPU's layout, which [`checksums`](ConcurrentSlots::checksums),
/// [`ages`](ConcurrentSlots::ages) and [`snapshot`](Self::snapshot) copy out), a guided CPU
/// frame of `mcg-demo`'s hidden-light room took 2-5 % more time with two threads and 4-8 %
/// more with one, and a frame missed the first-level data cache 1.5 times as often
/// (`benches/README.md`).
#[derive(Debug)]
pub struct SharedGrid {
    table: ConcurrentSlots<SharedState>,
}

impl SharedGrid {
    /// An empty grid of `capacity` slots, probing at most 8, with the default bucket hash.
    ///
    /// # Errors
    /// A [`TableError`] for a capacity below 8.
    pub fn new(capacity: u32) -> Result<Self, TableError> {
        Ok(Self {
            table: ConcurrentSlots::new(capacity, 8, BucketHash::default())?,
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
        self.table
            .evict_older_than(max_age, |_, state| state.reset())
    }

    /// The table: slots, checksums and ages.
    #[must_use]
    pub const fn table(&self) -> &ConcurrentSlots<SharedState> {
        &self.table
    }

    /// The state at `key` and its slot; `None` for a key the table does not hold and for a
    /// torn read (both count as MCPG's collision, Alg. 1 line 6).
    #[inline]
    #[must_use]
    pub fn load(&self, key: &CellKey) -> Option<(GridState, u32)> {
        let slot = self.table.find(key)?;
        Some((self.state(slot)?, slot))
    }

    /// The slot holding `key`, if any (the first half of [`load`](Self::load), for loading
    /// several candidates in one batch: all lookups first, then all states).
    #[inline]
    #[must_use]
    pub fn find(&self, key: &CellKey) -> Option<u32> {
        self.table.find(key)
    }

    /// Where the lookup of `key` starts ([`ConcurrentSlots::locate`]), with the cache line it
    /// will read asked for: the home slot's checksum, age and state (at a low load most keys
    /// sit in their home slot). Locate a vertex's candidates first, then
    /// [`find_located`](Self::find_located) them: their cache misses overlap.
    #[inline]
    #[must_use]
    pub fn locate(&self, key: &CellKey) -> Located {
        self.table.locate(key)
    }

    /// The slot of the key `at` was [`locate`](Self::locate)d for, if any: the same as
    /// [`find`](Self::find) of that key.
    #[inline]
    #[must_use]
    pub fn find_located(&self, at: Located) -> Option<u32> {
        self.table.find_located(at)
    }

    /// The state at `slot`; `None` for a torn read or a slot out of range (the second half
    /// of [`load`](Self::load)).
    #[inline]
    #[must_use]
    pub fn state(&self, slot: u32) -> Option<GridState> {
        self.table.value(slot)?.load()
    }

    /// The state at `slot` written into `out`; `false` (and `out` unchanged) for a torn read.
    #[inline]
    pub(crate) fn load_into(&self, slot: u32, out: &mut GridState) -> bool {
        match self.state(slot) {
            Some(state) => {
                *out = state;
                true
            }
            None => false,
        }
    }

    /// Writes `state` at `key` (claiming a slot if needed). `false` when the probe
    /// neighbourhood is full or another writer holds the slot: the state is dropped.
    #[inline]
    pub fn store(&self, key: &CellKey, state: &GridState) -> bool {
        self.table
            .insert_or_get(key)
            .slot()
            .and_then(|slot| self.table.value(slot))
            .is_some_and(|s| s.store(state))
    }

    /// Zeroes w̄ at `slot` (the discard heuristic).
    #[inline]
    pub fn discard(&self, slot: u32) -> bool {
        self.table
            .value(slot)
            .is_some_and(SharedState::clear_weight)
    }

    /// The states in slot order, for upload beside the table's
    /// [`checksums`](ConcurrentSlots::checksums): the `#[repr(C)]` array the GPU reads
    /// (`bytemuck::cast_slice` gives its bytes). Takes `&mut self`, so no writer is inside.
    #[must_use]
    pub fn snapshot(&mut self) -> Vec<GridState> {
        self.table.values_mut().map(SharedState::get_mut).collect()
    }

    /// Number of occupied slots.
    #[must_use]
    pub fn occupied(&self) -> u32 {
        self.table.count_occupied()
    }

    /// Empties every slot.
    pub fn clear(&mut self) {
        self.table.clear();
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
