//! The box room that the hash-grid key streams render: the demo's load sweep and hashgrid's
//! benches walk a camera through it.

use glam::Vec3;

/// The room's lower corner: 40 × 10 × 40 units with the floor at y = 0.
pub const ROOM_MIN: Vec3 = Vec3::new(-20.0, 0.0, -20.0);
/// The room's upper corner.
pub const ROOM_MAX: Vec3 = Vec3::new(20.0, 10.0, 20.0);

/// Hit point and inward normal of the ray from `camera` (inside the room) along `dir` on the
/// walls of the box [`ROOM_MIN`]..[`ROOM_MAX`]: the nearest exit of the slab test.
#[must_use]
pub fn hit_room(camera: Vec3, dir: Vec3) -> (Vec3, Vec3) {
    let inv = dir.recip();
    let t_exit = ((ROOM_MIN - camera) * inv).max((ROOM_MAX - camera) * inv);
    let t = t_exit.min_element();
    let axis = if t == t_exit.x {
        0
    } else if t == t_exit.y {
        1
    } else {
        2
    };
    let mut n = Vec3::ZERO;
    n[axis] = -dir[axis].signum();
    (camera + dir * t, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_hit_the_wall_they_point_at() {
        let camera = Vec3::new(0.0, 1.7, 0.0);
        assert_eq!(hit_room(camera, -Vec3::Y), (Vec3::ZERO, Vec3::Y));
        assert_eq!(
            hit_room(camera, Vec3::X),
            (Vec3::new(20.0, 1.7, 0.0), -Vec3::X)
        );
        let (p, n) = hit_room(camera, Vec3::new(0.3, 0.2, -0.9).normalize());
        assert!((p.z + 20.0).abs() < 1e-4 && n == Vec3::Z, "{p} {n}");
    }
}
