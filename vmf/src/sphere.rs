//! The uniform distribution on the unit sphere S²: the κ = 0 limit of a lobe and the baseline
//! that every guided sampler is compared with.

use core::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use crate::math;

/// 1/(4π), the density of the uniform distribution on S².
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// A uniformly distributed unit direction on S² from two uniforms: z = 1 − 2u_y, φ = 2πu_x
/// (Archimedes' hat-box theorem; pbrt-v4's `SampleUniformSphere`). Its density is
/// [`UNIFORM_SPHERE_PDF`].
///
/// `u` holds two uniforms in [0, 1); values outside are clamped into [0, 1] and NaN counts as
/// 0, so every `u` gives a unit direction.
///
/// # Example
/// ```
/// use mcg_vmf::{uniform_sphere, glam::{Vec2, Vec3}};
/// assert_eq!(uniform_sphere(Vec2::new(0.25, 0.0)), Vec3::Z);
/// let w = uniform_sphere(Vec2::new(0.3, 0.8));
/// assert!((w.length() - 1.0).abs() < 1e-6 && (w.z + 0.6).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    // `max` returns its non-NaN operand, so NaN → 0; in-range values pass unchanged.
    let u = u.max(Vec2::ZERO).min(Vec2::ONE);
    let z = 1.0 - 2.0 * u.y;
    let r = math::sqrt((1.0 - z * z).max(0.0));
    let (sin, cos) = math::sin_cos_turns(u.x);
    Vec3::new(r * cos, r * sin, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_directions_with_the_right_height_and_azimuth() {
        for i in 0..32 {
            for j in 0..32 {
                let u = Vec2::new((i as f32 + 0.5) / 32.0, (j as f32 + 0.5) / 32.0);
                let w = uniform_sphere(u);
                mcg_test_support::assert_close!(w.length(), 1.0, 1e-6, "{u}: {w}");
                mcg_test_support::assert_close!(w.z, (1.0 - 2.0 * u.y), 1e-6, "{u}: {w}");
                let phi = w.y.atan2(w.x).rem_euclid(core::f32::consts::TAU);
                mcg_test_support::assert_close!(
                    phi,
                    core::f32::consts::TAU * u.x,
                    1e-4,
                    "{u}: {w}"
                );
            }
        }
    }

    #[test]
    fn out_of_range_uniforms_are_clamped() {
        let bad = [
            (Vec2::new(f32::NAN, f32::NAN), Vec2::ZERO),
            (Vec2::new(-0.5, 1.5), Vec2::new(0.0, 1.0)),
            (Vec2::new(2.0, f32::NEG_INFINITY), Vec2::new(1.0, 0.0)),
        ];
        for (u, clamped) in bad {
            assert_eq!(uniform_sphere(u), uniform_sphere(clamped), "{u}");
            assert!(uniform_sphere(u).is_finite(), "{u}");
        }
    }
}
