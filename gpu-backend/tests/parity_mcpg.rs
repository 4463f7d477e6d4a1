//! CPU/GPU parity of the MCPG guide: `mcg::mcpg` (through a renderer-style kernel that binds the
//! guide at group 1) against `mcg_markov_guide::mcpg::Guide` for the same vertices,
//! observations and uniforms, frame after frame from empty grids, with the per-frame pass.
//!
//! Equal: every decision (the chosen candidate, the technique, the transition), every integer
//! of the tables (which slots hold states, N, T, the f16 velocity, the ages, the cache's frame
//! counts). Within tolerances from WGSL's accuracy rules (WGSL spec, "Floating Point
//! Accuracy"): `exp` within 3 + 2|x| ULP and `log` 2⁻²¹ absolute near 1, division 2.5 ULP,
//! and products that a compiler may fuse into an FMA:
//! - densities: relative 10⁻⁴ — C(κ) and e^{−κd²/2} for exponents up to ~400 (840 ULP), which
//!   covers every lobe a test builds; the GPU's pdf is compared with the CPU's at the GPU's
//!   own direction, so sampling differences do not enter;
//! - directions: 10⁻³ — the inverse CDF's r = cos θ − 1 carries log's 2⁻²¹ absolute error,
//!   and sin θ = √(−r(2 + r)) turns an error dr into √(2 dr) ≤ 7·10⁻⁴;
//! - state floats (ȳ, w̄, 1 − r̄, the cache's radiance): relative 10⁻⁴ after a few updates,
//!   each of which rounds a handful of products and one division.

mod common;
#[path = "mcpg/harness.rs"]
mod harness;

use glam::Vec3;
use harness::{Step, StepInput, Steps, cpu_step};
use mcg_gpu_backend::guides::mcpg::GpuMcpgGuide;
use mcg_gpu_backend::{GpuContext, codes};
use mcg_markov_guide::mcpg::{
    CacheConfig, DiscardRule, GridState, Guide, GuideConfig, Hemisphere, Traced, Transition,
    Vertex, VertexObservation, single_scattering::jittered_view_direction,
};
use mcg_test_support::assert_close;
use rand::{Rng, RngExt};

const FRAMES: usize = 6;
const STEPS_PER_FRAME: usize = 48;

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-30 || (a == b)
}

/// The configurations compared: the scene-scaled default (cosine product, engine discard,
/// cache, ages) with young chains' confidence N_c = 16 (mcg's extension, as mcg-demo's
/// renderer uses it), and the paper's whole-sphere lobes with the paper's discard rule and
/// Alg. 2, no cache and no ages, and the first with one sample in four added to the cache.
/// Small tables, so eviction and full neighbourhoods happen.
fn configs() -> Vec<(&'static str, GuideConfig)> {
    let mut scene = GuideConfig::for_scene(Vec3::ZERO, Vec3::new(1.0, 1.0, 2.0));
    scene.adaptive_capacity = 512;
    scene.static_capacity = 64;
    scene.cache = Some(CacheConfig {
        capacity: 256,
        max_age: 2,
        ..CacheConfig::DEFAULT
    });
    scene.max_state_age = Some(2);
    scene.params.confidence_samples = 16.0;
    let mut paper = scene;
    paper.params.confidence_samples = 0.0;
    paper.hemisphere = Hemisphere::Sphere;
    paper.params.discard = DiscardRule::Paper { ratio: 0.5 };
    paper.cache = None;
    paper.max_state_age = None;
    // One sample in four added to the cache (mcg-demo's CPU renderer adds one in eight).
    let mut sampled = scene;
    sampled.cache = scene.cache.map(|c| CacheConfig {
        add_probability: 0.25,
        ..c
    });
    vec![
        ("scene", scene),
        ("paper", paper),
        ("sampled cache", sampled),
    ]
}

fn random_step(rng: &mut impl Rng) -> Step {
    let mut u = || rng.random::<f32>();
    let volume = u() < 0.2;
    let x = Vec3::new(
        0.45 + 0.1 * u(),
        0.45 + 0.1 * u(),
        if volume { 0.1 + 0.1 * u() } else { 0.0 },
    );
    let (normal, class_pick) = (Vec3::Z, u());
    let normal = if class_pick < 0.1 { -Vec3::X } else { normal };
    let vertex = if volume {
        let view = (x - Vec3::new(0.5, -1.0, 1.5)).normalize();
        let jitter = glam::Vec2::new(u(), u());
        let v = Vertex::volume(x, view, jitter);
        assert_eq!(v.key_direction, jittered_view_direction(view, jitter));
        v
    } else {
        Vertex::surface(x, normal)
    };
    let begin = harness::candidate_uniforms(&mut u);
    let sample = harness::sample_uniforms(&mut u);
    let finish = harness::finish_uniforms(&mut u);
    let probe = common::random_unit(rng);
    let mut u = || rng.random::<f32>();
    let weight = if u() < 0.15 {
        Vec3::ZERO
    } else {
        Vec3::new(u(), u(), u()) * 2.0
    };
    let kind = u();
    // Hits on the lights above, or on the plane itself, where the cache holds what the
    // plane's vertices added in earlier frames.
    let (light, hit_normal) = if u() < 0.4 {
        (Vec3::new(0.45 + 0.1 * u(), 0.45 + 0.1 * u(), 0.0), Vec3::Z)
    } else {
        (Vec3::new(0.4 + 0.2 * u(), 0.4 + 0.2 * u(), 1.8), -Vec3::Z)
    };
    // A renderer's MIS weight of the emission: MCPG's 1, a weight, or the edge values
    // (clamped; NaN counts as 1). Drawn from a hash of the step's other values rather than from
    // `rng`, so that the steps (and the coverage the tests below count) stay those of the
    // stream without it.
    let bits = |v: f32| u64::from(v.to_bits());
    let h = (bits(weight.x) ^ bits(light.x) << 32 ^ bits(light.y) << 11)
        .wrapping_mul(0x9e37_79b9_7f4a_7c15);
    let (pick, value) = (
        (h >> 40) as f32 / 16_777_216.0,
        (h >> 8 & 0xff_ffff) as f32 / 16_777_216.0,
    );
    let emission_weight = match pick {
        p if p < 0.75 => 1.0,
        p if p < 0.9 => value,
        p if p < 0.94 => 0.0,
        p if p < 0.97 => f32::NAN,
        _ => 3.0,
    };
    let observation = if kind < 0.15 {
        VertexObservation {
            emission_weight,
            ..VertexObservation::escaped(Vec3::splat(u()), weight)
        }
    } else {
        let emitted = if u() < 0.3 {
            Vec3::ZERO
        } else {
            Vec3::new(u(), u(), u()) * 10.0
        };
        let previous_position = (u() < 0.2).then(|| light - Vec3::new(0.03, 0.0, 0.0));
        let reflected = (u() < 0.2).then(|| Vec3::splat(u()));
        VertexObservation {
            traced: Traced::Hit {
                position: light,
                normal: hit_normal,
                emitted,
                previous_position,
            },
            weight,
            reflected,
            emission_weight,
        }
    };
    Step {
        vertex,
        volume,
        begin,
        sample,
        finish,
        probe,
        observation,
    }
}

fn compare_step(
    label: &str,
    gpu: &harness::StepOutput,
    guide: &Guide,
    step: &Step,
    finish: bool,
) -> Option<Transition> {
    let (cpu, pdf_at_gpu) = cpu_step(guide, step, finish, Some(gpu.direction));
    let no = codes::MCPG_NO_LOBE;
    assert_eq!(
        cpu.selected.map_or(no, |k| k as u32),
        gpu.selected,
        "{label}: chosen candidate"
    );
    assert_eq!(
        cpu.sample.lobe.map_or(no, u32::from),
        gpu.lobe,
        "{label}: technique"
    );
    assert!(
        close(cpu.weight_sum, gpu.weight_sum, 1e-4),
        "{label}: Σw̄ {} vs {}",
        cpu.weight_sum,
        gpu.weight_sum
    );
    assert!(
        (cpu.sample.direction - gpu.direction).length() <= 1e-3,
        "{label}: direction {} vs {}",
        cpu.sample.direction,
        gpu.direction
    );
    // `mcpg_choose_mixture` with the same uniforms: the same lobe (or the scatter technique),
    // so the same direction.
    assert!(
        (cpu.mixture - gpu.mixture).length() <= 1e-3,
        "{label}: mixture direction {} vs {} (GPU lobe {})",
        cpu.mixture,
        gpu.mixture,
        gpu.mixture_lobe
    );
    assert!(
        close(pdf_at_gpu, gpu.pdf, 1e-4),
        "{label}: pdf {pdf_at_gpu} vs {}",
        gpu.pdf
    );
    assert!(
        close(cpu.probe_pdf, gpu.probe_pdf, 1e-4),
        "{label}: probe pdf {} vs {}",
        cpu.probe_pdf,
        gpu.probe_pdf
    );
    if finish {
        assert_eq!(
            cpu.transition,
            codes::transition(gpu.transition),
            "{label}: transition"
        );
    }
    cpu.transition
}

fn compare_states(label: &str, cpu: &[GridState], gpu: &[GridState]) {
    assert_eq!(cpu.len(), gpu.len());
    for (slot, (c, g)) in cpu.iter().zip(gpu).enumerate() {
        let l = format!("{label} slot {slot}");
        assert_eq!(
            *c == GridState::EMPTY,
            *g == GridState::EMPTY,
            "{l}: {c:?} vs {g:?}"
        );
        assert_eq!(c.sample_count(), g.sample_count(), "{l}: N");
        assert_eq!(c.time, g.time, "{l}: T");
        assert_eq!(c.velocity(), g.velocity(), "{l}: v");
        assert!(
            close(c.weight_sum, g.weight_sum, 1e-4),
            "{l}: w̄ {c:?} vs {g:?}"
        );
        assert!(
            (c.mean_target - g.mean_target).length() <= 1e-4 * (1.0 + c.mean_target.length()),
            "{l}: ȳ {c:?} vs {g:?}"
        );
        assert_close!(
            c.one_minus_mean_cosine,
            g.one_minus_mean_cosine,
            1e-4 * c.one_minus_mean_cosine.abs() + 1e-6,
            "{l}: 1 − r̄ {c:?} vs {g:?}"
        );
    }
}

fn compare_tables(label: &str, cpu: &mut Guide, gpu: &GpuMcpgGuide, ctx: &GpuContext) {
    let back = gpu.read_back(ctx).unwrap();
    assert_eq!(back.frame, cpu.frame(), "{label}: frame");
    assert_eq!(
        back.adaptive_ages,
        cpu.grids().0.table().ages(),
        "{label}: adaptive ages"
    );
    assert_eq!(
        back.static_ages,
        cpu.grids().1.table().ages(),
        "{label}: static ages"
    );
    let (a, s) = cpu.grids_mut();
    compare_states(
        &format!("{label} adaptive"),
        &a.snapshot(),
        &back.adaptive_states,
    );
    compare_states(
        &format!("{label} static"),
        &s.snapshot(),
        &back.static_states,
    );
    let occupied = |w: &[u32]| w.iter().filter(|&&c| c > 1).count() as u32;
    assert_eq!(
        occupied(&back.adaptive_checksums),
        cpu.grids().0.occupied(),
        "{label}"
    );
    assert_eq!(
        occupied(&back.static_checksums),
        cpu.grids().1.occupied(),
        "{label}"
    );
    if let Some(cache) = cpu.cache() {
        assert_eq!(
            occupied(&back.cache_checksums),
            cache.table().count_occupied()
        );
        for (slot, (c, g)) in cache.cells().iter().zip(&back.cache_cells).enumerate() {
            assert_eq!(c.weight, g.weight, "{label}: cache slot {slot} frames");
            for k in 0..3 {
                assert!(
                    close(c.radiance[k], g.radiance[k], 1e-4),
                    "{label}: cache slot {slot}: {c:?} vs {g:?}"
                );
            }
        }
    }
}

/// Hypothesis: for the same steps the GPU guide makes the CPU guide's choices and leaves the
/// same tables. 3 configurations × 6 frames × 48 vertices run serially (one invocation) on the
/// GPU, as the CPU runs them, through begin, sample (and `mcpg_choose_mixture`'s sample of the
/// whole mixture from the same uniforms, `GuidedVertex::sample_mixture`), pdf and finish, with
/// the per-frame pass between frames; every decision and integer must be equal, floats within the tolerances of
/// the file's header. Also checks that the run exercised every transition that a serial run
/// can take (stored, rejected, discarded) and cache reads and writes.
#[test]
fn serial_frames_match_the_cpu_guide() {
    let Some((ctx, mut rng)) =
        common::gpu_and_rng("serial_frames_match_the_cpu_guide", 0x6d63_7067)
    else {
        return;
    };
    let mut discarded = 0;
    for (name, config) in configs() {
        let mut cpu = Guide::new(config).unwrap();
        let mut gpu = GpuMcpgGuide::new(ctx, &config).unwrap();
        let camera = Vec3::new(0.5, 0.5, 2.5);
        cpu.set_camera(camera);
        gpu.set_camera(ctx, camera);
        let steps = Steps::new(ctx, &gpu, false);
        let mut seen = [0u32; 4];
        let mut lobes = 0;
        for frame in 0..FRAMES {
            let batch: Vec<Step> = (0..STEPS_PER_FRAME)
                .map(|_| random_step(&mut rng))
                .collect();
            let inputs: Vec<StepInput> = batch.iter().map(Step::gpu_input).collect();
            let outputs = steps.run(ctx, &gpu, "mcpg_steps_serial", &inputs, inputs.len(), 1);
            for (i, (step, out)) in batch.iter().zip(&outputs).enumerate() {
                let label = format!("{name} frame {frame} step {i}");
                let t = compare_step(&label, out, &cpu, step, true).unwrap();
                seen[t as usize] += 1;
                lobes += u32::from(out.lobe != codes::MCPG_NO_LOBE);
            }
            cpu.end_frame();
            gpu.end_frame(ctx).unwrap();
            compare_tables(&format!("{name} after frame {frame}"), &mut cpu, &gpu, ctx);
        }
        if let Some(cache) = cpu.cache() {
            let cached = cache.cells().iter().filter(|c| c.weight > 0.0).count();
            // Fewer cells are written when only some samples are added.
            let expected = if cache.config().add_probability < 1.0 {
                4
            } else {
                10
            };
            assert!(
                cached > expected,
                "{name}: only {cached} cache cells hold radiance"
            );
        }
        eprintln!("{name}: transitions stored/dropped/rejected/discarded {seen:?}, lobes {lobes}");
        assert!(seen[Transition::Stored as usize] > 20, "{name}: {seen:?}");
        assert!(seen[Transition::Rejected as usize] > 10, "{name}: {seen:?}");
        assert!(lobes > 20, "{name}: {lobes} lobe samples");
        discarded += seen[Transition::Discarded as usize];
    }
    assert!(discarded > 0, "no discard in either configuration");
}

/// Hypothesis: begin, sample and pdf run by many invocations at once (as a renderer runs them,
/// composed through naga_oil this time) read the same states as the CPU. After 4 serial
/// frames, 512 vertices run in parallel (no finish: the grids do not change) and each is
/// compared with the CPU guide's answer; more than 20 of their mixture samples must take
/// another lobe than Alg. 1's choice (rescaling the choice uniform wrongly in
/// `mcpg_choose_mixture` fails both tests, checked once).
#[test]
fn parallel_vertices_match_the_cpu_guide() {
    let Some((ctx, mut rng)) =
        common::gpu_and_rng("parallel_vertices_match_the_cpu_guide", 0x70_6172)
    else {
        return;
    };
    let (name, config) = configs()[0];
    let mut cpu = Guide::new(config).unwrap();
    let mut gpu = GpuMcpgGuide::new(ctx, &config).unwrap();
    let camera = Vec3::new(0.5, 0.5, 2.5);
    cpu.set_camera(camera);
    gpu.set_camera(ctx, camera);
    let steps = Steps::new(ctx, &gpu, true);
    for _ in 0..4 {
        let batch: Vec<Step> = (0..STEPS_PER_FRAME)
            .map(|_| random_step(&mut rng))
            .collect();
        let inputs: Vec<StepInput> = batch.iter().map(Step::gpu_input).collect();
        let outputs = steps.run(ctx, &gpu, "mcpg_steps_serial", &inputs, inputs.len(), 1);
        for (step, out) in batch.iter().zip(&outputs) {
            compare_step(name, out, &cpu, step, true);
        }
        cpu.end_frame();
        gpu.end_frame(ctx).unwrap();
    }
    let batch: Vec<Step> = (0..512).map(|_| random_step(&mut rng)).collect();
    let inputs: Vec<StepInput> = batch.iter().map(Step::gpu_input).collect();
    let outputs = steps.run(ctx, &gpu, "mcpg_sample_only", &inputs, inputs.len(), 8);
    let (mut guided, mut other_lobes) = (0, 0);
    for (i, (step, out)) in batch.iter().zip(&outputs).enumerate() {
        compare_step(&format!("parallel {i}"), out, &cpu, step, false);
        guided += u32::from(out.lobe != codes::MCPG_NO_LOBE);
        other_lobes +=
            u32::from(out.mixture_lobe != codes::MCPG_NO_LOBE && out.mixture_lobe != out.selected);
    }
    assert!(guided > 100, "only {guided} of 512 vertices sampled a lobe");
    assert!(
        other_lobes > 20,
        "only {other_lobes} of 512 mixture samples took another lobe than Alg. 1's"
    );
}

/// Hypothesis: racing stores never let a reader see a mixture of two states. 4 096 invocations
/// each store 64 whole states (all eight words derived from one number) into 4 slots while
/// loading a neighbour slot; any read whose words disagree fails. Some reads must succeed.
#[test]
fn racing_stores_never_produce_torn_reads() {
    let Some(ctx) = mcg_gpu_backend::testing::gpu_or_skip("racing_stores_never_produce_torn_reads")
    else {
        return;
    };
    let (_, config) = configs()[0];
    let gpu = GpuMcpgGuide::new(ctx, &config).unwrap();
    let steps = Steps::new(ctx, &gpu, false);
    let outputs = steps.run(ctx, &gpu, "mcpg_race", &[StepInput::default()], 4096, 64);
    let mixed: u32 = outputs.iter().map(|o| o.count).sum();
    let seen: u32 = outputs.iter().map(|o| o.target_level).sum();
    assert_eq!(mixed, 0, "{mixed} torn reads among {seen}");
    assert!(seen > 1000, "only {seen} successful reads");
    let states = gpu.read_back(ctx).unwrap().adaptive_states;
    for s in &states[..4] {
        assert!(
            s.weight_sum > 0.0 && s.mean_target == Vec3::splat(s.weight_sum),
            "{s:?}"
        );
    }
}

/// Hypothesis: a state whose words were overwritten halfway (a torn write: the guard still holds
/// the old stamp) reads as empty. Store one state, overwrite its last four words on the host,
/// load: the load must fail, while the untouched state loads before the tampering.
#[test]
fn torn_states_are_detected_and_read_as_empty() {
    let Some(ctx) =
        mcg_gpu_backend::testing::gpu_or_skip("torn_states_are_detected_and_read_as_empty")
    else {
        return;
    };
    let (_, config) = configs()[0];
    let gpu = GpuMcpgGuide::new(ctx, &config).unwrap();
    let steps = Steps::new(ctx, &gpu, false);
    let none = [StepInput::default()];
    steps.run(ctx, &gpu, "mcpg_store_one", &none, 4, 1);
    let loads = steps.run(ctx, &gpu, "mcpg_loads", &none, 4, 1);
    assert_eq!(loads[0].selected, 1, "the whole state loads");
    assert_eq!(loads[0].weight_sum, 7.0);
    assert_eq!(
        loads[1].selected, 1,
        "an empty slot loads as the empty state"
    );
    let offset = 4 * u64::from(gpu.params().adaptive_states + 4);
    ctx.queue().write_buffer(
        gpu.guide_words().raw(),
        offset,
        bytemuck::cast_slice(&[1.5f32; 4]),
    );
    let loads = steps.run(ctx, &gpu, "mcpg_loads", &none, 4, 1);
    assert_eq!(loads[0].selected, 0, "a torn state must not load");
    assert_eq!(loads[0].weight_sum, 0.0);
}

/// Hypothesis: `mcpg_volume_vertex` puts the CPU's key direction into a volume vertex
/// (`Vertex::volume`, MCPG sec. 4's jittered reverse view direction): 256 views and jitters,
/// each within 4 ε of the CPU's (the cosine hemisphere's twin rounds the same operations; a
/// compiler may fuse some of them).
#[test]
fn volume_vertices_take_the_cpus_key_direction() {
    let Some((ctx, mut rng)) =
        common::gpu_and_rng("volume_vertices_take_the_cpus_key_direction", 0x766f6c)
    else {
        return;
    };
    let (_, config) = configs()[0];
    let gpu = GpuMcpgGuide::new(ctx, &config).unwrap();
    let steps = Steps::new(ctx, &gpu, false);
    let cases: Vec<(Vec3, Vec3, glam::Vec2)> = (0..256)
        .map(|_| {
            let view = common::random_unit(&mut rng);
            let jitter = glam::Vec2::new(rng.random(), rng.random());
            (
                Vec3::new(rng.random(), rng.random(), rng.random()),
                view,
                jitter,
            )
        })
        .collect();
    let inputs: Vec<StepInput> = cases
        .iter()
        .map(|&(p, view, jitter)| {
            let mut input = StepInput::default();
            input.vertex.position = p;
            input.vertex.normal = view;
            input.sample = [0.0, jitter.x, jitter.y, 0.0];
            input
        })
        .collect();
    let outputs = steps.run(ctx, &gpu, "mcpg_volume_keys", &inputs, inputs.len(), 4);
    for ((p, view, jitter), out) in cases.iter().zip(&outputs) {
        let cpu = Vertex::volume(*p, *view, *jitter);
        assert!(cpu.normal.is_none());
        assert!(
            (cpu.key_direction - out.direction).abs().max_element() <= 4.0 * f32::EPSILON,
            "{view} {jitter}: {} vs {}",
            cpu.key_direction,
            out.direction
        );
        assert_eq!(out.selected, 0, "a volume vertex has no normal");
        assert_eq!(out.lobe, codes::MCPG_SCATTER_ISOTROPIC);
    }
}

/// `fitted_config` gives the largest adaptive table the device binds: the halved table builds,
/// twice it is `GuideTooLarge`; a configuration that fits, or one `new` rejects for another
/// reason, comes back unchanged. The shared context binds at most WebGPU's default 128 MiB,
/// which 2²⁴ slots (704 MiB) exceed.
#[test]
fn fitted_config_is_the_largest_adaptive_table_the_device_binds() {
    let Some(ctx) = mcg_gpu_backend::testing::gpu_or_skip(
        "fitted_config_is_the_largest_adaptive_table_the_device_binds",
    ) else {
        return;
    };
    let (_, small) = configs()[0];
    assert_eq!(GpuMcpgGuide::fitted_config(ctx, &small), small);
    let invalid = GuideConfig {
        adaptive_capacity: 4,
        ..small
    };
    assert_eq!(GpuMcpgGuide::fitted_config(ctx, &invalid), invalid);
    let large = GuideConfig {
        adaptive_capacity: 1 << 24,
        ..small
    };
    let fitted = GpuMcpgGuide::fitted_config(ctx, &large);
    assert!(
        fitted.adaptive_capacity < large.adaptive_capacity && fitted.adaptive_capacity >= 1 << 12,
        "{}",
        fitted.adaptive_capacity
    );
    assert_eq!(
        fitted,
        GuideConfig {
            adaptive_capacity: fitted.adaptive_capacity,
            ..large
        }
    );
    GpuMcpgGuide::new(ctx, &fitted).unwrap();
    let twice = GuideConfig {
        adaptive_capacity: 2 * fitted.adaptive_capacity,
        ..large
    };
    assert!(matches!(
        GpuMcpgGuide::new(ctx, &twice),
        Err(mcg_gpu_backend::GpuError::GuideTooLarge { .. })
    ));
}
