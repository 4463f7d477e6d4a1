//! `GpuProbeCache`: the buffers, bind group and steps of `mcg::adgi`.

use std::num::NonZeroU64;
use std::sync::OnceLock;

use glam::{UVec2, Vec3};
use mcg_color_codec::MovingAverage;
use mcg_probe_cache::{ClipVolumes, HeuristicParams, PilotPhase, TemporalTrigger};

use super::{
    AdgiConfigError, AdgiGpuParams, GpuClipVolumes, GpuIrradianceQuery, GpuPilotStep, GpuRaySample,
    GpuStepParams, ProbeCacheConfig,
};
use crate::runtime::{bind_group, build_pipelines, record_dispatch};
use crate::shaders::{defs, kernels};
use crate::{GpuBuffer, GpuContext, GpuError};

/// The steps' pipelines.
#[derive(Debug)]
struct Steps {
    update: wgpu::ComputePipeline,
    blend: wgpu::ComputePipeline,
    query: wgpu::ComputePipeline,
    clip_reset: wgpu::ComputePipeline,
    pilot_rays: wgpu::ComputePipeline,
    pilot_hits: wgpu::ComputePipeline,
}

/// One-element buffers bound where a step does not use a binding of the step group.
#[derive(Debug)]
struct Unused {
    samples: GpuBuffer<GpuRaySample>,
    uniforms: GpuBuffer<f32>,
    queries: GpuBuffer<GpuIrradianceQuery>,
    results: GpuBuffer<[f32; 4]>,
    clip: GpuBuffer<GpuClipVolumes>,
    pilot: GpuBuffer<GpuPilotStep>,
}

/// The step group's buffers of one dispatch (`None`: the unused one-element buffer).
#[derive(Default)]
struct StepInputs<'a> {
    samples: Option<&'a wgpu::Buffer>,
    uniforms: Option<&'a wgpu::Buffer>,
    queries: Option<&'a wgpu::Buffer>,
    results: Option<&'a wgpu::Buffer>,
    clip: Option<GpuClipVolumes>,
    pilot: Option<GpuPilotStep>,
    step: GpuStepParams,
}

/// ADGI's probe cache on the GPU (`mcg::adgi`): the texel words of a probe grid (irradiance
/// and visibility, `mcg_probe_cache::ProbeTexels`' layout), DDGI's rays buffer, the parameters,
/// the bind group a renderer's pipelines bind at a group index of its choice, and the steps,
/// one dispatch each, recorded into the renderer's encoder:
///
/// | step | record | CPU twin |
/// |---|---|---|
/// | ADGI's per-sample update | [`record_update_samples`](Self::record_update_samples) | `ProbeTexels::update_sample_with` |
/// | DDGI's uniform blend (the baseline) | [`record_blend`](Self::record_blend) | `ProbeTexels::blend_rays` |
/// | irradiance query | [`record_query`](Self::record_query) (or `adgi_irradiance_at` in the renderer's shader) | `ProbeTexels::irradiance_at` |
/// | clip-volume reset | [`record_clip_reset`](Self::record_clip_reset) | `ClipVolumes::classify` + `clamp_*_counts` |
/// | pilot directions | [`record_pilot_rays`](Self::record_pilot_rays) | `pilot_rays::pilot_rays` |
/// | pilot heuristics, temporal gradient, trigger | [`record_pilot_hits`](Self::record_pilot_hits) | `octant_heuristics`, `temporal_gradient`, `TemporalTrigger` |
///
/// The renderer traces the probe rays: into its own sample buffer for ADGI's update (or it calls
/// `adgi_update_sample` itself), into [`rays`](Self::rays) (probe-major) for DDGI's blend.
#[derive(Debug)]
pub struct GpuProbeCache {
    config: ProbeCacheConfig,
    params: AdgiGpuParams,
    params_buffer: GpuBuffer<AdgiGpuParams>,
    words: GpuBuffer<u32>,
    table: GpuBuffer<[f32; 4]>,
    rays: GpuBuffer<GpuRaySample>,
    pilot_state: GpuBuffer<[f32; 4]>,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    step_layout: wgpu::BindGroupLayout,
    unused: Unused,
    steps: OnceLock<Steps>,
}

fn layout_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

const READ: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: true };
const READ_WRITE: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: false };
const UNIFORM: wgpu::BufferBindingType = wgpu::BufferBindingType::Uniform;

/// The interior texels' directions and solid angles of the irradiance then visibility map.
fn texel_table(config: &ProbeCacheConfig) -> Vec<[f32; 4]> {
    let mut table = Vec::new();
    for map in [config.texels.irradiance_map, config.texels.visibility_map] {
        let (n, b) = (map.interior(), (map.side() - map.interior()) / 2);
        for k in 0..n * n {
            let t = UVec2::new(k % n + b, k / n + b);
            table.push(map.direction(t).extend(map.solid_angle(t)).to_array());
        }
    }
    table
}

/// The layout of the step group (samples, uniforms, queries, results, clip, pilot).
fn step_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("mcg::adgi steps"),
        entries: &[
            layout_entry(0, READ),
            layout_entry(1, READ),
            layout_entry(2, UNIFORM),
            layout_entry(3, READ),
            layout_entry(4, READ_WRITE),
            layout_entry(5, UNIFORM),
            layout_entry(6, UNIFORM),
        ],
    })
}

impl Unused {
    /// The one-element stand-ins, created on `ctx`'s device.
    fn new(ctx: &GpuContext) -> Self {
        Self {
            samples: ctx.zeroed_buffer("adgi unused samples", 1),
            uniforms: ctx.zeroed_buffer("adgi unused uniforms", 1),
            queries: ctx.zeroed_buffer("adgi unused queries", 1),
            results: ctx.zeroed_buffer("adgi unused results", 1),
            clip: ctx.uniform_buffer("adgi unused clip", &GpuClipVolumes::default()),
            pilot: ctx.uniform_buffer("adgi unused pilot", &GpuPilotStep::default()),
        }
    }
}

impl GpuProbeCache {
    /// The binding of the parameters in the cache's group.
    pub const PARAMS_BINDING: u32 = 0;
    /// The binding of the texel words (`mcg_codec_texels`).
    pub const WORDS_BINDING: u32 = 1;
    /// The binding of the interior texels' directions and solid angles.
    pub const TABLE_BINDING: u32 = 2;
    /// The binding of DDGI's rays (`adgi_rays`).
    pub const RAYS_BINDING: u32 = 3;
    /// The binding of the pilot state (`adgi_pilot_state`; 4 and 5 are the float texels of
    /// the benches' baseline).
    pub const PILOT_BINDING: u32 = 6;

    /// An empty cache (every word 0) on `ctx`'s device, from the same types as the CPU
    /// crate's `ProbeTexels`.
    ///
    /// # Errors
    /// [`AdgiConfigError`] for a configuration with no GPU twin or an invalid one;
    /// [`AdgiConfigError::TooManyWords`] also when the words exceed the device's binding size.
    pub fn new(ctx: &GpuContext, config: &ProbeCacheConfig) -> Result<Self, AdgiConfigError> {
        let (params, words) = AdgiGpuParams::new(config)?;
        let maximum = ctx.device().limits().max_storage_buffer_binding_size;
        let rays = u64::from(params.probe_count) * u64::from(config.rays_per_probe);
        if 4 * words > maximum || 32 * rays > maximum {
            return Err(AdgiConfigError::TooManyWords { words });
        }
        let table = texel_table(config);
        let params_buffer = ctx.uniform_buffer("adgi params", &params);
        let words = ctx.zeroed_buffer("adgi texel words", words as usize);
        let table = ctx.storage_buffer("adgi texel table", &table);
        let rays = ctx.zeroed_buffer("adgi rays", rays as usize);
        let pilot_state = ctx.zeroed_buffer("adgi pilot state", 8 * params.probe_count as usize);
        let device = ctx.device();
        let layout = Self::cache_layout(device);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mcg::adgi"),
            layout: &layout,
            entries: &[
                (Self::PARAMS_BINDING, params_buffer.raw()),
                (Self::WORDS_BINDING, words.raw()),
                (Self::TABLE_BINDING, table.raw()),
                (Self::RAYS_BINDING, rays.raw()),
                (Self::PILOT_BINDING, pilot_state.raw()),
            ]
            .map(|(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            }),
        });
        let step_layout = step_layout(device);
        let unused = Unused::new(ctx);
        Ok(Self {
            config: *config,
            params,
            params_buffer,
            words,
            table,
            rays,
            pilot_state,
            layout,
            bind_group,
            step_layout,
            unused,
            steps: OnceLock::new(),
        })
    }

    /// The layout of the cache's group: the parameters, words, table, rays and pilot state.
    fn cache_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mcg::adgi"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: Self::PARAMS_BINDING,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: UNIFORM,
                        has_dynamic_offset: false,
                        min_binding_size: NonZeroU64::new(size_of::<AdgiGpuParams>() as u64),
                    },
                    count: None,
                },
                layout_entry(Self::WORDS_BINDING, READ_WRITE),
                layout_entry(Self::TABLE_BINDING, READ),
                layout_entry(Self::RAYS_BINDING, READ),
                layout_entry(Self::PILOT_BINDING, READ_WRITE),
            ],
        })
    }

    /// The shader defs that put `mcg::adgi` (and the texel words it uses) at bind group
    /// `group`: pass them to naga_oil's `shader_defs` or to [`crate::shaders::compose`].
    #[must_use]
    pub const fn shader_defs(group: u32) -> [(&'static str, u32); 3] {
        [
            (defs::ADGI_GROUP, group),
            (defs::CODEC_TEXELS_GROUP, group),
            (defs::CODEC_TEXELS_BINDING, Self::WORDS_BINDING),
        ]
    }

    /// The layout of the cache's group (compute stage), for the renderer's pipeline layout.
    #[must_use]
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The cache's group, to set at the index given to [`shader_defs`](Self::shader_defs).
    #[must_use]
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &ProbeCacheConfig {
        &self.config
    }

    /// The parameters as the shaders read them.
    #[must_use]
    pub const fn params(&self) -> &AdgiGpuParams {
        &self.params
    }

    /// The texel words: irradiance words of every probe, then visibility words
    /// (`AdgiGpuParams::visibility_offset`), each probe-major as `ProbeTexels` lays them out.
    #[must_use]
    pub fn words(&self) -> &GpuBuffer<u32> {
        &self.words
    }

    /// DDGI's rays, `rays_per_probe` per probe, probe-major: the renderer writes them (binding
    /// this buffer in its own tracing pipeline), then [`record_blend`](Self::record_blend).
    #[must_use]
    pub fn rays(&self) -> &GpuBuffer<GpuRaySample> {
        &self.rays
    }

    /// Bytes of texel words per probe: `4 · (S_i² + S_v²)` (ADGI: 1 280 bytes), as
    /// `ProbeTexels::bytes_per_probe`.
    #[must_use]
    pub fn bytes_per_probe(&self) -> u64 {
        let (i, v) = (self.params.irradiance_side, self.params.visibility_side);
        4 * u64::from(i * i + v * v)
    }

    fn steps(&self, ctx: &GpuContext) -> Result<&Steps, GpuError> {
        if let Some(s) = self.steps.get() {
            return Ok(s);
        }
        let [update, blend, query, clip_reset, pilot_rays, pilot_hits] = build_pipelines(
            ctx,
            &[&self.layout, &self.step_layout],
            ("adgi steps", kernels::ADGI_STEPS, &Self::shader_defs(0)),
            [
                "adgi_update_samples",
                "adgi_blend",
                "adgi_query",
                "adgi_clip_reset",
                "adgi_pilot_rays",
                "adgi_pilot_hits",
            ],
        )?;
        let s = Steps {
            update,
            blend,
            query,
            clip_reset,
            pilot_rays,
            pilot_hits,
        };
        Ok(self.steps.get_or_init(|| s))
    }

    /// Records one dispatch of `pipeline` over `invocations` with the step group of `inputs`.
    fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        inputs: &StepInputs<'_>,
        invocations: u32,
    ) {
        let step = ctx.uniform_buffer("adgi step", &inputs.step);
        let clip = inputs
            .clip
            .map(|c| ctx.uniform_buffer("adgi clip volumes", &c));
        let pilot = inputs
            .pilot
            .map(|p| ctx.uniform_buffer("adgi pilot step", &p));
        let u = &self.unused;
        let group = bind_group(
            ctx,
            Some("adgi step"),
            &self.step_layout,
            &[
                inputs.samples.unwrap_or(u.samples.raw()),
                inputs.uniforms.unwrap_or(u.uniforms.raw()),
                step.raw(),
                inputs.queries.unwrap_or(u.queries.raw()),
                inputs.results.unwrap_or(u.results.raw()),
                clip.as_ref().map_or(u.clip.raw(), GpuBuffer::raw),
                pilot.as_ref().map_or(u.pilot.raw(), GpuBuffer::raw),
            ],
        );
        record_dispatch(
            ctx,
            encoder,
            "adgi step",
            pipeline,
            &[&self.bind_group, &group],
            invocations,
        );
    }

    /// Records ADGI's per-sample update (Alg. 2-4) of the first `count` samples of `samples`
    /// (an array of [`GpuRaySample`], each naming its probe) with the caller's uniforms
    /// (`uniforms`: one `f32` in [0, 1) per sample) and the moving average `average`
    /// (`MovingAverage::STATIC` for the static chain's samples, `DYNAMIC` for the dynamic
    /// chain's, ADGI Table 3). Samples of one dispatch race on shared texels; the result is the
    /// one some serial order of the CPU's `update_sample_with` gives. Samples naming a probe
    /// outside the grid are skipped.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    pub fn record_update_samples(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        samples: &wgpu::Buffer,
        uniforms: &wgpu::Buffer,
        count: u32,
        average: MovingAverage,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let inputs = StepInputs {
            samples: Some(samples),
            uniforms: Some(uniforms),
            step: GpuStepParams {
                count,
                max_count: average.max_count(),
                ..GpuStepParams::default()
            },
            ..StepInputs::default()
        };
        self.record(ctx, encoder, &steps.update, &inputs, count);
        Ok(())
    }

    /// Records DDGI's blend (DDGI sec. 4, `ProbeTexels::blend_rays` for every probe) of the
    /// rays in [`rays`](Self::rays): one invocation per interior texel of every probe, each
    /// taking one moving-average step toward the cosine-weighted mean of its probe's rays;
    /// `probe_uniforms` holds one `f32` in [0, 1) per probe (texel k rounds with its k-th
    /// rotation, as on the CPU).
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    pub fn record_blend(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        probe_uniforms: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let p = &self.params;
        let per_probe = p.irradiance_interior.pow(2) + p.visibility_interior.pow(2);
        let inputs = StepInputs {
            uniforms: Some(probe_uniforms),
            ..StepInputs::default()
        };
        self.record(
            ctx,
            encoder,
            &steps.blend,
            &inputs,
            p.probe_count * per_probe,
        );
        Ok(())
    }

    /// Records the irradiance query (`ProbeTexels::irradiance_at`) of the first `count`
    /// [`GpuIrradianceQuery`]s of `queries` into `results` (`vec4<f32>` each, irradiance in
    /// `xyz`).
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    pub fn record_query(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        queries: &wgpu::Buffer,
        results: &wgpu::Buffer,
        count: u32,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let inputs = StepInputs {
            queries: Some(queries),
            results: Some(results),
            step: GpuStepParams {
                count,
                ..GpuStepParams::default()
            },
            ..StepInputs::default()
        };
        self.record(ctx, encoder, &steps.query, &inputs, count);
        Ok(())
    }

    /// Records the clip-volume reset (ADGI Fig. 6b, sec. 4.8): every texel word of every probe
    /// in V_out − V_in gets its count lowered to at most `cap` (the paper's 16,
    /// `clip_volume::SHELL_COUNT`), keeping its value.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    pub fn record_clip_reset(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        volumes: &ClipVolumes,
        cap: u32,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let inputs = StepInputs {
            clip: Some(volumes.into()),
            step: GpuStepParams {
                cap,
                ..GpuStepParams::default()
            },
            ..StepInputs::default()
        };
        self.record(
            ctx,
            encoder,
            &steps.clip_reset,
            &inputs,
            self.words.len() as u32,
        );
        Ok(())
    }

    /// Records the pilot rays of every probe and octant (ADGI sec. 4.4; `pilot_rays`): into
    /// `out` (`vec4<f32>` per `probe · 8 + octant`) the direction of octant `octant` from the
    /// caller's uniforms (`uniforms[2i]`, `uniforms[2i + 1]`; key them by pattern, probe and
    /// octant so both frames of a pair trace the same rays) in `xyz`, and in `w` 1 for a probe
    /// in V_out of `volumes` (trace it) and 0 otherwise.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    pub fn record_pilot_rays(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        uniforms: &wgpu::Buffer,
        volumes: &ClipVolumes,
        out: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let inputs = StepInputs {
            uniforms: Some(uniforms),
            results: Some(out),
            clip: Some(volumes.into()),
            ..StepInputs::default()
        };
        self.record(
            ctx,
            encoder,
            &steps.pilot_rays,
            &inputs,
            8 * self.params.probe_count,
        );
        Ok(())
    }

    /// Records the pilot hits' update of the pilot state (ADGI eq. 11-17) for every probe in
    /// V_out: `hits` holds one [`GpuRaySample`] per `probe · 8 + octant` (the ray of
    /// [`record_pilot_rays`](Self::record_pilot_rays): its hit distance, +∞ for a miss, and
    /// the radiance arriving along it); f_v of an octant reads the hit of the opposite octant
    /// (eq. 11 traces −ω), f_r the luminance of its own. On a [`PilotPhase::Detect`] frame the
    /// temporal gradient against the stored reference drives the trigger states; then the
    /// finite heuristics become the reference. Read the state with
    /// [`read_pilot_state`](Self::read_pilot_state).
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the steps' pipelines fail to build (a bug of this crate).
    #[allow(clippy::too_many_arguments)] // the CPU types of one step, each needed
    pub fn record_pilot_hits(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        hits: &wgpu::Buffer,
        volumes: &ClipVolumes,
        heuristics: &HeuristicParams,
        trigger: TemporalTrigger,
        phase: PilotPhase,
    ) -> Result<(), GpuError> {
        let steps = self.steps(ctx)?;
        let inputs = StepInputs {
            samples: Some(hits),
            clip: Some(volumes.into()),
            pilot: Some(GpuPilotStep::new(heuristics, trigger, phase)),
            ..StepInputs::default()
        };
        self.record(
            ctx,
            encoder,
            &steps.pilot_hits,
            &inputs,
            8 * self.params.probe_count,
        );
        Ok(())
    }

    /// The pilot state (`adgi_pilot_state`): per `probe · 8 + octant`, the reference f_v and
    /// f_r and the trigger states of f_v and f_r.
    #[must_use]
    pub fn pilot_state(&self) -> &GpuBuffer<[f32; 4]> {
        &self.pilot_state
    }

    /// [`record_pilot_rays`](Self::record_pilot_rays) from host uniforms, read back.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there are 2 uniforms per probe and octant; as
    /// [`record_pilot_rays`](Self::record_pilot_rays); [`GpuError::Map`] when the read-back
    /// fails.
    pub fn pilot_rays(
        &self,
        ctx: &GpuContext,
        uniforms: &[f32],
        volumes: &ClipVolumes,
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let n = 8 * self.params.probe_count as usize;
        GpuError::check_len(2 * n, uniforms.len())?;
        let u = ctx.storage_buffer("adgi pilot uniforms", uniforms);
        let out = ctx.zeroed_buffer::<[f32; 4]>("adgi pilot rays", n);
        self.submit(ctx, |e| {
            self.record_pilot_rays(ctx, e, u.raw(), volumes, out.raw())
        })?;
        ctx.read_back(&out)
    }

    /// [`record_pilot_hits`](Self::record_pilot_hits) from host hits, submitted.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there is one hit per probe and octant; as
    /// [`record_pilot_hits`](Self::record_pilot_hits).
    pub fn pilot_hits(
        &self,
        ctx: &GpuContext,
        hits: &[GpuRaySample],
        volumes: &ClipVolumes,
        heuristics: &HeuristicParams,
        trigger: TemporalTrigger,
        phase: PilotPhase,
    ) -> Result<(), GpuError> {
        GpuError::check_len(8 * self.params.probe_count as usize, hits.len())?;
        let h = ctx.storage_buffer("adgi pilot hits", hits);
        self.submit(ctx, |e| {
            self.record_pilot_hits(ctx, e, h.raw(), volumes, heuristics, trigger, phase)
        })
    }

    /// The pilot state, read back (waits for the queue).
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_pilot_state(&self, ctx: &GpuContext) -> Result<Vec<[f32; 4]>, GpuError> {
        ctx.read_back(&self.pilot_state)
    }

    /// Runs `record` in an encoder of its own and submits it.
    fn submit(
        &self,
        ctx: &GpuContext,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<(), GpuError>,
    ) -> Result<(), GpuError> {
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        record(&mut encoder)?;
        ctx.queue().submit([encoder.finish()]);
        Ok(())
    }

    /// [`record_update_samples`](Self::record_update_samples) from host slices, submitted.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there is one uniform per sample; as
    /// [`record_update_samples`](Self::record_update_samples).
    pub fn update_samples(
        &self,
        ctx: &GpuContext,
        samples: &[GpuRaySample],
        uniforms: &[f32],
        average: MovingAverage,
    ) -> Result<(), GpuError> {
        GpuError::check_len(samples.len(), uniforms.len())?;
        let s = ctx.storage_buffer("adgi samples", samples);
        let u = ctx.storage_buffer("adgi uniforms", uniforms);
        self.submit(ctx, |e| {
            self.record_update_samples(ctx, e, s.raw(), u.raw(), samples.len() as u32, average)
        })
    }

    /// Uploads `rays` into [`rays`](Self::rays) and runs [`record_blend`](Self::record_blend).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless `rays` fills the rays buffer and there is one
    /// uniform per probe; as [`record_blend`](Self::record_blend).
    pub fn blend(
        &self,
        ctx: &GpuContext,
        rays: &[GpuRaySample],
        probe_uniforms: &[f32],
    ) -> Result<(), GpuError> {
        GpuError::check_len(self.params.probe_count as usize, probe_uniforms.len())?;
        ctx.write(&self.rays, rays)?;
        let u = ctx.storage_buffer("adgi probe uniforms", probe_uniforms);
        self.submit(ctx, |e| self.record_blend(ctx, e, u.raw()))
    }

    /// [`record_query`](Self::record_query) of host queries, read back.
    ///
    /// # Errors
    /// As [`record_query`](Self::record_query); [`GpuError::Map`] when the read-back fails.
    pub fn query(
        &self,
        ctx: &GpuContext,
        queries: &[GpuIrradianceQuery],
    ) -> Result<Vec<Vec3>, GpuError> {
        let q = ctx.storage_buffer("adgi queries", queries);
        let r = ctx.zeroed_buffer::<[f32; 4]>("adgi results", queries.len());
        self.submit(ctx, |e| {
            self.record_query(ctx, e, q.raw(), r.raw(), queries.len() as u32)
        })?;
        let out = ctx.read_back(&r)?;
        Ok(out.iter().map(|v| Vec3::new(v[0], v[1], v[2])).collect())
    }

    /// [`record_clip_reset`](Self::record_clip_reset), submitted.
    ///
    /// # Errors
    /// As [`record_clip_reset`](Self::record_clip_reset).
    pub fn clip_reset(
        &self,
        ctx: &GpuContext,
        volumes: &ClipVolumes,
        cap: u32,
    ) -> Result<(), GpuError> {
        self.submit(ctx, |e| self.record_clip_reset(ctx, e, volumes, cap))
    }

    /// Overwrites the words with a CPU grid's (`ProbeTexels::irradiance_words`, then
    /// `visibility_words`).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless the two together have the cache's word count.
    pub fn upload_words(
        &self,
        ctx: &GpuContext,
        irradiance: &[u32],
        visibility: &[u32],
    ) -> Result<(), GpuError> {
        let mut all = irradiance.to_vec();
        all.extend_from_slice(visibility);
        ctx.write(&self.words, &all)
    }

    /// The irradiance words and the visibility words, read back (waits for the queue).
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_words(&self, ctx: &GpuContext) -> Result<(Vec<u32>, Vec<u32>), GpuError> {
        let mut all = ctx.read_back(&self.words)?;
        let visibility = all.split_off(self.params.visibility_offset as usize);
        Ok((all, visibility))
    }

    /// Sets every word to 0 (black, no distance, count 0) and the pilot state to 0, keeping
    /// buffers and pipelines.
    pub fn reset(&self, ctx: &GpuContext) {
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.clear_buffer(self.words.raw(), 0, None);
        encoder.clear_buffer(self.pilot_state.raw(), 0, None);
        ctx.queue().submit([encoder.finish()]);
    }

    /// The parameters' uniform buffer (binding [`PARAMS_BINDING`](Self::PARAMS_BINDING)).
    #[must_use]
    pub fn params_buffer(&self) -> &GpuBuffer<AdgiGpuParams> {
        &self.params_buffer
    }

    /// The interior texels' table (centre direction, solid angle), irradiance map first.
    #[must_use]
    pub fn texel_table(&self) -> &GpuBuffer<[f32; 4]> {
        &self.table
    }
}
