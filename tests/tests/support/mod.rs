//! Helpers shared by the property suites of this folder (each suite includes it with
//! `mod support;`): the proptest configuration and strategies of adversarial values.
#![allow(dead_code)] // each suite uses part of it

use glam::{Vec2, Vec3};
use proptest::prelude::*;

/// The configuration of every `proptest!` block of this folder (fixed seed, no regression
/// files, `PROPTEST_*` overrides for `scripts/fuzz`).
pub use mcg_test_support::proptest_config;

/// Adversarial f32 values: NaN, ±∞, ±0, subnormals, the extremes of the finite range, values
/// just outside [0, 1], and arbitrary bit patterns.
pub fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(f32::from_bits(1)),
        1 => Just(-f32::from_bits(0x007f_ffff)),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN),
        1 => Just(1.0f32),
        1 => Just(1.000_000_1f32),
        1 => Just(-1e-7f32),
        1 => Just(1.0 - f32::EPSILON / 2.0),
        1 => Just(1e20f32),
        1 => Just(-1e20f32),
        3 => -10.0f32..10.0,
        3 => 0.0f32..1.0,
        3 => any::<u32>().prop_map(f32::from_bits),
    ]
}

/// Finite adversarial f32 values: [`any_f32`] without NaN and ±∞.
pub fn finite_f32() -> impl Strategy<Value = f32> {
    any_f32().prop_map(|x| if x.is_finite() { x } else { 0.5 })
}

/// Uniforms a caller may hand over by mistake: mostly [0, 1), sometimes anything.
pub fn any_uniform() -> impl Strategy<Value = f32> {
    prop_oneof![3 => 0.0f32..1.0, 2 => any_f32()]
}

/// Vectors with adversarial components, plus the zero vector and tiny and huge ones.
pub fn any_vec3() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        1 => Just(Vec3::ZERO),
        1 => Just(Vec3::new(3e-22, 4e-22, 0.0)),
        1 => Just(Vec3::splat(3e37)),
        4 => (any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
    ]
}

/// Finite vectors: [`any_vec3`] with non-finite components replaced.
pub fn finite_vec3() -> impl Strategy<Value = Vec3> {
    (finite_f32(), finite_f32(), finite_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Two uniforms, see [`any_uniform`].
pub fn any_uniform2() -> impl Strategy<Value = Vec2> {
    (any_uniform(), any_uniform()).prop_map(|(x, y)| Vec2::new(x, y))
}

/// Counts and indices: small ones, the edges of the `u32` range and arbitrary ones.
pub fn any_u32() -> impl Strategy<Value = u32> {
    prop_oneof![
        Just(0u32),
        Just(1u32),
        Just(u32::MAX),
        Just(u32::MAX - 1),
        Just(1u32 << 31),
        Just(1u32 << 24),
        0u32..64,
        any::<u32>(),
    ]
}
