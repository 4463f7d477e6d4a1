//! ADGI's clip volumes (Fig. 6b, sec. 4.4, 4.8): which probes trace pilot rays, which are
//! sampled adaptively, and which get their sample count reset.
//!
//! Fig. 6b: "we call the volume bounded by the blue frustum and black boundary as inner volume
//! V_in. Similarly, outer volume V_out is the volume bounded by green frustum and outer grey
//! boundary. All probes in V_out participate in the heuristic modelling \[pilot rays, sec. 4.4\].
//! Probes inside the blue frustum participate in adaptive sampling \[sec. 4.8\]. We set the probe
//! state N = 16 for all probes outside V_in but inside V_out." Sec. 4.8: "We lower the
//! hysteresis by setting N = 16 for all probes in the region V_out − V_in. This enables the probe
//! to quickly catch-up to the most recent values."
//!
//! A [`ClipVolume`] is a frustum (six planes, e.g. from the camera's view-projection matrix)
//! intersected with an axis-aligned box; [`ClipVolumes`] pairs the inner with the outer one
//! (an expanded frustum and a larger box). The count reset lowers the count N of every texel
//! word of a shell probe to at most [`SHELL_COUNT`] = 16 — lowering, since raising a smaller N
//! to 16 would *raise* the hysteresis, against the paper's intent.

use core::sync::atomic::{AtomicU32, Ordering};

use glam::{Mat4, Vec3, Vec4};
use mcg_color_codec::{IrradianceLayout, IrradianceWord, VisibilityLayout, VisibilityWord};

use crate::{ControlError, LayoutError, ProbeGrid};

/// The count N that sec. 4.8 sets in the shell V_out − V_in.
pub const SHELL_COUNT: u32 = 16;

/// A convex volume bounded by six planes `n · p + d ≥ 0` (inside), normalised so `|n| = 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    planes: [Vec4; 6],
}

impl Frustum {
    /// The six planes `(n, d)` with `n · p + d ≥ 0` inside; each is normalised.
    ///
    /// # Errors
    /// [`ControlError::ClipPlaneInvalid`] for a plane with a NaN or infinite component or a zero
    /// normal.
    pub fn from_planes(planes: [Vec4; 6]) -> Result<Self, ControlError> {
        let mut out = [Vec4::ZERO; 6];
        for (index, (o, p)) in out.iter_mut().zip(planes).enumerate() {
            let len = p.truncate().length();
            if !p.is_finite() || !(len > 0.0) || !len.is_finite() {
                return Err(ControlError::ClipPlaneInvalid { index, plane: p });
            }
            *o = p / len;
        }
        Ok(Self { planes: out })
    }

    /// The frustum of a view-projection matrix (world → clip space) with depth in [0, 1]
    /// (wgpu, D3D, Metal, Vulkan; e.g. `glam::camera::rh::proj::directx::perspective`), by the Gribb-Hartmann plane extraction: with rows r₀…r₃ of the
    /// matrix, left r₃ + r₀, right r₃ − r₀, bottom r₃ + r₁, top r₃ − r₁, near r₂, far r₃ − r₂.
    ///
    /// # Errors
    /// As [`Self::from_planes`] (a singular or non-finite matrix).
    pub fn from_view_projection(m: Mat4) -> Result<Self, ControlError> {
        let r = |i: usize| m.row(i);
        Self::from_planes([
            r(3) + r(0),
            r(3) - r(0),
            r(3) + r(1),
            r(3) - r(1),
            r(2),
            r(3) - r(2),
        ])
    }

    /// The same frustum with every plane pushed out by `margin` (the "extended camera frustum"
    /// of sec. 4.4); a negative margin shrinks it. A NaN margin gives the frustum unchanged.
    #[must_use]
    pub fn expanded(&self, margin: f32) -> Self {
        let margin = if margin.is_nan() { 0.0 } else { margin };
        let mut planes = self.planes;
        for p in &mut planes {
            p.w += margin;
        }
        Self { planes }
    }

    /// The normalised planes.
    #[inline]
    #[must_use]
    pub fn planes(&self) -> &[Vec4; 6] {
        &self.planes
    }

    /// Whether `p` is inside (or on) every plane; `false` for NaN.
    #[inline]
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.truncate().dot(p) + pl.w >= 0.0)
    }
}

/// A frustum intersected with an axis-aligned box `[min, max]` (Fig. 6b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVolume {
    frustum: Frustum,
    min: Vec3,
    max: Vec3,
}

impl ClipVolume {
    /// `frustum ∩ [min, max]`.
    ///
    /// # Errors
    /// [`ControlError::ClipBoxInvalid`] if a bound is NaN or `min > max` on an axis (infinite
    /// bounds are allowed: an unbounded box).
    pub fn new(frustum: Frustum, min: Vec3, max: Vec3) -> Result<Self, ControlError> {
        if !(min.cmple(max).all()) {
            return Err(ControlError::ClipBoxInvalid { min, max });
        }
        Ok(Self { frustum, min, max })
    }

    /// The frustum.
    #[inline]
    #[must_use]
    pub fn frustum(&self) -> &Frustum {
        &self.frustum
    }

    /// The box's corners.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.min, self.max)
    }

    /// Whether `p` is in the box and the frustum.
    #[inline]
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all() && self.frustum.contains(p)
    }
}

/// Where a probe lies with respect to the clip volumes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ClipRegion {
    /// In V_in: pilot rays and adaptive sampling.
    Inner,
    /// In V_out − V_in: pilot rays and the count reset to N ≤ 16.
    Shell,
    /// Outside V_out: untouched this frame.
    Outside,
}

/// ADGI's inner and outer clip volumes (Fig. 6b).
///
/// # Example
/// ```
/// use mcg_probe_cache::clip_volume::{ClipRegion, ClipVolumes};
/// use mcg_probe_cache::glam::{Vec3, camera::rh::{proj::directx::perspective, view::look_at_mat4}};
///
/// let view = look_at_mat4(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y);
/// let proj = perspective(1.0, 16.0 / 9.0, 0.1, 20.0);
/// let lo = Vec3::splat(-4.0);
/// let hi = Vec3::splat(4.0);
/// let clip = ClipVolumes::from_camera(proj * view, (lo, hi), 1.0, (lo - 2.0, hi + 2.0))?;
/// assert_eq!(clip.classify(Vec3::new(0.0, 1.0, 0.0)), ClipRegion::Inner);
/// assert_eq!(clip.classify(Vec3::new(0.0, 1.0, 5.5)), ClipRegion::Shell); // just behind the camera
/// assert_eq!(clip.classify(Vec3::new(0.0, 1.0, 9.0)), ClipRegion::Outside);
/// # Ok::<(), mcg_probe_cache::ProbeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVolumes {
    inner: ClipVolume,
    outer: ClipVolume,
}

impl ClipVolumes {
    /// The pair (V_in, V_out). V_in is meant to lie inside V_out; a point in V_in counts as
    /// [`ClipRegion::Inner`] regardless.
    #[must_use]
    pub fn new(inner: ClipVolume, outer: ClipVolume) -> Self {
        Self { inner, outer }
    }

    /// From a camera: V_in is the view-projection's frustum within `inner_bounds`, V_out the
    /// frustum expanded by `margin` (world units, e.g. one or two probe spacings) within
    /// `outer_bounds`.
    ///
    /// # Errors
    /// [`ControlError::ClipPlaneInvalid`] or [`ControlError::ClipBoxInvalid`] as
    /// [`Frustum::from_view_projection`] and [`ClipVolume::new`].
    pub fn from_camera(
        view_projection: Mat4,
        inner_bounds: (Vec3, Vec3),
        margin: f32,
        outer_bounds: (Vec3, Vec3),
    ) -> Result<Self, ControlError> {
        let f = Frustum::from_view_projection(view_projection)?;
        Ok(Self {
            inner: ClipVolume::new(f, inner_bounds.0, inner_bounds.1)?,
            outer: ClipVolume::new(f.expanded(margin), outer_bounds.0, outer_bounds.1)?,
        })
    }

    /// V_in.
    #[inline]
    #[must_use]
    pub fn inner(&self) -> &ClipVolume {
        &self.inner
    }

    /// V_out.
    #[inline]
    #[must_use]
    pub fn outer(&self) -> &ClipVolume {
        &self.outer
    }

    /// The region of point `p`.
    #[inline]
    #[must_use]
    pub fn classify(&self, p: Vec3) -> ClipRegion {
        if self.inner.contains(p) {
            ClipRegion::Inner
        } else if self.outer.contains(p) {
            ClipRegion::Shell
        } else {
            ClipRegion::Outside
        }
    }

    /// Whether probe position `p` traces pilot rays (in V_out, sec. 4.4).
    #[inline]
    #[must_use]
    pub fn traces_pilots(&self, p: Vec3) -> bool {
        self.classify(p) != ClipRegion::Outside
    }

    /// The region of every probe of `grid`, by linear index, into `out`.
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] unless `out.len() == grid.probe_count()`.
    pub fn classify_grid(
        &self,
        grid: &ProbeGrid,
        out: &mut [ClipRegion],
    ) -> Result<(), LayoutError> {
        LayoutError::check_tables(grid.probe_count(), &[out.len()])?;
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.classify(grid.probe_position(grid.probe_coords(i)));
        }
        Ok(())
    }
}

/// Lowers the count N of every irradiance word in `words` to at most `max_count` (the shell
/// reset of sec. 4.8 with `max_count` = [`SHELL_COUNT`]), keeping the colour. Lock-free
/// (compare-and-swap per word; a word updated concurrently is retried). Returns how many words
/// changed.
pub fn clamp_irradiance_counts(
    words: &[AtomicU32],
    layout: &IrradianceLayout,
    max_count: u32,
) -> usize {
    clamp_counts(
        words,
        max_count,
        |w| layout.count(IrradianceWord(w)),
        |w, n| layout.with_count(IrradianceWord(w), n).0,
    )
}

/// [`clamp_irradiance_counts`] for visibility words.
pub fn clamp_visibility_counts(
    words: &[AtomicU32],
    layout: &VisibilityLayout,
    max_count: u32,
) -> usize {
    clamp_counts(
        words,
        max_count,
        |w| layout.count(VisibilityWord(w)),
        |w, n| layout.with_count(VisibilityWord(w), n).0,
    )
}

fn clamp_counts(
    words: &[AtomicU32],
    max_count: u32,
    count: impl Fn(u32) -> u32,
    with_count: impl Fn(u32, u32) -> u32,
) -> usize {
    let mut changed = 0;
    for w in words {
        let r = w.fetch_update(Ordering::AcqRel, Ordering::Acquire, |old| {
            (count(old) > max_count).then(|| with_count(old, max_count))
        });
        changed += usize::from(r.is_ok());
    }
    changed
}

#[cfg(test)]
mod tests {
    use glam::camera::rh::proj::directx::perspective;
    use glam::camera::rh::view::look_at_mat4;
    use glam::{UVec3, Vec2};

    use super::*;

    fn camera() -> Mat4 {
        // At (0, 0, 10) looking down −z, 90° vertical field of view, aspect 1, near 1, far 100.
        let view = look_at_mat4(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y);
        perspective(core::f32::consts::FRAC_PI_2, 1.0, 1.0, 100.0) * view
    }

    #[test]
    fn frustum_planes_by_hand() {
        let f = Frustum::from_view_projection(camera()).unwrap();
        // 90° fov: the side planes are at 45°; at depth 5 (z = 5) the frustum spans |x| ≤ 5.
        assert!(f.contains(Vec3::new(4.9, 0.0, 5.0)));
        assert!(!f.contains(Vec3::new(5.1, 0.0, 5.0)));
        assert!(f.contains(Vec3::new(0.0, -4.9, 5.0)));
        assert!(!f.contains(Vec3::new(0.0, 0.0, 9.5))); // nearer than the near plane
        assert!(f.contains(Vec3::new(0.0, 0.0, -89.0)));
        assert!(!f.contains(Vec3::new(0.0, 0.0, -91.0))); // beyond far
        assert!(!f.contains(Vec3::NAN));
        // Expanded by 1: the side plane moves out by 1 along its normal (cos 45°):
        // x ≤ 5 + √2 at depth 5.
        let g = f.expanded(1.0);
        assert!(g.contains(Vec3::new(6.4, 0.0, 5.0)));
        assert!(!g.contains(Vec3::new(6.45, 0.0, 5.0)));
        assert!(g.contains(Vec3::new(0.0, 0.0, 9.5))); // nearer than near, within the margin
        for p in f.planes() {
            mcg_test_support::assert_close!(p.truncate().length(), 1.0, 1e-5);
        }
        assert_eq!(
            Frustum::from_view_projection(Mat4::ZERO),
            Err(ControlError::ClipPlaneInvalid {
                index: 0,
                plane: Vec4::ZERO
            })
        );
        assert_eq!(f.expanded(f32::NAN), f);
    }

    #[test]
    fn regions_on_a_grid() {
        let grid = ProbeGrid::new(Vec3::splat(-8.0), Vec3::splat(2.0), UVec3::splat(9)).unwrap();
        let clip = ClipVolumes::from_camera(
            camera(),
            (Vec3::splat(-4.0), Vec3::splat(4.0)),
            2.0,
            (Vec3::splat(-6.0), Vec3::splat(6.0)),
        )
        .unwrap();
        let mut regions = vec![ClipRegion::Outside; grid.probe_count()];
        clip.classify_grid(&grid, &mut regions).unwrap();
        let count = |r| regions.iter().filter(|&&x| x == r).count();
        // V_in: |x|, |y| ≤ 4 by the box; the frustum at z ≤ 4 spans |x| ≤ 6 > 4, so the inner
        // volume is the whole box's probes: x, y, z ∈ {−4, …, 4} = 5³ = 125.
        assert_eq!(count(ClipRegion::Inner), 125);
        // V_out: the box |·| ≤ 6 (7 probes per axis) within the expanded frustum; at z = 6 the
        // expanded frustum spans |x| ≤ 4 + 2√2 ≈ 6.83, so all 7³ = 343 probes are in V_out.
        assert_eq!(count(ClipRegion::Shell), 343 - 125);
        assert_eq!(count(ClipRegion::Outside), 729 - 343);
        assert!(clip.traces_pilots(Vec3::new(6.0, 6.0, 6.0)));
        assert!(!clip.traces_pilots(Vec3::new(8.0, 0.0, 0.0)));
        assert_eq!(clip.inner().bounds().0, Vec3::splat(-4.0));
        assert_eq!(
            clip.outer().frustum(),
            &clip.inner().frustum().expanded(2.0)
        );
        assert!(clip.classify_grid(&grid, &mut regions[1..]).is_err());
        assert!(ClipVolume::new(*clip.inner().frustum(), Vec3::ONE, Vec3::ZERO).is_err());
    }

    #[test]
    fn count_reset_lowers_only() {
        let irr = IrradianceLayout::ADGI;
        let vis = VisibilityLayout::ADGI;
        let colour = Vec3::new(0.5, 0.25, 2.0);
        let words: Vec<AtomicU32> = [3, 16, 40, 63]
            .iter()
            .map(|&n| {
                AtomicU32::new(
                    irr.with_count(irr.encode(colour, 0, mcg_color_codec::Rounding::Nearest), n)
                        .0,
                )
            })
            .collect();
        let before: Vec<Vec3> = words
            .iter()
            .map(|w| irr.decode(IrradianceWord(w.load(Ordering::Relaxed))))
            .collect();
        assert_eq!(clamp_irradiance_counts(&words, &irr, SHELL_COUNT), 2);
        let counts: Vec<u32> = words
            .iter()
            .map(|w| irr.count(IrradianceWord(w.load(Ordering::Relaxed))))
            .collect();
        assert_eq!(counts, [3, 16, 16, 16]);
        for (w, b) in words.iter().zip(before) {
            assert_eq!(irr.decode(IrradianceWord(w.load(Ordering::Relaxed))), b);
        }
        let v = AtomicU32::new(
            vis.encode(Vec2::new(0.3, 0.1), 60, mcg_color_codec::Rounding::Nearest)
                .0,
        );
        assert_eq!(
            clamp_visibility_counts(core::slice::from_ref(&v), &vis, SHELL_COUNT),
            1
        );
        assert_eq!(vis.count(VisibilityWord(v.load(Ordering::Relaxed))), 16);
    }

    #[test]
    fn value_stability() {
        let f = Frustum::from_view_projection(camera()).unwrap();
        let left = f.planes()[0].to_array().map(f32::to_bits);
        let near = f.planes()[4].to_array().map(f32::to_bits);
        // Left: x + (10 − z) ≥ 0 → (1, 0, −1, 10)/√2; near: 10 − z − 1 ≥ 0 → (0, 0, −1, 9).
        assert_eq!(
            (left, near),
            (
                [1060439283, 0, 3207922931, 1088570928],
                [0, 0, 3212836864, 1091567615]
            ),
            "{:?} {:?}",
            f.planes()[0],
            f.planes()[4]
        );
    }
}
