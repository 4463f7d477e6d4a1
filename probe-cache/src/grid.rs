//! The probe grid: a regular lattice of irradiance probes (DDGI; ADGI sec. 3.1).
//!
//! Probe `(i, j, k)` sits at `origin + (i, j, k) ⊙ spacing` for `i < counts.x` etc., and is
//! stored at the linear index `i + counts.x · (j + counts.y · k)` (x fastest). A shading point
//! between probes reads the eight corners of the cell that contains it with trilinear weights;
//! points outside the grid are clamped to its boundary cell, as DDGI does.

use glam::{UVec3, Vec3};

use crate::GridError;

/// A regular 3-D lattice of probes: origin, spacing and counts per axis.
///
/// `Copy`, validated at construction, and cheap to pass by value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeGrid {
    origin: Vec3,
    spacing: Vec3,
    counts: UVec3,
}

/// The cell of the probe grid that contains a point, and the point's position inside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeCell {
    /// Coordinates of the cell's lowest corner probe.
    pub base: UVec3,
    /// Position inside the cell in [0, 1]³ (0 on `base`'s faces), the trilinear parameters.
    pub alpha: Vec3,
}

impl ProbeGrid {
    /// A grid of `counts` probes per axis, the first at `origin`, `spacing` apart.
    ///
    /// # Errors
    /// [`GridError::OriginNotFinite`] for a NaN or infinite origin,
    /// [`GridError::SpacingNotPositive`] unless every spacing component is positive and finite,
    /// [`GridError::CountsOutOfRange`] for a zero count or more than `u32::MAX` probes.
    pub fn new(origin: Vec3, spacing: Vec3, counts: UVec3) -> Result<Self, GridError> {
        if !origin.is_finite() {
            return Err(GridError::OriginNotFinite { origin });
        }
        if !(spacing.min_element() > 0.0) || !spacing.is_finite() {
            return Err(GridError::SpacingNotPositive { spacing });
        }
        // In u128: three u32 factors cannot overflow it (u64 could: 2³¹ · 2³¹ · 4 = 2⁶⁴).
        let total = u128::from(counts.x) * u128::from(counts.y) * u128::from(counts.z);
        if counts.min_element() == 0 || total > u128::from(u32::MAX) {
            return Err(GridError::CountsOutOfRange { counts });
        }
        Ok(Self {
            origin,
            spacing,
            counts,
        })
    }

    /// Position of probe `(0, 0, 0)`.
    #[inline]
    #[must_use]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Distance between neighbouring probes along each axis.
    #[inline]
    #[must_use]
    pub fn spacing(&self) -> Vec3 {
        self.spacing
    }

    /// Number of probes along each axis.
    #[inline]
    #[must_use]
    pub fn counts(&self) -> UVec3 {
        self.counts
    }

    /// Total number of probes.
    #[inline]
    #[must_use]
    pub fn probe_count(&self) -> usize {
        (self.counts.x * self.counts.y * self.counts.z) as usize
    }

    /// Length of a cell's diagonal, `|spacing|`: the distance unit of ADGI's visibility
    /// texels (sec. 4.6 normalises distances by the probe cage diagonal).
    #[inline]
    #[must_use]
    pub fn cell_diagonal(&self) -> f32 {
        self.spacing.length()
    }

    /// Linear index of the probe at `coords` (x fastest). `coords` must be inside the grid.
    #[inline]
    #[must_use]
    pub fn probe_index(&self, coords: UVec3) -> usize {
        debug_assert!(
            coords.cmplt(self.counts).all(),
            "probe coordinates outside the grid"
        );
        linear_index(self.counts, coords)
    }

    /// Coordinates of the probe with linear index `index` (the inverse of [`Self::probe_index`]).
    #[inline]
    #[must_use]
    pub fn probe_coords(&self, index: usize) -> UVec3 {
        linear_coords(self.counts, index)
    }

    /// World-space position of the probe at `coords`.
    #[inline]
    #[must_use]
    pub fn probe_position(&self, coords: UVec3) -> Vec3 {
        self.origin + coords.as_vec3() * self.spacing
    }

    /// The cell containing `point`, clamped to the grid (a point outside reads the boundary
    /// cell with `alpha` clamped to [0, 1]). Along an axis with a single probe, `alpha` is 0.
    /// NaN components are treated as the grid origin's.
    #[inline]
    #[must_use]
    pub fn cell(&self, point: Vec3) -> ProbeCell {
        let last_cell = self.counts.saturating_sub(UVec3::splat(2)).as_vec3();
        let t = ((point - self.origin) / self.spacing).max(Vec3::ZERO); // NaN → 0
        let base = t.floor().min(last_cell);
        let single = self.counts.cmpeq(UVec3::ONE);
        let alpha = Vec3::select(single, Vec3::ZERO, (t - base).min(Vec3::ONE));
        ProbeCell {
            base: base.as_uvec3(),
            alpha,
        }
    }

    /// Corner `corner` (bits 0, 1, 2 step along x, y, z) of `cell`: its probe coordinates,
    /// clamped to the grid, and its trilinear weight `Π (alpha or 1 − alpha)`. The eight
    /// weights of a cell sum to 1.
    #[inline]
    #[must_use]
    pub fn corner(&self, cell: ProbeCell, corner: u32) -> (UVec3, f32) {
        let step = UVec3::new(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        // Saturating: a base at u32::MAX (counts near 2³², or a hand-made cell) must not wrap.
        let coords = cell.base.saturating_add(step).min(self.counts - UVec3::ONE);
        let stepped = step.cmpeq(UVec3::ONE);
        let w = Vec3::select(stepped, cell.alpha, Vec3::ONE - cell.alpha);
        (coords, w.x * w.y * w.z)
    }
}

/// Linear index of `coords` in a lattice of `counts` (x fastest): the layout of probes and of
/// proxies.
#[inline]
pub(crate) fn linear_index(counts: UVec3, coords: UVec3) -> usize {
    (coords.x + counts.x * (coords.y + counts.y * coords.z)) as usize
}

/// The inverse of [`linear_index`].
#[inline]
pub(crate) fn linear_coords(counts: UVec3, index: usize) -> UVec3 {
    let index = index as u32;
    let x = index % counts.x;
    let yz = index / counts.x;
    UVec3::new(x, yz % counts.y, yz / counts.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> ProbeGrid {
        ProbeGrid::new(
            Vec3::new(-1.0, 0.0, 2.0),
            Vec3::new(0.5, 1.0, 2.0),
            UVec3::new(4, 3, 2),
        )
        .unwrap()
    }

    #[test]
    fn rejects_bad_parameters() {
        let s = Vec3::ONE;
        let c = UVec3::splat(2);
        assert!(matches!(
            ProbeGrid::new(Vec3::NAN, s, c),
            Err(GridError::OriginNotFinite { origin }) if origin.is_nan()
        ));
        assert_eq!(
            ProbeGrid::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), c),
            Err(GridError::SpacingNotPositive {
                spacing: Vec3::new(1.0, 0.0, 1.0)
            })
        );
        assert!(matches!(
            ProbeGrid::new(Vec3::ZERO, Vec3::splat(f32::NAN), c),
            Err(GridError::SpacingNotPositive { spacing }) if spacing.is_nan()
        ));
        assert_eq!(
            ProbeGrid::new(Vec3::ZERO, Vec3::splat(f32::INFINITY), c),
            Err(GridError::SpacingNotPositive {
                spacing: Vec3::splat(f32::INFINITY)
            })
        );
        assert_eq!(
            ProbeGrid::new(Vec3::ZERO, s, UVec3::new(2, 0, 2)),
            Err(GridError::CountsOutOfRange {
                counts: UVec3::new(2, 0, 2)
            })
        );
        assert_eq!(
            ProbeGrid::new(Vec3::ZERO, s, UVec3::splat(2048)),
            Err(GridError::CountsOutOfRange {
                counts: UVec3::splat(2048)
            })
        );
        // Issue 14 row 13: 2³¹ · 2³¹ · 4 = 2⁶⁴ overflowed the u64 product (debug panic;
        // release accepted the grid with probe_count() == 0).
        for counts in [
            UVec3::new(1 << 31, 1 << 31, 4),
            UVec3::splat(u32::MAX),
            UVec3::new(1 << 16, 1 << 16, 1),
        ] {
            assert_eq!(
                ProbeGrid::new(Vec3::ZERO, s, counts),
                Err(GridError::CountsOutOfRange { counts }),
                "{counts}"
            );
        }
        let g = ProbeGrid::new(Vec3::ZERO, s, UVec3::new(u32::MAX, 1, 1)).unwrap();
        assert_eq!(g.probe_count(), u32::MAX as usize);
    }

    #[test]
    fn index_round_trip() {
        let g = grid();
        assert_eq!(g.probe_count(), 24);
        for i in 0..g.probe_count() {
            assert_eq!(g.probe_index(g.probe_coords(i)), i);
        }
        assert_eq!(g.probe_index(UVec3::new(1, 2, 1)), 1 + 4 * (2 + 3));
        assert_eq!(
            g.probe_position(UVec3::new(1, 2, 1)),
            Vec3::new(-0.5, 2.0, 4.0)
        );
    }

    #[test]
    fn trilinear_weights_sum_to_one_and_interpolate_positions() {
        let g = grid();
        for p in [
            Vec3::new(-0.3, 1.7, 3.1),
            Vec3::new(0.5, 2.0, 4.0),
            Vec3::new(-5.0, 9.0, 2.5),
        ] {
            let cell = g.cell(p);
            let mut sum = 0.0;
            let mut interp = Vec3::ZERO;
            for c in 0..8 {
                let (coords, w) = g.corner(cell, c);
                assert!(coords.cmplt(g.counts()).all());
                sum += w;
                interp += w * g.probe_position(coords);
            }
            mcg_test_support::assert_close!(sum, 1.0, 1e-6);
            let lo = g.origin();
            let hi = g.probe_position(g.counts() - UVec3::ONE);
            assert!(
                (interp - p.clamp(lo, hi)).abs().max_element() < 1e-5,
                "{p} → {interp}"
            );
        }
    }

    #[test]
    fn degenerate_axes_and_nan() {
        let g = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(1, 2, 1)).unwrap();
        let cell = g.cell(Vec3::new(3.0, 0.25, -1.0));
        assert_eq!(cell.base, UVec3::ZERO);
        assert_eq!(cell.alpha, Vec3::new(0.0, 0.25, 0.0));
        let nan = g.cell(Vec3::NAN);
        assert_eq!(nan.base, UVec3::ZERO);
        assert!(nan.alpha.is_finite());
    }
}
