//! Where the probe methods' error comes from after the door of the door room opens (CPU):
//! renders each method at the Dynamic GI section's sizes (64 × 64, 8 spp, 196 probes of
//! 0.75 m, 32 rays per probe, 56 frames, the door opening at frame 32) for a few seeds and
//! prints
//! - per frame from 2 frames before the event: the event region's relMSE (mean over seeds),
//!   whether ADGI's dynamic phase ran, its rays, the probes whose f_d > 0 (all / near the
//!   doorway), and the mean moving-average count of the near probes' irradiance texels;
//! - at a few frames after the event, the event region's error split into a bias part (the
//!   relMSE of the image averaged over the seeds, less its noise share) and a noise part (the
//!   rest of the mean per-seed relMSE).
//!
//! ```text
//! cargo run --release -p mcg-demo --example probe_gi_diagnostics -- [METHOD …] [--seeds N]
//! ```
//!
//! Methods default to `ddgi adgi adgi-refill adgi-blend`; seeds to 4 (render seeds 1..=N).
//! The state references are cached under `out/diag/reference/` (the same files as the
//! `render` command's with `--out out/diag/…`).

use std::path::Path;

use clap::ValueEnum;
use glam::Vec3;
use mcg_demo::render::cpu::{Method, RenderSettings};
use mcg_demo::render::output::errors;
use mcg_demo::render::probe_gi::{ProbeGi, fit_grid};
use mcg_demo::render::scene::{SceneFile, frame_time};
use mcg_demo::render::scene_generator::DOOR_ROOM_OPENS_AT_FRAME;
use mcg_demo::render::states::{ReferenceSettings, SceneStates};

const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/door_room.gltf");
const FRAMES: u32 = 56;
const SIZE: u32 = 64;
/// The doorway's centre (the door hangs at x = 2 between z = −0.5 and 0.5, 2.2 m high).
const DOORWAY: Vec3 = Vec3::new(2.0, 1.1, 0.0);
/// Probes within this distance of the doorway are "near".
const NEAR: f32 = 1.5;
/// Frames after the event at which the bias / noise split is printed.
const SPLIT_AFTER: [u32; 4] = [2, 4, 8, 23];

/// One frame's numbers of one run.
#[derive(Clone, Copy, Default)]
struct FrameStats {
    event_rel_mse: f64,
    dynamic_phase: bool,
    rays_dynamic: u64,
    changed: usize,
    changed_near: usize,
    near_count: f64,
}

fn main() -> mcg_demo::Result<()> {
    let mut methods = Vec::new();
    let mut seeds = 4_u32;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--seeds" {
            seeds = args.next().ok_or("--seeds N")?.parse()?;
        } else {
            methods.push(Method::from_str(&a, true)?);
        }
    }
    if methods.is_empty() {
        methods = vec![
            Method::Ddgi,
            Method::Adgi,
            Method::AdgiRefill,
            Method::AdgiBlend,
        ];
    }
    let file = SceneFile::open(SCENE)?;
    let reference = ReferenceSettings {
        width: SIZE,
        height: SIZE,
        spp: 256,
        bounces: 8,
    };
    let event = DOOR_ROOM_OPENS_AT_FRAME;
    for method in methods {
        let mut runs: Vec<Vec<FrameStats>> = Vec::new();
        // Per split frame: each seed's event-region pixels, and the reference's.
        let mut split: Vec<Vec<Vec<Vec3>>> = vec![Vec::new(); SPLIT_AFTER.len()];
        let mut split_reference: Vec<Vec<Vec3>> = vec![Vec::new(); SPLIT_AFTER.len()];
        for seed in 1..=seeds {
            let mut states =
                SceneStates::new(&file, FRAMES, reference, Path::new("out/diag"), 0.07)?;
            let mut scene = file.build(frame_time(0))?;
            let grid = fit_grid(&scene, 0.75).map_err(|e| format!("{e:?}"))?;
            let near: Vec<usize> = (0..grid.probe_count())
                .filter(|&p| grid.probe_position(grid.probe_coords(p)).distance(DOORWAY) < NEAR)
                .collect();
            let mut gi = ProbeGi::new(method, grid, 32, seed)?;
            let settings = RenderSettings {
                width: SIZE,
                height: SIZE,
                spp: 8,
                bounces: 1,
                seed,
                method,
            };
            let mut stats = Vec::new();
            for frame in 0..FRAMES {
                if frame > 0 {
                    scene = file.build(frame_time(frame))?;
                }
                let image = gi.frame(&scene, &settings, frame)?;
                let _ = states.frame_errors(frame, &image);
                let (refs, mask) = states.reference_and_mask(frame);
                let pick = |v: &[Vec3]| -> Vec<Vec3> {
                    v.iter()
                        .zip(mask)
                        .filter_map(|(p, &m)| m.then_some(*p))
                        .collect()
                };
                if let Some(k) = SPLIT_AFTER.iter().position(|&a| frame == event + a) {
                    split[k].push(pick(&image));
                    split_reference[k] = pick(refs);
                }
                let rays = gi.last_frame();
                let updater = gi.updater();
                let f_d = updater.heuristics().map(|(_, d)| d);
                let changed_of =
                    |p: usize| f_d.is_some_and(|d| d[p * 8..][..8].iter().any(|&v| v > 0.0));
                let layout = updater.texels().config().irradiance_layout;
                let texels = updater.interior_texels();
                let near_count = near
                    .iter()
                    .flat_map(|&p| {
                        texels.iter().map(move |&(i, _)| {
                            f64::from(layout.count(updater.texels().irradiance_word(p, i)))
                        })
                    })
                    .sum::<f64>()
                    / (near.len() * texels.len()).max(1) as f64;
                stats.push(FrameStats {
                    event_rel_mse: 0.0,
                    dynamic_phase: rays.dynamic_phase,
                    rays_dynamic: rays.rays_dynamic,
                    changed: (0..grid.probe_count()).filter(|&p| changed_of(p)).count(),
                    changed_near: near.iter().filter(|&&p| changed_of(p)).count(),
                    near_count,
                });
            }
            let record = states.finish();
            for (s, e) in stats.iter_mut().zip(&record.event_errors) {
                s.event_rel_mse = e.rel_mse;
            }
            println!(
                "{} seed {seed}: frames to 0.07 {:?}, near probes {}",
                method.name(),
                record.frames_to_threshold,
                near.len()
            );
            runs.push(stats);
        }
        println!(
            "{}: frame, event relMSE (mean of {seeds} seeds), dynamic phase (runs), dynamic rays, \
             probes with f_d > 0 (all / near), mean texel count near",
            method.name()
        );
        let n = f64::from(seeds);
        for frame in (event - 2)..FRAMES {
            let f = frame as usize;
            let mean = |g: fn(&FrameStats) -> f64| runs.iter().map(|r| g(&r[f])).sum::<f64>() / n;
            println!(
                "  {frame:2} {:.4} {} {:7.0} {:5.1} / {:4.1} {:5.1}",
                mean(|s| s.event_rel_mse),
                runs.iter().filter(|r| r[f].dynamic_phase).count(),
                mean(|s| s.rays_dynamic as f64),
                mean(|s| s.changed as f64),
                mean(|s| s.changed_near as f64),
                mean(|s| s.near_count),
            );
        }
        for (k, after) in SPLIT_AFTER.iter().enumerate() {
            let reference = &split_reference[k];
            let per_seed: f64 = split[k]
                .iter()
                .filter_map(|img| errors(img, reference))
                .map(|e| e.rel_mse)
                .sum::<f64>()
                / n;
            let mean_image: Vec<Vec3> = (0..reference.len())
                .map(|i| split[k].iter().map(|img| img[i]).sum::<Vec3>() / seeds as f32)
                .collect();
            let of_mean = errors(&mean_image, reference).map_or(f64::NAN, |e| e.rel_mse);
            // E[relMSE of one] = bias² + var; relMSE of the mean of n = bias² + var / n.
            let noise = (per_seed - of_mean) * n / (n - 1.0).max(1.0);
            println!(
                "  event + {after:2}: relMSE {per_seed:.4} = bias {:.4} + noise {noise:.4}",
                per_seed - noise
            );
        }
    }
    Ok(())
}
