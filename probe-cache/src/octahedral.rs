//! The octahedral sphere ↔ square map of DDGI and the RTXGI SDK, and the exact solid angle of
//! its texels.
//!
//! A unit direction `d` is projected onto the octahedron `|x| + |y| + |z| = 1`; the upper half
//! (`z ≥ 0`) is the square's inner diamond `|u| + |v| ≤ 1`, the lower half is folded out into the
//! four corners (Cigolle et al. 2014, *A Survey of Efficient Representations for Independent Unit
//! Vectors*, JCGT 3(2); used by DDGI, Majercik et al. 2019, and by the RTXGI SDK's
//! `DDGIGetOctahedralCoordinates` / `DDGIGetOctahedralDirection`, whose formulas these are):
//!
//! ```text
//! encode:  (u, v) = (x, y) / (|x| + |y| + |z|);  if z < 0: (u, v) ← (1 − |v|, 1 − |u|) ⊙ sign(u, v)
//! decode:  p = (u, v, 1 − |u| − |v|);             if p.z < 0: (p.x, p.y) ← (1 − |v|, 1 − |u|) ⊙ sign(u, v)
//!          d = p / |p|
//! ```
//!
//! with `sign(0) = +1` (RTXGI's `DDGISignNotZero`).
//!
//! # Solid angle
//! Within one octant the decode is a central (gnomonic) projection of a flat octahedron face, so
//! a straight segment of the square that stays in one octant maps to a great-circle arc. The
//! octant boundaries are the axes `u = 0`, `v = 0` and the fold lines `|u| + |v| = 1`. On the
//! `2n × 2n` grid of half-texels every one of them runs along grid lines or through grid corners
//! only (for any `n`), so every edge of a half-texel lies in one octant and the half-texel is a
//! geodesic spherical quadrilateral, whose area is the sum of two spherical triangles (Van
//! Oosterom & Strackee 1983). [`octahedral_solid_angle`] sums the four half-texels, which is
//! exact up to f32 rounding (for even `n` the texels themselves would do; the split makes odd
//! `n` exact too). The density it integrates is `dω = du dv / |p|³` (the face's Jacobian: `p · (∂p/∂u
//! × ∂p/∂v) = 1`), which the tests integrate numerically as the reference.

use glam::{Vec2, Vec3};

/// `±1` with the sign of `x`, `+1` for `±0` (RTXGI's `DDGISignNotZero`).
#[inline(always)]
fn sign_not_zero(v: Vec2) -> Vec2 {
    Vec2::new(
        if v.x >= 0.0 { 1.0 } else { -1.0 },
        if v.y >= 0.0 { 1.0 } else { -1.0 },
    )
}

/// The octahedral square coordinates `(u, v) ∈ [−1, 1]²` of direction `d` (need not be unit
/// length). A zero or NaN direction maps to `(0, 0)`, the `+z` pole.
#[inline]
#[must_use]
pub fn octahedral_encode(d: Vec3) -> Vec2 {
    let l1 = d.x.abs() + d.y.abs() + d.z.abs();
    if !(l1 > 0.0) || !l1.is_finite() {
        return Vec2::ZERO;
    }
    let uv = Vec2::new(d.x, d.y) / l1;
    let uv = if d.z < 0.0 {
        (Vec2::ONE - Vec2::new(uv.y.abs(), uv.x.abs())) * sign_not_zero(uv)
    } else {
        uv
    };
    uv.clamp(Vec2::NEG_ONE, Vec2::ONE)
}

/// The point of the octahedron `|x| + |y| + |z| = 1` at square coordinates `p ∈ [−1, 1]²`
/// (not normalised; see [`octahedral_decode`]).
#[inline]
#[must_use]
pub fn octahedron_point(p: Vec2) -> Vec3 {
    let p = p.clamp(Vec2::NEG_ONE, Vec2::ONE);
    let z = 1.0 - p.x.abs() - p.y.abs();
    if z < 0.0 {
        let xy = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * sign_not_zero(p);
        Vec3::new(xy.x, xy.y, z)
    } else {
        Vec3::new(p.x, p.y, z)
    }
}

/// The unit direction at octahedral square coordinates `p ∈ [−1, 1]²` (clamped to the square).
#[inline]
#[must_use]
pub fn octahedral_decode(p: Vec2) -> Vec3 {
    octahedron_point(p).normalize()
}

/// Solid angle of the spherical triangle with unit vertices `a`, `b`, `c` (Van Oosterom &
/// Strackee 1983: `tan(Ω/2) = |a · (b × c)| / (1 + a·b + b·c + c·a)`). The triple product is
/// taken on edge vectors, which keeps it accurate for small triangles.
#[inline]
pub(crate) fn spherical_triangle_area(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let triple = (b - a).cross(c - a).dot(a).abs();
    let denom = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * triple.atan2(denom)
}

/// Exact solid angle (up to f32 rounding) of the square region `[lo, hi]` of the octahedral map,
/// whose edges each lie in one octant (true for every half-texel; see the module docs): a
/// geodesic quadrilateral, split into two spherical triangles along the diagonal parallel to
/// its quadrant's fold lines (either diagonal gives the same area for such a quadrilateral).
fn cell_area(lo: Vec2, hi: Vec2) -> f32 {
    let c00 = octahedral_decode(lo);
    let c10 = octahedral_decode(Vec2::new(hi.x, lo.y));
    let c01 = octahedral_decode(Vec2::new(lo.x, hi.y));
    let c11 = octahedral_decode(hi);
    let mid = (lo + hi) * 0.5;
    if mid.x * mid.y >= 0.0 {
        // Quadrants I and III: fold lines u + v = ±1 run along (1, −1); split along c10–c01.
        spherical_triangle_area(c00, c10, c01) + spherical_triangle_area(c11, c01, c10)
    } else {
        // Quadrants II and IV: fold lines u − v = ±1 run along (1, 1); split along c00–c11.
        spherical_triangle_area(c00, c10, c11) + spherical_triangle_area(c00, c11, c01)
    }
}

/// Solid angle of interior texel `(x, y)` of an `n × n` octahedral map (texel `(x, y)` covers
/// `u ∈ [−1 + 2x/n, −1 + 2(x+1)/n]`, likewise `v` with `y`). Exact up to f32 rounding (module
/// docs); the `n²` values sum to 4π. `x`, `y` are meant to be below `n`: larger ones are
/// clamped to `n − 1`, and `n = 0` is treated as 1, so the result is always finite.
#[must_use]
pub fn octahedral_solid_angle(n: u32, x: u32, y: u32) -> f32 {
    let n = n.max(1);
    let (x, y) = (x.min(n - 1), y.min(n - 1));
    let step = 2.0 / n as f32;
    let lo = Vec2::new(-1.0 + step * x as f32, -1.0 + step * y as f32);
    let half = 0.5 * step;
    let mut sum = 0.0;
    for (i, j) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let a = lo + Vec2::new(i * half, j * half);
        sum += cell_area(a, a + Vec2::splat(half));
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn round_trip_direction() {
        crate::test_support::assert_direction_round_trips(
            octahedral_encode,
            octahedral_decode,
            2e-6,
        );
    }

    #[test]
    fn round_trip_square() {
        for i in 0..101 {
            for j in 0..101 {
                let p = Vec2::new(-1.0 + 0.02 * i as f32, -1.0 + 0.02 * j as f32);
                let q = octahedral_encode(octahedral_decode(p));
                // Points on the square's boundary are identified in mirrored pairs.
                let on_edge = p.x.abs() > 0.999 || p.y.abs() > 0.999;
                if !on_edge {
                    assert!((p - q).length() < 1e-5, "{p} → {q}");
                }
            }
        }
    }

    #[test]
    fn degenerate_inputs() {
        assert_eq!(octahedral_encode(Vec3::ZERO), Vec2::ZERO);
        assert_eq!(octahedral_encode(Vec3::NAN), Vec2::ZERO);
        assert_eq!(octahedral_encode(Vec3::INFINITY), Vec2::ZERO);
        assert!(octahedral_decode(Vec2::new(0.0, 3.0)).is_normalized());
        assert!(octahedral_decode(Vec2::new(7.0, -9.0)).is_normalized());
    }

    /// Midpoint integration of `du dv / |p|³` in f64 on `sub × sub` points per texel; the test
    /// takes the Richardson combination (4·I₆₄ − I₃₂)/3, which agrees with the exact areas to
    /// 1.2·10⁻⁶ (relative) on every texel of the 3, 6, 8 and 14 maps.
    fn reference_area(n: u32, x: u32, y: u32, sub: u32) -> f64 {
        let step = 2.0 / n as f64;
        let h = step / sub as f64;
        let mut s = 0.0;
        for a in 0..sub {
            for b in 0..sub {
                let u = -1.0 + step * x as f64 + h * (a as f64 + 0.5);
                let v = -1.0 + step * y as f64 + h * (b as f64 + 0.5);
                let z = 1.0 - u.abs() - v.abs();
                let (px, py) = if z < 0.0 {
                    ((1.0 - v.abs()) * u.signum(), (1.0 - u.abs()) * v.signum())
                } else {
                    (u, v)
                };
                s += h * h / (px * px + py * py + z * z).powf(1.5);
            }
        }
        s
    }

    #[test]
    fn solid_angle_matches_jacobian_integration_and_sums_to_4pi() {
        for n in [3u32, 6, 8, 14] {
            let mut sum = 0.0f64;
            for x in 0..n {
                for y in 0..n {
                    let exact = octahedral_solid_angle(n, x, y) as f64;
                    let reference =
                        (4.0 * reference_area(n, x, y, 64) - reference_area(n, x, y, 32)) / 3.0;
                    mcg_test_support::assert_close!(
                        exact,
                        reference,
                        1e-5 * reference,
                        "n {n} ({x}, {y}): {exact} vs {reference}"
                    );
                    sum += exact;
                }
            }
            mcg_test_support::assert_close!(sum, 4.0 * PI, 2e-5 * 4.0 * PI, "n {n}: {sum}");
        }
    }

    #[test]
    fn value_stability() {
        let p = octahedral_encode(Vec3::new(0.3, -0.5, -0.8));
        assert!((p - Vec2::new(0.6875, -0.8125)).length() < 1e-6, "{p}");
        let d = octahedral_decode(Vec2::new(0.25, 0.5));
        assert!((d - Vec3::new(0.25, 0.5, 0.25) / 0.612_372_4).length() < 1e-6);
        // Centre texel vs corner texel of the 8 × 8 map.
        let centre = octahedral_solid_angle(8, 3, 3);
        let corner = octahedral_solid_angle(8, 0, 0);
        mcg_test_support::assert_close!(centre, 0.140_693, 1e-5, "{centre}");
        // The texels at the ±z vertices are congruent, and smaller than those at face centres.
        mcg_test_support::assert_close!(corner, centre, 1e-6);
        assert!(octahedral_solid_angle(8, 5, 5) > 2.0 * centre);
    }
}
