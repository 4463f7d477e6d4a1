//! CPU/GPU parity of `mcg::mcmm` and `GpuMcmmGuide`: one MCMM iteration per pixel (Alg. 1
//! collaborative discovery with B-spline offsets and motion vectors, Alg. 2 technique choice,
//! sampling and pdf, both scores, Alg. 3 acceptance and update) against
//! `mcg_markov_guide::mcmm` fed the same uniforms, and the portable tile shuffles against
//! `mcg_smis::{CyclicShift, XorPermutation}`.
//!
//! Runs on whatever wgpu adapter exists (lavapipe in CI); every test skips with a printed
//! reason when there is none, and fails instead when `MCG_REQUIRE_GPU=1`. Integer results
//! (neighbour choices, the reservoir's state bit for bit, technique choices, sample counts,
//! acceptances away from ties) must match exactly; directions, pdfs and the updated
//! statistics within tolerances derived from WGSL's precision (`common::tolerance`).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::guides::mcmm::GpuMcmmGuide;
use mcg_gpu_backend::sampling::next_uniform;
use mcg_gpu_backend::{GpuContext, GuidedKernel, shaders, storage_entry, wgpu};
use mcg_markov_guide::mcmm::{
    CosineChainTechnique, McmmParams, McmmPrior, PixelState, PixelStateBuffers, ScoreDensity,
    bspline_offset, resample_neighbour, update,
};
use mcg_markov_guide::{cosine_hemisphere, cosine_hemisphere_pdf};
use mcg_smis::{CyclicShift, Technique, XorPermutation, smis_one_sample};
use mcg_test_support::assert_close;
use mcg_vmf::{FitParams, SufficientStats};
use rand::{Rng, RngExt};

mod common;
use common::{EPS, gpu_and_rng, random_unit, tolerance};

const KERNEL: &str = include_str!("kernels/mcmm_step.wgsl");
/// Pixels per tile and workgroup of the kernel.
const TILE: u32 = 32;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct StepInput {
    x: Vec3,
    seed: u32,
    normal: Vec3,
    value: f32,
    hit: Vec3,
    pad_a: f32,
    motion: Vec2,
    pad_b: Vec2,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct StepOutput {
    discovered: PixelState,
    pdf: f32,
    direction: Vec3,
    score: f32,
    flags: u32,
    taken: u32,
    pad: [u32; 2],
}

/// The test kernel's two pipelines with the guide's bind group layout at group 1 (the
/// renderer's choice here) and the test's buffers at group 0.
struct Kernel {
    kernel: GuidedKernel,
    step: wgpu::ComputePipeline,
    shuffle: wgpu::ComputePipeline,
}

impl Kernel {
    fn new(ctx: &GpuContext, guide: &GpuMcmmGuide) -> Self {
        let source = shaders::compose(KERNEL, &GpuMcmmGuide::shader_defs(1)).unwrap();
        let kernel = GuidedKernel::from_wgsl(
            ctx,
            "mcmm parity",
            source,
            &[storage_entry(0, true), storage_entry(1, false)],
            guide.bind_group_layout(),
        );
        Self {
            step: kernel.pipeline(ctx, "mcmm_step"),
            shuffle: kernel.pipeline(ctx, "mcmm_shuffle"),
            kernel,
        }
    }

    /// Runs `pipeline` over `invocations` invocations (tiles of 32) with the guide's bind
    /// group of this frame and reads the outputs back.
    fn run(
        &self,
        ctx: &GpuContext,
        guide: &GpuMcmmGuide,
        pipeline: &wgpu::ComputePipeline,
        inputs: &[StepInput],
        invocations: u32,
    ) -> Vec<StepOutput> {
        let device = ctx.device();
        let input = ctx.storage_buffer("inputs", inputs);
        let output = ctx.zeroed_buffer::<StepOutput>("outputs", inputs.len());
        let io = self.kernel.io_bind_group(ctx, &[input.raw(), output.raw()]);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &io, &[]);
            pass.set_bind_group(1, guide.bind_group(), &[]);
            pass.dispatch_workgroups(invocations.div_ceil(TILE), 1, 1);
        }
        ctx.queue().submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
        ctx.read_back(&output).unwrap()
    }
}

/// Previous-frame states: a third empty, the rest fits of 1..60 samples towards targets
/// around (0, 0, 4) with random scores (some zero), plus a few poisoned ones (NaN score,
/// negative score) that Alg. 1 must skip.
fn random_states(rng: &mut impl Rng, n: usize) -> Vec<PixelState> {
    (0..n)
        .map(|i| {
            if i % 3 == 0 {
                return PixelState::EMPTY;
            }
            let mut stats = SufficientStats::EMPTY;
            let centre = Vec3::new(0.0, 0.0, 4.0) + random_unit(rng) * 2.0;
            for _ in 0..rng.random_range(1..60) {
                stats.update(
                    Vec3::ZERO,
                    centre + random_unit(rng) * 0.3,
                    rng.random_range(0.0..3.0),
                    &FitParams::MCMM,
                );
            }
            let score = match i % 17 {
                1 => f32::NAN,
                2 => -1.0,
                4 => 0.0,
                _ => rng.random_range(0.0..5.0),
            };
            PixelState { stats, score }
        })
        .collect()
}

/// The states' bits (NaN scores compare equal to themselves).
fn bits(states: &[PixelState]) -> Vec<u32> {
    bytemuck::cast_slice(states).to_vec()
}

/// What the CPU computes for one pixel, replaying the GPU's stream of uniforms.
struct CpuStep {
    taken: u32,
    discovered: PixelState,
    lobe_chosen: bool,
    uniforms: Vec2,
    /// The technique of the discovered state at the pixel (the chain's, for the TSMIS sets).
    technique: CosineChainTechnique,
    u_accept: f32,
    start: PixelState,
}

/// Alg. 1 and the technique choice of Alg. 2 on the CPU with the GPU's uniform stream:
/// 12 uniforms per candidate offset, one to select it, then u_select, u (2), u_accept.
fn cpu_discover(
    buffers: &PixelStateBuffers,
    params: &McmmParams,
    width: u32,
    i: usize,
    input: &StepInput,
) -> CpuStep {
    let pixel = ((i as u32 % width) as i32, (i as u32 / width) as i32);
    let mut rng = input.seed;
    let start = buffers.previous(pixel.0, pixel.1).unwrap();
    let mut state = start;
    let mut sum = state.resampling_score();
    let mut taken = 0;
    for _ in 0..params.neighbour_candidates {
        let u: [f32; 12] = core::array::from_fn(|_| next_uniform(&mut rng));
        let offset = bspline_offset(&u, params.window_half_width);
        let select = next_uniform(&mut rng);
        if let Some(c) = buffers.neighbour(pixel, offset, input.motion) {
            taken += u32::from(resample_neighbour(&mut state, &mut sum, c, select));
        }
    }
    let u_select = next_uniform(&mut rng);
    let uniforms = Vec2::new(next_uniform(&mut rng), next_uniform(&mut rng));
    let technique = CosineChainTechnique::new(&state, input.x, input.normal, params);
    let lobe_chosen = !technique.sample_with_branch(u_select, uniforms).1;
    CpuStep {
        taken,
        discovered: state,
        lobe_chosen,
        uniforms,
        technique,
        u_accept: next_uniform(&mut rng),
        start,
    }
}

/// One frame of `width × height` pixels (width a multiple of 32) on both sides from the same
/// previous states, checked as the module docs say. Returns (pixels checked, lobe samples,
/// acceptances, tie skips).
#[allow(clippy::too_many_lines)]
fn check_frame(
    ctx: &GpuContext,
    rng: &mut impl Rng,
    params: &McmmParams,
    width: u32,
    height: u32,
) -> [usize; 4] {
    let n = (width * height) as usize;
    let mut guide = GpuMcmmGuide::new(ctx, width, height, params).unwrap();
    let mut buffers = PixelStateBuffers::new(width, height).unwrap();
    let previous = random_states(rng, n);
    for (i, &s) in previous.iter().enumerate() {
        buffers.set_current(i as i32 % width as i32, i as i32 / width as i32, s);
    }
    buffers.swap();
    guide.write_previous(ctx, &previous).unwrap();
    let inputs: Vec<StepInput> = (0..n)
        .map(|i| {
            let normal = (Vec3::Z + 0.3 * random_unit(rng)).normalize();
            StepInput {
                x: Vec3::new((i as u32 % width) as f32, (i as u32 / width) as f32, 0.0) * 0.01,
                seed: rng.random(),
                normal,
                value: if i % 5 == 0 {
                    0.0
                } else {
                    rng.random_range(0.1..4.0)
                },
                hit: Vec3::new(0.0, 0.0, 4.0) + random_unit(rng) * 2.0,
                motion: match i % 4 {
                    0 => Vec2::ZERO,
                    1 => Vec2::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)),
                    2 => Vec2::new(0.5, -1.5),
                    _ => Vec2::new(f32::NAN, 0.0),
                },
                ..Default::default()
            }
        })
        .collect();
    let kernel = Kernel::new(ctx, &guide);
    let outputs = kernel.run(ctx, &guide, &kernel.step, &inputs, n as u32);
    let written = guide.read_current(ctx).unwrap();
    guide.swap();
    assert!(
        bits(&guide.read_previous(ctx).unwrap()) == bits(&written),
        "swap: this frame's states become the previous ones"
    );
    let cpu: Vec<CpuStep> = (0..n)
        .map(|i| cpu_discover(&buffers, params, width, i, &inputs[i]))
        .collect();
    let mut counts = [0; 4];
    for i in 0..n {
        let (g, c, input) = (outputs[i], &cpu[i], inputs[i]);
        assert_eq!(g.taken, c.taken, "{i}: Alg. 1 replacements");
        assert_eq!(
            bits(&[g.discovered]),
            bits(&[c.discovered]),
            "{i}: Alg. 1 reservoir {:?} vs {:?}",
            g.discovered,
            c.discovered
        );
        assert_eq!(g.flags & 1 != 0, c.lobe_chosen, "{i}: Alg. 2 technique");
        // Direction: the CPU's sample with the same uniforms.
        let (w, dir_tol) = match c.technique.lobe() {
            Some(lobe) if c.lobe_chosen => {
                let w = lobe.sample(c.uniforms);
                let kappa = f64::from(lobe.kappa());
                let r = f64::from(lobe.mu().dot(w)) - 1.0;
                let dr = tolerance::cos_theta_minus_one(kappa, f64::from(c.uniforms.y), r);
                (w, tolerance::direction(dr))
            }
            _ => (cosine_hemisphere(input.normal, c.uniforms).0, 1e-5),
        };
        let err = f64::from((g.direction - w).length());
        assert!(
            err <= dir_tol,
            "{i}: ω {} vs {w}, {err} > {dir_tol}",
            g.direction
        );
        // Density at the GPU's direction: the chain's technique, or the tile's mixture.
        let wg = g.direction;
        let tile = i / TILE as usize * TILE as usize;
        let set: Vec<CosineChainTechnique> = if params.score_density == ScoreDensity::TileMixture {
            (tile..tile + TILE as usize)
                .map(|j| {
                    CosineChainTechnique::new(&cpu[j].discovered, input.x, input.normal, params)
                })
                .collect()
        } else {
            vec![c.technique]
        };
        let pdf = set.iter().map(|t| f64::from(t.pdf(&wg))).sum::<f64>() / set.len() as f64;
        // Each lobe's pdf within `tolerance::pdf`; the hemisphere branch within 4ε.
        let tol: f64 = set
            .iter()
            .map(|t| match t.lobe() {
                Some(l) => {
                    let k = f64::from(l.kappa());
                    let e = 0.5 * k * f64::from((wg - l.mu()).length_squared());
                    f64::from(t.pdf(&wg)) * (tolerance::pdf(k, e) + 4.0 * EPS)
                        + f64::from(l.normalization()) * 2.0 * f64::from(f32::MIN_POSITIVE)
                }
                None => f64::from(cosine_hemisphere_pdf(input.normal, wg)) * 4.0 * EPS,
            })
            .sum::<f64>()
            / set.len() as f64
            + 4.0 * EPS * pdf;
        assert_close!(f64::from(g.pdf), pdf, tol, "{i}: pdf");
        let value = input.value * input.normal.dot(wg).max(0.0);
        let f = smis_one_sample(&set, &wg, value);
        let rel = tol / pdf.max(f64::MIN_POSITIVE) + 4.0 * EPS;
        assert_close!(
            f64::from(g.score),
            f64::from(f),
            rel * f64::from(f) + f64::from(f32::MIN_POSITIVE),
            "{i}: score"
        );
        // Alg. 3 with the CPU's f; acceptance decisions equal unless u·S_c.f is within the
        // score's tolerance of f (a tie the two sides may break differently).
        let mut tentative = c.discovered;
        let mut current = c.start;
        let accepted = update(
            &mut tentative,
            &mut current,
            input.x,
            input.hit,
            f,
            g.flags & 1 == 0,
            c.u_accept,
            params,
        );
        let margin = f64::from(c.u_accept) * f64::from(c.start.score) - f64::from(f);
        if c.start.is_valid() && f > 0.0 && margin.abs() <= 2.0 * rel * f64::from(f) {
            counts[3] += 1;
            continue;
        }
        assert_eq!(g.flags & 2 != 0, accepted, "{i}: Alg. 3 acceptance");
        let s = written[i];
        if !accepted {
            // S_c stays the pixel's own state, bit for bit.
            assert_eq!(bits(&[s]), bits(&[c.start]), "{i}: rejected S_c");
            counts[0] += 1;
            counts[1] += usize::from(c.lobe_chosen);
            continue;
        }
        assert_eq!(s.stats.sample_count, current.stats.sample_count, "{i}: N");
        let close = |a: f32, b: f32, tol: f64| (f64::from(a) - f64::from(b)).abs() <= tol;
        assert!(
            close(s.score, current.score, rel * f64::from(current.score)),
            "{i}: S_c.f {} vs {}",
            s.score,
            current.score
        );
        let w_tol = (rel + 8.0 * EPS) * f64::from(current.stats.weight_sum);
        assert!(
            close(s.stats.weight_sum, current.stats.weight_sum, w_tol),
            "{i}: w̄ {} vs {}",
            s.stats.weight_sum,
            current.stats.weight_sum
        );
        // ȳ moves by β (y − ȳ) with β ∝ f: its error is rel·|y − ȳ| plus roundings.
        let scale = f64::from(current.stats.mean_target.length() + input.hit.length());
        let y_tol = 16.0 * EPS * scale + 2.0 * rel * scale;
        assert!(
            f64::from((s.stats.mean_target - current.stats.mean_target).length()) <= y_tol,
            "{i}: ȳ {} vs {}",
            s.stats.mean_target,
            current.stats.mean_target
        );
        let e_tol = 2.0 * rel + 64.0 * EPS + 1e-6;
        assert!(
            close(
                s.stats.one_minus_mean_cosine,
                current.stats.one_minus_mean_cosine,
                e_tol
            ),
            "{i}: 1 − r̄ {} vs {}",
            s.stats.one_minus_mean_cosine,
            current.stats.one_minus_mean_cosine
        );
        counts[0] += 1;
        counts[1] += usize::from(c.lobe_chosen);
        counts[2] += usize::from(accepted);
    }
    counts
}

/// One iteration on 64 × 32 pixels from random previous states (incl. empty and poisoned
/// ones), with motion vectors (zero, random, half-pixel ties, NaN), for the paper's
/// parameters, a zero window (exact rounding ties), a light-size prior and the tile-mixture
/// score. Hypotheses: Alg. 1 picks the same neighbours
/// and ends with the same state bit for bit; Alg. 2 picks the same technique; ω, p(ω), f and
/// the written state agree within WGSL's tolerances; acceptances agree except at ties within
/// the score's tolerance (counted, at most 1 %). Also checks `swap`.
#[test]
fn one_iteration_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("one_iteration_matches_the_cpu", 1919) else {
        return;
    };
    let mut small_window = McmmParams::PAPER;
    small_window.window_half_width = 6.0;
    let mut light = small_window;
    light.prior = McmmPrior::LightSize {
        radius: 0.4,
        weight: 2.0,
    };
    let mut tile = small_window;
    tile.score_density = ScoreDensity::TileMixture;
    // A zero window: every candidate sits at pixel + motion, so the ±½ motions are exact
    // rounding ties (f32::round: away from zero, WGSL's round: to even).
    let mut zero_window = McmmParams::PAPER;
    zero_window.window_half_width = 0.0;
    for (name, params) in [
        ("paper", McmmParams::PAPER),
        ("zero window", zero_window),
        ("light size", light),
        ("tile mixture", tile),
    ] {
        let [checked, lobes, accepted, ties] = check_frame(ctx, &mut rng, &params, 64, 32);
        println!(
            "{name}: {checked} pixels, {lobes} lobe samples, {accepted} accepted, {ties} ties"
        );
        assert!(ties * 100 <= 64 * 32, "{name}: {ties} ties");
        assert!(
            lobes > 300 && accepted > 300,
            "{name}: the test exercises both branches"
        );
    }
}

/// The portable tile shuffles through workgroup memory: every cyclic shift of tiles of 1..=32
/// lanes and every xor mask of power-of-two tiles move the states exactly as
/// `CyclicShift::apply` and `XorPermutation::apply` do on the CPU (lanes past the tile keep
/// their state).
#[test]
fn tile_shuffles_match_the_cpu_permutations() {
    let Some((ctx, mut rng)) = gpu_and_rng("tile_shuffles_match_the_cpu_permutations", 1920) else {
        return;
    };
    let states: Vec<PixelState> = (0..TILE)
        .map(|i| {
            let mut s = random_states(&mut rng, 2)[1];
            s.score = i as f32;
            s
        })
        .collect();
    let guide = GpuMcmmGuide::new(ctx, TILE, 1, &McmmParams::PAPER).unwrap();
    guide.write_previous(ctx, &states).unwrap();
    let kernel = Kernel::new(ctx, &guide);
    let mut cases = 0;
    for size in 1..=TILE {
        let mut check = |mode: u32, value: f32, expected: Vec<PixelState>| {
            let input = StepInput {
                seed: mode,
                value,
                pad_a: size as f32,
                ..Default::default()
            };
            kernel.run(ctx, &guide, &kernel.shuffle, &[input], TILE);
            let got = guide.read_current(ctx).unwrap();
            assert_eq!(got, expected, "size {size} mode {mode} value {value}");
            cases += 1;
        };
        for shift in 0..size {
            let mut want = states.clone();
            CyclicShift::new(size, shift)
                .unwrap()
                .apply(&mut want[..size as usize]);
            check(0, shift as f32, want);
        }
        if size.is_power_of_two() {
            for mask in 0..size {
                let u = (mask as f32 + 0.5) / size as f32;
                let p = XorPermutation::from_uniform(size, u).unwrap();
                assert_eq!(p.mask(), mask);
                let mut want = states.clone();
                p.apply(&mut want[..size as usize]);
                check(1, u, want);
            }
        }
    }
    println!("{cases} shuffles");
}

/// `GpuMcmmGuide::new` rejects what the CPU rejects (a NaN hemisphere probability, zero
/// candidates) and images whose state buffer exceeds one storage binding (also when
/// width · height · 28 overflows u64), and accepts an empty image.
#[test]
fn guide_validates_its_inputs() {
    use mcg_gpu_backend::GpuError;
    use mcg_markov_guide::{GuideError, ParamsError};
    let Some((ctx, _)) = gpu_and_rng("guide_validates_its_inputs", 0) else {
        return;
    };
    let mut p = McmmParams::PAPER;
    p.hemisphere_probability = f32::NAN;
    assert!(matches!(
        GpuMcmmGuide::new(ctx, 4, 4, &p),
        Err(GpuError::Guide(GuideError::Params(
            ParamsError::ProbabilityOutOfRange {
                parameter: "hemisphere_probability",
                ..
            }
        )))
    ));
    let mut p = McmmParams::PAPER;
    p.neighbour_candidates = 0;
    let mut guide = GpuMcmmGuide::new(ctx, 4, 4, &McmmParams::PAPER).unwrap();
    assert!(matches!(
        guide.set_params(ctx, &p),
        Err(GpuError::Guide(GuideError::Params(
            ParamsError::NoCandidates {
                parameter: "neighbour_candidates"
            }
        )))
    ));
    for (w, h) in [(1 << 20, 1 << 20), (u32::MAX, u32::MAX)] {
        assert!(matches!(
            GpuMcmmGuide::new(ctx, w, h, &McmmParams::PAPER),
            Err(GpuError::GuideTooLarge { .. })
        ));
    }
    let empty = GpuMcmmGuide::new(ctx, 0, 7, &McmmParams::PAPER).unwrap();
    assert!(empty.read_previous(ctx).unwrap().is_empty());
    empty.clear(ctx).unwrap();
}
