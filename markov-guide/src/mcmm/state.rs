//! The per-pixel chain state of MCMM (Table 1) and the frame buffers that hold it.

use bytemuck::{Pod, Zeroable};
use mcg_vmf::glam::Vec3;
use mcg_vmf::{MapPrior, SufficientStats, Vmf};

#[cfg(feature = "std")]
use crate::BufferError;

/// MCMM's Markov chain state S = (ȳ, r̄, w̄, N, f) of one pixel (Dittebrandt et al. 2023,
/// Table 1): the sufficient statistics of the vMF fit and the score f, a one-sample estimate of
/// the pixel's direct illumination used for acceptance and resampling.
///
/// 28 bytes, `#[repr(C)]` + [`Pod`]: all zeros is the empty state, so zeroed GPU memory is a
/// buffer of empty chains.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PixelState {
    /// ȳ, r̄, w̄ and N.
    pub stats: SufficientStats,
    /// f, the score: lum(L_e · f_r)/p(ω) of the sample that last advanced this state (Alg. 3 l. 1).
    pub score: f32,
}

const _: () = assert!(core::mem::size_of::<PixelState>() == 28);

impl PixelState {
    /// The empty state ({0} in Alg. 3 line 6).
    pub const EMPTY: Self = Self {
        stats: SufficientStats::EMPTY,
        score: 0.0,
    };

    /// `true` when the state carries a lobe: w̄ > 0 (MCMM sec. 4.1, "valid"), with a finite
    /// target and a finite, non-negative score.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.stats.is_valid()
            && self.stats.weight_sum.is_finite()
            && self.stats.mean_target.is_finite()
            && self.score >= 0.0
            && self.score.is_finite()
    }

    /// The resampling score of Alg. 1, score(S) = S.f, or 0 for an invalid state.
    #[inline]
    #[must_use]
    pub fn resampling_score(&self) -> f32 {
        if self.is_valid() { self.score } else { 0.0 }
    }

    /// The lobe at shading point `x` (Alg. 2 lines 5-8) with the fixed prior `prior`, `None`
    /// for an invalid state or when ȳ coincides with `x`.
    #[inline]
    #[must_use]
    pub fn lobe(&self, x: Vec3, prior: MapPrior) -> Option<Vmf> {
        if !self.is_valid() {
            return None;
        }
        self.stats.to_vmf(x, prior)
    }

    /// The lobe at shading point `x` with MCMM's prior policy ([`McmmPrior`](super::McmmPrior)),
    /// which may depend on the distance |ȳ − x|.
    #[inline]
    #[must_use]
    pub fn lobe_with(&self, x: Vec3, prior: &super::McmmPrior) -> Option<Vmf> {
        self.lobe(x, prior.at_distance(self.stats.target_distance(x)))
    }
}

/// The previous-frame and current-frame state buffers of a `width × height` image (MCMM sec. 4.1:
/// neighbours are read from the states written in the last frame).
#[cfg(feature = "std")]
#[derive(Clone, Debug, PartialEq)]
pub struct PixelStateBuffers {
    width: u32,
    height: u32,
    previous: std::vec::Vec<PixelState>,
    current: std::vec::Vec<PixelState>,
}

#[cfg(feature = "std")]
impl PixelStateBuffers {
    /// Two buffers of empty states, 2 × 28 bytes per pixel.
    ///
    /// # Errors
    /// [`BufferError::DimensionAboveMax`] when `width` or `height` exceeds `i32::MAX` (pixels
    /// are addressed with `i32` coordinates) or the two buffers would exceed `isize::MAX` bytes;
    /// [`BufferError::AllocationFailed`] when the allocator cannot provide them (instead of
    /// aborting the process).
    pub fn new(width: u32, height: u32) -> Result<Self, BufferError> {
        let too_large = BufferError::DimensionAboveMax { width, height };
        if width > i32::MAX as u32 || height > i32::MAX as u32 {
            return Err(too_large);
        }
        let n = (width as usize)
            .checked_mul(height as usize)
            .filter(|&n| {
                n.checked_mul(2 * core::mem::size_of::<PixelState>())
                    .is_some_and(|bytes| bytes <= isize::MAX as usize)
            })
            .ok_or(too_large)?;
        let buffer = || {
            let mut v = std::vec::Vec::new();
            v.try_reserve_exact(n)
                .map_err(|source| BufferError::AllocationFailed { states: n, source })?;
            v.resize(n, PixelState::EMPTY);
            Ok(v)
        };
        Ok(Self {
            width,
            height,
            previous: buffer()?,
            current: buffer()?,
        })
    }

    /// Image width in pixels.
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.width
    }

    /// Image height in pixels.
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.height
    }

    fn index(&self, x: i32, y: i32) -> Option<usize> {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return None;
        }
        Some(y as usize * self.width as usize + x as usize)
    }

    /// The previous frame's state at pixel `(x, y)`, `None` off screen.
    #[must_use]
    pub fn previous(&self, x: i32, y: i32) -> Option<PixelState> {
        self.index(x, y).map(|i| self.previous[i])
    }

    /// The previous frame's state that pixel `pixel` sees at screen offset `offset`, after the
    /// motion correction: the state at `pixel + offset + motion`, rounded to the nearest pixel,
    /// where `motion` maps this frame's pixel to its position in the previous frame
    /// (MCMM Alg. 1 line 4). `None` off screen or for a non-finite position.
    #[must_use]
    pub fn neighbour(
        &self,
        pixel: (i32, i32),
        offset: mcg_vmf::glam::Vec2,
        motion: mcg_vmf::glam::Vec2,
    ) -> Option<PixelState> {
        let q = mcg_vmf::glam::Vec2::new(pixel.0 as f32, pixel.1 as f32) + offset + motion;
        if !q.is_finite() {
            return None;
        }
        let q = q.round();
        if q.x.abs() > 1.0e9 || q.y.abs() > 1.0e9 {
            return None;
        }
        self.previous(q.x as i32, q.y as i32)
    }

    /// Writes this frame's state of pixel `(x, y)` (ignored off screen).
    pub fn set_current(&mut self, x: i32, y: i32, state: PixelState) {
        if let Some(i) = self.index(x, y) {
            self.current[i] = state;
        }
    }

    /// This frame's states, row-major, ready to upload (`bytemuck::cast_slice`).
    #[must_use]
    pub fn current(&self) -> &[PixelState] {
        &self.current
    }

    /// The previous frame's states, row-major.
    #[must_use]
    pub fn previous_states(&self) -> &[PixelState] {
        &self.previous
    }

    /// Ends the frame: this frame's states become the previous frame's.
    pub fn swap(&mut self) {
        core::mem::swap(&mut self.previous, &mut self.current);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeroed_state_is_empty_and_invalid() {
        let zero: PixelState = bytemuck::Zeroable::zeroed();
        assert_eq!(zero, PixelState::EMPTY);
        assert!(!zero.is_valid());
        assert_eq!(zero.resampling_score(), 0.0);
        assert_eq!(zero.lobe(Vec3::ZERO, MapPrior::NONE), None);
    }

    #[test]
    fn poisoned_states_are_invalid() {
        let mut s = PixelState::EMPTY;
        s.stats.weight_sum = 1.0;
        s.stats.sample_count = 1;
        s.stats.mean_target = Vec3::Z;
        s.score = 1.0;
        assert!(s.is_valid());
        for bad in [f32::NAN, f32::INFINITY, -1.0] {
            let mut t = s;
            t.score = bad;
            assert!(!t.is_valid());
            let mut t = s;
            t.stats.mean_target.x = bad;
            assert_eq!(t.is_valid(), bad == -1.0);
        }
    }

    #[cfg(feature = "std")]
    #[test]
    fn buffers_swap_and_clip() {
        use mcg_vmf::glam::Vec2;
        let mut b = PixelStateBuffers::new(4, 3).unwrap();
        let mut s = PixelState::EMPTY;
        s.score = 2.0;
        b.set_current(3, 2, s);
        b.set_current(4, 2, s); // off screen: ignored
        b.swap();
        assert_eq!(b.previous(3, 2), Some(s));
        assert_eq!(b.previous(-1, 0), None);
        assert_eq!(
            b.neighbour((1, 1), Vec2::new(1.6, 0.0), Vec2::new(0.2, 0.9)),
            Some(s)
        );
        assert_eq!(
            b.neighbour((1, 1), Vec2::new(f32::NAN, 0.0), Vec2::ZERO),
            None
        );
        assert_eq!(b.neighbour((1, 1), Vec2::new(1e30, 0.0), Vec2::ZERO), None);
        assert_eq!(
            bytemuck::cast_slice::<PixelState, u8>(b.previous_states()).len(),
            12 * 28
        );
    }

    #[cfg(feature = "std")]
    #[test]
    fn oversized_buffers_are_an_error() {
        // Issue 14: `new(u32::MAX, 1)` aborted the process on a 120 GB allocation.
        assert_eq!(
            PixelStateBuffers::new(u32::MAX, 1),
            Err(BufferError::DimensionAboveMax {
                width: u32::MAX,
                height: 1
            })
        );
        assert_eq!(
            PixelStateBuffers::new(1, 1 << 31),
            Err(BufferError::DimensionAboveMax {
                width: 1,
                height: 1 << 31
            })
        );
        // 2³¹ − 1 pixels square is 1.3·10²⁰ bytes: above isize::MAX on every target.
        assert_eq!(
            PixelStateBuffers::new(i32::MAX as u32, i32::MAX as u32),
            Err(BufferError::DimensionAboveMax {
                width: i32::MAX as u32,
                height: i32::MAX as u32
            })
        );
        let b = PixelStateBuffers::new(0, 5).unwrap();
        assert_eq!(b.previous(0, 0), None);
    }
}
