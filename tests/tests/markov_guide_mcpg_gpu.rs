//! Statistical suite of the GPU MCPG guide (`mcg::mcpg` through `GpuMcpgGuide`, on lavapipe in
//! CI): a plane of shading points lit by one sphere light, one guided sample per point and
//! frame from a WGSL kernel that imports the guide (`support/mcpg_scene.wgsl`), the irradiance
//! estimate L·cos/p checked against the closed form (`ToyScene::irradiance`).
//!
//! The scenes of issue 17's table (measured on a first WGSL attempt at 4 096 points, 64 frames,
//! 16 seeds): one small light (variance guided/cosine 0.010-0.011), a large light (0.255), a
//! far small light (0.065) and a light moving 0.03 per frame (0.018; 0.67 without velocity
//! prediction). Here 1 024 points, 40 frames (the first 12 discarded as warm-up) and 8 seeds
//! per scene (24 where a z-test decides) keep the suite at seconds on lavapipe.
//!
//! Skipped without an adapter unless `MCG_REQUIRE_GPU=1`.

use glam::Vec3;
use mcg_gpu_backend::guides::mcpg::GpuMcpgGuide;
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::{
    GpuBuffer, GpuContext, GuidedKernel, buffer_entry, shaders, storage_entry, wgpu,
};
use mcg_markov_guide::mcpg::GuideConfig;
use mcg_markov_guide::toy_scene::{SphereLight, ToyScene};
use mcg_tests::{RunningStats, assert_z_test, z_test};

const SCENE: &str = include_str!("support/mcpg_scene.wgsl");
const SIDE: u32 = 32;
const EXTENT: f32 = 1.0;
const FRAMES: u32 = 40;
const WARM_UP: u32 = 12;
const SEEDS: u32 = 8;

const MODE_GUIDED: u32 = 0;
const MODE_TRAP: u32 = 2;
const MODE_NO_VELOCITY: u32 = 3;

/// WGSL `SceneParams` (288 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SceneParams {
    frame: u32,
    seed: u32,
    side: u32,
    mode: u32,
    extent: f32,
    light_count: u32,
    pad: [u32; 2],
    /// Per light: (centre, radius), (velocity, radiance).
    lights: [[f32; 4]; 16],
}

/// The scene kernel with the guide's layout at group 1.
struct SceneKernel {
    kernel: GuidedKernel,
    pipeline: wgpu::ComputePipeline,
}

impl SceneKernel {
    fn new(ctx: &GpuContext, guide: &GpuMcpgGuide) -> Self {
        let source = shaders::compose(SCENE, &GpuMcpgGuide::shader_defs(1)).unwrap();
        let kernel = GuidedKernel::from_wgsl(
            ctx,
            "mcpg scene",
            source,
            &[
                buffer_entry(0, wgpu::BufferBindingType::Uniform),
                storage_entry(1, false),
            ],
            guide.bind_group_layout(),
        );
        Self {
            pipeline: kernel.pipeline(ctx, "scene_frame"),
            kernel,
        }
    }
}

/// The guide's configuration for the plane and light: the scene's bounds, adaptive cells of
/// about 8 "pixels" of the 32 × 32 points seen with a 60° field of view
/// (`GuideConfig::for_camera`), small tables.
fn config() -> GuideConfig {
    let mut c = GuideConfig::for_scene(Vec3::new(-3.0, -3.0, 0.0), Vec3::new(3.0, 3.0, 6.0))
        .for_camera(60f32.to_radians(), SIDE);
    c.adaptive_capacity = 1 << 15;
    c.static_capacity = 1 << 12;
    if let Some(cache) = &mut c.cache {
        cache.capacity = 1 << 12;
    }
    c
}

/// A guide and the scene kernel bound to it, built once per test.
struct Bench {
    guide: GpuMcpgGuide,
    kernel: SceneKernel,
}

impl Bench {
    fn new(ctx: &GpuContext) -> Self {
        let mut guide = GpuMcpgGuide::new(ctx, &config()).unwrap();
        guide.set_camera(ctx, Vec3::new(0.0, -2.0, 4.0));
        let kernel = SceneKernel::new(ctx, &guide);
        Self { guide, kernel }
    }
}

/// One run from empty grids: per frame and point, (estimate, exact irradiance, lobe sample).
fn run(
    ctx: &GpuContext,
    bench: &mut Bench,
    scene: &ToyScene,
    mode: u32,
    seed: u32,
) -> Vec<(f64, f64, f64)> {
    bench.guide.reset(ctx);
    let Bench { guide, kernel } = bench;
    let count = (SIDE * SIDE) as usize;
    let estimates: GpuBuffer<[f32; 2]> = ctx.zeroed_buffer("estimates", count * FRAMES as usize);
    let mut params = SceneParams {
        seed,
        side: SIDE,
        mode,
        extent: EXTENT,
        ..Default::default()
    };
    let params_buffer = ctx.uniform_buffer("scene", &params);
    let io = kernel
        .kernel
        .io_bind_group(ctx, &[params_buffer.raw(), estimates.raw()]);
    let mut exact = Vec::with_capacity(count * FRAMES as usize);
    for frame in 0..FRAMES {
        let now = scene.at_time(frame as f32);
        params.frame = frame;
        params.light_count = now.lights.len().min(8) as u32;
        for (k, l) in now.lights.iter().take(8).enumerate() {
            params.lights[2 * k] = l.center.extend(l.radius).to_array();
            params.lights[2 * k + 1] = l.velocity.extend(l.radiance).to_array();
        }
        ctx.write(&params_buffer, &[params]).unwrap();
        for i in 0..count as u32 {
            exact.push(
                now.irradiance(point(i))
                    .expect("the lights are above every horizon"),
            );
        }
        let mut encoder = ctx.device().create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&kernel.pipeline);
            pass.set_bind_group(0, &io, &[]);
            pass.set_bind_group(1, guide.bind_group(), &[]);
            pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
        }
        guide.record_end_frame(ctx, &mut encoder).unwrap();
        ctx.queue().submit([encoder.finish()]);
    }
    ctx.read_back(&estimates)
        .unwrap()
        .into_iter()
        .zip(exact)
        .map(|([e, lobe], exact)| (f64::from(e), exact, f64::from(lobe)))
        .collect()
}

/// Per seed: the mean relative error (e/E − 1) and the mean squared relative error over the
/// frames after warm-up.
fn relative_errors(samples: &[(f64, f64, f64)]) -> (f64, f64) {
    let start = (WARM_UP * SIDE * SIDE) as usize;
    let (mut sum, mut sum_sq, mut n) = (0.0, 0.0, 0.0);
    for &(e, exact, _) in &samples[start..] {
        if exact > 0.0 {
            let r = e / exact - 1.0;
            sum += r;
            sum_sq += r * r;
            n += 1.0;
        }
    }
    (sum / n, sum_sq / n)
}

/// Bias (per-seed means) and mean squared relative error over `seeds` seeds (at most 64).
fn measure_seeds(
    ctx: &GpuContext,
    bench: &mut Bench,
    scene: &ToyScene,
    mode: u32,
    salt: u32,
    seeds: u32,
) -> (RunningStats, Vec<f64>) {
    let mut bias = RunningStats::default();
    let mut mse = Vec::with_capacity(seeds as usize);
    for s in 0..seeds {
        let (b, m) = relative_errors(&run(ctx, bench, scene, mode, 0x6d63_0000 + salt * 64 + s));
        bias.push(b);
        mse.push(m);
    }
    (bias, mse)
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len() as f64
}

/// The groups of [`median_of_means`] in the variance-ratio test: 6 groups of 4 seeds.
const MSE_GROUPS: usize = 6;

/// The median of the means of `groups` consecutive equal groups of `values` (the median of
/// means): an estimate of the mean that one outlying value moves by at most one group's
/// median rank, where it moves the plain mean by value/n.
fn median_of_means(values: &[f64], groups: usize) -> f64 {
    let size = values.len() / groups;
    let means: Vec<f64> = values.chunks_exact(size).map(mean).collect();
    median(&means)
}

/// The median, the mean of the two middle values for an even count.
fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    0.5 * (sorted[(n - 1) / 2] + sorted[n / 2])
}

/// Two lights of radius 0.5 at height 3, 3 units apart, one ten times brighter: chains
/// towards the bright one carry ten times the weight of those towards the dim one.
fn two_lights() -> ToyScene {
    ToyScene {
        lights: vec![
            SphereLight::fixed(Vec3::new(-1.5, 0.0, 3.0), 0.5, 40.0),
            SphereLight::fixed(Vec3::new(1.5, 0.0, 3.0), 0.5, 4.0),
        ],
        occluders: Vec::new(),
    }
}

/// The mean squared relative error of cosine sampling over the frames after warm-up, exactly:
/// one light of radiance L seen with irradiance E is hit with probability P = E/(πL), and the
/// estimate πL·[hit] has relative variance 1/P − 1.
fn cosine_mse(scene: &ToyScene) -> f64 {
    let mut sum = 0.0;
    let mut n = 0.0;
    for frame in WARM_UP..FRAMES {
        let now = scene.at_time(frame as f32);
        let radiance = f64::from(now.lights[0].radiance);
        for i in 0..SIDE * SIDE {
            let e = now.irradiance(point(i)).expect("above the horizon");
            sum += core::f64::consts::PI * radiance / e - 1.0;
            n += 1.0;
        }
    }
    sum / n
}

/// Shading point `i` of the plane (as `scene_frame` places it).
fn point(i: u32) -> Vec3 {
    let cell = (glam::Vec2::new((i % SIDE) as f32, (i / SIDE) as f32) + 0.5) / SIDE as f32;
    (EXTENT * (2.0 * cell - 1.0)).extend(0.0)
}

fn far_light() -> ToyScene {
    ToyScene {
        lights: vec![SphereLight::fixed(Vec3::new(0.0, 0.0, 6.0), 0.1, 200.0)],
        occluders: Vec::new(),
    }
}

/// H₀: the GPU guide's estimator L·cos/p is unbiased, and it beats cosine sampling. Per scene,
/// 24 seeds × 28 frames × 1 024 points; the per-seed mean relative errors must pass a 5σ z-test
/// against 0, and the mean squared relative error relative to cosine sampling (exact,
/// [`cosine_mse`]) must stay below a bar. The bars are the issue table's ratios (small light
/// 0.011 with 50 % slack for the smaller sample, large light 0.255, moving light 0.018) except
/// for the far small light: there the guided error is heavy-tailed (a light of 9·10⁻⁴ sr that
/// a cosine sample finds once per 3 600 tries, so a cell that learns it late contributes a few
/// huge estimates), and one seed in 32 decides the mean — measured 0.041 with 8 seeds, 0.165
/// with 32 (issue table: 0.065) — so the bar is 0.25.
///
/// Why 24 seeds: the per-seed mean errors are skewed (most seeds slightly low, a few high when
/// a cell learns the light late), so with 8 seeds the sample standard deviation is often far
/// below the true one and the z statistic of an unbiased guide is inflated. On the large light
/// 8 seeds gave bias −0.0034 ± 0.0007 (z −5.2, a false rejection in CI) and −0.0033 ± 0.0025
/// (z −1.4) in two runs; 48 seeds gave −0.0013 ± 0.0007 (z −1.8).
///
/// The guided MSE is the median of means over 6 groups of 4 seeds ([`median_of_means`]), not
/// the plain mean: in a CI run of [`gpu_mcpg_tracks_a_moving_light_with_velocity_prediction`]
/// one outlying seed lifted the plain mean of the same scene and mode over 24 seeds to 4.24,
/// which here would be a ratio of 0.017 against the bar's 0.018 (three runs of this test:
/// medians of means 2.46-2.58, means 2.46-2.67, ratios 0.0099-0.0103). Without velocity
/// prediction the moving light's ratio is 0.067 and the test fails.
#[test]
fn gpu_mcpg_is_unbiased_and_beats_cosine_sampling() {
    let Some(ctx) = gpu_or_skip("gpu_mcpg_is_unbiased_and_beats_cosine_sampling") else {
        return;
    };
    let mut bench = Bench::new(ctx);
    for (k, (name, scene, bar)) in [
        ("small light", ToyScene::single_light(), 1.5 * 0.011),
        ("large light", ToyScene::large_light(), 0.255),
        ("far small light", far_light(), 0.25),
        ("moving light", ToyScene::moving_light(0.03), 0.018),
    ]
    .into_iter()
    .enumerate()
    {
        let (bias, per_seed) = measure_seeds(
            ctx,
            &mut bench,
            &scene,
            MODE_GUIDED,
            2 * k as u32,
            3 * SEEDS,
        );
        let guided = median_of_means(&per_seed, MSE_GROUPS);
        let cosine = cosine_mse(&scene);
        let z = z_test(&bias, 0.0);
        let ratio = guided / cosine;
        println!(
            "GPU MCPG {name}: bias {:+.5} ± {:.5} (z {:.2}), MSE {guided:.4} (mean {:.4}) vs cosine {cosine:.4}, ratio {ratio:.4}",
            z.mean,
            z.standard_error,
            z.z,
            mean(&per_seed)
        );
        assert_z_test(&format!("GPU MCPG, {name}"), &bias, 0.0, 5.0);
        assert!(ratio <= bar, "{name}: variance ratio {ratio:.4} > {bar}");
    }
}

/// The trap of issue 17: dividing by the plain mean of the accessed states' densities (eq. 7
/// read literally) instead of the mixture the resampling sampled from is biased. On two
/// lights of different power ([`two_lights`]), where the candidates' weights differ, the same
/// 5σ z-test must reject it (|z| ≥ 5) and accept the exact mixture, both over 24 seeds × 28
/// frames × 1 024 points. The GPU's racing stores make runs differ slightly from one launch to
/// the next; with 8 seeds the trap's z ranged from −4 to −10 between runs (the standard error
/// estimated from 8 seed means is itself noisy), so the test uses three times the seeds
/// (expected |z| ≈ 12).
#[test]
fn plain_mean_of_the_candidate_pdfs_is_detected_as_biased() {
    let Some(ctx) = gpu_or_skip("plain_mean_of_the_candidate_pdfs_is_detected_as_biased") else {
        return;
    };
    let mut bench = Bench::new(ctx);
    let scene = two_lights();
    let (trap, _) = measure_seeds(ctx, &mut bench, &scene, MODE_TRAP, 20, 3 * SEEDS);
    let (exact, _) = measure_seeds(ctx, &mut bench, &scene, MODE_GUIDED, 21, 3 * SEEDS);
    let (t, e) = (z_test(&trap, 0.0), z_test(&exact, 0.0));
    println!(
        "two lights: plain mean of pdfs bias {:+.5} ± {:.5} (z {:.2}), mixture {:+.5} ± {:.5} (z {:.2})",
        t.mean, t.standard_error, t.z, e.mean, e.standard_error, e.z
    );
    assert!(
        t.z.abs() >= 5.0,
        "the biased pdf was not detected: z = {:.2}",
        t.z
    );
    assert_z_test("GPU MCPG, two lights", &exact, 0.0, 5.0);
}

/// Velocity prediction (MCPG eq. 9-10) pays on the moving light: without the light's previous
/// position the chains lag behind and the mean squared relative error is several times larger
/// (issue table: 0.018 vs 0.67 relative to cosine).
///
/// Hypothesis: the median over 24 seeds of the per-seed MSE without velocity is at least 3× the
/// median with it. The median, not the mean: the per-seed MSE is heavy-tailed (a rare path that
/// finds the light through an untrained direction), and the GPU's racing stores make every
/// launch differ. Three runs on lavapipe gave medians 2.54 / 12.57, 2.46 / 12.68 and
/// 2.36 / 16.05 (ratios 4.9-6.8), per-seed values 1.4-4.7 with velocity and 4.7-74 without;
/// the means (2.3-2.6 against 14.8-15.5) once reached 4.24 against 13.23 in CI through one
/// outlying seed, which is why a 4× bar on the means failed there. With the velocity term
/// switched off in both runs the ratio is about 1 and the test fails.
#[test]
fn gpu_mcpg_tracks_a_moving_light_with_velocity_prediction() {
    let Some(ctx) = gpu_or_skip("gpu_mcpg_tracks_a_moving_light_with_velocity_prediction") else {
        return;
    };
    let mut bench = Bench::new(ctx);
    let scene = ToyScene::moving_light(0.03);
    let (_, with) = measure_seeds(ctx, &mut bench, &scene, MODE_GUIDED, 30, 3 * SEEDS);
    let (_, without) = measure_seeds(ctx, &mut bench, &scene, MODE_NO_VELOCITY, 31, 3 * SEEDS);
    let (with, without) = (median(&with), median(&without));
    println!("moving light: median per-seed MSE with velocity {with:.4}, without {without:.4}");
    assert!(without >= 3.0 * with, "{without:.4} < 3 × {with:.4}");
}

/// The discard heuristic (MCPG sec. 5): after the light vanishes (frame 16), lobe samples
/// that point at it find nothing and zero their states, so the fraction of lobe samples falls
/// from the last lit frames to frames 24-31 by at least half. 4 seeds.
#[test]
fn gpu_mcpg_stops_sampling_a_vanished_light() {
    let Some(ctx) = gpu_or_skip("gpu_mcpg_stops_sampling_a_vanished_light") else {
        return;
    };
    let mut bench = Bench::new(ctx);
    let mut scene = ToyScene::single_light();
    scene.lights[0].vanish = 16.0;
    let per_frame = (SIDE * SIDE) as usize;
    let (mut before, mut after) = (0.0, 0.0);
    for s in 0..4 {
        let samples = run(ctx, &mut bench, &scene, MODE_GUIDED, 0x6d63_0f00 + s);
        let lobes = |frames: core::ops::Range<usize>| {
            samples[frames.start * per_frame..frames.end * per_frame]
                .iter()
                .map(|&(_, _, l)| l)
                .sum::<f64>()
                / (frames.len() * per_frame) as f64
        };
        before += lobes(12..16) / 4.0;
        after += lobes(24..32) / 4.0;
    }
    println!("lobe samples: {before:.3} before the light vanished, {after:.3} after");
    assert!(
        before > 0.5,
        "the guide never learned the light: {before:.3}"
    );
    assert!(after <= 0.5 * before, "{after:.3} > half of {before:.3}");
}
