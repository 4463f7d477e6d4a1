//! Reference probe irradiance: many rays per texel direction, for measuring a probe grid's
//! error (ADGI sec. 5, "Reference": a true average of many rays per texel, no hysteresis).
//!
//! For a probe at p and a texel direction n the reference is the irradiance
//!
//! E(p, n) = ∫_{H(n)} L(p, ω) (n·ω) dω,
//!
//! with L the scene's one-bounce probe-ray radiance ([`Scene::trace_probe_ray`]). It is
//! estimated with cosine-weighted hemisphere samples (density (n·ω)/π, so
//! E ≈ π/N · Σ L(ω_i)), stratified over an m × m grid of the unit square with one jittered
//! sample per stratum (Malley's method: a concentric disk sample lifted to the hemisphere;
//! Shirley and Chiu 1997). All uniforms come from a counter hash of (seed, direction, ray),
//! so the reference is deterministic and independent of evaluation order. The error of the
//! estimate shrinks like 1/N with stratification for smooth L and like 1/√N at shadow
//! boundaries (the light sample of each ray is not stratified).
//!
//! DDGI's cosine-weighted blend stores E/π (the cosine-weighted mean radiance) in a texel;
//! divide by π to compare.

use std::vec::Vec;

use glam::{Vec2, Vec3};

use crate::scene::Scene;

/// A deterministic uniform in [0, 1) from a 64-bit counter (SplitMix64 finaliser; Steele et
/// al. 2014), top 24 bits.
#[inline]
#[must_use]
pub fn hash_uniform(counter: u64) -> f32 {
    let mut z = counter.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^= z >> 31;
    (z >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// An orthonormal basis (t, b, n) around the unit vector `n` (Duff et al. 2017, *Building an
/// orthonormal basis, revisited*).
#[inline]
#[must_use]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0_f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The cosine-weighted direction around unit `n` at uniforms `u` ∈ [0, 1)²: Shirley–Chiu's
/// concentric disk map lifted to the hemisphere (Malley's method), density (n·ω)/π.
#[inline]
#[must_use]
pub fn cosine_hemisphere(n: Vec3, u: Vec2) -> Vec3 {
    let a = 2.0 * u - Vec2::ONE;
    let (r, phi) = if a == Vec2::ZERO {
        (0.0, 0.0)
    } else if a.x.abs() > a.y.abs() {
        (a.x, core::f32::consts::FRAC_PI_4 * (a.y / a.x))
    } else {
        (
            a.y,
            core::f32::consts::FRAC_PI_2 - core::f32::consts::FRAC_PI_4 * (a.x / a.y),
        )
    };
    let (s, c) = phi.sin_cos();
    let d = Vec2::new(r * c, r * s);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    let (t, b) = basis(n);
    (d.x * t + d.y * b + z * n).normalize()
}

/// Reference irradiance E(p, n) for each unit direction in `directions` at the probe position
/// `position`, from `strata × strata` stratified cosine-weighted rays per direction (see the
/// [module docs](self)). `seed` selects the jitter. Returns one irradiance per direction.
#[must_use]
pub fn reference_irradiance(
    scene: &Scene,
    position: Vec3,
    directions: &[Vec3],
    strata: u32,
    seed: u64,
) -> Vec<Vec3> {
    directions
        .iter()
        .enumerate()
        .map(|(k, &n)| irradiance_one(scene, position, n, strata, seed, k as u64))
        .collect()
}

fn irradiance_one(scene: &Scene, p: Vec3, n: Vec3, strata: u32, seed: u64, k: u64) -> Vec3 {
    let m = strata.max(1);
    let inv = 1.0 / m as f32;
    let mut sum = Vec3::ZERO;
    // Distinct counters per (seed, direction, ray, coordinate); the hash decorrelates them.
    let base = seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    for i in 0..m {
        let mut row = Vec3::ZERO;
        for j in 0..m {
            let c = base.wrapping_add(u64::from(i * m + j) << 2);
            let u = Vec2::new(
                (i as f32 + hash_uniform(c)) * inv,
                (j as f32 + hash_uniform(c + 1)) * inv,
            );
            let w = cosine_hemisphere(n, u.min(Vec2::splat(1.0 - f32::EPSILON)));
            let light_u = Vec2::new(hash_uniform(c + 2), hash_uniform(c + 3));
            row += scene.trace_probe_ray(p, w, light_u).radiance;
        }
        sum += row;
    }
    sum * (core::f32::consts::PI / (m * m) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{DynamicScene, RectLight};

    #[test]
    fn hash_uniforms_are_uniform_enough() {
        let n = 100_000;
        let mut bins = [0u32; 10];
        for i in 0..n {
            let u = hash_uniform(i);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 10.0) as usize] += 1;
        }
        for b in bins {
            // 5σ of a binomial(10⁵, 0.1): σ ≈ 95.
            assert!((b as i32 - 10_000).abs() < 475, "{bins:?}");
        }
    }

    #[test]
    fn cosine_directions_have_cosine_density() {
        // E[n·ω] = 2/3 under the density cos/π; E[(n·ω)²] = 1/2.
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        let m = 64;
        let (mut m1, mut m2) = (0.0_f64, 0.0_f64);
        for i in 0..m {
            for j in 0..m {
                let u = Vec2::new((i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32);
                let w = cosine_hemisphere(n, u);
                assert!((w.length() - 1.0).abs() < 1e-5);
                let c = f64::from(n.dot(w));
                assert!(c >= -1e-6);
                m1 += c;
                m2 += c * c;
            }
        }
        let k = f64::from(m * m);
        assert!((m1 / k - 2.0 / 3.0).abs() < 2e-3, "{}", m1 / k);
        assert!((m2 / k - 0.5).abs() < 2e-3, "{}", m2 / k);
    }

    /// In a closed box whose only surface is the light's rectangle — replaced here by a scene
    /// with no objects and a huge light above — a probe facing the light sees the constant
    /// radiance L_e over its whole hemisphere, so E = π·L_e exactly.
    #[test]
    fn constant_radiance_gives_pi_l() {
        let scene = Scene {
            objects: Vec::new(),
            light: RectLight {
                corner: Vec3::new(-1.0e3, 1.0, -1.0e3),
                edge_u: Vec3::new(2.0e3, 0.0, 0.0),
                edge_v: Vec3::new(0.0, 0.0, 2.0e3),
                radiance: Vec3::splat(2.0),
            },
        };
        let e = reference_irradiance(&scene, Vec3::ZERO, &[Vec3::Y], 16, 1)[0];
        // The hemisphere's horizon grazes past the light's edge: a 1e-3 rad sliver is missed.
        assert!(
            (e.x / (2.0 * core::f32::consts::PI) - 1.0).abs() < 2e-3,
            "{e}"
        );
        let e = reference_irradiance(&scene, Vec3::ZERO, &[-Vec3::Y], 16, 1)[0];
        assert_eq!(e, Vec3::ZERO);
    }

    /// The reference converges: its error against a 128² reference shrinks as the stratum
    /// count grows (root-mean-square over directions and seeds).
    #[test]
    fn reference_converges() {
        let scene = DynamicScene::door_opens(0, 1);
        let p = Vec3::new(4.75, 1.125, 2.25); // in the side room, facing the doorway
        let dirs: Vec<Vec3> = [
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(-0.5, -0.7, 0.2),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.3, 0.2, -0.9),
        ]
        .iter()
        .map(|d| d.normalize())
        .collect();
        let truth = reference_irradiance(&scene.after, p, &dirs, 128, 99);
        let rms = |strata: u32| {
            let mut s = 0.0_f64;
            let seeds = 8;
            for seed in 0..seeds {
                let est = reference_irradiance(&scene.after, p, &dirs, strata, seed);
                for (e, t) in est.iter().zip(&truth) {
                    s += f64::from((*e - *t).length_squared());
                }
            }
            (s / (seeds as f64 * dirs.len() as f64)).sqrt()
        };
        let (e4, e16, e32) = (rms(4), rms(16), rms(32));
        let scale = f64::from(truth.iter().map(|t| t.length()).fold(0.0, f32::max));
        assert!(
            scale > 0.01,
            "the side room is lit with the door open: {scale}"
        );
        assert!(e16 < 0.5 * e4 && e32 < 0.7 * e16, "{e4} {e16} {e32}");
        assert!(e32 < 0.05 * scale, "{e32} vs {scale}");
    }

    #[test]
    fn value_stability() {
        let scene = DynamicScene::door_opens(0, 1);
        let e = reference_irradiance(&scene.after, Vec3::new(2.25, 1.125, 2.25), &[Vec3::Y], 4, 7);
        assert_eq!(
            e[0].to_array().map(f32::to_bits),
            [1_075_761_526, 1_074_789_221, 1_072_399_098]
        );
    }
}
