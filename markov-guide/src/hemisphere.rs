//! Cosine-weighted hemisphere sampling, the defensive technique of MCMM Alg. 2 and MCPG Alg. 2.

use core::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, TAU};

use glam::{Vec2, Vec3};
use mcg_vmf::Frame;

use crate::math;

/// Samples a direction with density cos θ / π about the unit `normal` (Malley's method: a
/// uniform disk point lifted to the hemisphere) and returns it with its pdf.
///
/// `u` holds two uniforms in [0, 1); values outside are clamped into [0, 1] and NaN counts
/// as 0, so every `u` gives a unit direction and a finite pdf. The pdf of a direction on the
/// horizon is 0; callers that divide by it should treat such a sample as carrying no
/// contribution.
///
/// # Example
/// ```
/// use mcg_markov_guide::{cosine_hemisphere, glam::{Vec2, Vec3}};
/// let (w, pdf) = cosine_hemisphere(Vec3::Z, Vec2::new(0.0, 0.25));
/// assert!((w - Vec3::Z).length() < 1e-6 && (pdf - 1.0 / core::f32::consts::PI).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn cosine_hemisphere(normal: Vec3, u: Vec2) -> (Vec3, f32) {
    // `max` returns its non-NaN operand, so NaN → 0; in-range values pass unchanged.
    let u = u.max(Vec2::ZERO).min(Vec2::ONE);
    let r = math::sqrt(u.x);
    let (sin, cos) = math::sin_cos(TAU * u.y);
    let z = math::sqrt((1.0 - u.x).max(0.0));
    let local = Vec3::new(r * cos, r * sin, z);
    (Frame::from_normal(normal).to_world(local), z * FRAC_1_PI)
}

/// Samples a direction with density cos θ / π about the unit `normal` through Shirley and
/// Chiu's concentric square-to-disk map lifted to the hemisphere, and returns it with its pdf.
///
/// The same density as [`cosine_hemisphere`] with a map that keeps areas and neighbourhoods
/// of the unit square, so stratified or jittered `u` stay stratified on the hemisphere (what a
/// reference estimator wants); [`cosine_hemisphere`]'s polar map is cheaper. Uniforms outside
/// [0, 1] are clamped and NaN counts as 0, as there.
///
/// See also [`cosine_hemisphere_pdf`].
///
/// # Example
/// ```
/// use mcg_markov_guide::{cosine_hemisphere_concentric, glam::{Vec2, Vec3}};
/// let (w, pdf) = cosine_hemisphere_concentric(Vec3::Z, Vec2::splat(0.5));
/// assert_eq!(w, Vec3::Z);
/// assert!((pdf - 1.0 / core::f32::consts::PI).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn cosine_hemisphere_concentric(normal: Vec3, u: Vec2) -> (Vec3, f32) {
    let u = u.max(Vec2::ZERO).min(Vec2::ONE);
    let a = 2.0 * u - Vec2::ONE;
    let (r, phi) = if a == Vec2::ZERO {
        (0.0, 0.0)
    } else if a.x.abs() > a.y.abs() {
        (a.x, FRAC_PI_4 * (a.y / a.x))
    } else {
        (a.y, FRAC_PI_2 - FRAC_PI_4 * (a.x / a.y))
    };
    let (sin, cos) = math::sin_cos(phi);
    let d = Vec2::new(r * cos, r * sin);
    let z = math::sqrt((1.0 - d.length_squared()).max(0.0));
    let local = Vec3::new(d.x, d.y, z);
    (Frame::from_normal(normal).to_world(local), z * FRAC_1_PI)
}

/// The density max(0, n·ω)/π of [`cosine_hemisphere`] and [`cosine_hemisphere_concentric`].
#[inline]
#[must_use]
pub fn cosine_hemisphere_pdf(normal: Vec3, w: Vec3) -> f32 {
    normal.dot(w).max(0.0) * FRAC_1_PI
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_uniforms_are_clamped() {
        // Issue 14 row 12: u.x = −10⁻⁷ gave NaN.
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        for (u, clamped) in [
            (Vec2::new(-1e-7, 0.5), Vec2::new(0.0, 0.5)),
            (Vec2::new(1.5, 0.5), Vec2::new(1.0, 0.5)),
            (Vec2::new(0.3, f32::INFINITY), Vec2::new(0.3, 1.0)),
            (Vec2::new(0.3, -2.0), Vec2::new(0.3, 0.0)),
            (Vec2::new(f32::NAN, f32::NAN), Vec2::ZERO),
            (Vec2::new(f32::NEG_INFINITY, 0.2), Vec2::new(0.0, 0.2)),
        ] {
            let (w, pdf) = cosine_hemisphere(n, u);
            assert!(w.is_finite() && (w.length() - 1.0).abs() < 1e-5, "{u}: {w}");
            assert!(pdf.is_finite() && pdf >= 0.0, "{u}: {pdf}");
            assert_eq!((w, pdf), cosine_hemisphere(n, clamped), "{u}");
        }
    }

    #[test]
    fn samples_are_unit_and_match_pdf() {
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        for sample in [cosine_hemisphere, cosine_hemisphere_concentric] {
            for i in 0..64 {
                for j in 0..64 {
                    let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                    let (w, pdf) = sample(n, u);
                    mcg_test_support::assert_close!(w.length(), 1.0, 1e-5);
                    assert!(w.dot(n) >= -1e-6);
                    mcg_test_support::assert_close!(pdf, cosine_hemisphere_pdf(n, w), 1e-5);
                }
            }
        }
    }

    #[test]
    fn concentric_map_keeps_quadrants_and_clamps() {
        // The square's centre is the pole, its edge midpoints the horizon along ±t and ±b.
        let frame = Frame::from_normal(Vec3::Z);
        let (w, _) = cosine_hemisphere_concentric(Vec3::Z, Vec2::new(1.0, 0.5));
        assert!((w - frame.tangent).length() < 1e-6, "{w}");
        let (w, _) = cosine_hemisphere_concentric(Vec3::Z, Vec2::new(0.5, 0.0));
        assert!((w + frame.bitangent).length() < 1e-6, "{w}");
        // A stratum of the square lands in the matching sector: u in the right half → t·ω > 0.
        for j in 0..16 {
            let u = Vec2::new(0.8, 0.3 + 0.4 * j as f32 / 16.0);
            assert!(
                cosine_hemisphere_concentric(Vec3::Z, u)
                    .0
                    .dot(frame.tangent)
                    > 0.0
            );
        }
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        assert_eq!(
            cosine_hemisphere_concentric(n, Vec2::new(f32::NAN, 1.5)),
            cosine_hemisphere_concentric(n, Vec2::new(0.0, 1.0))
        );
    }
}
