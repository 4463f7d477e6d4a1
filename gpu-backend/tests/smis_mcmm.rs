//! MCMM Fig. 16 on the GPU: MCMM chains (`mcg::mcmm`, Alg. 1-3 with the paper's constants)
//! estimated with TSMIS (eq. 8) and SSMIS (eq. 9) on lavapipe, with the decorrelating
//! permutations of sec. 4.2 done through workgroup memory (`mcmm_tile_exchange`): unbiased
//! with them, biased without (appendix A).
//!
//! Scene (`kernels/mcmm_smis.wgsl`): a sphere light of radius 0.3 and radiance L at
//! (0, 0, 1) above the plane z = 0; tile = one image row of 32 pixels 0.05 apart along x
//! (each pixel sees the light from its own direction), normal +z, cosine sampling as the
//! defensive technique. The exact irradiance is π L (r/d)² cos θ (the sphere is entirely
//! above the plane). The neighbour window is 0, so Alg. 1 re-offers only the pixel's own
//! previous state and the rows are independent tiles; each frame takes n = 4 steps.
//!
//! Hypothesis per scheme: the mean over 256 independent tiles of the tile's estimate (averaged
//! over its 32 pixels and 12 measured frames after 8 warm-up frames) equals the tile's mean
//! exact irradiance. Two-sided z-test, threshold 5σ, fixed seed per scheme. Unshuffled TSMIS
//! (each pixel keeps its chain, whose lobe at step k + 1 sits on its sample of step k) must
//! miss it by more than 5σ; so must unshuffled SSMIS. The same holds with the tile = one
//! subgroup and `subgroupShuffle` (`mcmm_subgroup_*`, wgpu's `SUBGROUP` feature).

use glam::Vec3;
use mcg_gpu_backend::guides::mcmm::GpuMcmmGuide;
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::{GpuContext, GuidedKernel, buffer_entry, shaders, storage_entry, wgpu};
use mcg_markov_guide::mcmm::McmmParams;

const KERNEL: &str = include_str!("kernels/mcmm_smis.wgsl");
const TILE: u32 = 32;
const TILES: u32 = 256;
const WARM_UP: u32 = 8;
const FRAMES: u32 = 12;
const STEPS: u32 = 4;
const CENTRE: Vec3 = Vec3::new(0.0, 0.0, 1.0);
const RADIUS: f32 = 0.3;
const ORIGIN: Vec3 = Vec3::new(-0.775, 0.0, 0.0);
const SPACING: f32 = 0.05;

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct Frame {
    light_centre: Vec3,
    light_radius: f32,
    origin: Vec3,
    spacing: f32,
    radiance: f32,
    seed: u32,
    scheme: u32,
    steps: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scheme {
    TsmisShuffled = 0,
    SsmisShuffled = 1,
    TsmisUnshuffled = 2,
    SsmisUnshuffled = 3,
}

/// L such that the irradiance straight below the light is 1: π L sin²α = 1.
fn radiance() -> f64 {
    let sin2 = f64::from(RADIUS / CENTRE.z).powi(2);
    1.0 / (core::f64::consts::PI * sin2)
}

/// π L (r/d)² cos θ at pixel `px` of a row.
fn exact(px: u32) -> f64 {
    let x = f64::from(ORIGIN.x) + f64::from(SPACING) * f64::from(px);
    let to = [
        f64::from(CENTRE.x) - x,
        f64::from(CENTRE.y - ORIGIN.y),
        f64::from(CENTRE.z - ORIGIN.z),
    ];
    let d = to.iter().map(|c| c * c).sum::<f64>().sqrt();
    core::f64::consts::PI * radiance() * (f64::from(RADIUS) / d).powi(2) * (to[2] / d)
}

/// The per-tile observations of one scheme: each tile's estimate averaged over its pixels
/// and the measured frames.
fn observations(ctx: &GpuContext, scheme: Scheme, seed: u32, subgroups: bool) -> Vec<f64> {
    let device = ctx.device();
    let mut params = McmmParams::PAPER;
    params.window_half_width = 0.0;
    params.neighbour_candidates = 1;
    let mut guide = GpuMcmmGuide::new(ctx, TILE, TILES, &params).unwrap();
    let mut defs = GpuMcmmGuide::shader_defs(1).to_vec();
    if subgroups {
        defs.push((shaders::defs::MCMM_SUBGROUPS, 1));
    }
    let source = shaders::compose(KERNEL, &defs).unwrap();
    let kernel = GuidedKernel::from_wgsl(
        ctx,
        "mcmm smis",
        source,
        &[
            buffer_entry(0, wgpu::BufferBindingType::Uniform),
            storage_entry(1, false),
        ],
        guide.bind_group_layout(),
    );
    let pipeline = kernel.pipeline(ctx, "mcmm_smis_frame");
    let n = (TILE * TILES) as usize;
    let estimates = ctx.zeroed_buffer::<f32>("estimates", n);
    let mut sums = vec![0.0f64; TILES as usize];
    for f in 0..WARM_UP + FRAMES {
        let frame = Frame {
            light_centre: CENTRE,
            light_radius: RADIUS,
            origin: ORIGIN,
            spacing: SPACING,
            radiance: radiance() as f32,
            seed: seed.wrapping_mul(0x0100_0193).wrapping_add(f),
            scheme: scheme as u32,
            steps: STEPS,
        };
        let uniform = ctx.uniform_buffer("frame", &frame);
        let io = kernel.io_bind_group(ctx, &[uniform.raw(), estimates.raw()]);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &io, &[]);
            pass.set_bind_group(1, guide.bind_group(), &[]);
            pass.dispatch_workgroups(TILES, 1, 1);
        }
        ctx.queue().submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
        guide.swap();
        if f >= WARM_UP {
            for (i, e) in ctx.read_back(&estimates).unwrap().into_iter().enumerate() {
                sums[i / TILE as usize] += f64::from(e);
            }
        }
    }
    sums.into_iter()
        .map(|s| s / f64::from(TILE * FRAMES))
        .collect()
}

/// (mean, expected, z) of a scheme's observations; asserts that the test can see a bias of
/// 2 % of the integral (σ of the mean below 0.4 % of it).
fn z_test(ctx: &GpuContext, scheme: Scheme, seed: u32, subgroups: bool) -> (f64, f64, f64) {
    let obs = observations(ctx, scheme, seed, subgroups);
    let k = obs.len() as f64;
    let mean = obs.iter().sum::<f64>() / k;
    let var = obs.iter().map(|o| (o - mean).powi(2)).sum::<f64>() / (k - 1.0);
    let expected = (0..TILE).map(exact).sum::<f64>() / f64::from(TILE);
    let z = (mean - expected) / (var / k).sqrt();
    let se = (var / k).sqrt();
    let path = if subgroups { "subgroup" } else { "workgroup" };
    println!(
        "{scheme:?} ({path}): mean {mean:.5} expected {expected:.5} z {z:+.2} (σ of the mean {se:.5})"
    );
    assert!(se < 0.004 * expected, "{scheme:?}: σ of the mean {se}");
    (mean, expected, z)
}

#[test]
fn shuffled_tsmis_and_ssmis_are_unbiased_on_the_gpu() {
    let Some(ctx) = gpu_or_skip("shuffled_tsmis_and_ssmis_are_unbiased_on_the_gpu") else {
        return;
    };
    for (scheme, seed) in [
        (Scheme::TsmisShuffled, 0x16_01),
        (Scheme::SsmisShuffled, 0x16_02),
    ] {
        let (_, _, z) = z_test(ctx, scheme, seed, false);
        assert!(z.abs() < 5.0, "{scheme:?}: z = {z}");
    }
}

/// Without the shift a pixel's TSMIS denominators hold lobes fitted to its own samples:
/// biased low. Without the xor permutation a pixel samples its own chain, adapted to its own
/// view of the light, while eq. 9 assumes a uniform pick among the tile's: biased high.
#[test]
fn unshuffled_estimators_are_biased_on_the_gpu() {
    let Some(ctx) = gpu_or_skip("unshuffled_estimators_are_biased_on_the_gpu") else {
        return;
    };
    for (scheme, seed) in [
        (Scheme::TsmisUnshuffled, 0x16_03),
        (Scheme::SsmisUnshuffled, 0x16_04),
    ] {
        let (_, _, z) = z_test(ctx, scheme, seed, false);
        assert!(z.abs() > 5.0, "{scheme:?}: no detectable bias, z = {z}");
    }
}

/// A device with wgpu's `SUBGROUP` feature and subgroups of `STEPS..=32` lanes (TSMIS needs
/// n ≤ tile size; a 32-lane workgroup holds whole subgroups), or `None` with the reason.
fn subgroup_context() -> Result<GpuContext, String> {
    let instance =
        wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))
        .map_err(|e| e.to_string())?;
    let info = adapter.get_info();
    if !adapter.features().contains(wgpu::Features::SUBGROUP) {
        return Err(format!("{} has no SUBGROUP feature", info.name));
    }
    if info.subgroup_min_size < STEPS || info.subgroup_max_size > TILE {
        return Err(format!(
            "subgroups of {}..={} lanes",
            info.subgroup_min_size, info.subgroup_max_size
        ));
    }
    println!(
        "{}: subgroups of {}..={} lanes",
        info.name, info.subgroup_min_size, info.subgroup_max_size
    );
    let descriptor = wgpu::DeviceDescriptor {
        label: Some("mcmm subgroups"),
        required_features: wgpu::Features::SUBGROUP,
        required_limits: wgpu::Limits::default().using_resolution(adapter.limits()),
        ..Default::default()
    };
    let (device, queue) =
        pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| e.to_string())?;
    GpuContext::from_device(device, queue).map_err(|e| e.to_string())
}

/// The same four schemes with the tile = one subgroup and the shuffles done with
/// `subgroupShuffle` (`mcmm_subgroup_exchange`, `mcmm_subgroup_mixture_pdf`): the same
/// verdicts (shuffled |z| < 5, unshuffled |z| > 5) at the same sizes. Skips, printing why,
/// when there is no adapter (fails with `MCG_REQUIRE_GPU=1`) or the adapter has no suitable
/// subgroups.
#[test]
fn subgroup_shuffles_give_the_same_verdicts() {
    if gpu_or_skip("subgroup_shuffles_give_the_same_verdicts").is_none() {
        return;
    }
    let ctx = match subgroup_context() {
        Ok(ctx) => ctx,
        Err(why) => {
            eprintln!("skipping subgroup_shuffles_give_the_same_verdicts: {why}");
            return;
        }
    };
    for (scheme, seed, biased) in [
        (Scheme::TsmisShuffled, 0x16_11, false),
        (Scheme::SsmisShuffled, 0x16_12, false),
        (Scheme::TsmisUnshuffled, 0x16_13, true),
        (Scheme::SsmisUnshuffled, 0x16_14, true),
    ] {
        let (_, _, z) = z_test(&ctx, scheme, seed, true);
        assert_eq!(z.abs() > 5.0, biased, "{scheme:?} (subgroups): z = {z}");
    }
}

/// Without a GPU: the Fig. 16 kernel composes and validates with naga both ways — the
/// workgroup path with no capability at all, the subgroup path (`MCG_MCMM_SUBGROUPS`) with
/// naga's `SUBGROUP` capability and not without it, so the default build of `mcg::mcmm` never
/// needs the feature.
#[test]
fn both_shuffle_paths_validate_with_naga() {
    use naga::valid::{Capabilities, ValidationFlags, Validator};
    let validate = |subgroups: bool, capabilities: Capabilities| {
        let mut defs = GpuMcmmGuide::shader_defs(1).to_vec();
        if subgroups {
            defs.push((shaders::defs::MCMM_SUBGROUPS, 1));
        }
        let source = shaders::compose(KERNEL, &defs).unwrap();
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        Validator::new(ValidationFlags::all(), capabilities)
            .validate(&module)
            .is_ok()
    };
    assert!(validate(false, Capabilities::empty()));
    assert!(validate(true, Capabilities::SUBGROUP));
    assert!(!validate(true, Capabilities::empty()));
}
