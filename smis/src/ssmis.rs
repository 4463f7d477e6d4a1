//! Spatial SMIS decorrelation: a random xor-mask permutation of Markov chain states within a
//! tile (MCMM sec. 4.2, Fig. 5 right).

use crate::SmisError;
use crate::technique::select_uniform;
use crate::tsmis::{assert_tile_len, validate_tile};

/// Lane that lane `lane` takes its state from under the xor permutation with `mask`:
/// `lane ^ mask`. An involution, so it is also the lane that receives `lane`'s state.
///
/// The unchecked building block of [`XorPermutation`]: a permutation of 0..size exactly when
/// `size` is a power of two and `mask < size`.
#[inline]
#[must_use]
pub const fn xor_source_lane(lane: u32, mask: u32) -> u32 {
    lane ^ mask
}

/// The xor-mask permutation of states within a power-of-two tile of up to 32 lanes: the
/// stratified technique selection of spatial SMIS (SSMIS, MCMM sec. 4.2: "we implement the
/// permutation by xoring a random mask on the subgroup invocation id").
///
/// With the mask drawn uniformly from 0..size, lane l samples from the state of lane l ⊕ mask,
/// which is uniformly distributed over the tile for every l, and every state is sampled by
/// exactly one lane (no state is lost to duplicate selections, and the sample can advance the
/// chain it came from). Each lane then evaluates the one-sample estimator
/// [`smis_one_sample`](crate::smis_one_sample) over all states of the tile (MCMM eq. 9).
///
/// # Example
/// ```
/// use mcg_smis::XorPermutation;
/// let p = XorPermutation::from_uniform(4, 0.8)?; // mask ⌊0.8·4⌋ = 3
/// let mut states = ['a', 'b', 'c', 'd'];
/// p.apply(&mut states);
/// assert_eq!(states, ['d', 'c', 'b', 'a']);
/// assert_eq!(p.source(1), 2);
/// # Ok::<(), mcg_smis::SmisError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct XorPermutation {
    size: u32,
    mask: u32,
}

impl XorPermutation {
    /// The permutation l ↦ l ⊕ `mask` of a tile of `size` lanes.
    ///
    /// Errors: [`SmisError::TileSizeZero`], [`SmisError::TileSizeTooLarge`] (`size` > 32),
    /// [`SmisError::TileSizeNotPowerOfTwo`], [`SmisError::OffsetOutOfRange`] (`mask ≥ size`).
    #[inline]
    pub const fn new(size: u32, mask: u32) -> Result<Self, SmisError> {
        match validate_tile(size, mask, true) {
            Ok(()) => Ok(Self { size, mask }),
            Err(e) => Err(e),
        }
    }

    /// The permutation with mask ⌊u·size⌋ (clamped to size − 1): uniform over all masks for a
    /// uniform `u` ∈ [0, 1). Errors as [`new`](Self::new).
    #[inline]
    pub fn from_uniform(size: u32, u: f32) -> Result<Self, SmisError> {
        // Validate the size first so that `select_uniform` never sees 0.
        let checked = Self::new(size, 0)?;
        Ok(Self {
            mask: select_uniform(size as usize, u) as u32,
            ..checked
        })
    }

    /// The tile size.
    #[inline]
    #[must_use]
    pub const fn size(&self) -> u32 {
        self.size
    }

    /// The mask.
    #[inline]
    #[must_use]
    pub const fn mask(&self) -> u32 {
        self.mask
    }

    /// The lane whose state `lane` takes (and, the permutation being an involution, the lane
    /// that takes `lane`'s state). `lane` is taken modulo the tile size.
    #[inline]
    #[must_use]
    pub const fn source(&self, lane: u32) -> u32 {
        xor_source_lane(lane % self.size, self.mask)
    }

    /// Applies the permutation to the states of one tile in place: afterwards `tile[l]` holds
    /// what `tile[l ^ mask]` held.
    ///
    /// # Panics
    /// If `tile.len()` is not the tile size.
    #[inline]
    pub fn apply<X>(&self, tile: &mut [X]) {
        assert_tile_len(tile.len(), self.size);
        for lane in 0..self.size {
            let other = lane ^ self.mask;
            if other > lane {
                tile.swap(lane as usize, other as usize);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tsmis::MAX_TILE_SIZE;

    #[test]
    fn exhaustively_a_permutation() {
        let mut size = 1;
        while size <= MAX_TILE_SIZE {
            for mask in 0..size {
                let p = XorPermutation::new(size, mask).unwrap();
                let mut tile: [u32; 32] = core::array::from_fn(|i| i as u32);
                p.apply(&mut tile[..size as usize]);
                let mut hit = 0_u64;
                for lane in 0..size {
                    let src = p.source(lane);
                    assert!(src < size);
                    hit |= 1 << src;
                    assert_eq!(p.source(src), lane, "involution");
                    assert_eq!(tile[lane as usize], src, "size {size} mask {mask}");
                }
                assert_eq!(hit, (1_u64 << size) - 1, "size {size} mask {mask}");
            }
            size *= 2;
        }
    }

    #[test]
    fn xor_is_no_permutation_of_other_sizes() {
        // Why `new` insists on powers of two: for every other size some mask leaves the tile.
        for size in 1..=MAX_TILE_SIZE {
            let closed = (0..size).all(|mask| (0..size).all(|l| xor_source_lane(l, mask) < size));
            assert_eq!(closed, size.is_power_of_two(), "size {size}");
            assert_eq!(XorPermutation::new(size, 0).is_ok(), size.is_power_of_two());
        }
    }

    #[test]
    fn validates_and_draws_uniform_masks() {
        assert_eq!(XorPermutation::new(0, 0), Err(SmisError::TileSizeZero));
        assert_eq!(
            XorPermutation::new(64, 0),
            Err(SmisError::TileSizeTooLarge {
                size: 64,
                maximum: 32
            })
        );
        assert_eq!(
            XorPermutation::new(12, 0),
            Err(SmisError::TileSizeNotPowerOfTwo { size: 12 })
        );
        assert_eq!(
            XorPermutation::new(8, 8),
            Err(SmisError::OffsetOutOfRange { offset: 8, size: 8 })
        );
        assert_eq!(
            XorPermutation::from_uniform(0, 0.5),
            Err(SmisError::TileSizeZero)
        );
        for (u, mask) in [(0.0, 0), (0.124, 0), (0.125, 1), (0.99, 7), (1.0, 7)] {
            assert_eq!(XorPermutation::from_uniform(8, u).unwrap().mask(), mask);
        }
    }

    #[test]
    fn value_stability() {
        let p = XorPermutation::new(32, 21).unwrap();
        assert_eq!((p.source(0), p.source(10), p.source(31)), (21, 31, 10));
    }
}
