//! Deterministic random numbers for the suites.

use std::f64::consts::TAU;

use glam::{DVec3, Vec2};
use rand::{Rng, RngExt, SeedableRng};
pub use rand_pcg::Pcg64Mcg;

/// The generator of every suite: PCG-64 (MCG variant) seeded from `seed` with
/// `SeedableRng::seed_from_u64`, so a test with a fixed seed draws the same numbers on every
/// platform and run.
#[must_use]
pub fn seeded_rng(seed: u64) -> Pcg64Mcg {
    Pcg64Mcg::seed_from_u64(seed)
}

/// Two f32 uniforms in [0, 1) (24 random bits each), the input of the samplers'
/// `sample(u: Vec2)`.
#[must_use]
pub fn uniform_vec2<R: Rng + ?Sized>(rng: &mut R) -> Vec2 {
    Vec2::new(rng.random::<f32>(), rng.random::<f32>())
}

/// A uniformly distributed unit direction on S² in f64 (z uniform in [−1, 1), φ uniform in
/// [0, 2π)), for reference computations and for probing functions at arbitrary directions.
#[must_use]
pub fn uniform_sphere_direction<R: Rng + ?Sized>(rng: &mut R) -> DVec3 {
    let z = 2.0 * rng.random::<f64>() - 1.0;
    let phi = TAU * rng.random::<f64>();
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeded_streams_repeat_and_stay_in_range() {
        let (mut a, mut b) = (seeded_rng(7), seeded_rng(7));
        for _ in 0..1000 {
            let (u, v) = (uniform_vec2(&mut a), uniform_vec2(&mut b));
            assert_eq!(u, v);
            assert!(u.cmpge(Vec2::ZERO).all() && u.cmplt(Vec2::ONE).all(), "{u}");
        }
        assert_ne!(
            uniform_vec2(&mut seeded_rng(7)),
            uniform_vec2(&mut seeded_rng(8))
        );
        let w = uniform_sphere_direction(&mut a);
        mcg_test_support::assert_close!(w.length(), 1.0, 1e-15);
    }
}
