//! Helpers shared by the unit tests of the texel maps.

use glam::{Vec2, Vec3};

/// `n` directions on a Fibonacci spiral, nearly uniform over the sphere.
pub(crate) fn fibonacci_directions(n: usize) -> impl Iterator<Item = Vec3> {
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
        let phi = i as f32 * 2.399_963;
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

/// `decode(encode(d))` returns `d` within `tolerance` for 20 000 spiral directions, and within
/// 10⁻⁶ for the six axis directions (the map's corners and centre).
pub(crate) fn assert_direction_round_trips(
    encode: fn(Vec3) -> Vec2,
    decode: fn(Vec2) -> Vec3,
    tolerance: f32,
) {
    for d in fibonacci_directions(20_000) {
        let back = decode(encode(d));
        assert!((back - d).length() < tolerance, "{d} → {back}");
    }
    for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        assert!((decode(encode(d)) - d).length() < 1e-6, "{d}");
    }
}
