//! Cosine-weighted hemisphere sampling, the defensive technique of MCMM Alg. 2 and MCPG Alg. 2.

use core::f32::consts::{FRAC_1_PI, TAU};

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

/// The density max(0, n·ω)/π of [`cosine_hemisphere`].
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
        for i in 0..64 {
            for j in 0..64 {
                let u = Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0);
                let (w, pdf) = cosine_hemisphere(n, u);
                assert!((w.length() - 1.0).abs() < 1e-5);
                assert!(w.dot(n) >= -1e-6);
                assert!((pdf - cosine_hemisphere_pdf(n, w)).abs() < 1e-5);
            }
        }
    }
}
