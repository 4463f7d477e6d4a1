//! `--method ddgi|adgi|adgi-refill --device gpu`: the probe GI of the WGSL renderer against
//! the analytic furnace, under environments, and against the CPU's probe GI, equal ray budgets
//! and per-frame errors in the JSON.
//!
//! Each test needs a wgpu adapter (lavapipe in CI): without one it is skipped with a message,
//! unless `MCG_REQUIRE_GPU=1`, which turns the skip into a failure.

mod common;

use common::{
    assert_equal_budgets, assert_pixel_mean, assert_tiles_agree, door_args, environment_floors,
    furnace, scenes_dir, sky_settings, temp_dir, tile_stats,
};
use glam::Vec3;
use mcg_demo::render::cpu::{Method, RenderSettings};
use mcg_demo::render::gpu::{GpuProbeRequest, GpuTracer, NO_PROBE};
use mcg_demo::render::probe_gi::{ProbeGi, fit_grid, probe_ray_seed};
use mcg_demo::render::scene::{Scene, SceneFile};
use mcg_demo::render::scene_generator::DOOR_ROOM_OPENS_AT_FRAME;
use mcg_demo::render::{Device, RenderArgs, render, write_outputs};
use mcg_gpu_backend::guides::adgi::{GpuIrradianceQuery, GpuProbeChains, GpuRaySample};
use mcg_gpu_backend::sampling::{pcg_hash, uniform_float};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_probe_cache::{GuideParams, ProbeChains, ProbeTexels, TexelContent};

/// A tracer on a device of its own with the adapter's limits (the probe pipelines bind 13
/// storage buffers, more than the shared test device's WebGPU defaults), `scene` uploaded and
/// empty probes of `method` on `scene`'s grid of spacing `spacing` started, or `None` (skip).
fn probe_tracer(
    test: &str,
    scene: &Scene,
    method: Method,
    (spacing, rays, seed): (f32, u32, u32),
) -> Option<GpuTracer> {
    gpu_or_skip(test)?;
    let mut tracer = GpuTracer::new().unwrap();
    tracer.upload(scene).unwrap();
    let grid = fit_grid(scene, spacing).unwrap();
    tracer.start_probes(method, grid, rays, seed).unwrap();
    Some(tracer)
}

/// The furnace's probes after a GPU run, each value relative to its analytic one.
struct Furnace {
    /// The 48 queries of the GPU cache at the 8 inner probes × 6 axis normals, over
    /// E = π·L_e·ρ/(1 − ρ).
    queries: Vec<f32>,
    /// The mean of every interior irradiance texel of all 64 probes over L_e·ρ/(1 − ρ): the
    /// reflected radiance every probe ray carries in expectation, which is also E/π (what a
    /// `ddgi` texel holds).
    texel_mean: f32,
    /// The mean sample count of those texels (the moving average's window, at most N_max).
    count_mean: f32,
    /// The mean pixel of the last frame over L_e/(1 − ρ).
    pixel: f32,
}

/// The probe methods on the GPU under an environment, as on the CPU
/// (`probe_gi::probe_methods_shade_with_the_environment`): [`environment_floors`],
/// `sky_floor` under L_env = (1, 2, 0.5) and `sky_map_floor`, ρ = (0.5, 0.3, 0.8), `ddgi` and
/// `adgi` with a 4 × 2 × 4 grid, 64 rays per probe, the fourth 16×16 frame of 16 spp, seed 5: the pixel mean is ρ·L_env and
/// ρ × `upward_reflection`, |z| < 5 per channel. Probe rays that return the environment's
/// radiance where they leave the scene (WGSL `probe_ray`) fail it at z = 65 (`ddgi`, uniform sky;
/// checked once).
#[test]
fn gpu_probe_methods_shade_with_the_environment() {
    for (scene, expected, what) in environment_floors() {
        for method in [Method::Ddgi, Method::Adgi] {
            let test = "gpu_probe_methods_shade_with_the_environment";
            let Some(mut tracer) = probe_tracer(test, &scene, method, (50.0, 64, 0x5eed)) else {
                return;
            };
            let settings = sky_settings(method, 1);
            let mut image = Vec::new();
            for frame in 0..4 {
                image = tracer.render_frame(&settings, frame).unwrap().0;
            }
            assert_pixel_mean(&image, expected, 0.0, &format!("GPU {method:?}, {what}"));
        }
    }
}

/// Runs `frames` frames of `method` on the GPU in the furnace of ρ = 0.3, L_e = 0.5 (4 × 4 × 4
/// probes, 64 rays per probe, probe seed `seed`).
fn gpu_furnace(test: &str, method: Method, frames: u32, seed: u32) -> Option<Furnace> {
    let (rho, le) = (0.3f32, 0.5f32);
    let scene = furnace(Vec3::splat(rho), Vec3::splat(le));
    let grid = fit_grid(&scene, 0.5).unwrap();
    assert_eq!(grid.counts(), glam::UVec3::splat(4));
    let mut tracer = probe_tracer(test, &scene, method, (0.5, 64, seed))?;
    let settings = RenderSettings {
        width: 16,
        height: 16,
        spp: 4,
        bounces: 1,
        seed: 3,
        method,
    };
    let mut image = Vec::new();
    for frame in 0..frames {
        image = tracer.render_frame(&settings, frame).unwrap().0;
        let rays = tracer.probe_rays_last_frame().unwrap();
        assert!(rays > 0 && rays <= 64 * 64, "{rays}");
    }
    let mut queries = Vec::new();
    for c in 1..3u32 {
        for b in 1..3u32 {
            for a in 1..3u32 {
                let x = grid.probe_position(glam::UVec3::new(a, b, c));
                for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
                    queries.push(GpuIrradianceQuery::new(x, n, n));
                }
            }
        }
    }
    let cache = tracer.probe_cache().unwrap();
    // The GPU `adgi` frame keeps ADGI's per-sample radiance texels in the cache, so its query
    // must convolve them; the furnace's uniform radiance L gives E = πL either way and cannot
    // tell (reading them as irradiance texels made the door room 10-30 % dark in places).
    let content = match method {
        Method::Adgi => TexelContent::Radiance,
        _ => TexelContent::Irradiance,
    };
    assert_eq!(cache.config().query.content, content, "{}", method.name());
    let e = cache.query(tracer.context(), &queries).unwrap();
    let expected = core::f32::consts::PI * le * rho / (1.0 - rho);
    let (irradiance, visibility) = cache.read_words(tracer.context()).unwrap();
    let config = cache.config().texels;
    let texels = ProbeTexels::from_words(grid, config, &irradiance, &visibility).unwrap();
    let map = config.irradiance_map;
    let interior: Vec<usize> = (0..map.texel_count())
        .filter(|&t| !map.is_border(map.coords(t)))
        .collect();
    let layout = config.irradiance_layout;
    let (sum, counts) = (0..grid.probe_count())
        .flat_map(|p| interior.iter().map(move |&t| (p, t)))
        .fold((0.0f32, 0u32), |(s, c), (p, t)| {
            let count = layout.count(texels.irradiance_word(p, t));
            (s + texels.irradiance(p, t).x, c + count)
        });
    let n = (grid.probe_count() * interior.len()) as f32;
    let texel_mean = sum / n / (le * rho / (1.0 - rho));
    let pixel = image.iter().map(|p| p.x).sum::<f32>() / image.len() as f32;
    Some(Furnace {
        queries: e.iter().map(|e| e.x / expected).collect(),
        texel_mean,
        count_mean: counts as f32 / n,
        pixel: pixel / (le / (1.0 - rho)),
    })
}

/// Asserts that the furnace's probe queries (relative to the analytic E) have a mean within
/// `mean_tol` of 1 and each within `each_tol`, and the mean pixel (relative) within 3 %.
fn assert_furnace(what: &str, f: &Furnace, mean_tol: f32, each_tol: f32) {
    let queries = &f.queries;
    let mean = queries.iter().sum::<f32>() / queries.len() as f32;
    let (lo, hi) = queries
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &q| (a.min(q), b.max(q)));
    eprintln!(
        "{what}: mean {mean:.4}, queries {lo:.4} … {hi:.4}, pixel {:.4}",
        f.pixel
    );
    assert!((mean - 1.0).abs() < mean_tol, "{what}: mean E/E₀ = {mean}");
    for (i, q) in queries.iter().enumerate() {
        assert!((q - 1.0).abs() < each_tol, "{what}: query {i}: E/E₀ = {q}");
    }
    assert!(
        (f.pixel - 1.0).abs() < 0.03,
        "{what}: pixel/L = {}",
        f.pixel
    );
}

/// GPU `ddgi` furnace: a closed cube of albedo ρ = 0.3 emitting L_e = 0.5 from every inner
/// face; the probes must hold the indirect irradiance E = π·L_e·ρ/(1 − ρ) at every point and
/// normal, each pixel is L_e/(1 − ρ) (the CPU test `furnace_probe_irradiance_converges_to_the_
/// analytic_value` of `probe_gi.rs`, same grid, rays and frames).
///
/// Hypothesis: after 120 frames (one bounce added per frame, N_max = 17, < 0.5 % of the loop's
/// error left), the mean of the 48 queries (8 inner probes × 6 axis normals) is within 5 % of
/// E, each within 12 %, the mean pixel of a 16×16 frame at 4 spp within 3 % of L_e/(1 − ρ) —
/// the CPU's thresholds. Fixed seeds. A wrong bounce count fails it: without the probes'
/// irradiance at the probe rays' hits E = π·L_e·ρ (−30 %); with the hit's emission added,
/// +230 %.
#[test]
fn gpu_ddgi_furnace_converges_to_the_analytic_value() {
    let test = "gpu_ddgi_furnace_converges_to_the_analytic_value";
    let Some(result) = gpu_furnace(test, Method::Ddgi, 120, 0x5eed) else {
        return;
    };
    assert_furnace("gpu ddgi", &result, 0.05, 0.12);
}

/// GPU `adgi` furnace: as the `ddgi` test, with ADGI's whole update on the GPU (pilot rays,
/// trigger, heuristics, feedback ĝ, static and dynamic chains, per-sample radiance texels of
/// N_max 63 convolved to irradiance).
///
/// No bound on a single query holds here: ADGI's texels are moving averages of single probe
/// rays (N_max 63, 10 after a dynamic update, which the flicker of the pilot hits triggers on
/// some probes every frame), and a probe ray's light sample is heavy-tailed near the cube's
/// edges (up to the codec's maximum 9.8, 46 × its mean), so one such ray lifts its texel
/// several-fold and with it the up to three axis queries facing it, however many frames run.
/// Largest of the 48 queries per run, measured: GPU, 48 runs, 1.02-1.37 E (above 1.25 E in 3);
/// the CPU's ADGI (`ProbeGi`: the same steps with every decision on the host, deterministic per
/// seed), 118 seeds, up to 1.95 E (above 1.25 E in 23), and their mean up to 1.053 E. The test
/// bounds the statistics the tail does not reach instead.
///
/// Hypothesis: after 120 frames (probe seed 0x5eed; the chains' slot order follows the GPU's
/// atomics, so runs differ)
/// - the mean sample count of the 4096 interior texels of all 64 probes is above 40: the
///   static chains' texel updates keep the windows near N_max 63. Measured 59.2-61.0 over 18
///   runs (sd 0.4); skipping the static texel updates gives 16.5-17.7 (3 runs) and fails it;
/// - the mean of those texels is within 10 % of L_e·ρ/(1 − ρ): measured 0.964-0.996 (32
///   runs, sd 0.008); one ray at the codec's maximum moves it by 1.1 %;
/// - the median of the 48 queries is within 10 % of E: GPU 0.960-0.990 (32 runs, sd 0.008),
///   host 0.949-1.014 (118 seeds, sd 0.011), the bound 6.5 sd below their mean;
/// - every query is above 0.80 E (no probe or direction left dark; the lower tail is light):
///   the smallest query per run, GPU 0.886-0.952 (66 runs, mean 0.913, sd 0.013), host
///   0.874-0.941 (118 seeds), the bound 8 sd below;
/// - the mean pixel is within 3 % of L_e/(1 − ρ) (measured 0.989-1.000, 66 runs).
///
/// A wrong bounce count fails the texel mean and the median (both move by −30 % or +230 %).
/// The furnace's queries cannot see the lookup's radiance-vs-irradiance confusion (uniform
/// radiance L gives E = πL either way): `gpu_furnace` asserts the cache's texel content.
#[test]
fn gpu_adgi_furnace_converges_to_the_analytic_value() {
    let test = "gpu_adgi_furnace_converges_to_the_analytic_value";
    let Some(f) = gpu_furnace(test, Method::Adgi, 120, 0x5eed) else {
        return;
    };
    let mut sorted = f.queries.clone();
    sorted.sort_by(f32::total_cmp);
    let median = 0.5 * (sorted[23] + sorted[24]);
    let (lo, hi) = (sorted[0], sorted[47]);
    eprintln!(
        "gpu adgi: texels {:.4} (count {:.2}), queries median {median:.4}, {lo:.4} … {hi:.4}, \
         pixel {:.4}",
        f.texel_mean, f.count_mean, f.pixel
    );
    assert!(
        f.count_mean > 40.0,
        "gpu adgi: mean texel count {}",
        f.count_mean
    );
    assert!(
        (f.texel_mean - 1.0).abs() < 0.10,
        "gpu adgi: texel mean {}",
        f.texel_mean
    );
    assert!(
        (median - 1.0).abs() < 0.10,
        "gpu adgi: median E/E₀ = {median}"
    );
    for (i, q) in f.queries.iter().enumerate() {
        assert!(*q > 0.80, "gpu adgi: query {i}: E/E₀ = {q}");
    }
    assert!(
        (f.pixel - 1.0).abs() < 0.03,
        "gpu adgi: pixel/L = {}",
        f.pixel
    );
}

/// The door room before its event (door closed), 24 × 24 pixels, 1 spp, 1 m probes, 16 rays.
fn door_scene() -> Scene {
    SceneFile::open(scenes_dir().join("door_room.gltf"))
        .unwrap()
        .build(0.0)
        .unwrap()
}

/// The mean of frames 12..16 of a `method` run of seed `seed` on `device` on the static door
/// room (24 × 24, 1 spp, 1 m probes, 16 rays per probe).
fn door_run(scene: &Scene, method: Method, seed: u32, gpu: Option<&mut GpuTracer>) -> Vec<Vec3> {
    const FRAMES: u32 = 16;
    const SHOWN: u32 = 4;
    let settings = RenderSettings {
        width: 24,
        height: 24,
        spp: 1,
        bounces: 1,
        seed,
        method,
    };
    let mut sum = vec![Vec3::ZERO; 24 * 24];
    let mut add = |f: u32, image: Vec<Vec3>| {
        if f >= FRAMES - SHOWN {
            for (s, p) in sum.iter_mut().zip(image) {
                *s += p / SHOWN as f32;
            }
        }
    };
    let grid = fit_grid(scene, 1.0).unwrap();
    match gpu {
        Some(g) => {
            g.start_probes(method, grid, 16, seed).unwrap();
            for f in 0..FRAMES {
                add(f, g.render_frame(&settings, f).unwrap().0);
            }
        }
        None => {
            let mut gi = ProbeGi::new(method, grid, 16, seed).unwrap();
            for f in 0..FRAMES {
                add(f, gi.frame(scene, &settings, f).unwrap());
            }
        }
    }
    sum
}

/// CPU and GPU probe GI agree in expectation on the door room (door closed): per 8 × 8 tile
/// and channel, the mean over 12 independent runs (seeds) of the mean of frames 12-15 agrees
/// between the devices.
///
/// Hypothesis: both devices compute the same estimator (same probe grid and update policy, the
/// same conventions for probe rays and camera shading), so the run means differ by noise
/// only. Test: per tile and channel Welch's t-test on the 12 runs' tile means of each device
/// (a run's pixels share its probes, so only the runs are independent samples), below the
/// Bonferroni critical value over 9 tiles × 3 channels at family-wise α = 10⁻³ for `ddgi`
/// (deterministic on both devices) and 10⁻⁴ for `adgi` (its GPU runs differ: the chains' slot
/// order follows the GPU's atomics, so α is its false-failure rate per run). 12 runs per
/// device for `ddgi` and `adgi`; fixed seeds. Breaking the GPU's probe rays (dropping the
/// probes' irradiance at their hits, i.e. one bounce less) fails it: `ddgi` tile 0 red
/// 0.107 (CPU) vs 0.068 (GPU), t = 10.9 against the critical 5.17 (21 dof). Measured: worst
/// t −1.54 (critical 5.17) for `ddgi`; for `adgi`, whose update runs wholly on the GPU with its
/// own random streams, −1.91 and −2.02 (critical 6.69 at 17 dof). Querying its radiance
/// texels as irradiance texels (a bilinear lookup instead of the cosine convolution) made red
/// 10-30 % darker in tiles 0, 3, 6, worst t 3.5-5.1 over 5 runs: this test does not reliably
/// catch that break. (Skipping its static texel updates does not fail it either, t 1.73: at
/// frames 12-15 the pilot and dynamic rays carry these tiles; the furnace test's texel count
/// catches that break.)
#[test]
fn gpu_and_cpu_probe_gi_agree_per_tile() {
    let test = "gpu_and_cpu_probe_gi_agree_per_tile";
    let scene = door_scene();
    let Some(mut tracer) = probe_tracer(test, &scene, Method::Ddgi, (1.0, 16, 0)) else {
        return;
    };
    const RUNS: u32 = 12;
    for (method, alpha) in [(Method::Ddgi, 1e-3), (Method::Adgi, 1e-4)] {
        let cpu = tile_stats((24, 24, 8, RUNS), |k| {
            door_run(&scene, method, 100 + k, None)
        });
        let gpu = tile_stats((24, 24, 8, RUNS), |k| {
            door_run(&scene, method, 200 + k, Some(&mut tracer))
        });
        assert_tiles_agree(&cpu, &gpu, alpha, &format!("{} cpu vs gpu", method.name()));
    }
}

/// `ddgi`, `adgi` and `adgi-refill` on the GPU render the door room through its event at equal
/// ray budgets (`ddgi` the same positive count every frame, the others never more and at
/// least 99 % of it over the run), and the JSON of each holds `device: gpu`, each frame's
/// errors against its state's reference, the event frame and frames-to-threshold; `adgi`
/// runs under `--device auto` and lands on the GPU.
#[test]
fn gpu_probe_methods_run_at_equal_rays_with_per_frame_errors() {
    let test = "gpu_probe_methods_run_at_equal_rays_with_per_frame_errors";
    if gpu_or_skip(test).is_none() {
        return;
    }
    let scratch = temp_dir("mcg-probe-gpu", "door");
    let out = scratch.path().to_path_buf();
    let frames = DOOR_ROOM_OPENS_AT_FRAME + 4;
    let mut rays: Vec<Vec<u64>> = Vec::new();
    for method in [Method::Ddgi, Method::Adgi, Method::AdgiRefill] {
        // The CPU test's door render, on the GPU (`adgi` through `--device auto`), B = 1.
        let args = RenderArgs {
            device: if method == Method::Adgi {
                Device::Auto
            } else {
                Device::Gpu
            },
            bounces: 1,
            ..door_args(method, out.clone(), frames)
        };
        let rendered = render(&args).unwrap();
        let r = &rendered.report;
        assert_eq!(r.device, "gpu", "{}", method.name());
        assert_eq!(r.frame_errors.len(), frames as usize);
        assert!(r.frame_errors.iter().all(|e| e.rel_mse.is_finite()));
        let d = r.dynamic.as_ref().unwrap();
        assert_eq!(d.event_frame, Some(DOOR_ROOM_OPENS_AT_FRAME));
        assert_eq!(d.event_errors.len(), frames as usize);
        rays.push(r.probe_rays_per_frame.clone());
        let files = write_outputs(&out, &rendered).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&files[2]).unwrap()).unwrap();
        assert_eq!(json["method"], method.name());
        assert_eq!(json["device"], "gpu");
        assert_eq!(json["gpu_timing"], "wall");
        assert_eq!(
            json["frame_errors"].as_array().unwrap().len(),
            frames as usize
        );
        assert!(json["dynamic"].get("frames_to_threshold").is_some());
    }
    assert_equal_budgets(&rays[0], &rays[1]);
    assert_equal_budgets(&rays[0], &rays[2]);
}

/// The static chains' samples traced on the GPU (`GpuTracer::record_chain_rays`, kernel
/// `trace_chain_samples`) are the rays `trace_probe_rays` traces for the same probes,
/// directions and light seeds, bit for bit: 24 static chains on the door room's 1 m grid, f_s 1
/// on even probes and 0 on odd ones, ĝ 0, one frame. Slot i below the chains' count traces from its probe with light
/// seed `probe_ray_seed(seed, frame, probe, i)`; the slots of a budget above the count are
/// empty (probe `NO_PROBE`), a budget below it drops the later slots (the CPU's `take(budget)`);
/// every slot's rounding uniform is `uniform_float(probe_ray_seed(seed, frame, NO_PROBE, i))`.
#[test]
fn gpu_chain_samples_trace_as_probe_requests() {
    let test = "gpu_chain_samples_trace_as_probe_requests";
    let scene = door_scene();
    let (seed, frame) = (7, 5);
    let Some(tracer) = probe_tracer(test, &scene, Method::Adgi, (1.0, 16, seed)) else {
        return;
    };
    let ctx = tracer.context();
    let grid = fit_grid(&scene, 1.0).unwrap();
    let mut k = 0_u32;
    let chains = ProbeChains::new_static(grid, 24, || {
        k += 1;
        core::array::from_fn(|d| uniform_float(pcg_hash(5 * k + d as u32)))
    })
    .unwrap();
    let gpu = GpuProbeChains::new(ctx, &chains, GuideParams::STATIC).unwrap();
    let cells = 8 * grid.probe_count();
    // f_s 1 on even probes, 0 on odd ones: chains there drop their samples (h = 0), so the
    // frame fills fewer slots than it has.
    let table: Vec<f32> = (0..cells).map(|i| ((i / 8) % 2 == 0).into()).collect();
    gpu.write_guide_table(ctx, &table).unwrap();
    gpu.write_feedback(ctx, &vec![0.0; cells]).unwrap();
    gpu.step_frame(ctx, 0x5eed).unwrap();
    let samples = gpu.read_samples(ctx).unwrap();
    let count = samples.len();
    let capacity = gpu.samples().len();
    assert!(count > 8 && count < capacity, "{count} of {capacity}");
    let requests: Vec<GpuProbeRequest> = samples
        .iter()
        .enumerate()
        .map(|(i, s)| GpuProbeRequest {
            origin: grid
                .probe_position(grid.probe_coords(s.probe as usize))
                .to_array(),
            seed: probe_ray_seed(seed, frame, s.probe, i as u32),
            direction: s.direction.to_array(),
            probe: s.probe,
        })
        .collect();
    let expected = tracer.trace_probe_requests(&requests).unwrap();
    assert!(expected.iter().any(|r| r.radiance.max_element() > 0.0));
    let rays = ctx.zeroed_buffer::<GpuRaySample>("chain rays", capacity);
    let rounding = ctx.zeroed_buffer::<f32>("chain rounding", capacity);
    for (limit, spent) in [
        (capacity, 0),
        (count / 2, 0),
        (capacity, capacity - count / 3),
    ] {
        let spent_buffer = ctx.storage_buffer("spent", &[0, spent as u32]);
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        let budget = (limit as u32, Some(spent_buffer.raw()));
        tracer
            .record_chain_rays(&mut encoder, &gpu, (&rays, &rounding), budget, frame)
            .unwrap();
        ctx.queue().submit([encoder.finish()]);
        let traced = ctx.read_back(&rays).unwrap();
        let uniforms = ctx.read_back(&rounding).unwrap();
        let traced_slots = count.min(limit - spent);
        assert_eq!(
            traced[..traced_slots],
            expected[..traced_slots],
            "limit {limit}, spent {spent}"
        );
        assert!(
            traced[traced_slots..limit]
                .iter()
                .all(|r| r.probe == NO_PROBE)
        );
        for (i, &u) in uniforms[..limit].iter().enumerate() {
            let want = uniform_float(probe_ray_seed(seed, frame, NO_PROBE, i as u32));
            assert_eq!(u.to_bits(), want.to_bits(), "slot {i}");
        }
    }
    assert!(
        tracer
            .record_chain_rays(
                &mut ctx.device().create_command_encoder(&Default::default()),
                &gpu,
                (&rays, &rounding),
                (capacity as u32 + 1, None),
                frame,
            )
            .is_err()
    );
}
