//! `GpuProbeChains` (ADGI's guiding function and Metropolis probe chains) and
//! `GpuTriggerSmoothing` (the triggers' 5 × 5 × 5 × octant smoothing, on a `GpuProbeCache`).

use std::sync::OnceLock;

use glam::Vec3;
use mcg_probe_cache::{
    ChainKind, FrameStats, GuideParams, HeuristicField, HeuristicParams, ProbeChainState,
    ProbeChains, SmoothingKernel,
};

use super::{
    AdgiConfigError, GpuChainParams, GpuChainState, GpuComposeParams, GpuGuideQuery, GpuProbeCache,
    GpuProbeSample, GpuSmoothingPass,
};
use crate::runtime::{bind_group, build_pipelines, record_dispatch};
use crate::shaders::kernels;
use crate::{GpuBuffer, GpuContext, GpuError, storage_entry};

/// The label of this file's passes and bind groups in wgpu's messages.
const LABEL: &str = "adgi chains";

/// The pipeline in `cell`, built on first use from entry point `entry` of a kernel that reads
/// `cache`'s group (`mcg::adgi`) at group 0 and `layout` at group 1.
fn cache_pipeline<'a>(
    ctx: &GpuContext,
    cell: &'a OnceLock<wgpu::ComputePipeline>,
    cache: &GpuProbeCache,
    layout: &wgpu::BindGroupLayout,
    (label, source): (&str, &str),
    entry: &str,
) -> Result<&'a wgpu::ComputePipeline, GpuError> {
    if let Some(p) = cell.get() {
        return Ok(p);
    }
    let defs = GpuProbeCache::shader_defs(0);
    let [p] = build_pipelines(
        ctx,
        &[cache.bind_group_layout(), layout],
        (label, source, &defs),
        [entry],
    )?;
    Ok(cell.get_or_init(|| p))
}

/// Records one dispatch of a [`cache_pipeline`] over `invocations`: `cache`'s group at group 0
/// and a group of `layout` with `buffers[i]` at binding i at group 1.
fn record_cache_dispatch(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::ComputePipeline,
    cache: &GpuProbeCache,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
    invocations: u32,
) {
    let group = bind_group(ctx, Some(LABEL), layout, buffers);
    let groups = [cache.bind_group(), &group];
    record_dispatch(ctx, encoder, LABEL, pipeline, &groups, invocations);
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    crate::buffer_entry(binding, wgpu::BufferBindingType::Uniform)
}

/// Runs `record` in an encoder of its own and submits it.
fn submit(
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

/// The chains' pipelines.
#[derive(Debug)]
struct ChainPipelines {
    table: wgpu::ComputePipeline,
    values: wgpu::ComputePipeline,
    frame: wgpu::ComputePipeline,
}

/// Counters before the claimed bits in the counter buffer (`chain_counters`).
const COUNTERS: usize = 8;

/// ADGI's static or dynamic Metropolis probe chains on the GPU (ADGI sec. 3.3, 4.8, 4.9,
/// Alg. 1 and 5), the twin of `mcg_probe_cache::ProbeChains` with its `GuidingFunction`: one
/// chain per invocation, persistent chain states, the guide tabulated per cell and octant, the
/// frame's samples appended to a buffer through an atomic counter. Each step is one dispatch
/// recorded into the caller's encoder:
///
/// | step | record | CPU twin |
/// |---|---|---|
/// | the guide's table: f_s or f_d of the heuristics words, max-pooled into the cells | [`record_guide`](Self::record_guide) | `guiding_function::decode_field` + `ProxyGrid::max_pool` |
/// | h(p, ω) at given points | [`record_guide_values`](Self::record_guide_values) | `GuidingFunction::guiding_value` |
/// | one frame of every chain | [`record_frame`](Self::record_frame) | `ProbeChains::step_frame_parallel` with [`chain_step_uniforms`](super::chain_step_uniforms) |
/// | the feedback ĝ from a cache's irradiance words | [`record_feedback`](Self::record_feedback) | `guiding_function::octant_feedback` per probe |
///
/// The guide is `GuidingFunction` over the chains' cells with the given [`GuideParams`]: the
/// static chains (sec. 4.8) read f_s per probe and octant and the feedback ĝ
/// ([`feedback`](Self::feedback), 0 until recorded or written) with `GuideParams::STATIC`, i.e.
/// h = exp(min(ĝ/f_s, 1)) f_s; the dynamic chains (sec. 4.9) read f_d max-pooled into ADGI's
/// 3 × 3 × 3 virtual proxies with α = 0, i.e. h = f_d, and emit each (proxy, octant) at most
/// once per frame (the first invocation to claim it, an atomic bit per texel).
///
/// Samples: up to chains × (M − K) [`GpuProbeSample`]s per frame in [`samples`](Self::samples),
/// their number in `counters()[0]`, in the order the invocations claimed slots. Trace them as
/// the CPU's `ProbeSample`s (see `mcg_probe_cache::probe_chains`), e.g. into
/// `GpuProbeCache::record_update_samples`. Bit i of a state's `accepted` records step i of the
/// last frame for i < 32.
#[derive(Debug)]
pub struct GpuProbeChains {
    params: GpuChainParams,
    cell_table: u32,
    guide: GpuBuffer<f32>,
    feedback: GpuBuffer<f32>,
    states: GpuBuffer<GpuChainState>,
    samples: GpuBuffer<GpuProbeSample>,
    counters: GpuBuffer<u32>,
    unused_words: GpuBuffer<u32>,
    unused_queries: GpuBuffer<GpuGuideQuery>,
    unused_values: GpuBuffer<f32>,
    layout: wgpu::BindGroupLayout,
    pipelines: OnceLock<ChainPipelines>,
    feedback_layout: wgpu::BindGroupLayout,
    feedback_pipeline: OnceLock<wgpu::ComputePipeline>,
}

/// The buffers of one chain step at bindings 1, 7, 8 (`None`: the unused stand-in).
#[derive(Default)]
struct ChainInputs<'a> {
    words: Option<&'a wgpu::Buffer>,
    queries: Option<&'a wgpu::Buffer>,
    values: Option<&'a wgpu::Buffer>,
}

impl GpuProbeChains {
    /// The chains of `chains` (its kind, cells, walk, schedule and current states) on the GPU,
    /// sampling the guide `guide`: f_s for static chains, f_d for dynamic ones, the feedback ĝ
    /// read when α > 0.
    ///
    /// # Errors
    /// [`AdgiConfigError::TooManyChainSamples`] when a frame's samples exceed what one binding
    /// holds.
    pub fn new(
        ctx: &GpuContext,
        chains: &ProbeChains,
        guide: GuideParams,
    ) -> Result<Self, AdgiConfigError> {
        let cells = chains.cells();
        let field = match chains.kind() {
            ChainKind::Static => HeuristicField::Static,
            ChainKind::Dynamic => HeuristicField::Dynamic,
        };
        let params = GpuChainParams::new(chains, guide, field, guide.alpha() > 0.0);
        let schedule = chains.schedule();
        let samples =
            chains.states().len() as u64 * u64::from(schedule.iterations() - schedule.burn_in());
        let maximum = ctx.device().limits().max_storage_buffer_binding_size;
        if samples > u64::from(u32::MAX) || 48 * samples > maximum {
            return Err(AdgiConfigError::TooManyChainSamples { samples });
        }
        let cell_table = cells.table_len() as u32;
        let states: Vec<GpuChainState> = chains.states().iter().map(Into::into).collect();
        let layout = ctx
            .device()
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("adgi chains"),
                entries: &[
                    uniform_entry(0),
                    storage_entry(1, true),
                    storage_entry(2, false),
                    storage_entry(3, true),
                    storage_entry(4, false),
                    storage_entry(5, false),
                    storage_entry(6, false),
                    storage_entry(7, true),
                    storage_entry(8, false),
                ],
            });
        let feedback_layout =
            ctx.device()
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("adgi feedback"),
                    entries: &[storage_entry(0, false)],
                });
        let claimed = cell_table.div_ceil(32) as usize;
        Ok(Self {
            params,
            cell_table,
            guide: ctx.zeroed_buffer("adgi chains guide", cell_table as usize),
            feedback: ctx.zeroed_buffer("adgi chains feedback", cell_table as usize),
            states: ctx.storage_buffer("adgi chain states", &states),
            samples: ctx.zeroed_buffer("adgi chain samples", samples as usize),
            counters: ctx.zeroed_buffer("adgi chain counters", COUNTERS + claimed),
            unused_words: ctx.zeroed_buffer("adgi chains unused words", 1),
            unused_queries: ctx.zeroed_buffer("adgi chains unused queries", 1),
            unused_values: ctx.zeroed_buffer("adgi chains unused values", 1),
            layout,
            pipelines: OnceLock::new(),
            feedback_layout,
            feedback_pipeline: OnceLock::new(),
        })
    }

    fn pipelines(&self, ctx: &GpuContext) -> Result<&ChainPipelines, GpuError> {
        if let Some(p) = self.pipelines.get() {
            return Ok(p);
        }
        let [table, values, frame] = build_pipelines(
            ctx,
            &[&self.layout],
            ("adgi chains", kernels::ADGI_CHAINS, &[]),
            ["adgi_guide_table", "adgi_guide_values", "adgi_chain_frame"],
        )?;
        Ok(self.pipelines.get_or_init(|| ChainPipelines {
            table,
            values,
            frame,
        }))
    }

    /// Records one dispatch of `pipeline` over `invocations` with `params` and `inputs`.
    fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        params: &GpuChainParams,
        inputs: &ChainInputs<'_>,
        invocations: u32,
    ) {
        let uniform = ctx.uniform_buffer("adgi chain params", params);
        let group = bind_group(
            ctx,
            Some(LABEL),
            &self.layout,
            &[
                uniform.raw(),
                inputs.words.unwrap_or(self.unused_words.raw()),
                self.guide.raw(),
                self.feedback.raw(),
                self.states.raw(),
                self.samples.raw(),
                self.counters.raw(),
                inputs.queries.unwrap_or(self.unused_queries.raw()),
                inputs.values.unwrap_or(self.unused_values.raw()),
            ],
        );
        record_dispatch(ctx, encoder, LABEL, pipeline, &[&group], invocations);
    }

    /// Records the guide's table from the heuristics words `words` (one `HeuristicsWord` per
    /// `probe · 8 + octant`, ADGI sec. 4.3): the chains' heuristic (f_s or f_d) of every probe,
    /// max-pooled into the cells (sec. 4.9; the static chains' cells are single probes).
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pipelines fail to build (a bug of this crate).
    pub fn record_guide(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        words: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let p = self.pipelines(ctx)?;
        let inputs = ChainInputs {
            words: Some(words),
            ..ChainInputs::default()
        };
        self.record(
            ctx,
            encoder,
            &p.table,
            &self.params,
            &inputs,
            self.cell_table,
        );
        Ok(())
    }

    /// Records h(p, ω) of the first `count` [`GpuGuideQuery`]s of `queries` into `values`
    /// (one `f32` each), from the guide's current table and feedback.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pipelines fail to build (a bug of this crate).
    pub fn record_guide_values(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        queries: &wgpu::Buffer,
        values: &wgpu::Buffer,
        count: u32,
    ) -> Result<(), GpuError> {
        let p = self.pipelines(ctx)?;
        let params = GpuChainParams {
            count,
            ..self.params
        };
        let inputs = ChainInputs {
            queries: Some(queries),
            values: Some(values),
            ..ChainInputs::default()
        };
        self.record(ctx, encoder, &p.values, &params, &inputs, count);
        Ok(())
    }

    /// Records one frame of every chain (ADGI Alg. 1): clears the counters and the claimed
    /// texels, then one dispatch; chain `j` draws its `k`-th uniforms as
    /// [`chain_step_uniforms`](super::chain_step_uniforms)`(seed, j, k)` (use a new `seed`
    /// every frame).
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pipelines fail to build (a bug of this crate).
    pub fn record_frame(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        seed: u32,
    ) -> Result<(), GpuError> {
        let p = self.pipelines(ctx)?;
        encoder.clear_buffer(self.counters.raw(), 0, None);
        let params = GpuChainParams {
            seed,
            ..self.params
        };
        let n = self.params.chain_count;
        self.record(ctx, encoder, &p.frame, &params, &ChainInputs::default(), n);
        Ok(())
    }

    /// [`record_guide`](Self::record_guide) from host words, submitted.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there is one word per probe and octant; as
    /// [`record_guide`](Self::record_guide).
    pub fn guide_from_words(&self, ctx: &GpuContext, words: &[u32]) -> Result<(), GpuError> {
        GpuError::check_len(8 * self.params.probe_count as usize, words.len())?;
        let w = ctx.storage_buffer("adgi heuristics words", words);
        submit(ctx, |e| self.record_guide(ctx, e, w.raw()))
    }

    /// [`record_guide_values`](Self::record_guide_values) of host queries, read back.
    ///
    /// # Errors
    /// As [`record_guide_values`](Self::record_guide_values); [`GpuError::Map`] when the
    /// read-back fails.
    pub fn guide_values(
        &self,
        ctx: &GpuContext,
        queries: &[GpuGuideQuery],
    ) -> Result<Vec<f32>, GpuError> {
        let q = ctx.storage_buffer("adgi guide queries", queries);
        let v = ctx.zeroed_buffer::<f32>("adgi guide values", queries.len());
        let n = queries.len() as u32;
        submit(ctx, |e| {
            self.record_guide_values(ctx, e, q.raw(), v.raw(), n)
        })?;
        ctx.read_back(&v)
    }

    /// [`record_frame`](Self::record_frame), submitted.
    ///
    /// # Errors
    /// As [`record_frame`](Self::record_frame).
    pub fn step_frame(&self, ctx: &GpuContext, seed: u32) -> Result<(), GpuError> {
        submit(ctx, |e| self.record_frame(ctx, e, seed))
    }

    /// Records the feedback ĝ of ADGI eq. 2 (sec. 4.8: the static chains' target "from a higher
    /// mip-level") from `cache`'s irradiance words into [`feedback`](Self::feedback), one
    /// dispatch: per probe and octant the mean Rec. 709 luminance of the probe's interior
    /// irradiance texels whose centre lies in the octant, non-finite or non-positive luminances
    /// counted as 0 (`guiding_function::octant_feedback` of every probe, as the CPU's
    /// `ProbeUpdater` computes it). Record it before the frame's texel updates so the target
    /// stays fixed within the frame. The sums are the CPU's bit for bit, the mean's division
    /// WGSL's (within 2.5 ULP).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless the chains' cells are `cache`'s probes (static
    /// chains on the same grid); [`GpuError::Shader`] if the pipeline fails to build (a bug of
    /// this crate).
    pub fn record_feedback(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        cache: &GpuProbeCache,
    ) -> Result<(), GpuError> {
        let n = 8 * cache.params().probe_count;
        GpuError::check_len(self.cell_table as usize, n as usize)?;
        let pipeline = cache_pipeline(
            ctx,
            &self.feedback_pipeline,
            cache,
            &self.feedback_layout,
            ("adgi feedback", kernels::ADGI_FEEDBACK),
            "adgi_octant_feedback",
        )?;
        let buffers = [self.feedback.raw()];
        record_cache_dispatch(
            ctx,
            encoder,
            pipeline,
            cache,
            &self.feedback_layout,
            &buffers,
            n,
        );
        Ok(())
    }

    /// [`record_feedback`](Self::record_feedback), submitted, and ĝ read back.
    ///
    /// # Errors
    /// As [`record_feedback`](Self::record_feedback); [`GpuError::Map`] when the read-back
    /// fails.
    pub fn feedback_from_cache(
        &self,
        ctx: &GpuContext,
        cache: &GpuProbeCache,
    ) -> Result<Vec<f32>, GpuError> {
        submit(ctx, |e| self.record_feedback(ctx, e, cache))?;
        ctx.read_back(&self.feedback)
    }

    /// Overwrites the feedback ĝ per cell and octant (e.g. `guiding_function::octant_feedback`
    /// of the previous frame's irradiance computed on the host; on the GPU:
    /// [`record_feedback`](Self::record_feedback)).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless `feedback` has one value per cell and octant.
    pub fn write_feedback(&self, ctx: &GpuContext, feedback: &[f32]) -> Result<(), GpuError> {
        ctx.write(&self.feedback, feedback)
    }

    /// Overwrites the guide's table f per cell and octant (instead of
    /// [`record_guide`](Self::record_guide)).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless `f` has one value per cell and octant.
    pub fn write_guide_table(&self, ctx: &GpuContext, f: &[f32]) -> Result<(), GpuError> {
        ctx.write(&self.guide, f)
    }

    /// The guide's table f per cell and octant, read back.
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_guide_table(&self, ctx: &GpuContext) -> Result<Vec<f32>, GpuError> {
        ctx.read_back(&self.guide)
    }

    /// Overwrites the chain states (h is re-evaluated at the next frame anyway).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there is one state per chain.
    pub fn write_states(
        &self,
        ctx: &GpuContext,
        states: &[ProbeChainState],
    ) -> Result<(), GpuError> {
        let s: Vec<GpuChainState> = states.iter().map(Into::into).collect();
        ctx.write(&self.states, &s)
    }

    /// The chain states after the last frame, read back.
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_states(&self, ctx: &GpuContext) -> Result<Vec<GpuChainState>, GpuError> {
        ctx.read_back(&self.states)
    }

    /// The last frame's samples, read back (in slot order).
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_samples(&self, ctx: &GpuContext) -> Result<Vec<GpuProbeSample>, GpuError> {
        let n = ctx.read_back(&self.counters)?[0] as usize;
        let mut all = ctx.read_back(&self.samples)?;
        all.truncate(n.min(self.samples.len()));
        Ok(all)
    }

    /// The last frame's counters, as the CPU's [`FrameStats`].
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_stats(&self, ctx: &GpuContext) -> Result<FrameStats, GpuError> {
        let c = ctx.read_back(&self.counters)?;
        Ok(FrameStats {
            emitted: c[0],
            proposals: c[1],
            accepted: c[2],
            restarts: c[3],
            dropped: c[4],
        })
    }

    /// The chains' constants.
    #[must_use]
    pub const fn params(&self) -> &GpuChainParams {
        &self.params
    }

    /// The chain states ([`GpuChainState`] per chain).
    #[must_use]
    pub fn states(&self) -> &GpuBuffer<GpuChainState> {
        &self.states
    }

    /// The samples of the last frame (the first `counters()[0]` are written).
    #[must_use]
    pub fn samples(&self) -> &GpuBuffer<GpuProbeSample> {
        &self.samples
    }

    /// The counters of the last frame: samples written, proposals, accepted, restarts,
    /// dropped, three unused words, then the claimed bits of the (cell, octant) texels.
    #[must_use]
    pub fn counters(&self) -> &GpuBuffer<u32> {
        &self.counters
    }

    /// The feedback ĝ per cell and octant.
    #[must_use]
    pub fn feedback(&self) -> &GpuBuffer<f32> {
        &self.feedback
    }

    /// The guide's table f per cell and octant.
    #[must_use]
    pub fn guide_table(&self) -> &GpuBuffer<f32> {
        &self.guide
    }
}

/// The smoothing of the temporal triggers on the GPU (ADGI sec. 4.1.4, eq. 15 and 18): the
/// twin of `temporal_gradient::spatial_smoothing` applied to the trigger states that
/// `GpuProbeCache::record_pilot_hits` keeps (f_1 and f_3 of eq. 14, 17), writing f_Δv and f_Δr
/// per probe and octant into [`delta`](Self::delta), equal to the CPU's bit for bit. Three
/// dispatches (x, y, z; the octant average rides in the x pass).
///
/// From those, [`record_compose`](Self::record_compose) composes the heuristics words (ADGI
/// sec. 4.1-4.3, eq. 10, 19, 20; the twin of `heuristics::compose_grid`) that
/// [`GpuProbeChains::record_guide`] reads: one dispatch.
#[derive(Debug)]
pub struct GpuTriggerSmoothing {
    delta: GpuBuffer<[f32; 2]>,
    scratch: GpuBuffer<[f32; 2]>,
    reciprocals: GpuBuffer<f32>,
    layout: wgpu::BindGroupLayout,
    pipeline: OnceLock<wgpu::ComputePipeline>,
    compose_layout: wgpu::BindGroupLayout,
    compose_pipeline: OnceLock<wgpu::ComputePipeline>,
}

impl GpuTriggerSmoothing {
    /// The smoothing's buffers for `cache`'s grid.
    #[must_use]
    pub fn new(ctx: &GpuContext, cache: &GpuProbeCache) -> Self {
        let p = cache.params();
        let n = 8 * p.probe_count as usize;
        let longest = p.counts.max_element();
        // 1/n as the CPU rounds it (index 0 unused).
        let reciprocals: Vec<f32> = (0..=longest)
            .map(|k| if k == 0 { 0.0 } else { 1.0 / k as f32 })
            .collect();
        let layout = ctx
            .device()
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("adgi smoothing"),
                entries: &[
                    uniform_entry(0),
                    storage_entry(1, true),
                    storage_entry(2, false),
                    storage_entry(3, true),
                ],
            });
        let compose_layout =
            ctx.device()
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("adgi compose"),
                    entries: &[
                        uniform_entry(0),
                        storage_entry(1, true),
                        storage_entry(2, false),
                    ],
                });
        Self {
            delta: ctx.zeroed_buffer("adgi smoothed triggers", n),
            scratch: ctx.zeroed_buffer("adgi smoothing scratch", n),
            reciprocals: ctx.storage_buffer("adgi smoothing reciprocals", &reciprocals),
            layout,
            pipeline: OnceLock::new(),
            compose_layout,
            compose_pipeline: OnceLock::new(),
        }
    }

    /// Records the smoothing of `cache`'s trigger states with `kernel` into
    /// [`delta`](Self::delta): three dispatches.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pipeline fails to build (a bug of this crate).
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        cache: &GpuProbeCache,
        kernel: SmoothingKernel,
    ) -> Result<(), GpuError> {
        let pipeline = cache_pipeline(
            ctx,
            &self.pipeline,
            cache,
            &self.layout,
            ("adgi smoothing", kernels::ADGI_SMOOTHING),
            "adgi_smooth_axis",
        )?;
        // x: triggers → delta, y: delta → scratch, z: scratch → delta.
        let (d, s) = (self.delta.raw(), self.scratch.raw());
        let routes = [(s, d), (d, s), (s, d)];
        let invocations = self.delta.len() as u32;
        for (pass, (src, dst)) in GpuSmoothingPass::passes(kernel).iter().zip(routes) {
            let uniform = ctx.uniform_buffer("adgi smoothing pass", pass);
            let buffers = [uniform.raw(), src, dst, self.reciprocals.raw()];
            record_cache_dispatch(
                ctx,
                encoder,
                pipeline,
                cache,
                &self.layout,
                &buffers,
                invocations,
            );
        }
        Ok(())
    }

    /// [`record`](Self::record), submitted, and f_Δv, f_Δr read back.
    ///
    /// # Errors
    /// As [`record`](Self::record); [`GpuError::Map`] when the read-back fails.
    pub fn smooth(
        &self,
        ctx: &GpuContext,
        cache: &GpuProbeCache,
        kernel: SmoothingKernel,
    ) -> Result<(Vec<f32>, Vec<f32>), GpuError> {
        submit(ctx, |e| self.record(ctx, e, cache, kernel))?;
        let d = ctx.read_back(&self.delta)?;
        Ok(d.iter().map(|v| (v[0], v[1])).unzip())
    }

    /// Records the composition of the heuristics words (ADGI sec. 4.1-4.3) into `words` (one
    /// `HeuristicsWord` per `probe · 8 + octant`, read and written; their flag bits are kept),
    /// one dispatch: per probe f_c of its distance to `camera` (eq. 10, `heuristics`'
    /// threshold), per octant f_v of the pilot rays (eq. 11, the cache's pilot state, see
    /// `GpuProbeCache::record_pilot_hits`), f_s = f_c f_v (eq. 19) and
    /// f_d = f_c f_v (f_Δv + μ f_Δr)/(1 + μ) (eq. 20 over its bound) from [`delta`](Self::delta)
    /// (after [`record`](Self::record)), packed into the 6-10-10 word rounded to nearest: the
    /// twin of `heuristics::compose_grid`. Equal to the CPU's word bit for bit except that
    /// WGSL's `sqrt`, `exp` and division (a few ULP) can move a field's code by one where the
    /// CPU's value lies within those ULP of a rounding tie.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pipeline fails to build (a bug of this crate).
    pub fn record_compose(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        cache: &GpuProbeCache,
        heuristics: &HeuristicParams,
        camera: Vec3,
        words: &wgpu::Buffer,
    ) -> Result<(), GpuError> {
        let pipeline = cache_pipeline(
            ctx,
            &self.compose_pipeline,
            cache,
            &self.compose_layout,
            ("adgi compose", kernels::ADGI_COMPOSE),
            "adgi_compose_heuristics",
        )?;
        let params = GpuComposeParams::new(heuristics, camera);
        let uniform = ctx.uniform_buffer("adgi compose params", &params);
        let buffers = [uniform.raw(), self.delta.raw(), words];
        let n = self.delta.len() as u32;
        record_cache_dispatch(
            ctx,
            encoder,
            pipeline,
            cache,
            &self.compose_layout,
            &buffers,
            n,
        );
        Ok(())
    }

    /// [`record_compose`](Self::record_compose) on host words (their flags are kept),
    /// submitted, and the words read back.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless there is one word per probe and octant; as
    /// [`record_compose`](Self::record_compose); [`GpuError::Map`] when the read-back fails.
    pub fn compose(
        &self,
        ctx: &GpuContext,
        cache: &GpuProbeCache,
        heuristics: &HeuristicParams,
        camera: Vec3,
        words: &[u32],
    ) -> Result<Vec<u32>, GpuError> {
        GpuError::check_len(self.delta.len(), words.len())?;
        let w = ctx.storage_buffer("adgi heuristics words", words);
        submit(ctx, |e| {
            self.record_compose(ctx, e, cache, heuristics, camera, w.raw())
        })?;
        ctx.read_back(&w)
    }

    /// f_Δv, f_Δr per `probe · 8 + octant` as `[f_Δv, f_Δr]` (after [`record`](Self::record)).
    #[must_use]
    pub fn delta(&self) -> &GpuBuffer<[f32; 2]> {
        &self.delta
    }
}
