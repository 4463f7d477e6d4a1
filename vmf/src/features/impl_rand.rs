//! `rand::distr::Distribution` implementations (feature `rand`).

use glam::{Vec2, Vec3};
use rand::{Rng, RngExt, distr::Distribution};

use crate::{Vmf, VmfMixture};

fn uniforms<R: Rng + ?Sized>(rng: &mut R) -> Vec2 {
    Vec2::new(rng.random::<f32>(), rng.random::<f32>())
}

impl Distribution<Vec3> for Vmf {
    /// Draws two uniforms in [0, 1) from `rng` and calls [`Vmf::sample`].
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec3 {
        Vmf::sample(self, uniforms(rng))
    }
}

impl<const K: usize> Distribution<Vec3> for VmfMixture<K> {
    /// Draws two uniforms in [0, 1) from `rng` and calls [`VmfMixture::sample`].
    fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> Vec3 {
        VmfMixture::sample(self, uniforms(rng))
    }
}
