//! A renderer's kernel (`steps.wgsl`) that imports `mcg::mcpg` and binds the guide at group 1,
//! with the host twins of its I/O and the CPU guide's answer for the same inputs.
#![allow(dead_code)] // each test file uses a part

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use mcg_gpu_backend::guides::mcpg::GpuMcpgGuide;
use mcg_gpu_backend::shaders;
use mcg_gpu_backend::{GpuBuffer, GpuContext, GuidedKernel, codes, storage_entry, wgpu};
use mcg_markov_guide::mcpg::{
    BeginUniforms, CandidateUniforms, FinishUniforms, GridUniforms, Guide, GuidedSample,
    IsotropicPhase, Lambertian, SampleUniforms, Scatter, Traced, Transition, Vertex,
    VertexObservation,
};

pub const STEPS: &str = include_str!("steps.wgsl");
/// The guide's group in `steps.wgsl`.
pub const GUIDE_GROUP: u32 = 1;

/// WGSL `McpgVertex` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VertexGpu {
    pub position: Vec3,
    pub scatter: u32,
    pub key_direction: Vec3,
    pub has_normal: u32,
    pub normal: Vec3,
    pub pad: u32,
}

/// WGSL `McpgObservation` (112 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ObservationGpu {
    pub traced: u32,
    pub has_previous: u32,
    pub has_reflected: u32,
    pub emission_weight: f32,
    pub position: Vec3,
    pub pad_a: f32,
    pub normal: Vec3,
    pub pad_b: f32,
    pub emitted: Vec3,
    pub pad_c: f32,
    pub previous_position: Vec3,
    pub pad_d: f32,
    pub weight: Vec3,
    pub pad_e: f32,
    pub reflected: Vec3,
    pub pad_f: f32,
}

/// WGSL `StepInput` (336 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StepInput {
    pub vertex: VertexGpu,
    pub begin: [[f32; 4]; 8],
    pub sample: [f32; 4],
    pub finish: [f32; 4],
    pub cache_and_probe: [f32; 4],
    pub observation: ObservationGpu,
}
const _: () = assert!(size_of::<StepInput>() == 336);

/// WGSL `StepOutput` (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StepOutput {
    pub direction: Vec3,
    pub pdf: f32,
    pub probe_pdf: f32,
    pub lobe: u32,
    pub selected: u32,
    pub transition: u32,
    pub weight_sum: f32,
    pub count: u32,
    pub target_level: u32,
    pub normal_class: u32,
    pub mixture: Vec3,
    pub mixture_lobe: u32,
}

/// A vertex with the CPU's types: where, what the ray found, and every uniform.
#[derive(Clone, Copy, Debug)]
pub struct Step {
    pub vertex: Vertex,
    pub volume: bool,
    pub begin: BeginUniforms,
    pub sample: SampleUniforms,
    pub finish: FinishUniforms,
    pub probe: Vec3,
    pub observation: VertexObservation,
}

impl Step {
    pub fn gpu_input(&self) -> StepInput {
        let v = &self.vertex;
        let vertex = VertexGpu {
            position: v.position,
            scatter: if self.volume {
                codes::MCPG_SCATTER_ISOTROPIC
            } else {
                codes::MCPG_SCATTER_LAMBERTIAN
            },
            key_direction: v.key_direction,
            has_normal: u32::from(v.normal.is_some()),
            normal: v.normal.unwrap_or(Vec3::ZERO),
            pad: 0,
        };
        let mut begin = [[0.0; 4]; 8];
        for (b, c) in begin.iter_mut().zip(&self.begin.candidates) {
            *b = [c.grid, c.level, c.corner, c.reservoir];
        }
        let o = &self.observation;
        let mut obs = ObservationGpu {
            weight: o.weight,
            has_reflected: u32::from(o.reflected.is_some()),
            reflected: o.reflected.unwrap_or(Vec3::ZERO),
            emission_weight: o.emission_weight,
            ..Default::default()
        };
        match o.traced {
            Traced::Hit {
                position,
                normal,
                emitted,
                previous_position,
            } => {
                obs.traced = codes::MCPG_TRACED_HIT;
                obs.position = position;
                obs.normal = normal;
                obs.emitted = emitted;
                obs.has_previous = u32::from(previous_position.is_some());
                obs.previous_position = previous_position.unwrap_or(position);
            }
            Traced::Escaped { radiance } => {
                obs.traced = codes::MCPG_TRACED_ESCAPED;
                obs.emitted = radiance;
            }
        }
        let f = &self.finish;
        StepInput {
            vertex,
            begin,
            sample: [
                self.sample.choice,
                self.sample.direction.x,
                self.sample.direction.y,
                0.0,
            ],
            finish: [f.accept, f.store.grid, f.store.level, f.store.corner],
            cache_and_probe: [f.cache, self.probe.x, self.probe.y, self.probe.z],
            observation: obs,
        }
    }
}

/// What the CPU guide answered for one step.
#[derive(Clone, Copy, Debug)]
pub struct CpuStep {
    pub sample: GuidedSample,
    /// [`GuidedVertex::sample_mixture`](mcg_markov_guide::mcpg::GuidedVertex::sample_mixture)
    /// of the same uniforms.
    pub mixture: Vec3,
    pub probe_pdf: f32,
    pub selected: Option<usize>,
    pub weight_sum: f32,
    pub transition: Option<Transition>,
}

fn cpu_step_with<S: Scatter>(guide: &Guide, step: &Step, scatter: S, finish: bool) -> CpuStep {
    let v = guide.begin(step.vertex, scatter, &step.begin);
    let sample = v.sample(&step.sample);
    let weight_sum = v
        .candidates()
        .iter()
        .map(|s| s.resampling_weight())
        .sum::<f32>();
    CpuStep {
        sample,
        mixture: v.sample_mixture(&step.sample),
        probe_pdf: v.pdf(step.probe),
        selected: v.selected(),
        weight_sum,
        transition: finish.then(|| v.finish(&sample, &step.observation, &step.finish)),
    }
}

/// The CPU guide's begin, sample, probe pdf and (with `finish`) finish for `step`; also the
/// CPU pdf at `at` (the GPU's direction).
pub fn cpu_step(guide: &Guide, step: &Step, finish: bool, at: Option<Vec3>) -> (CpuStep, f32) {
    let pdf_at = |s: &CpuStep| -> f32 {
        at.map_or(s.sample.pdf, |w| {
            if step.volume {
                guide.begin(step.vertex, IsotropicPhase, &step.begin).pdf(w)
            } else {
                let n = step.vertex.normal.unwrap_or(Vec3::Z);
                guide
                    .begin(step.vertex, Lambertian { normal: n }, &step.begin)
                    .pdf(w)
            }
        })
    };
    // The pdf at the GPU's direction is read before finish changes the grids.
    if step.volume {
        let p = pdf_at(&cpu_step_with(guide, step, IsotropicPhase, false));
        (cpu_step_with(guide, step, IsotropicPhase, finish), p)
    } else {
        let n = step.vertex.normal.unwrap_or(Vec3::Z);
        let s = Lambertian { normal: n };
        let p = pdf_at(&cpu_step_with(guide, step, s, false));
        (cpu_step_with(guide, step, s, finish), p)
    }
}

/// Uniform-source helpers for building steps.
pub fn candidate_uniforms(mut next: impl FnMut() -> f32) -> BeginUniforms {
    let mut u = BeginUniforms::default();
    for c in &mut u.candidates {
        *c = CandidateUniforms {
            grid: next(),
            level: next(),
            corner: next(),
            reservoir: next(),
        };
    }
    u
}

pub fn finish_uniforms(mut next: impl FnMut() -> f32) -> FinishUniforms {
    FinishUniforms {
        accept: next(),
        store: GridUniforms {
            grid: next(),
            level: next(),
            corner: next(),
        },
        cache: next(),
    }
}

pub fn sample_uniforms(mut next: impl FnMut() -> f32) -> SampleUniforms {
    let choice = next();
    let x = next();
    SampleUniforms {
        choice,
        direction: Vec2::new(x, next()),
    }
}

/// The pipelines of `steps.wgsl` with the guide's layout at group 1.
pub struct Steps {
    kernel: GuidedKernel,
}

impl Steps {
    /// Composes `steps.wgsl` as plain WGSL (`naga_oil` false) or through naga_oil.
    pub fn new(ctx: &GpuContext, guide: &GpuMcpgGuide, naga_oil: bool) -> Self {
        let defs = GpuMcpgGuide::shader_defs(GUIDE_GROUP);
        let source = if naga_oil {
            use naga_oil::compose::{Composer, NagaModuleDescriptor, ShaderDefValue};
            let mut composer = Composer::default();
            shaders::add_to_composer(&mut composer).unwrap();
            let module = composer
                .make_naga_module(NagaModuleDescriptor {
                    source: STEPS,
                    file_path: "steps.wgsl",
                    shader_defs: defs
                        .iter()
                        .map(|(k, v)| ((*k).to_owned(), ShaderDefValue::UInt(*v)))
                        .collect(),
                    ..Default::default()
                })
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&composer)));
            wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(module))
        } else {
            wgpu::ShaderSource::Wgsl(shaders::compose(STEPS, &defs).unwrap().into())
        };
        let io = [storage_entry(0, true), storage_entry(1, false)];
        let kernel = GuidedKernel::new(ctx, "steps", source, &io, guide.bind_group_layout());
        Self { kernel }
    }

    /// Runs `entry` with `invocations` invocations (64 per workgroup unless the entry's
    /// workgroup is 1) on `inputs`; returns the outputs (`outputs_len` of them).
    pub fn run(
        &self,
        ctx: &GpuContext,
        guide: &GpuMcpgGuide,
        entry: &str,
        inputs: &[StepInput],
        outputs_len: usize,
        workgroups: u32,
    ) -> Vec<StepOutput> {
        let device = ctx.device();
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let pipeline = self.kernel.pipeline(ctx, entry);
        let inputs: GpuBuffer<StepInput> = ctx.storage_buffer("inputs", inputs);
        let outputs: GpuBuffer<StepOutput> = ctx.zeroed_buffer("outputs", outputs_len);
        let io = self
            .kernel
            .io_bind_group(ctx, &[inputs.raw(), outputs.raw()]);
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &io, &[]);
            pass.set_bind_group(GUIDE_GROUP, guide.bind_group(), &[]);
            pass.dispatch_workgroups(workgroups, 1, 1);
        }
        ctx.queue().submit([encoder.finish()]);
        if let Some(e) = pollster::block_on(scope.pop()) {
            panic!("{entry}: {e}");
        }
        ctx.read_back(&outputs).unwrap()
    }
}
