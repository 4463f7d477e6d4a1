//! `--method adgi --device gpu`: ADGI's pilot requests (sec. 4.4) as the GPU frame lays them out
//! (`lay_out_pilot_rays`, `GpuTracer::pilot_requests`) against the CPU's, the first batch of
//! each `ProbeUpdater` frame of `ProbeGi::update`.
//!
//! Needs a wgpu adapter (lavapipe in CI): without one it is skipped with a message, unless
//! `MCG_REQUIRE_GPU=1`, which turns the skip into a failure.

mod common;

use common::furnace;
use glam::Vec3;
use mcg_demo::render::cpu::Method;
use mcg_demo::render::gpu::{GpuProbeRequest, GpuTracer};
use mcg_demo::render::probe_gi::{ProbeGi, fit_grid, request_seed};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_probe_cache::heuristics::octant;

/// The bound on a direction component's difference: the one `mcg-gpu-backend`'s
/// `parity_adgi::pilot_rays_and_trigger_match_the_cpu` holds `adgi_pilot_direction` to (its
/// `sqrt`, `sin` and `cos` are WGSL's, the CPU's the platform's).
const DIRECTION_TOLERANCE: f32 = 2e-6;

/// For render seeds 7 and 0xdead_beef on the furnace's 4 × 4 × 4 probes, frames 0-5: the GPU's
/// `8 · 64` pilot requests equal the CPU's in order — probe, light seed (`request_seed`, integer
/// hashing of the bit-exact uniforms) and origin bit for bit, directions within
/// [`DIRECTION_TOLERANCE`] in the same octant; both frames of a pair lay out the same requests
/// and the next pair others (sec. 4.4's `AABBCC…`). Broken once on purpose (the light seed
/// from the uniforms of k = 1 instead of 2): failed at request 0.
#[test]
fn gpu_pilot_requests_match_the_cpu() {
    let test = "gpu_pilot_requests_match_the_cpu";
    if gpu_or_skip(test).is_none() {
        return;
    }
    let scene = furnace(Vec3::splat(0.3), Vec3::splat(0.5));
    let grid = fit_grid(&scene, 0.5).unwrap();
    let n = 8 * grid.probe_count();
    assert_eq!(n, 512);
    let mut worst = 0.0_f32;
    for seed in [7, 0xdead_beef] {
        let mut tracer = GpuTracer::new().unwrap();
        tracer.upload(&scene).unwrap();
        tracer.start_probes(Method::Adgi, grid, 64, seed).unwrap();
        let mut cpu = ProbeGi::new(Method::Adgi, grid, 64, seed).unwrap();
        let mut frames: Vec<Vec<GpuProbeRequest>> = Vec::new();
        for frame in 0..6 {
            let mut pilots = None;
            cpu.update(scene.camera.position, frame, |_, batch, _| {
                pilots.get_or_insert_with(|| batch.to_vec());
            })
            .unwrap();
            let want = pilots.expect("an ADGI frame traces its pilots first");
            let got = tracer.pilot_requests(frame).unwrap();
            assert_eq!((got.len(), want.len()), (n, n), "seed {seed} frame {frame}");
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                let at = format!("seed {seed} frame {frame} request {i}");
                assert_eq!(g.probe, w.probe, "{at}: probe");
                assert_eq!(g.seed, request_seed(w), "{at}: light seed");
                let origin = w.origin.to_array().map(f32::to_bits);
                assert_eq!(g.origin.map(f32::to_bits), origin, "{at}: origin");
                let d = Vec3::from_array(g.direction);
                let error = (d - w.direction).abs().max_element();
                assert!(
                    error <= DIRECTION_TOLERANCE,
                    "{at}: GPU {d} CPU {}",
                    w.direction
                );
                assert_eq!(octant(d), octant(w.direction), "{at}: octant");
                worst = worst.max(error);
            }
            frames.push(got);
        }
        for pair in 0..3 {
            assert_eq!(
                frames[2 * pair],
                frames[2 * pair + 1],
                "seed {seed} pair {pair}"
            );
        }
        assert_ne!(frames[0], frames[2], "seed {seed}");
        assert_ne!(frames[2], frames[4], "seed {seed}");
    }
    println!("pilot directions: worst component difference {worst:e}");
}
