//! Reference probe irradiance: many rays per texel direction, for measuring a probe grid's
//! error (ADGI sec. 5, "Reference": a true average of many rays per texel, no hysteresis).
//!
//! For a probe at p and a texel direction n the reference is the irradiance
//!
//! E(p, n) = ∫_{H(n)} L(p, ω) (n·ω) dω,
//!
//! with L the scene's one-bounce probe-ray radiance ([`Scene::trace_probe_ray`]). It splits
//! into the light seen directly and the light's first bounce, each estimated the way that
//! suits it (next-event estimation at the probe; Veach 1997, ch. 9):
//!
//! - **emission**: E_e = ∫_A L_e V(p, y) max(0, n·ω) max(0, −n_l·ω) / |y − p|² dA(y), area
//!   samples of the light on an m × m jittered grid (a bright light seen at grazing angles
//!   would otherwise be found by a handful of hemisphere rays, and dominate the error);
//! - **bounce**: cosine-weighted hemisphere rays (density (n·ω)/π, so E_b ≈ π/N · Σ L_b),
//!   stratified over an m × m jittered grid of the unit square (Malley's method: a concentric
//!   disk sample lifted to the hemisphere; Shirley and Chiu 1997); a ray that hits the light
//!   counts 0 here, a surface hit ρ/π times the mean of [`LIGHT_SAMPLES_PER_HIT`] stratified
//!   one-sample direct-irradiance estimates ([`Scene::direct_irradiance`]).
//!
//! Both are unbiased for their part, so E = E_e + E_b is. All uniforms come from a counter hash
//! of (seed, direction, sample), so the reference is deterministic and independent of
//! evaluation order.
//!
//! DDGI's cosine-weighted blend stores E/π (the cosine-weighted mean radiance) in a texel;
//! divide by π to compare.

use std::vec::Vec;

use glam::{Vec2, Vec3};
use mcg_markov_guide::cosine_hemisphere_concentric;

use crate::TexelMap;
use crate::scene::{MISS_DISTANCE, Scene, Surface};

pub use crate::probe_update::hash_uniform;

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

/// [`reference_irradiance`] at the centre directions of the interior texels of `map` (border
/// texels copy interior ones and are skipped): `(stored texel index, E)` for each, in storage
/// order. With DDGI's texels (E/π at their centres) compare `E / π` with the texel.
#[must_use]
pub fn reference_texel_irradiance(
    scene: &Scene,
    position: Vec3,
    map: &TexelMap,
    strata: u32,
    seed: u64,
) -> Vec<(usize, Vec3)> {
    let texels: Vec<(usize, Vec3)> = (0..map.texel_count())
        .filter_map(|i| {
            let t = map.coords(i);
            (!map.is_border(t)).then(|| (i, map.direction(t)))
        })
        .collect();
    let dirs: Vec<Vec3> = texels.iter().map(|t| t.1).collect();
    let e = reference_irradiance(scene, position, &dirs, strata, seed);
    texels.iter().zip(e).map(|(t, e)| (t.0, e)).collect()
}

/// The cosine-weighted direction around unit `n` through the concentric map (it keeps the
/// jittered grid stratified), renormalised.
#[inline]
fn cosine_direction(n: Vec3, u: Vec2) -> Vec3 {
    cosine_hemisphere_concentric(n, u).0.normalize()
}

/// Light samples per bounce-ray hit in [`reference_irradiance`] (a 2 × 2 jittered grid).
pub const LIGHT_SAMPLES_PER_HIT: u32 = 4;

fn irradiance_one(scene: &Scene, p: Vec3, n: Vec3, strata: u32, seed: u64, k: u64) -> Vec3 {
    let m = strata.max(1);
    let inv = 1.0 / m as f32;
    let jitter = |i: u32, j: u32, c: u64| {
        Vec2::new(
            (i as f32 + hash_uniform(c)) * inv,
            (j as f32 + hash_uniform(c + 1)) * inv,
        )
        .min(Vec2::splat(1.0 - f32::EPSILON))
    };
    // Distinct counters per (seed, direction, sample, coordinate); the hash decorrelates them.
    let base = seed.wrapping_mul(0x2545_f491_4f6c_dd1d) ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    let light = scene.light;
    let mut emission = Vec3::ZERO;
    let mut bounce = Vec3::ZERO;
    let emitting = light.radiance != Vec3::ZERO;
    for i in 0..m {
        for j in 0..m {
            let c = base.wrapping_add(u64::from(i * m + j) << 4);
            // Emission: one area sample of the light per stratum.
            if emitting {
                let s = light.sample(jitter(i, j, c));
                let d = s.point - p;
                let dist2 = d.length_squared();
                let w = d / dist2.sqrt();
                let cos_n = n.dot(w);
                let cos_l = -s.normal.dot(w);
                if cos_n > 0.0 && cos_l > 0.0 && !scene.occluded(p, s.point) {
                    emission += light.radiance * (cos_n * cos_l / (dist2 * s.pdf_area));
                }
            }
            // Bounce: one cosine-weighted ray per stratum.
            let w = cosine_direction(n, jitter(i, j, c + 2));
            let Some(hit) = scene.intersect(p, w, 0.0, MISS_DISTANCE) else {
                continue;
            };
            let Surface::Object { albedo, .. } = hit.surface else {
                continue;
            };
            if !emitting || hit.normal.dot(w) > 0.0 {
                continue;
            }
            let mut e = Vec3::ZERO;
            for l in 0..LIGHT_SAMPLES_PER_HIT {
                let cl = c + 4 + 2 * u64::from(l);
                let u = Vec2::new(
                    ((l & 1) as f32 + hash_uniform(cl)) * 0.5,
                    ((l >> 1) as f32 + hash_uniform(cl + 1)) * 0.5,
                );
                e += scene.direct_irradiance(hit.point, hit.normal, u);
            }
            bounce += albedo * e * (core::f32::consts::FRAC_1_PI / LIGHT_SAMPLES_PER_HIT as f32);
        }
    }
    let n2 = (m * m) as f32;
    emission / n2 + bounce * (core::f32::consts::PI / n2)
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
            mcg_test_support::assert_close!(b as i32, 10_000, 475, "{bins:?}");
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
                let w = cosine_direction(n, u);
                mcg_test_support::assert_close!(w.length(), 1.0, 1e-5);
                let c = f64::from(n.dot(w));
                assert!(c >= -1e-6);
                m1 += c;
                m2 += c * c;
            }
        }
        let k = f64::from(m * m);
        mcg_test_support::assert_close!(m1 / k, 2.0 / 3.0, 2e-3, "{}", m1 / k);
        mcg_test_support::assert_close!(m2 / k, 0.5, 2e-3, "{}", m2 / k);
    }

    /// With no objects, the reference is the light's irradiance alone, which Lambert's formula
    /// gives in closed form for a polygon above the hemisphere's horizon:
    /// E = L/2 · |Σ_edges Θ_i (n · Γ_i)| (Arvo 1995); and 0 facing away.
    #[test]
    fn unoccluded_light_matches_lambert_formula() {
        let light = RectLight {
            corner: Vec3::new(-1.0, 1.0, -0.7),
            edge_u: Vec3::new(2.0, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 1.5),
            radiance: Vec3::splat(2.0),
        };
        let scene = Scene {
            objects: Vec::new(),
            light,
        };
        for n in [Vec3::Y, Vec3::new(0.3, 0.9, -0.2).normalize()] {
            let verts = [
                light.corner,
                light.corner + light.edge_u,
                light.corner + light.edge_u + light.edge_v,
                light.corner + light.edge_v,
            ];
            let mut sum = 0.0_f32;
            for i in 0..4 {
                let a = verts[i].normalize();
                let b = verts[(i + 1) % 4].normalize();
                sum += a.dot(b).clamp(-1.0, 1.0).acos() * a.cross(b).normalize().dot(n);
            }
            let exact = 2.0 * 0.5 * sum.abs();
            let e = reference_irradiance(&scene, Vec3::ZERO, &[n], 16, 1)[0];
            mcg_test_support::assert_close!(e.x / exact, 1.0, 5e-3, "{e} vs {exact}");
        }
        let e = reference_irradiance(&scene, Vec3::ZERO, &[-Vec3::Y], 16, 1)[0];
        assert_eq!(e, Vec3::ZERO);
    }

    /// The reference converges: its error against a 128² reference shrinks as the stratum
    /// count grows (root-mean-square over directions and seeds).
    #[test]
    fn reference_converges() {
        let scene = DynamicScene::door_opens(0, 1);
        let p = Vec3::new(8.75, 1.125, 2.25); // in the closet, facing the doorway
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
            "the closet is lit with the door open: {scale}"
        );
        assert!(e16 < 0.5 * e4 && e32 < 0.7 * e16, "{e4} {e16} {e32}");
        assert!(e32 < 0.05 * scale, "{e32} vs {scale}");
    }

    #[test]
    fn texel_map_reference_covers_the_interior() {
        let scene = DynamicScene::door_opens(0, 1);
        let map = TexelMap::ADGI_IRRADIANCE;
        let p = Vec3::new(6.25, 1.125, 2.25);
        let e = reference_texel_irradiance(&scene.after, p, &map, 16, 5);
        assert_eq!(e.len(), (map.interior() * map.interior()) as usize);
        for &(i, _) in &e {
            assert!(!map.is_border(map.coords(i)));
        }
        // The same irradiance as asked for direction by direction (other uniforms: the
        // direction index keys them), within the 256-ray estimates' error.
        for k in [0, 7, 20, 35] {
            let (i, value) = e[k];
            let d = map.direction(map.coords(i));
            let direct = reference_irradiance(&scene.after, p, &[d], 16, 5)[0];
            let rel = (value - direct).length() / direct.length().max(1e-6);
            assert!(rel < 0.1, "texel {i}: {value} vs {direct}");
        }
    }

    #[test]
    fn value_stability() {
        let scene = DynamicScene::door_opens(0, 1);
        let e = reference_irradiance(&scene.after, Vec3::new(6.25, 1.125, 2.25), &[Vec3::Y], 4, 7);
        assert_eq!(
            e[0].to_array().map(f32::to_bits),
            [1_072_136_788, 1_070_914_081, 1_068_487_818]
        );
    }
}
