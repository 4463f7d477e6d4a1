//! Cosine-weighted hemisphere sampling, the defensive technique of MCMM Alg. 2 and MCPG Alg. 2.

use core::f32::consts::{FRAC_1_PI, TAU};

use glam::{Vec2, Vec3};
use mcg_vmf::Frame;

use crate::math;

/// Samples a direction with density cos θ / π about the unit `normal` (Malley's method: a
/// uniform disk point lifted to the hemisphere) and returns it with its pdf.
///
/// `u` holds two uniforms in [0, 1). The pdf of a direction on the horizon is 0; callers that
/// divide by it should treat such a sample as carrying no contribution.
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
