//! Where `mcmm`'s error comes from on the many-lights room (CPU): renders `bsdf` and `mcmm`
//! at the report's sizes (64 × 64, 4 spp × 64 frames, direct light) against a reference EXR
//! and prints
//! - each method's relMSE and its split by what the pixel's centre ray hits (diffuse, metal,
//!   light, nothing) and by the pixel's effective number of lights (Σc)²/Σc², c the unshadowed
//!   contribution of each light at the centre's shading point (visibility tested to the light's
//!   centre);
//! - the running relMSE at frames 1, 2, 4, …, 64 (do the chains converge or plateau?);
//! - chain statistics at those frames: valid states, mean sample count N, the distinct lights
//!   the 64 states of a tile point at (a state's mean target within 0.25 m of a light's
//!   centre), against the lights that matter at the tile's pixels.
//!
//! ```text
//! cargo run --release -p mcg-demo --example mcmm_diagnostics -- REFERENCE.exr [FRAMES] [SPP]
//! ```
//!
//! The MCMM constants come from `mcmm_params` and may be overridden by the environment:
//! `MCMM_WINDOW` (half width, pixels), `MCMM_PH` (p_h), `MCMM_ALPHA` (α_min), `MCMM_NMAX`,
//! `MCMM_CANDIDATES`, `MCMM_SCORE` (`paper` or `tile-mixture`), the prior's `MCMM_PRIOR_COS`
//! and `MCMM_PRIOR_WEIGHT` (a fixed prior, both needed) or `MCMM_PRIOR_RADIUS` and
//! `MCMM_PRIOR_WEIGHT` (the light-size prior), `MCMM_SEED`. `MCMM_SKIP_BSDF=1` skips the
//! `bsdf` render.

use std::path::PathBuf;

use glam::Vec3;
use mcg_demo::render::cpu::{BsdfSampler, Method, RenderSettings, render_frame};
use mcg_demo::render::mcmm::{McmmRenderer, McmmScore, TILE_HEIGHT, TILE_WIDTH, mcmm_params};
use mcg_demo::render::output::{RgbImage, errors};
use mcg_demo::render::scene::{Scene, SceneFile, frame_time};

/// What a pixel's centre ray hits.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    Diffuse,
    Metal,
    Light,
    Miss,
}

const CLASSES: [(Class, &str); 4] = [
    (Class::Diffuse, "diffuse"),
    (Class::Metal, "metal"),
    (Class::Light, "light"),
    (Class::Miss, "miss"),
];

/// A pixel's class, its lights' contributions (luminance, unshadowed-by-others, visible to
/// the light's centre) and its shading point.
struct PixelInfo {
    class: Class,
    contributions: Vec<f32>,
}

fn env_f32(name: &str) -> Option<f32> {
    std::env::var(name).ok().and_then(|s| s.parse().ok())
}

/// The centres, normals, areas and radiances of the lights (emitting triangles paired by
/// material).
fn lights(scene: &Scene) -> Vec<(Vec3, Vec3, f32, Vec3)> {
    let mut by_material: Vec<(u32, Vec3, Vec3, f32, Vec3)> = Vec::new();
    for t in &scene.bvh.triangles {
        let m = &scene.materials[t.material as usize];
        if !m.is_emitter() {
            continue;
        }
        let e1 = Vec3::from(t.e1);
        let e2 = Vec3::from(t.e2);
        let c = e1.cross(e2);
        let area = 0.5 * c.length();
        let centroid = Vec3::from(t.v0) + (e1 + e2) / 3.0;
        // Lights are quads of two triangles; distinct lights are more than 0.3 m apart.
        if let Some(l) = by_material
            .iter_mut()
            .find(|l| l.0 == t.material && (l.1 / l.3 - centroid).length() < 0.3)
        {
            l.1 += centroid * area;
            l.3 += area;
        } else {
            by_material.push((
                t.material,
                centroid * area,
                c.normalize(),
                area,
                m.emission(),
            ));
        }
    }
    by_material
        .into_iter()
        .map(|(_, c, n, a, e)| (c / a, n, a, e))
        .collect()
}

fn pixel_info(
    scene: &Scene,
    lights: &[(Vec3, Vec3, f32, Vec3)],
    x: u32,
    y: u32,
    size: u32,
) -> PixelInfo {
    let d = scene
        .camera
        .direction(x as f32 + 0.5, y as f32 + 0.5, size, size);
    let origin = scene.camera.position;
    let Some(hit) = scene.bvh.intersect(origin, d, 0.0, f32::INFINITY) else {
        return PixelInfo {
            class: Class::Miss,
            contributions: Vec::new(),
        };
    };
    let tri = scene.bvh.triangles[hit.triangle as usize];
    let material = scene.material_at(&hit);
    if material.is_emitter() {
        return PixelInfo {
            class: Class::Light,
            contributions: Vec::new(),
        };
    }
    let n_front = Vec3::from(tri.e1).cross(Vec3::from(tri.e2)).normalize();
    let normal = if n_front.dot(d) < 0.0 {
        n_front
    } else {
        -n_front
    };
    let p = origin + hit.t * d;
    let o = p + normal * 1e-3;
    let contributions = lights
        .iter()
        .map(|&(c, n, area, e)| {
            let to = c - o;
            let dist = to.length();
            let w = to / dist;
            let cos_l = -n.dot(w);
            if cos_l <= 0.0 || normal.dot(w) <= 0.0 {
                return 0.0;
            }
            let visible = scene
                .bvh
                .intersect(o, w, 0.0, dist * 0.999)
                .is_none_or(|h| scene.material_at(&h).is_emitter());
            if !visible {
                return 0.0;
            }
            let f = material.eval(normal, -d, w);
            (f * e).dot(Vec3::new(0.2126, 0.7152, 0.0722)) * cos_l * area / (dist * dist)
        })
        .collect();
    PixelInfo {
        class: if material.metallic > 0.5 {
            Class::Metal
        } else {
            Class::Diffuse
        },
        contributions,
    }
}

/// Per-pixel relMSE terms (mean over the three channels), as `output::errors` sums them.
fn pixel_terms(image: &[Vec3], reference: &[Vec3]) -> Vec<f64> {
    image
        .iter()
        .zip(reference)
        .map(|(p, r)| {
            (0..3)
                .map(|c| {
                    let (x, y) = (f64::from(p[c]), f64::from(r[c]));
                    (x - y) * (x - y) / (y * y + 1e-2)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect()
}

fn main() -> mcg_demo::Result<()> {
    let mut args = std::env::args().skip(1);
    let reference = RgbImage::read_exr(&PathBuf::from(
        args.next()
            .ok_or("usage: mcmm_diagnostics REFERENCE.exr [FRAMES] [SPP]")?,
    ))?;
    let frames: u32 = args
        .next()
        .map_or(Ok(64), |s| s.parse())
        .map_err(|_| "FRAMES")?;
    let spp: u32 = args
        .next()
        .map_or(Ok(4), |s| s.parse())
        .map_err(|_| "SPP")?;
    let size = reference.width;
    let scene_path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/many_lights_room.gltf");
    let scene = SceneFile::open(scene_path)?.build(frame_time(0))?;
    let lights = lights(&scene);
    println!("{} lights", lights.len());
    let info: Vec<PixelInfo> = (0..size * size)
        .map(|i| pixel_info(&scene, &lights, i % size, i / size, size))
        .collect();

    // The pixels' effective light counts, binned.
    let effective: Vec<f32> = info
        .iter()
        .map(|p| {
            let s: f32 = p.contributions.iter().sum();
            let s2: f32 = p.contributions.iter().map(|c| c * c).sum();
            if s2 > 0.0 { s * s / s2 } else { 0.0 }
        })
        .collect();
    let bins = [(0.0, 1.0), (1.0, 2.0), (2.0, 4.0), (4.0, 8.0), (8.0, 100.0)];

    let score = match std::env::var("MCMM_SCORE").as_deref() {
        Ok("paper") => McmmScore::Paper,
        _ => McmmScore::TileMixture,
    };
    let mut params = mcmm_params(score, size);
    if let Some(v) = env_f32("MCMM_WINDOW") {
        params.window_half_width = v;
    }
    if let Some(v) = env_f32("MCMM_PH") {
        params.hemisphere_probability = v;
    }
    if let Some(v) = env_f32("MCMM_ALPHA") {
        params.fit.alpha_min = v;
    }
    if let Some(v) = env_f32("MCMM_NMAX") {
        params.fit.max_count = v as u32;
    }
    if let Some(v) = env_f32("MCMM_CANDIDATES") {
        params.neighbour_candidates = v as u32;
    }
    if let (Some(c), Some(w)) = (env_f32("MCMM_PRIOR_COS"), env_f32("MCMM_PRIOR_WEIGHT")) {
        params.prior = mcg_markov_guide::mcmm::McmmPrior::Fixed(mcg_vmf::MapPrior {
            mean_cosine: c,
            weight: w,
            decay: mcg_vmf::PriorDecay::SquaredCount,
        });
    }
    if let (Some(r), Some(w)) = (env_f32("MCMM_PRIOR_RADIUS"), env_f32("MCMM_PRIOR_WEIGHT")) {
        params.prior = mcg_markov_guide::mcmm::McmmPrior::LightSize {
            radius: r,
            weight: w,
        };
    }
    println!("params: {params:?}");

    let settings = |method| RenderSettings {
        width: size,
        height: size,
        spp,
        bounces: 1,
        seed: std::env::var("MCMM_SEED")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0x6d_6367),
        method,
    };
    let checkpoints: Vec<u32> = (0..)
        .map(|k| 1u32 << k)
        .take_while(|&f| f <= frames)
        .collect();
    let report = |name: &str, sum: &[Vec3], f: u32| {
        let image: Vec<Vec3> = sum.iter().map(|s| *s / f as f32).collect();
        let total = errors(&image, &reference.pixels)
            .expect("same size")
            .rel_mse;
        let terms = pixel_terms(&image, &reference.pixels);
        let n = terms.len() as f64;
        let mut line = format!("{name:>5} frame {f:>3}: relMSE {total:.4}");
        for (class, label) in CLASSES {
            let (count, share) = info
                .iter()
                .zip(&terms)
                .filter(|(p, _)| p.class == class)
                .fold((0, 0.0), |(c, s), (_, t)| (c + 1, s + t / n));
            line += &format!(" | {label} {count} px {share:.4}");
        }
        line += " || by effective lights:";
        for (lo, hi) in bins {
            let (count, share) = effective
                .iter()
                .zip(&terms)
                .zip(&info)
                .filter(|((e, _), p)| p.class == Class::Diffuse && **e >= lo && **e < hi)
                .fold((0, 0.0), |(c, s), ((_, t), _)| (c + 1, s + t / n));
            line += &format!(" [{lo},{hi}) {count} px {share:.4}");
        }
        println!("{line}");
        image
    };

    let mut bsdf_final = None;
    let mut late_bsdf = vec![Vec3::ZERO; (size * size) as usize];
    let mut late_mcmm = vec![Vec3::ZERO; (size * size) as usize];
    if std::env::var("MCMM_SKIP_BSDF").is_err() {
        let s = settings(Method::Bsdf);
        let mut sum = vec![Vec3::ZERO; (size * size) as usize];
        for frame in 0..frames {
            let image = render_frame(&scene, &s, frame, || BsdfSampler, || ());
            for (a, b) in sum.iter_mut().zip(&image) {
                *a += *b;
            }
            if frame >= frames - frames / 4 {
                for (a, b) in late_bsdf.iter_mut().zip(&image) {
                    *a += *b;
                }
            }
            if checkpoints.contains(&(frame + 1)) {
                bsdf_final = Some(report("bsdf", &sum, frame + 1));
            }
        }
    }

    let s = settings(Method::Mcmm);
    let mut renderer = McmmRenderer::new(size, size, params)?;
    let mut sum = vec![Vec3::ZERO; (size * size) as usize];
    let mut mcmm_final = None;
    for frame in 0..frames {
        let image = renderer.render_frame(&scene, &s, frame)?;
        for (a, b) in sum.iter_mut().zip(&image) {
            *a += *b;
        }
        if frame >= frames - frames / 4 {
            for (a, b) in late_mcmm.iter_mut().zip(&image) {
                *a += *b;
            }
        }
        if checkpoints.contains(&(frame + 1)) {
            mcmm_final = Some(report("mcmm", &sum, frame + 1));
            chain_stats(renderer.states(), &lights, &info, size);
        }
    }
    if let (Some(b), Some(m)) = (bsdf_final, mcmm_final) {
        let tb = pixel_terms(&b, &reference.pixels);
        let tm = pixel_terms(&m, &reference.pixels);
        let (sb, sm): (f64, f64) = (tb.iter().sum(), tm.iter().sum());
        println!("mcmm / bsdf = {:.3}", sm / sb);
        let late = |sum: &[Vec3]| {
            let image: Vec<Vec3> = sum.iter().map(|s| *s / (frames / 4) as f32).collect();
            errors(&image, &reference.pixels)
                .expect("same size")
                .rel_mse
        };
        println!(
            "last quarter of the frames alone: mcmm / bsdf = {:.3}",
            late(&late_mcmm) / late(&late_bsdf)
        );
        for (class, label) in CLASSES {
            let pick = |t: &[f64]| -> f64 {
                info.iter()
                    .zip(t)
                    .filter(|(p, _)| p.class == class)
                    .map(|(_, t)| t)
                    .sum()
            };
            println!(
                "  {label}: bsdf {:.4} mcmm {:.4} (ratio {:.3}; share of mcmm's error {:.3})",
                pick(&tb) / tb.len() as f64,
                pick(&tm) / tm.len() as f64,
                pick(&tm) / pick(&tb),
                pick(&tm) / sm
            );
        }
        // The ratio over diffuse pixels by effective light count.
        for (lo, hi) in bins {
            let pick = |t: &[f64]| -> f64 {
                effective
                    .iter()
                    .zip(t)
                    .zip(&info)
                    .filter(|((e, _), p)| p.class == Class::Diffuse && **e >= lo && **e < hi)
                    .map(|((_, t), _)| t)
                    .sum()
            };
            println!(
                "  diffuse with [{lo},{hi}) lights: mcmm/bsdf {:.3}, share of mcmm's error {:.3}",
                pick(&tm) / pick(&tb),
                pick(&tm) / sm
            );
        }
    }
    Ok(())
}

/// Valid states, mean N, and per tile the lights the states point at against the lights that
/// carry 90 % of the tile's pixels' light.
fn chain_stats(
    states: &[mcg_markov_guide::mcmm::PixelState],
    lights: &[(Vec3, Vec3, f32, Vec3)],
    info: &[PixelInfo],
    size: u32,
) {
    let valid: Vec<_> = states.iter().filter(|s| s.is_valid()).collect();
    let mean_n = valid
        .iter()
        .map(|s| f64::from(s.stats.sample_count))
        .sum::<f64>()
        / valid.len().max(1) as f64;
    let young = valid.iter().filter(|s| s.stats.sample_count <= 4).count();
    let on_light = valid
        .iter()
        .filter(|s| {
            lights
                .iter()
                .any(|l| (l.0 - s.stats.mean_target).length() < 0.25)
        })
        .count();
    let (tiles_x, tiles_y) = (size / TILE_WIDTH, size / TILE_HEIGHT);
    let (mut found, mut needed, mut covered) = (0.0, 0.0, 0.0);
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            let mut seen = vec![false; lights.len()];
            let mut weight = vec![0.0f32; lights.len()];
            for ly in 0..TILE_HEIGHT {
                for lx in 0..TILE_WIDTH {
                    let i = ((ty * TILE_HEIGHT + ly) * size + tx * TILE_WIDTH + lx) as usize;
                    let s = &states[i];
                    if s.is_valid()
                        && let Some((k, _)) = lights
                            .iter()
                            .enumerate()
                            .map(|(k, l)| (k, (l.0 - s.stats.mean_target).length()))
                            .filter(|(_, d)| *d < 0.25)
                            .min_by(|a, b| a.1.total_cmp(&b.1))
                    {
                        seen[k] = true;
                    }
                    let total: f32 = info[i].contributions.iter().sum();
                    if total > 0.0 {
                        for (w, c) in weight.iter_mut().zip(&info[i].contributions) {
                            *w += c / total;
                        }
                    }
                }
            }
            // The lights carrying 90 % of the tile's (pixel-normalised) light.
            let total: f32 = weight.iter().sum();
            let mut order: Vec<usize> = (0..lights.len()).collect();
            order.sort_by(|&a, &b| weight[b].total_cmp(&weight[a]));
            let mut acc = 0.0;
            let mut need = Vec::new();
            for k in order {
                if acc >= 0.9 * total || weight[k] <= 0.0 {
                    break;
                }
                acc += weight[k];
                need.push(k);
            }
            found += seen.iter().filter(|&&b| b).count() as f64;
            needed += need.len() as f64;
            covered += need.iter().filter(|&&k| seen[k]).count() as f64;
        }
    }
    let tiles = f64::from(tiles_x * tiles_y);
    println!(
        "       chains: valid {}/{} mean N {mean_n:.1} young(N≤4) {young} on a light {on_light}; per tile: lights pointed at {:.2}, lights carrying 90% {:.2}, of those covered {:.2}",
        valid.len(),
        states.len(),
        found / tiles,
        needed / tiles,
        covered / tiles
    );
}
