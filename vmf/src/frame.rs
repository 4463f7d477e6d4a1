//! A branchless orthonormal frame around a unit direction.

use glam::Vec3;

/// A right-handed orthonormal frame `(tangent, bitangent, normal)` built around a unit vector.
///
/// Construction is branchless and continuous everywhere except across the plane `normal.z = 0`
/// (where the sign flips), following Duff et al. 2017, *Building an Orthonormal Basis, Revisited*
/// (JCGT 6(1)), which fixes the precision loss of Frisvad 2012 near `normal.z = -1`. The
/// tangents are glam's [`Vec3::any_orthonormal_pair`], which implements that construction.
///
/// # Example
/// ```
/// use mcg_vmf::{Frame, glam::Vec3};
/// let frame = Frame::from_normal(Vec3::new(0.0, 0.6, 0.8));
/// let v = frame.to_world(Vec3::Z);
/// assert!((v - Vec3::new(0.0, 0.6, 0.8)).length() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent direction (local x axis).
    pub tangent: Vec3,
    /// Second tangent direction (local y axis), `normal × tangent`.
    pub bitangent: Vec3,
    /// The direction the frame was built around (local z axis).
    pub normal: Vec3,
}

impl Frame {
    /// Builds a frame whose local z axis is `normal`.
    ///
    /// `normal` must be unit length; the result is orthonormal to f32 precision then.
    /// `normal.z = -0.0` counts as negative, as in Duff et al.
    ///
    /// See also [`Vec3::any_orthonormal_pair`], the tangents alone.
    #[inline]
    #[must_use]
    pub fn from_normal(normal: Vec3) -> Self {
        let (tangent, bitangent) = normal.any_orthonormal_pair();
        Self {
            tangent,
            bitangent,
            normal,
        }
    }

    /// Maps a vector given in local coordinates to world coordinates.
    #[inline]
    #[must_use]
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        self.tangent * local.x + self.bitangent * local.y + self.normal * local.z
    }

    /// Maps a world-space vector to local coordinates (the inverse of [`Frame::to_world`]).
    #[inline]
    #[must_use]
    pub fn to_local(&self, world: Vec3) -> Vec3 {
        Vec3::new(
            world.dot(self.tangent),
            world.dot(self.bitangent),
            world.dot(self.normal),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthonormal_and_right_handed_everywhere() {
        let dirs = [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::X,
            -Vec3::Y,
            -Vec3::Z,
            Vec3::new(0.0, 0.0, -0.0),
            Vec3::new(1.0, 2.0, 3.0).normalize(),
            Vec3::new(1e-4, -2e-4, -1.0).normalize(),
            Vec3::new(0.3, -0.9, 1e-7).normalize(),
        ];
        for n in dirs {
            let n = if n.length_squared() == 0.0 {
                Vec3::Z
            } else {
                n
            };
            let f = Frame::from_normal(n);
            for v in [f.tangent, f.bitangent, f.normal] {
                mcg_test_support::assert_close!(v.length(), 1.0, 1e-6, "{n}: {v}");
            }
            assert!(f.tangent.dot(f.bitangent).abs() < 1e-6);
            assert!(f.tangent.dot(f.normal).abs() < 1e-6);
            assert!(f.bitangent.dot(f.normal).abs() < 1e-6);
            assert!((f.tangent.cross(f.bitangent) - f.normal).length() < 1e-6);
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-6);
        }
    }
}
