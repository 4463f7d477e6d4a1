//! Clarberg's equal-area sphere ↔ square map (Clarberg 2008, *Fast Equal-Area Mapping of the
//! (Hemi)Sphere using SIMD*, JGT 13(3); the form of pbrt-v4's `EqualAreaSquareToSphere` /
//! `EqualAreaSphereToSquare`), on the same `[−1, 1]²` square and with the same octant layout and
//! edge folding as the octahedral map, so the same texel grid, border rule and bilinear lookup
//! serve both.
//!
//! ```text
//! decode (u, v) → d:  r = 1 − |1 − |u| − |v||,   φ = π/4 · ((|v| − |u|)/r + 1)   (φ = π/4 at r = 0)
//!                     z = sign(1 − |u| − |v|) · (1 − r²)
//!                     (x, y) = r √(2 − r²) · (cos φ · sign u, sin φ · sign v)
//! encode d → (u, v):  r = √(1 − |z|),   φ' = (2/π) · atan(min(|x|,|y|) / max(|x|,|y|)), φ' ← 1 − φ' if |x| < |y|
//!                     v' = φ' r,  u' = r − v';  if z < 0: (u', v') ← (1 − v', 1 − u');  (u, v) = (u', v') ⊙ sign(x, y)
//! ```
//!
//! The map is area-preserving: `dω = π du dv` (the square has area 4, the sphere 4π), so every
//! texel of an `n × n` grid has the solid angle `4π / n²` exactly ([`equal_area_solid_angle`]).

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3};

/// The equal-area square coordinates `(u, v) ∈ [−1, 1]²` of direction `d` (need not be unit
/// length). A zero or NaN direction maps to `(0, 0)`, the `+z` pole.
#[inline]
#[must_use]
pub fn equal_area_encode(d: Vec3) -> Vec2 {
    let len = d.length();
    if !(len > 0.0) || !len.is_finite() {
        return Vec2::ZERO;
    }
    let d = d / len;
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let a = x.max(y);
    let b = if a > 0.0 { x.min(y) / a } else { 0.0 };
    let mut phi = b.atan() / FRAC_PI_2;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        core::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    Vec2::new(u.copysign(d.x), v.copysign(d.y)).clamp(Vec2::NEG_ONE, Vec2::ONE)
}

/// The unit direction at equal-area square coordinates `p ∈ [−1, 1]²` (clamped to the square).
#[inline]
#[must_use]
pub fn equal_area_decode(p: Vec2) -> Vec3 {
    let p = p.clamp(Vec2::NEG_ONE, Vec2::ONE);
    let (up, vp) = (p.x.abs(), p.y.abs());
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    let x = (phi.cos() * s).copysign(p.x);
    let y = (phi.sin() * s).copysign(p.y);
    Vec3::new(x, y, z).normalize()
}

/// Solid angle of any texel of an `n × n` equal-area map: `4π / n²`. `n = 0` is treated as 1
/// (one texel covering the sphere, 4π) so the result is always finite.
#[inline]
#[must_use]
pub fn equal_area_solid_angle(n: u32) -> f32 {
    let n = n.max(1) as f32;
    4.0 * PI / (n * n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octahedral::spherical_triangle_area;

    #[test]
    fn round_trips() {
        crate::test_support::assert_direction_round_trips(
            equal_area_encode,
            equal_area_decode,
            2e-5,
        );
        for i in 1..100 {
            for j in 1..100 {
                let p = Vec2::new(-1.0 + 0.02 * i as f32, -1.0 + 0.02 * j as f32);
                let q = equal_area_encode(equal_area_decode(p));
                assert!((p - q).length() < 5e-5, "{p} → {q}");
            }
        }
        assert_eq!(equal_area_encode(Vec3::NAN), Vec2::ZERO);
        assert_eq!(equal_area_encode(Vec3::ZERO), Vec2::ZERO);
    }

    /// The area preservation itself: fine sub-squares (well approximated by flat spherical
    /// quads) of any texel add up to 4π/n².
    #[test]
    fn texels_have_equal_solid_angle() {
        let n = 6u32;
        let sub = 24u32;
        let step = 2.0 / (n * sub) as f32;
        for (x, y) in [(0, 0), (2, 3), (5, 1), (3, 3)] {
            let mut s = 0.0f64;
            for a in 0..sub {
                for b in 0..sub {
                    let lo = Vec2::new(
                        -1.0 + step * (x * sub + a) as f32,
                        -1.0 + step * (y * sub + b) as f32,
                    );
                    let c00 = equal_area_decode(lo);
                    let c10 = equal_area_decode(lo + Vec2::new(step, 0.0));
                    let c01 = equal_area_decode(lo + Vec2::new(0.0, step));
                    let c11 = equal_area_decode(lo + Vec2::splat(step));
                    s += f64::from(spherical_triangle_area(c00, c10, c11))
                        + f64::from(spherical_triangle_area(c00, c11, c01));
                }
            }
            let want = f64::from(equal_area_solid_angle(n));
            mcg_test_support::assert_close!(s, want, 2e-3 * want, "({x}, {y}): {s} vs {want}");
        }
    }

    #[test]
    fn zero_side_is_finite() {
        // Issue 14 row 16: n = 0 gave +∞.
        assert_eq!(equal_area_solid_angle(0), 4.0 * PI);
        assert_eq!(equal_area_solid_angle(1), 4.0 * PI);
        let tiny = equal_area_solid_angle(u32::MAX);
        assert!(tiny.is_finite() && tiny > 0.0);
    }

    #[test]
    fn value_stability() {
        let p = equal_area_encode(Vec3::new(0.3, -0.5, -0.8));
        let d = equal_area_decode(p);
        assert!((d - Vec3::new(0.3, -0.5, -0.8).normalize()).length() < 1e-5);
        assert!(p.x > 0.0 && p.y < 0.0 && p.x.abs() + p.y.abs() > 1.0);
        assert!(
            (equal_area_decode(Vec2::new(0.5, 0.0)) - Vec3::new(0.661_437_8, 0.0, 0.75)).length()
                < 1e-5
        );
    }
}
