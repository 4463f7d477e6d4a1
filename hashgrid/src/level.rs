//! Level choice of the adaptive grid, and the static grid of fixed cell width.

use glam::{IVec3, Vec3};

use crate::constants::{
    DEFAULT_LEVEL_POWER, DEFAULT_LEVEL_STEPS, DEFAULT_MIN_WIDTH, DEFAULT_STATIC_WIDTH,
    DEFAULT_TAN_HALF_ANGLE, MAX_LEVEL,
};
use crate::error::GridError;
use crate::key::{CellKey, normal_class};
use crate::math::{self, sanitize_uniform};
use crate::trilinear::stochastic_trilinear;

/// Parameters of the adaptive grid's level choice; validated by [`AdaptiveGrid::new`].
///
/// The defaults ([`LevelParams::MCPG`]) are MCPG's system: an angular resolution of 0.6°
/// (MCPG sec. 6), a finest width of 0.01 scene units, and widths growing by 4 every 4 levels
/// (√2 per level), as in merian-quake.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelParams {
    /// tan(α/2) of the angular resolution α a cell should subtend from the camera.
    pub tan_half_angle: f32,
    /// Width of level 0, the finest cells, in scene units (`w_min`).
    pub min_width: f32,
    /// Width ratio over `steps` levels (`POWER` > 1).
    pub power: f32,
    /// Levels per factor `power` in width (`STEPS` ≥ 1).
    pub steps: u32,
    /// Highest level; chosen levels are clamped to it (≤ [`MAX_LEVEL`] = 255).
    pub max_level: u32,
}

impl LevelParams {
    /// MCPG's defaults: tan(0.3°), 0.01, 4, 4, 255 (see [`constants`](crate::constants)).
    pub const MCPG: LevelParams = LevelParams {
        tan_half_angle: DEFAULT_TAN_HALF_ANGLE,
        min_width: DEFAULT_MIN_WIDTH,
        power: DEFAULT_LEVEL_POWER,
        steps: DEFAULT_LEVEL_STEPS,
        max_level: MAX_LEVEL,
    };
}

impl Default for LevelParams {
    fn default() -> Self {
        Self::MCPG
    }
}

/// MCPG's adaptive grid: a cell width that follows the camera distance, so that cells keep a
/// roughly constant projected size (MCPG sec. 4, "Hash Grid"), and a geometric jitter towards
/// coarser levels (sec. 4, Step 1: "an exponential distribution is sampled to select a level
/// that is coarser than the target level").
///
/// With `d` the distance from the camera:
///
/// ```text
/// w(d)      = 2 · tan(α/2) · d                                       target cell width
/// level(d)  = round(STEPS · ln(max(w, w_min)/w_min) / ln POWER) + ⌊−log₂(1 − ξ)⌋
/// width(l)  = w_min · POWER^(l / STEPS)
/// ```
///
/// clamped to `max_level`. `⌊−log₂(1 − ξ)⌋` for a uniform ξ is k with probability 2^−(k+1)
/// ([`geometric_jitter`]).
///
/// The widths of all levels are tabulated once in [`new`](Self::new) (1 KiB), so that
/// [`width`](Self::width) and [`vertex_key`](Self::vertex_key) cost a load, not an `exp`.
#[derive(Clone, Copy, PartialEq)]
pub struct AdaptiveGrid {
    params: LevelParams,
    /// STEPS / ln POWER.
    levels_per_ln: f32,
    /// `w_min · exp(level · ln POWER / STEPS)` for every level up to [`MAX_LEVEL`]; levels
    /// above `max_level` hold `max_level`'s width.
    widths: [f32; MAX_LEVEL as usize + 1],
}

impl core::fmt::Debug for AdaptiveGrid {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        // The width table is a function of the parameters.
        f.debug_struct("AdaptiveGrid")
            .field("params", &self.params)
            .finish_non_exhaustive()
    }
}

impl AdaptiveGrid {
    /// Validates `params`: tan(α/2) and `min_width` positive and finite, `power` finite and
    /// above 1, `steps` ≥ 1, `max_level` ≤ 255, and both the width ratio
    /// `POWER^(max_level/STEPS)` and the coarsest width `w_min · POWER^(max_level/STEPS)`
    /// below e^88.5 ≈ 2.7·10³⁸ (MCPG's defaults reach
    /// 2.4·10³⁶; with 255 levels, POWER^(1/STEPS) up to about 1.6 fits for w_min = 0.01).
    ///
    /// # Errors
    /// The [`GridError`] variant named for the first broken condition;
    /// [`GridError::CoarsestWidthNotFinite`] for the last one.
    pub fn new(params: LevelParams) -> Result<Self, GridError> {
        if !(params.tan_half_angle > 0.0 && params.tan_half_angle.is_finite()) {
            return Err(GridError::TanHalfAngleNotPositive {
                tan_half_angle: params.tan_half_angle,
            });
        }
        if !(params.min_width > 0.0 && params.min_width.is_finite()) {
            return Err(GridError::WidthNotPositive {
                width: params.min_width,
            });
        }
        if !(params.power > 1.0 && params.power.is_finite()) {
            return Err(GridError::PowerNotAboveOne {
                power: params.power,
            });
        }
        if params.steps == 0 {
            return Err(GridError::StepsZero);
        }
        if params.max_level > MAX_LEVEL {
            return Err(GridError::MaxLevelTooLarge {
                max_level: params.max_level,
                maximum: MAX_LEVEL,
            });
        }
        let ln_power = math::ln(params.power);
        // `width` evaluates w_min · exp(level · ln POWER / STEPS): both the exponential (the
        // width ratio) and the product (the coarsest width) must stay finite.
        let ln_ratio = params.max_level as f32 * (ln_power / params.steps as f32);
        let ln_coarsest = math::ln(params.min_width) + ln_ratio;
        if !(ln_ratio < LN_WIDTH_MAX && ln_coarsest < LN_WIDTH_MAX) {
            return Err(GridError::CoarsestWidthNotFinite { params });
        }
        let ln_per_level = ln_power / params.steps as f32;
        let mut widths = [0.0; MAX_LEVEL as usize + 1];
        for (level, w) in widths.iter_mut().enumerate() {
            let level = (level as u32).min(params.max_level);
            *w = params.min_width * math::exp(level as f32 * ln_per_level);
        }
        Ok(Self {
            params,
            levels_per_ln: params.steps as f32 / ln_power,
            widths,
        })
    }

    /// The grid with MCPG's defaults ([`LevelParams::MCPG`]).
    #[must_use]
    pub fn mcpg() -> Self {
        Self::new(LevelParams::MCPG).expect("the defaults are valid")
    }

    /// The parameters.
    #[must_use]
    pub const fn params(&self) -> &LevelParams {
        &self.params
    }

    /// Target cell width `2 · tan(α/2) · distance`; 0 at distance 0 for every valid tan(α/2)
    /// (the product is formed as `tan(α/2) · distance · 2`, the same bits wherever it does not
    /// overflow, so a huge tan(α/2) at distance 0 gives 0, not ∞ · 0 = NaN).
    #[inline]
    #[must_use]
    pub fn target_width(&self, distance: f32) -> f32 {
        self.params.tan_half_angle * distance * 2.0
    }

    /// The level without jitter: `round(STEPS · ln(max(w, w_min)/w_min) / ln POWER)`, clamped
    /// to `max_level`; non-decreasing in `distance`.
    ///
    /// Distances that are NaN, negative or so small that `w < w_min` give level 0; +∞ gives
    /// `max_level`. Rounding is half up.
    #[inline]
    #[must_use]
    pub fn target_level(&self, distance: f32) -> u32 {
        let w = self.target_width(distance).max(self.params.min_width);
        let x = math::ln(w / self.params.min_width) * self.levels_per_ln;
        // x ≥ 0 (or +∞); the cast saturates.
        ((x + 0.5) as u32).min(self.params.max_level)
    }

    /// The level with MCPG's jitter: [`target_level`](Self::target_level) plus
    /// [`geometric_jitter`]`(xi)`, clamped to `max_level`.
    #[inline]
    #[must_use]
    pub fn level(&self, distance: f32, xi: f32) -> u32 {
        (self.target_level(distance) + geometric_jitter(xi)).min(self.params.max_level)
    }

    /// Cell width of `level`: `w_min · POWER^(level/STEPS)` (evaluated as
    /// `w_min · exp(level · ln POWER / STEPS)` once per level in [`new`](Self::new), then
    /// read from a table). Levels above `max_level` are treated as `max_level`, so the width
    /// is always finite.
    #[inline]
    #[must_use]
    pub fn width(&self, level: u32) -> f32 {
        self.widths[level.min(self.params.max_level) as usize]
    }

    /// The key of a grid vertex near `position` for a surface with normal `normal` seen from
    /// `camera`: the level from [`level`](Self::level)`(|camera − position|, xi_level)`, a
    /// corner of the enclosing cell from [`stochastic_trilinear`]`(position / width, u_corner)`,
    /// and the class [`normal_class`]`(normal)` — MCPG's `grid.load`/`grid.store` position for
    /// the adaptive grid.
    #[inline]
    #[must_use]
    pub fn vertex_key(
        &self,
        position: Vec3,
        normal: Vec3,
        camera: Vec3,
        xi_level: f32,
        u_corner: f32,
    ) -> CellKey {
        let level = self.level(camera.distance(position), xi_level);
        let vertex = stochastic_trilinear(position / self.width(level), u_corner);
        CellKey::new(vertex, level as u8, normal_class(normal))
    }
}

impl Default for AdaptiveGrid {
    fn default() -> Self {
        Self::mcpg()
    }
}

/// ln of the largest width ratio and coarsest width [`AdaptiveGrid::new`] accepts: 88.5, so
/// both (e^88.5 ≈ 2.7·10³⁸) and the rounding of `exp` stay below `f32::MAX` ≈ e^88.72 (MCPG's
/// defaults have a ratio of 4^63.75 = e^88.4).
const LN_WIDTH_MAX: f32 = 88.5;

/// `⌊−log₂(1 − ξ)⌋`: the number of extra, coarser levels, k with probability 2^−(k+1)
/// (a geometric distribution with p = ½; mean 1).
///
/// Computed exactly from the bits of `1 − ξ` (exponent and whether the mantissa is zero), with
/// no logarithm, so CPU and GPU agree bit for bit. For ξ on the 2⁻²⁴ grid of f32 uniforms the
/// probabilities are exact; the result is at most 24. NaN and negative ξ count as 0, ξ ≥ 1 as
/// the largest f32 below 1.
#[inline]
#[must_use]
pub fn geometric_jitter(xi: f32) -> u32 {
    let y = 1.0 - sanitize_uniform(xi); // in [2⁻²⁴, 1], a normal float
    let bits = y.to_bits();
    let exponent = 127 - ((bits >> 23) & 0xFF); // −(e) ≥ 0 for y = m · 2^e, m ∈ [1, 2)
    exponent - u32::from(bits & 0x007F_FFFF != 0)
}

/// Probability that [`geometric_jitter`] of a uniform ξ returns `k`: 2^−(k+1) (for k ≤ 23;
/// k = 24 has 2⁻²⁴ for f32 uniforms, the rest of the tail).
#[must_use]
pub fn geometric_jitter_probability(k: u32) -> f64 {
    match k {
        // 2^−n exactly, without `powi` (not in `core`, so not in `no_std` builds).
        0..=23 => 1.0 / (1u64 << (k + 1)) as f64,
        24 => 1.0 / (1u64 << 24) as f64,
        _ => 0.0,
    }
}

/// MCPG's static grid: one fixed cell width everywhere, no levels and no normal in the key
/// (MCPG sec. 4: "a coarse hash grid with a constant cell width, which we refer to as the
/// static grid").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StaticGrid {
    width: f32,
}

impl StaticGrid {
    /// A static grid with cells `width` wide (positive and finite).
    pub fn new(width: f32) -> Result<Self, GridError> {
        if !(width > 0.0 && width.is_finite()) {
            return Err(GridError::WidthNotPositive { width });
        }
        Ok(Self { width })
    }

    /// The static grid with merian-quake's cell width of 25 scene units.
    #[must_use]
    pub fn mcpg() -> Self {
        Self {
            width: DEFAULT_STATIC_WIDTH,
        }
    }

    /// The cell width.
    #[must_use]
    pub const fn width(&self) -> f32 {
        self.width
    }

    /// The key of a grid vertex near `position`: [`stochastic_trilinear`] at `position / width`
    /// with `u_corner`, as an [`unclassed`](CellKey::unclassed) key (level 0, no normal class).
    #[inline]
    #[must_use]
    pub fn vertex_key(&self, position: Vec3, u_corner: f32) -> CellKey {
        CellKey::unclassed(stochastic_trilinear(position / self.width, u_corner))
    }

    /// The cell containing `position` (the vertex at its lower corner), without jitter.
    #[inline]
    #[must_use]
    pub fn cell(&self, position: Vec3) -> IVec3 {
        crate::trilinear::floor_ivec3(position / self.width)
    }
}

impl Default for StaticGrid {
    fn default() -> Self {
        Self::mcpg()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn constructors_validate() {
        let ok = LevelParams::MCPG;
        let bad = |f: fn(&mut LevelParams)| {
            let mut p = ok;
            f(&mut p);
            AdaptiveGrid::new(p).unwrap_err()
        };
        assert!(matches!(
            bad(|p| p.tan_half_angle = f32::NAN),
            GridError::TanHalfAngleNotPositive { tan_half_angle } if tan_half_angle.is_nan()
        ));
        assert_eq!(
            bad(|p| p.tan_half_angle = 0.0),
            GridError::TanHalfAngleNotPositive {
                tan_half_angle: 0.0
            }
        );
        assert_eq!(
            bad(|p| p.min_width = -1.0),
            GridError::WidthNotPositive { width: -1.0 }
        );
        assert_eq!(
            bad(|p| p.min_width = f32::INFINITY),
            GridError::WidthNotPositive {
                width: f32::INFINITY
            }
        );
        assert_eq!(
            bad(|p| p.power = 1.0),
            GridError::PowerNotAboveOne { power: 1.0 }
        );
        assert!(matches!(
            bad(|p| p.power = f32::NAN),
            GridError::PowerNotAboveOne { power } if power.is_nan()
        ));
        assert_eq!(bad(|p| p.steps = 0), GridError::StepsZero);
        assert_eq!(
            bad(|p| p.max_level = 256),
            GridError::MaxLevelTooLarge {
                max_level: 256,
                maximum: 255
            }
        );
        // Issue 14 row 8: power 10¹⁰ per level was accepted and width(level 25) was +∞.
        assert_eq!(
            bad(|p| {
                p.power = 1e10;
                p.steps = 1;
            }),
            GridError::CoarsestWidthNotFinite {
                params: LevelParams {
                    power: 1e10,
                    steps: 1,
                    ..ok
                }
            }
        );
        let e = bad(|p| p.min_width = 1e38);
        assert!(
            matches!(e, GridError::CoarsestWidthNotFinite { params } if params.min_width == 1e38)
        );
        assert_eq!(
            e.to_string(),
            "coarsest cell width 100000000000000000000000000000000000000 * 4^(255/4) overflows f32"
        );
        let wide = AdaptiveGrid::new(LevelParams {
            tan_half_angle: f32::MAX,
            ..ok
        })
        .unwrap();
        assert_eq!(wide.target_width(0.0), 0.0);
        assert_eq!(wide.target_level(0.0), 0);
        // A tiny w_min does not excuse a ratio whose exp overflows (found by scripts/fuzz).
        assert_eq!(
            bad(|p| {
                p.min_width = 1e-45;
                p.power = 1e20;
                p.steps = 43;
                p.max_level = 83;
            }),
            GridError::CoarsestWidthNotFinite {
                params: LevelParams {
                    min_width: 1e-45,
                    power: 1e20,
                    steps: 43,
                    max_level: 83,
                    ..ok
                }
            }
        );
        let g = AdaptiveGrid::new(LevelParams {
            power: 1e10,
            steps: 1,
            max_level: 3,
            ..ok
        })
        .unwrap();
        for level in [0, 3, 4, 255, u32::MAX] {
            let w = g.width(level);
            assert!(w.is_finite() && w > 0.0, "{level}: {w}");
        }
        assert_eq!(g.width(u32::MAX), g.width(3));
        let w = g.width(g.level(1e30, 0.999_999_9));
        assert!(w.is_finite(), "{w}");
        assert!(AdaptiveGrid::new(ok).is_ok());
        assert_eq!(
            StaticGrid::new(0.0),
            Err(GridError::WidthNotPositive { width: 0.0 })
        );
        assert!(matches!(
            StaticGrid::new(f32::NAN),
            Err(GridError::WidthNotPositive { width }) if width.is_nan()
        ));
        assert_eq!(StaticGrid::new(2.0).unwrap().width(), 2.0);
    }

    #[test]
    fn levels_follow_distance_and_widths() {
        let g = AdaptiveGrid::mcpg();
        // w < w_min up to d = 0.01 / (2 · 0.005236) ≈ 0.955.
        assert_eq!(g.target_level(0.5), 0);
        assert_eq!(g.target_level(-3.0), 0);
        assert_eq!(g.target_level(f32::NAN), 0);
        assert_eq!(g.target_level(f32::INFINITY), 255);
        // Width 4× w_min at d ≈ 3.82 → level 4; the chosen width matches the target within √2.
        for d in [2.0_f32, 3.82, 10.0, 100.0, 1e4] {
            let l = g.target_level(d);
            let ratio = g.width(l) / g.target_width(d);
            assert!(
                (0.84..1.19).contains(&ratio),
                "d = {d}: level {l}, ratio {ratio}"
            );
        }
        assert_eq!(g.width(0), 0.01);
        mcg_test_support::assert_close!(g.width(4) / 0.04, 1.0, 1e-6);
        mcg_test_support::assert_close!(g.width(8) / 0.16, 1.0, 1e-6);
    }

    #[test]
    fn jitter_is_exact_at_the_boundaries() {
        assert_eq!(geometric_jitter(0.0), 0);
        assert_eq!(geometric_jitter(0.499_999_94), 0);
        // Off the 2⁻²⁴ grid 1 − ξ rounds: 1 − (0.5 − 2⁻²⁵) is a tie that rounds to 0.5.
        assert_eq!(geometric_jitter(0.499_999_97), 1);
        assert_eq!(geometric_jitter(0.5), 1);
        assert_eq!(geometric_jitter(0.75), 2);
        assert_eq!(geometric_jitter(0.874_999_94), 2);
        assert_eq!(geometric_jitter(0.875), 3);
        assert_eq!(geometric_jitter(1.0 - f32::EPSILON / 2.0), 24);
        assert_eq!(geometric_jitter(1.0), 24);
        assert_eq!(geometric_jitter(f32::NAN), 0);
        assert_eq!(geometric_jitter(-1.0), 0);
        let total: f64 = (0..30).map(geometric_jitter_probability).sum();
        mcg_test_support::assert_close!(total, 1.0, 1e-15);
        let g = AdaptiveGrid::mcpg();
        assert_eq!(g.level(f32::INFINITY, 0.99), 255);
        assert_eq!(g.level(10.0, 0.6), g.target_level(10.0) + 1);
    }

    #[test]
    fn vertex_keys_carry_level_and_class() {
        let g = AdaptiveGrid::mcpg();
        let p = Vec3::new(1.3, -2.2, 5.0);
        let key = g.vertex_key(
            p,
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.3, -2.2, 15.0),
            0.2,
            0.5,
        );
        assert_eq!(key.level as u32, g.target_level(10.0));
        assert_eq!(key.class, 5);
        let w = g.width(key.level as u32);
        assert!((key.cell.as_vec3() * w - p).abs().max_element() <= w);
        let s = StaticGrid::mcpg();
        assert_eq!(s.cell(Vec3::new(-1.0, 30.0, 49.9)), IVec3::new(-1, 1, 1));
        assert_eq!(s.vertex_key(Vec3::splat(0.1), 0.0).cell, IVec3::ZERO);
    }

    #[test]
    fn value_stability() {
        let g = AdaptiveGrid::mcpg();
        let levels: [u32; 5] = [1.0, 7.5, 42.0, 300.0, 5000.0].map(|d| g.target_level(d));
        assert_eq!(levels, [0, 6, 11, 17, 25]);
        let widths = [1, 5, 17].map(|l| g.width(l));
        // 0.01 · √2^l (std and libm `exp` may differ in the last bit).
        for (w, want) in widths
            .iter()
            .zip([0.014_142_136_f32, 0.056_568_54, 3.620_387_3])
        {
            mcg_test_support::assert_close!(w / want, 1.0, 4.0 * f32::EPSILON);
        }
    }
}
