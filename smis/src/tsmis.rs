//! Temporal SMIS decorrelation: a cyclic shift of Markov chain states within a tile
//! (MCMM sec. 4.2, Fig. 5 left).

use crate::SmisError;

/// The largest tile this crate's permutations support: one GPU subgroup of 32 lanes
/// ("We choose tile sizes below or equal to 32 pixels", MCMM sec. 4.2).
pub const MAX_TILE_SIZE: u32 = 32;

/// The checks shared by the tile permutations' constructors ([`CyclicShift::new`],
/// [`XorPermutation::new`](crate::XorPermutation::new)), in this order: `size` is not zero
/// ([`SmisError::TileSizeZero`]) and at most [`MAX_TILE_SIZE`]
/// ([`SmisError::TileSizeTooLarge`]); with `power_of_two`, `size` is a power of two
/// ([`SmisError::TileSizeNotPowerOfTwo`]); `offset` (the shift or mask) is below `size`
/// ([`SmisError::OffsetOutOfRange`]).
#[inline]
pub(crate) const fn validate_tile(
    size: u32,
    offset: u32,
    power_of_two: bool,
) -> Result<(), SmisError> {
    if size == 0 {
        return Err(SmisError::TileSizeZero);
    }
    if size > MAX_TILE_SIZE {
        return Err(SmisError::TileSizeTooLarge {
            size,
            maximum: MAX_TILE_SIZE,
        });
    }
    if power_of_two && !size.is_power_of_two() {
        return Err(SmisError::TileSizeNotPowerOfTwo { size });
    }
    if offset >= size {
        return Err(SmisError::OffsetOutOfRange { offset, size });
    }
    Ok(())
}

/// The length check of the tile permutations' `apply`: panics unless a tile of `len` states
/// has the permutation's `size`.
///
/// # Panics
/// If `len` is not `size`.
#[inline]
#[track_caller]
pub(crate) fn assert_tile_len(len: usize, size: u32) {
    assert_eq!(len, size as usize, "tile length is the tile size");
}

/// Lane that lane `lane` receives its state from under a cyclic shift by `shift` in a tile of
/// `size` lanes: `(lane + size − shift mod size) mod size`. The state of lane l moves to lane
/// (l + shift) mod size (MCMM's "shuffle up": shift 1 sends lane l's state to lane l + 1 and
/// rotates the last one back to the first).
///
/// The unchecked building block of [`CyclicShift`] (for GPU twins and tight loops): the caller
/// guarantees `0 < size` (a zero `size` panics, as `% 0` does) and `lane < size`; then the
/// result is `< size`. Any `lane` gives `(lane − shift) mod size`, with no overflow (the sum
/// is formed in u64).
///
/// # Panics
/// If `size == 0`.
#[inline]
#[must_use]
pub const fn cyclic_source_lane(lane: u32, size: u32, shift: u32) -> u32 {
    let size = size as u64;
    ((lane as u64 % size + size - shift as u64 % size) % size) as u32
}

/// A cyclic shift of states within a tile of up to 32 lanes: the decorrelation of temporal SMIS
/// (TSMIS, MCMM sec. 4.2).
///
/// Each lane (pixel) advances its own Markov chain with the sample it draws; the next lobe then
/// depends on that sample, and an SMIS estimator over one lane's history of lobes would be
/// biased (MCMM sec. 4.2, Fig. 16). Shifting the states by one lane after every step makes a
/// lane's history over n ≤ `size` steps consist of n different chains — each (tᵢ, xᵢ) pair from
/// a chain whose other samples are not in this estimator — so the n-sample
/// [`smis`](crate::smis()) over the history is unbiased (MCMM appendix A).
///
/// # Example
/// ```
/// use mcg_smis::CyclicShift;
/// let shift = CyclicShift::new(4, 1)?;
/// let mut states = ['a', 'b', 'c', 'd'];
/// shift.apply(&mut states);
/// assert_eq!(states, ['d', 'a', 'b', 'c']); // lane 1 now holds lane 0's state
/// assert_eq!((shift.source(1), shift.destination(3)), (0, 0));
/// # Ok::<(), mcg_smis::SmisError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CyclicShift {
    size: u32,
    shift: u32,
}

impl CyclicShift {
    /// A shift by `shift` lanes in a tile of `size` lanes.
    ///
    /// Errors: [`SmisError::TileSizeZero`], [`SmisError::TileSizeTooLarge`] (`size` > 32),
    /// [`SmisError::OffsetOutOfRange`] (`shift ≥ size`).
    #[inline]
    pub const fn new(size: u32, shift: u32) -> Result<Self, SmisError> {
        match validate_tile(size, shift, false) {
            Ok(()) => Ok(Self { size, shift }),
            Err(e) => Err(e),
        }
    }

    /// The tile size.
    #[inline]
    #[must_use]
    pub const fn size(&self) -> u32 {
        self.size
    }

    /// The shift.
    #[inline]
    #[must_use]
    pub const fn shift(&self) -> u32 {
        self.shift
    }

    /// The lane whose state `lane` receives; see [`cyclic_source_lane`]. `lane` is taken
    /// modulo the tile size.
    #[inline]
    #[must_use]
    pub const fn source(&self, lane: u32) -> u32 {
        cyclic_source_lane(lane % self.size, self.size, self.shift)
    }

    /// The lane that receives the state of `lane`: `(lane + shift) mod size`.
    #[inline]
    #[must_use]
    pub const fn destination(&self, lane: u32) -> u32 {
        (lane % self.size + self.shift) % self.size
    }

    /// Applies the shift to the states of one tile in place: afterwards `tile[l]` holds what
    /// `tile[self.source(l)]` held.
    ///
    /// # Panics
    /// If `tile.len()` is not the tile size.
    #[inline]
    pub fn apply<X>(&self, tile: &mut [X]) {
        assert_tile_len(tile.len(), self.size);
        tile.rotate_right(self.shift as usize);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exhaustively_a_permutation() {
        for size in 1..=MAX_TILE_SIZE {
            for shift in 0..size {
                let s = CyclicShift::new(size, shift).unwrap();
                let mut hit = 0_u64;
                let mut tile: [u32; 32] = core::array::from_fn(|i| i as u32);
                s.apply(&mut tile[..size as usize]);
                for lane in 0..size {
                    let src = s.source(lane);
                    assert!(src < size);
                    hit |= 1 << src;
                    assert_eq!(s.destination(src), lane);
                    assert_eq!(tile[lane as usize], src, "size {size} shift {shift}");
                }
                assert_eq!(hit, (1_u64 << size) - 1, "size {size} shift {shift}");
            }
        }
    }

    #[test]
    fn validates() {
        assert_eq!(CyclicShift::new(0, 0), Err(SmisError::TileSizeZero));
        assert_eq!(
            CyclicShift::new(33, 1),
            Err(SmisError::TileSizeTooLarge {
                size: 33,
                maximum: 32
            })
        );
        assert_eq!(
            CyclicShift::new(8, 8),
            Err(SmisError::OffsetOutOfRange { offset: 8, size: 8 })
        );
    }

    #[test]
    fn value_stability() {
        // MCMM's shuffle up in a subgroup of 32: lane 0 receives lane 31.
        let s = CyclicShift::new(32, 1).unwrap();
        assert_eq!((s.source(0), s.source(5), s.destination(31)), (31, 4, 0));
        assert_eq!(cyclic_source_lane(2, 5, 3), 4);
    }
}
