//! Vertex choice: stochastic trilinear interpolation and its jittered-cell twin.
//!
//! MCPG (sec. 4, "Hash Grid") reads and writes states at grid vertices and, "to alleviate
//! block artifacts", picks "a vertex with a probability proportional to the trilinear
//! interpolation weight". For a point `q` in grid units (position / cell width) with
//! `b = ⌊q⌋` and `f = q − b`, corner `c = (cx, cy, cz) ∈ {0,1}³` of the cell is the vertex
//! `b + c` with weight
//!
//! ```text
//! W(c) = Π_{axis} (c_axis ? f_axis : 1 − f_axis)
//! ```
//!
//! Corners are numbered `index = cx + 2·cy + 4·cz` ([`trilinear_weights`]).

use glam::{IVec3, Vec3};

use crate::math::{ONE_MINUS_EPSILON, floor_i32, sanitize_uniform};

/// `⌊q⌋` per component, saturating at the `i32` range (NaN gives 0).
#[inline]
#[must_use]
pub fn floor_ivec3(q: Vec3) -> IVec3 {
    IVec3::new(floor_i32(q.x), floor_i32(q.y), floor_i32(q.z))
}

/// The lower corner `⌊q⌋` and the fractional position `f = q − ⌊q⌋` in [0, 1]³.
///
/// `f` is clamped to [0, 1] (it can round to 1 just below an integer), and it is 0 for NaN
/// and for q beyond the `i32` range (q ≥ 2³¹ or q < −2³¹, where `⌊q⌋` saturates at
/// `i32::MAX` / `i32::MIN`), so the vertex choices below never step past the saturated corner:
/// points beyond the range map to the outermost vertex, never wrap to the opposite end.
#[inline]
#[must_use]
pub fn cell_and_fraction(q: Vec3) -> (IVec3, Vec3) {
    let base = floor_ivec3(q);
    let f = (q - base.as_vec3()).max(Vec3::ZERO).min(Vec3::ONE);
    // Below −2³¹ the clamp already gives 0; at and above 2³¹ (`i32::MAX` reads back as 2³¹),
    // f would be q − 2³¹ > 0 and the upper corner would overflow.
    let f = Vec3::select(q.cmplt(Vec3::splat(I32_RANGE_END)), f, Vec3::ZERO);
    (base, f)
}

/// 2³¹, where `⌊q⌋` leaves the `i32` range.
const I32_RANGE_END: f32 = 2_147_483_648.0;

/// The eight trilinear weights `W(c)` of the corners of a cell for the fractional position `f`,
/// indexed by `cx + 2·cy + 4·cz`. They sum to 1 up to rounding.
#[inline]
#[must_use]
pub fn trilinear_weights(f: Vec3) -> [f32; 8] {
    let g = Vec3::ONE - f;
    core::array::from_fn(|i| {
        let x = if i & 1 != 0 { f.x } else { g.x };
        let y = if i & 2 != 0 { f.y } else { g.y };
        let z = if i & 4 != 0 { f.z } else { g.z };
        x * y * z
    })
}

/// One binary choice of the walk: upper corner with probability `f`, and `u` rescaled to
/// [0, 1) within the chosen part.
#[inline(always)]
fn split(u: f32, f: f32) -> (i32, f32) {
    let lower = 1.0 - f;
    if u < lower {
        (0, (u / lower).min(ONE_MINUS_EPSILON))
    } else {
        (1, ((u - lower) / f).min(ONE_MINUS_EPSILON))
    }
}

/// MCPG's stochastic trilinear vertex choice from **one** uniform `u`: returns the vertex
/// `⌊q⌋ + c` with probability `W(c)`.
///
/// The corner is the one whose interval of the cumulative weights
/// `[Σ_{j<c} W(j), Σ_{j≤c} W(j))`, with corners in the order `index = cx + 2·cy + 4·cz`,
/// contains `u`. Because the weights factor per axis, the walk is done axis by axis (z, then y,
/// then x): `cz = [u ≥ 1 − f_z]`, then `u` is rescaled into the chosen part and the next axis
/// is split the same way. That never picks a corner of weight zero, always picks a corner, and
/// costs three compares and three divides. Each split consumes about −log₂ of the chosen
/// probability in bits of `u`; with 24-bit uniforms the corner probabilities are exact to about
/// 2⁻²¹.
///
/// NaN or negative `u` counts as 0, `u ≥ 1` as the largest f32 below 1; for NaN components of
/// `q`, see [`cell_and_fraction`].
#[inline]
#[must_use]
pub fn stochastic_trilinear(q: Vec3, u: f32) -> IVec3 {
    let (base, f) = cell_and_fraction(q);
    let u = sanitize_uniform(u);
    let (cz, u) = split(u, f.z);
    let (cy, u) = split(u, f.y);
    let (cx, _) = split(u, f.x);
    base + IVec3::new(cx, cy, cz)
}

/// The corner index (`cx + 2·cy + 4·cz`) that [`stochastic_trilinear`] picks for the fractional
/// position `f` ∈ [0, 1]³ and uniform `u`.
#[inline]
#[must_use]
pub fn stochastic_corner(f: Vec3, u: f32) -> usize {
    let u = sanitize_uniform(u);
    let (cz, u) = split(u, f.z);
    let (cy, u) = split(u, f.y);
    let (cx, _) = split(u, f.x);
    (cx + 2 * cy + 4 * cz) as usize
}

/// The jittered-cell alternative: `⌊q + u⌋` for three uniforms `u` ∈ [0, 1)³.
///
/// Per axis `⌊q + u⌋ = ⌊q⌋ + [u ≥ 1 − f]`, which is the upper vertex with probability `f`
/// exactly, independently per axis: the same distribution as [`stochastic_trilinear`]
/// (the box-jittered position rounded down), at the price of three uniforms instead of one and
/// with no division. Components of `u` are sanitised like single uniforms.
#[inline]
#[must_use]
pub fn jittered_vertex(q: Vec3, u: Vec3) -> IVec3 {
    let (base, f) = cell_and_fraction(q);
    let u = Vec3::new(
        sanitize_uniform(u.x),
        sanitize_uniform(u.y),
        sanitize_uniform(u.z),
    );
    // Compare with 1 − f instead of adding u to q: the result is then exact even where q + u
    // would round (large |q|).
    let up = u.cmpge(Vec3::ONE - f);
    base + IVec3::new(
        i32::from(up.test(0)),
        i32::from(up.test(1)),
        i32::from(up.test(2)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_corners_are_the_nearest() {
        let f = Vec3::new(0.2, 0.7, 0.5);
        let w = trilinear_weights(f);
        mcg_test_support::assert_close!(w.iter().sum::<f32>(), 1.0, 1e-6);
        mcg_test_support::assert_close!(w[0], 0.8 * 0.3 * 0.5, 1e-7);
        mcg_test_support::assert_close!(w[7], 0.2 * 0.7 * 0.5, 1e-7);
        // At a vertex the choice is that vertex, whatever u.
        for u in [0.0, 0.3, 0.999_999_9] {
            assert_eq!(
                stochastic_trilinear(Vec3::new(2.0, -3.0, 0.0), u),
                IVec3::new(2, -3, 0)
            );
            assert_eq!(
                jittered_vertex(Vec3::new(2.0, -3.0, 0.0), Vec3::splat(u)),
                IVec3::new(2, -3, 0)
            );
        }
    }

    #[test]
    fn walk_follows_the_cumulative_weights() {
        let f = Vec3::new(0.25, 0.5, 0.75);
        let w = trilinear_weights(f);
        let mut cdf = 0.0;
        for (c, &wc) in w.iter().enumerate() {
            // Points inside each cumulative interval map to that corner.
            for t in [0.01_f32, 0.5, 0.99] {
                assert_eq!(stochastic_corner(f, cdf + t * wc), c, "corner {c}, t {t}");
            }
            cdf += wc;
        }
    }

    #[test]
    fn zero_weight_corners_are_never_chosen() {
        for f in [
            Vec3::ZERO,
            Vec3::ONE,
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.5, 0.0),
        ] {
            let w = trilinear_weights(f);
            for i in 0..1000 {
                let u = i as f32 / 1000.0;
                assert!(w[stochastic_corner(f, u)] > 0.0, "f {f}, u {u}");
            }
            assert!(w[stochastic_corner(f, 1.0)] > 0.0);
            assert!(w[stochastic_corner(f, f32::NAN)] > 0.0);
        }
    }

    #[test]
    fn degenerate_positions_do_not_panic() {
        for q in [
            Vec3::NAN,
            Vec3::INFINITY,
            Vec3::splat(-1e12),
            Vec3::new(-1e-10, 3e9, 0.5),
        ] {
            let _ = stochastic_trilinear(q, 0.5);
            let _ = jittered_vertex(q, Vec3::splat(0.5));
        }
        assert_eq!(stochastic_trilinear(Vec3::NAN, 0.5), IVec3::ZERO);
        // Issue 14 row 7: beyond the i32 range the upper corner overflowed (debug panic;
        // release wrapped to i32::MIN, the opposite end of the grid).
        for (q, want) in [
            (Vec3::new(1e12, 0.0, 0.0), IVec3::new(i32::MAX, 0, 0)),
            (
                Vec3::new(2_147_483_648.0, 0.0, 0.0),
                IVec3::new(i32::MAX, 0, 0),
            ),
            (Vec3::INFINITY, IVec3::MAX),
            (Vec3::NEG_INFINITY, IVec3::MIN),
            (Vec3::splat(-1e12), IVec3::MIN),
            (Vec3::new(-1e-10, 3e9, 0.5), IVec3::new(0, i32::MAX, 0)),
        ] {
            for u in [0.0, 0.5, 0.999_999_9, 1.0] {
                let v = stochastic_trilinear(q, u);
                let j = jittered_vertex(q, Vec3::splat(u));
                assert_eq!((v.x, v.y), (want.x, want.y), "{q} {u}");
                assert_eq!((j.x, j.y), (want.x, want.y), "{q} {u}");
            }
            let (_, f) = cell_and_fraction(q);
            for axis in 0..3 {
                if !(q[axis].abs() < 2_147_483_648.0) {
                    assert_eq!(f[axis], 0.0, "{q}: {f}");
                }
            }
        }
        assert_eq!(
            crate::StaticGrid::mcpg().vertex_key(Vec3::new(1e12, 0.0, 0.0), 0.9),
            crate::CellKey::unclassed(IVec3::new(i32::MAX, 0, 0))
        );
        // Just inside the range: 2³¹ − 128 is an integer, f = 0.
        let (b, f) = cell_and_fraction(Vec3::splat(2_147_483_520.0));
        assert_eq!((b, f), (IVec3::splat(2_147_483_520), Vec3::ZERO));
        // −10⁻¹⁰ + 1 rounds to 1: the point is at vertex 0.
        assert_eq!(
            stochastic_trilinear(Vec3::new(-1e-10, 0.0, 0.0), 0.3),
            IVec3::ZERO
        );
    }

    #[test]
    fn value_stability() {
        let q = Vec3::new(10.3, -4.6, 0.5);
        let picks = [0.0_f32, 0.2, 0.45, 0.7, 0.95].map(|u| stochastic_trilinear(q, u));
        assert_eq!(
            picks,
            [
                IVec3::new(10, -5, 0),
                IVec3::new(10, -5, 0),
                IVec3::new(11, -4, 0),
                IVec3::new(10, -5, 1),
                IVec3::new(11, -4, 1)
            ]
        );
        assert_eq!(
            jittered_vertex(q, Vec3::new(0.8, 0.1, 0.6)),
            IVec3::new(11, -5, 1)
        );
    }
}
