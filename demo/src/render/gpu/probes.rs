//! `ddgi`, `adgi` and `adgi-refill` on the GPU: the twin of [`super::super::probe_gi`].
//!
//! The shader is the tracer's, composed with [`PROBE_GI_DEF`] and the probe cache `mcg::adgi`
//! ([`GpuProbeCache`]) at group [`GUIDE_GROUP`]. A frame records, before the camera's tiles:
//!
//! - **`ddgi`, the update on the GPU:** the host lays out every probe's rays (DDGI's spherical
//!   Fibonacci set under the frame's random rotation, drawn from the same stream as the CPU's
//!   `ProbeUpdater` draws it; one upload of 32 bytes per ray), the kernel `trace_probe_rays`
//!   traces them in the scene's BVH and writes their [`GpuRaySample`]s, which are copied into
//!   the cache's rays and blended into its texel words by [`GpuProbeCache::record_blend`]
//!   (DDGI sec. 4, N_max 17) — one submission, no read-back. (Making the rays in the kernel
//!   instead stalled lavapipe for seconds on some frames.)
//! - **`adgi`, the update on the GPU:** ADGI's frame (`UpdatePolicy::Adgi`, the twin of
//!   `ProbeUpdater::frame`, same budget and order of steps) in one submission, no read-back
//!   (`GpuTracer::adgi_frame`): the pilot rays laid out on the GPU by the kernel
//!   `lay_out_pilot_rays` (`GpuTracer::record_pilot_layout`: the CPU's pilot uniforms,
//!   `mcg::adgi_chains::adgi_pilot_uniforms`, bit for bit, hence its light seeds, and its
//!   directions within WGSL's `sqrt`/`sin`/`cos`; only the 16-byte seed and pattern are
//!   uploaded), traced by `trace_probe_rays`, their hits into the texels on the first frame
//!   of a pair (with rounding uniforms drawn on the host) and into the temporal trigger
//!   ([`GpuProbeCache::record_pilot_hits`]); the triggers smoothed and the heuristics words
//!   composed ([`GpuTriggerSmoothing`]); the dynamic chains on the proxies, each sample
//!   expanded by the kernel `expand_dynamic_samples` into rays for every probe of its proxy
//!   within the dynamic budget, traced (their count copied on the GPU) and averaged with the
//!   dynamic N_max; the feedback ĝ, the static chains and their samples traced by
//!   `trace_chain_samples` ([`GpuTracer::record_chain_rays`]) on the rays left, each averaged
//!   into its texel ([`GpuProbeCache::record_update_samples`]). The chains start from the CPU
//!   updater's states; the GPU draws its own uniforms, so the devices agree in expectation.
//! - **`adgi-refill`:** the decisions run on the host. mcg-probe-cache's `ProbeUpdater` (the
//!   same object and seed as `--device cpu`: pilot rays, temporal trigger, heuristics, dynamic
//!   and static Metropolis chains, refill) asks for its batches of rays; each batch is
//!   uploaded, traced by `trace_probe_rays` on the GPU and read back, and the updater updates
//!   its texels on the host. The convolved irradiance texels are then uploaded into the cache
//!   for the camera's query (the refill's decisions have no GPU twin).
//!
//! The camera's `render` shades each first hit with its emission, one light sample and
//! albedo/π · `adgi_irradiance_at` — the CPU's conventions ([`super::super::probe_gi`]), so
//! both devices agree in expectation (`ddgi`: the same rotations, other light-sample seeds;
//! `adgi`: the same pilot rays, the chains' own random streams; `adgi-refill`: the same rays
//! and seeds, traced in f32 on either device).

use bytemuck::{Pod, Zeroable};
use std::sync::OnceLock;

use glam::{Quat, UVec2, Vec3};

use mcg_gpu_backend::guides::adgi::{
    GpuProbeCache, GpuProbeChains, GpuRaySample, GpuTriggerSmoothing, ProbeCacheConfig,
};
use mcg_gpu_backend::sampling::next_uniform;
use mcg_gpu_backend::{GpuBuffer, GpuContext, wgpu};
use mcg_probe_cache::{
    AdgiParts, ClipVolume, ClipVolumes, Frustum, GuideParams, PilotPhase, UpdatePolicy,
};
use mcg_probe_cache::{ProbeGrid, ProbeRayRequest, RaySample};

use super::{GUIDE_GROUP, GpuTracer, Guided, SceneBuffers, UNUSED_GROUP, guide_defs};
use crate::Result;
use crate::render::cpu::Method;
use crate::render::probe_gi::{ProbeGi, probe_ray_seed, request_seed};

/// The shader def that compiles the probe GI: `render` shades from the probes and the kernel
/// `trace_probe_rays` exists, with `mcg::adgi` at group [`GUIDE_GROUP`].
pub const PROBE_GI_DEF: &str = "MCG_DEMO_PROBE_GI";

/// The group `mcg::mcmm` moves to in the probe shader (groups 1 and 2 are taken).
const MCMM_UNUSED_GROUP: u32 = 3;

/// Storage buffers per stage of the `trace_probe_rays` pipeline: the scene's 7, requests and
/// samples, and the cache's 4.
pub const PROBE_STORAGE_BUFFERS: u32 = 13;

/// Storage buffers per stage of the `trace_chain_samples` pipeline: the scene's 7, the
/// chains' samples and counters, the traced samples, their rounding uniforms and the spent
/// slots, and the cache's 4.
pub const CHAIN_TRACE_STORAGE_BUFFERS: u32 = 16;

/// The probe of an empty slot of [`GpuTracer::record_chain_rays`]: outside every grid, so
/// [`GpuProbeCache::record_update_samples`] skips it (WGSL `NO_PROBE`).
pub const NO_PROBE: u32 = u32::MAX;

/// Invocations per workgroup of `trace_probe_rays` and `trace_chain_samples`.
const PROBE_GROUP: u32 = 64;

/// One probe ray for `trace_probe_rays` (WGSL `ProbeRequest`, 32 bytes): a request of
/// mcg-probe-cache's `ProbeUpdater` with its light-sample seed ([`request_seed`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuProbeRequest {
    /// The probe's position.
    pub origin: [f32; 3],
    /// Seed of the three uniforms of the light sample at the hit.
    pub seed: u32,
    /// Unit direction.
    pub direction: [f32; 3],
    /// Linear probe index.
    pub probe: u32,
}

impl From<&ProbeRayRequest> for GpuProbeRequest {
    fn from(r: &ProbeRayRequest) -> Self {
        Self {
            origin: r.origin.to_array(),
            seed: request_seed(r),
            direction: r.direction.to_array(),
            probe: r.probe,
        }
    }
}

/// The dispatch of `trace_probe_rays` (WGSL `ProbeFrame`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuProbeFrame {
    /// Rays of the dispatch.
    pub count: u32,
    /// Invocations per row of the 2D dispatch.
    pub row: u32,
    /// Slots `count..limit` are emptied (probe [`NO_PROBE`]); at most `count` traces nothing
    /// else.
    pub limit: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

/// The dispatch of `trace_chain_samples` (WGSL `ChainTrace`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuChainTrace {
    /// Slots traced: the phase's ray budget, at most the chains' sample capacity.
    pub limit: u32,
    /// Invocations per row of the 2D dispatch.
    pub row: u32,
    /// The render's seed (keys the light samples and rounding uniforms, [`probe_ray_seed`]).
    pub seed: u32,
    /// The frame (keys them too).
    pub frame: u32,
}

/// The dispatch of `expand_dynamic_samples` (WGSL `DynamicFrame`, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuDynamicFrame {
    /// The dynamic phase's ray budget.
    pub budget: u32,
    /// `UpdateConfig::dynamic_rays_per_octant` (ADGI sec. 4.9).
    pub rays_per_octant: u32,
    /// The render's seed ([`probe_ray_seed`] keys the rays' jitter, light samples and rounding).
    pub seed: u32,
    /// The frame.
    pub frame: u32,
}

/// The dispatch of `lay_out_pilot_rays` (WGSL `PilotLayout`, 16 bytes): two u64 as
/// `[low, high]` words.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPilotLayout {
    /// `UpdateConfig::pilot_seed`.
    pub seed: [u32; 2],
    /// `PilotFrame::pattern` of the frame (ADGI sec. 4.4: both frames of a pair share it).
    pub pattern: [u32; 2],
}

impl GpuPilotLayout {
    /// The dispatch of pilot seed `seed` and pattern `pattern`.
    #[must_use]
    pub fn new(seed: u64, pattern: u64) -> Self {
        let words = |v: u64| [v as u32, (v >> 32) as u32];
        Self {
            seed: words(seed),
            pattern: words(pattern),
        }
    }
}

/// ADGI's frame on the GPU (`--method adgi`, `UpdatePolicy::Adgi`): the twin of
/// `ProbeUpdater::frame`'s ADGI branch, every step recorded into one encoder, no read-back.
struct GpuAdgi {
    /// The static chains (sec. 4.8), from the CPU updater's initial states.
    static_chains: GpuProbeChains,
    /// The dynamic chains on the 3 × 3 × 3 proxies (sec. 4.9).
    dynamic_chains: GpuProbeChains,
    /// f_Δv, f_Δr (eq. 15, 18) and the heuristics words' composition.
    smoothing: GpuTriggerSmoothing,
    /// The heuristics words (sec. 4.3), one per probe octant.
    words: GpuBuffer<u32>,
    /// [`dynamic_tables`].
    tables: GpuBuffer<u32>,
    /// The dynamic slots claimed and the dynamic rays written this frame.
    spent: GpuBuffer<u32>,
    /// The dynamic, then the static rays of the frame, and their rounding uniforms.
    rays: GpuBuffer<GpuRaySample>,
    rounding: GpuBuffer<f32>,
    /// The pilot rays' rounding uniforms (frames that update the texels with them).
    pilot_rounding: GpuBuffer<f32>,
    /// V_in = V_out = every probe: the CPU's ADGI frame traces the pilots of every probe.
    volumes: ClipVolumes,
    /// `expand_dynamic_samples` and its group 0 layout.
    expand: (wgpu::ComputePipeline, wgpu::BindGroupLayout),
    /// `lay_out_pilot_rays` and its group 0 layout.
    lay_out: (wgpu::ComputePipeline, wgpu::BindGroupLayout),
    /// The pilot rays of the last frame (for its ray count).
    pilots: u32,
}

/// The tables of `expand_dynamic_samples`: `[0]` where the proxy offsets start, `[1..10]` the
/// offsets of each octant's interior irradiance texels (`x | y << 16`, interior coordinates;
/// `parts.octant_texels`), then from `[0]` the offsets of each proxy's probes (one more than
/// the proxies), then the probes' linear indices.
fn dynamic_tables(grid: &ProbeGrid, parts: &AdgiParts<'_>, side: u32) -> Vec<u32> {
    let mut t = vec![0_u32; 10];
    for (o, texels) in parts.octant_texels.iter().enumerate() {
        t[1 + o] = t.len() as u32;
        t.extend(texels.iter().map(|&i| {
            let c = UVec2::new(i as u32 % side, i as u32 / side) - UVec2::ONE;
            c.x | c.y << 16
        }));
    }
    t[9] = t.len() as u32;
    let proxies = parts.dynamic_chains.cells();
    let count = proxies.proxy_count();
    t[0] = t.len() as u32;
    let offsets = t.len();
    t.resize(offsets + count + 1, 0);
    for cell in 0..count {
        t[offsets + cell] = t.len() as u32;
        t.extend(proxies.probes_of(cell).map(|c| grid.probe_index(c) as u32));
    }
    t[offsets + count] = t.len() as u32;
    t
}

/// Clip volumes whose V_in and V_out hold every probe of `grid` (a box one unit around it,
/// no frustum cut).
fn all_probes(grid: &ProbeGrid) -> Result<ClipVolumes> {
    let lo = grid.probe_position(glam::UVec3::ZERO) - glam::Vec3::ONE;
    let hi = grid.probe_position(grid.counts() - glam::UVec3::ONE) + glam::Vec3::ONE;
    let far = 1e30;
    let planes = [
        glam::Vec4::new(1.0, 0.0, 0.0, far),
        glam::Vec4::new(-1.0, 0.0, 0.0, far),
        glam::Vec4::new(0.0, 1.0, 0.0, far),
        glam::Vec4::new(0.0, -1.0, 0.0, far),
        glam::Vec4::new(0.0, 0.0, 1.0, far),
        glam::Vec4::new(0.0, 0.0, -1.0, far),
    ];
    let volume = ClipVolume::new(Frustum::from_planes(planes)?, lo, hi)?;
    Ok(ClipVolumes::new(volume, volume))
}

/// The group 0 layout of `expand_dynamic_samples`: the chains' samples (14) and counters
/// (15), the rounding uniforms (16), the requests (18), the spent slots (19), the tables (20)
/// and the dispatch (21).
fn expand_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entries = [
        mcg_gpu_backend::storage_entry(14, true),
        mcg_gpu_backend::storage_entry(15, true),
        mcg_gpu_backend::storage_entry(16, false),
        mcg_gpu_backend::storage_entry(18, false),
        mcg_gpu_backend::storage_entry(19, false),
        mcg_gpu_backend::storage_entry(20, true),
        mcg_gpu_backend::buffer_entry(21, wgpu::BufferBindingType::Uniform),
    ];
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("expand_dynamic_samples"),
        entries: &entries,
    })
}

/// The group 0 layout of `lay_out_pilot_rays`: the requests (18) and the dispatch (23).
fn lay_out_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let entries = [
        mcg_gpu_backend::storage_entry(18, false),
        mcg_gpu_backend::buffer_entry(23, wgpu::BufferBindingType::Uniform),
    ];
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lay_out_pilot_rays"),
        entries: &entries,
    })
}

impl GpuAdgi {
    /// ADGI's frame for `probes` (an `adgi` updater) with ADGI's `parts`.
    fn new(
        ctx: &GpuContext,
        probes: &GpuProbes,
        parts: &AdgiParts<'_>,
        [expand, lay_out]: [(wgpu::ComputePipeline, wgpu::BindGroupLayout); 2],
    ) -> Result<Self> {
        let updater = probes.gi.updater();
        let grid = updater.grid();
        let n = 8 * grid.probe_count();
        let side = updater.texels().config().irradiance_map.side();
        let slots = updater.budget() as usize - n;
        Ok(Self {
            static_chains: GpuProbeChains::new(ctx, parts.static_chains, GuideParams::STATIC)?,
            dynamic_chains: GpuProbeChains::new(ctx, parts.dynamic_chains, GuideParams::DYNAMIC)?,
            smoothing: GpuTriggerSmoothing::new(ctx, &probes.cache),
            words: ctx.zeroed_buffer("mcg-demo adgi words", n),
            tables: ctx.storage_buffer(
                "mcg-demo adgi dynamic tables",
                &dynamic_tables(grid, parts, side),
            ),
            spent: ctx.zeroed_buffer("mcg-demo adgi spent", 2),
            rays: ctx.zeroed_buffer("mcg-demo adgi rays", slots.max(1)),
            rounding: ctx.zeroed_buffer("mcg-demo adgi rounding", slots.max(1)),
            pilot_rounding: ctx.zeroed_buffer("mcg-demo adgi pilot rounding", n),
            volumes: all_probes(grid)?,
            expand,
            lay_out,
            pilots: 0,
        })
    }
}

/// The probe GI of a GPU render: the CPU object (the updater and its seed), the cache, the
/// tracing pipeline and its buffers.
pub(super) struct GpuProbes {
    gi: ProbeGi,
    pub(super) cache: GpuProbeCache,
    trace: wgpu::ComputePipeline,
    trace_layout: wgpu::BindGroupLayout,
    requests: GpuBuffer<GpuProbeRequest>,
    samples: GpuBuffer<GpuRaySample>,
    rounding: GpuBuffer<f32>,
    rays_last_frame: u64,
    /// `trace_chain_samples` and its group 0 layout, built on first use.
    chain_trace: OnceLock<(wgpu::ComputePipeline, wgpu::BindGroupLayout)>,
    /// Two zero words: no slots spent ([`GpuTracer::record_chain_rays`] without `spent`).
    no_spent: GpuBuffer<u32>,
    /// ADGI's frame on the GPU (`--method adgi`).
    adgi: Option<GpuAdgi>,
}

/// The tracer's WGSL for the probe methods: `render` and `trace_probe_rays` with
/// [`PROBE_GI_DEF`], `mcg::adgi` at [`GUIDE_GROUP`] (`mcg::mcpg` and `mcg::mcmm` at unused
/// groups), with the attributes' code and the other defs of `scene` (the alpha test, the
/// environment).
///
/// # Errors
/// When composition fails (an unknown import).
pub fn composed_probe_shader(scene: super::SceneDefs) -> Result<String> {
    let mut defs = guide_defs(UNUSED_GROUP, MCMM_UNUSED_GROUP, GUIDE_GROUP);
    defs.push((PROBE_GI_DEF, 1));
    super::SceneDefs {
        attributes: true,
        ..scene
    }
    .push_to(&mut defs);
    Ok(mcg_gpu_backend::shaders::compose(super::SHADER, &defs)?)
}

/// The group 0 layout of `trace_chain_samples`: the parameters, the scene (1–7), the traced
/// samples (12), the chains' samples (14) and counters (15), the rounding uniforms (16), the
/// dispatch (17) and the spent slots (22).
fn chain_trace_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let uniform = |b| mcg_gpu_backend::buffer_entry(b, wgpu::BufferBindingType::Uniform);
    let mut entries = vec![uniform(0)];
    entries.extend((1..=7).map(|b| mcg_gpu_backend::storage_entry(b, true)));
    entries.push(mcg_gpu_backend::storage_entry(12, false));
    entries.push(mcg_gpu_backend::storage_entry(14, true));
    entries.push(mcg_gpu_backend::storage_entry(15, true));
    entries.push(mcg_gpu_backend::storage_entry(16, false));
    entries.push(uniform(17));
    entries.push(mcg_gpu_backend::storage_entry(22, true));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("trace_chain_samples"),
        entries: &entries,
    })
}

/// The group 0 layout of `trace_probe_rays`: the parameters, the scene (1–7), the requests
/// (11), the samples (12) and the dispatch (13).
fn trace_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let uniform = |b| mcg_gpu_backend::buffer_entry(b, wgpu::BufferBindingType::Uniform);
    let mut entries = vec![uniform(0)];
    entries.extend((1..=7).map(|b| mcg_gpu_backend::storage_entry(b, true)));
    entries.push(mcg_gpu_backend::storage_entry(11, true));
    entries.push(mcg_gpu_backend::storage_entry(12, false));
    entries.push(uniform(13));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("trace_probe_rays"),
        entries: &entries,
    })
}

impl GpuTracer {
    /// Starts `method` (`ddgi`, `adgi` or `adgi-refill`) on `grid` with `rays_per_probe` rays
    /// per probe per frame and `seed`, as [`ProbeGi::new`] on the CPU: empty probes (a cache of
    /// the same configuration is emptied and kept), the probe shader compiled on the first
    /// call. [`GpuTracer::render_frame`] with the method
    /// then updates the probes and shades from them.
    ///
    /// # Errors
    /// As [`ProbeGi::new`]; when the device binds fewer than [`PROBE_STORAGE_BUFFERS`] storage
    /// buffers per stage, the cache does not fit it, or the shader fails.
    pub fn start_probes(
        &mut self,
        method: Method,
        grid: ProbeGrid,
        rays_per_probe: u32,
        seed: u32,
    ) -> Result<()> {
        let gi = ProbeGi::new(method, grid, rays_per_probe, seed)?;
        self.check_storage_buffers(method.name(), PROBE_STORAGE_BUFFERS)?;
        // The GPU ADGI frame keeps ADGI's per-sample radiance texels in the cache, so the query
        // convolves them (the host paths upload convolved irradiance texels instead).
        let gpu_adgi = gi.updater().policy() == UpdatePolicy::Adgi;
        let content = if gpu_adgi {
            gi.updater().content()
        } else {
            gi.shading().query.content
        };
        let config = ProbeCacheConfig {
            grid,
            texels: *gi.updater().texels().config(),
            query: mcg_probe_cache::QueryConfig {
                content,
                ..gi.shading().query
            },
            blend: gi.updater().config().blend_weights,
            rays_per_probe,
        };
        if let Some(p) = self
            .probes
            .as_mut()
            .filter(|p| p.guide.cache.config() == &config)
        {
            // The same cache: emptied, its compiled steps kept (seconds on a software adapter).
            p.guide.cache.reset(&self.ctx);
            p.guide.gi = gi;
            p.guide.rays_last_frame = 0;
            return self.start_adgi();
        }
        let ctx = &self.ctx;
        let cache = GpuProbeCache::new(ctx, &config)?;
        if self.probe_module.is_none() {
            let source = composed_probe_shader(self.guided_defs.scene)?;
            self.probe_module = Some(self.module("mcg-demo probe gi", source));
        }
        let module = self.probe_module.as_ref().expect("compiled above");
        let (pipeline, layout) =
            self.guided_pipeline(module, "render", cache.bind_group_layout())?;
        let trace_layout = trace_layout(ctx.device());
        let trace = self.pipeline_with(
            module,
            "trace_probe_rays",
            &[&trace_layout, cache.bind_group_layout()],
        )?;
        let budget = gi.updater().budget() as usize;
        let probes = Box::new(GpuProbes {
            requests: ctx.zeroed_buffer("mcg-demo probe requests", budget),
            samples: ctx.zeroed_buffer("mcg-demo probe samples", budget),
            rounding: ctx.zeroed_buffer("mcg-demo probe rounding", grid.probe_count()),
            gi,
            cache,
            trace,
            trace_layout,
            rays_last_frame: 0,
            chain_trace: OnceLock::new(),
            no_spent: ctx.zeroed_buffer("mcg-demo no spent slots", 2),
            adgi: None,
        });
        self.probes = Some(Guided {
            guide: probes,
            pipeline,
            layout,
        });
        self.start_adgi()
    }

    /// ADGI's frame on the GPU for `--method adgi` (`UpdatePolicy::Adgi`; none for the other
    /// probe methods): its chains from the CPU updater's (the same initial states), the
    /// tables of the dynamic rays and the frame's buffers; an existing one is reused with the
    /// new chain states and cleared words. So `GpuProbes::adgi` is `Some` exactly when the
    /// probes' policy is `UpdatePolicy::Adgi`.
    fn start_adgi(&mut self) -> Result<()> {
        let probes = &mut self
            .probes
            .as_mut()
            .ok_or("GpuTracer: no probes started")?
            .guide;
        if probes.gi.updater().policy() != UpdatePolicy::Adgi {
            // A restart with another probe method drops the frame of an earlier `adgi`.
            probes.adgi = None;
            return Ok(());
        }
        let probes = &self
            .probes
            .as_ref()
            .ok_or("GpuTracer: no probes started")?
            .guide;
        let updater = probes.gi.updater();
        let parts = updater.adgi_parts().ok_or("adgi: no ADGI state")?;
        let ctx = &self.ctx;
        if let Some(a) = &probes.adgi {
            a.static_chains
                .write_states(ctx, parts.static_chains.states())?;
            a.dynamic_chains
                .write_states(ctx, parts.dynamic_chains.states())?;
            a.static_chains
                .write_feedback(ctx, &vec![0.0; a.words.len()])?;
            ctx.write(&a.words, &vec![0; a.words.len()])?;
            return Ok(());
        }
        self.check_storage_buffers("adgi", CHAIN_TRACE_STORAGE_BUFFERS)?;
        let module = self
            .probe_module
            .as_ref()
            .ok_or("GpuTracer: no probe shader")?;
        let expand_layout = expand_layout(ctx.device());
        let expand = self.pipeline_with(
            module,
            "expand_dynamic_samples",
            &[&expand_layout, probes.cache.bind_group_layout()],
        )?;
        let lay_out_layout = lay_out_layout(ctx.device());
        let lay_out = self.pipeline_with(
            module,
            "lay_out_pilot_rays",
            &[&lay_out_layout, probes.cache.bind_group_layout()],
        )?;
        let kernels = [(expand, expand_layout), (lay_out, lay_out_layout)];
        let adgi = GpuAdgi::new(ctx, probes, &parts, kernels)?;
        self.probes
            .as_mut()
            .ok_or("GpuTracer: no probes started")?
            .guide
            .adgi = Some(adgi);
        Ok(())
    }

    /// Probe rays traced in the last frame of a probe method (`None` before one).
    #[must_use]
    pub fn probe_rays_last_frame(&self) -> Option<u64> {
        let p = &self.probes.as_ref()?.guide;
        match &p.adgi {
            Some(a) => Some(self.adgi_rays(p, a).unwrap_or(p.rays_last_frame)),
            None => Some(p.rays_last_frame),
        }
    }

    /// The rays of the last GPU ADGI frame: its pilots, the dynamic rays written and the
    /// static samples traced (read back from the frame's counters when asked; the frame
    /// itself reads nothing back).
    fn adgi_rays(&self, p: &GpuProbes, a: &GpuAdgi) -> Result<u64> {
        let spent = self.ctx.read_back(&a.spent)?;
        let emitted = self.ctx.read_back(a.static_chains.counters())?[0];
        let non_pilot = (p.gi.updater().budget() as u32).saturating_sub(a.pilots);
        let statics = emitted
            .min(a.static_chains.samples().len() as u32)
            .min(non_pilot.saturating_sub(spent[1]));
        Ok(u64::from(a.pilots) + u64::from(spent[1]) + u64::from(statics))
    }

    /// The probe cache of a probe method ([`GpuTracer::start_probes`]), e.g. to read its
    /// words.
    #[must_use]
    pub fn probe_cache(&self) -> Option<&GpuProbeCache> {
        self.probes.as_ref().map(|p| &p.guide.cache)
    }

    /// Records into `encoder` the tracing of the samples that `chains` emitted in their last
    /// recorded frame (ADGI sec. 4.8-4.9: a chain sample is a probe ray), one dispatch of the
    /// kernel `trace_chain_samples` over slots `0..limit` (the phase's ray budget; the CPU's
    /// `ProbeUpdater` takes the static samples in order up to it): slot i below the chains'
    /// sample count (`counters()[0]`, read on the GPU) traces its sample from its probe's
    /// position along its direction, with the light seed [`probe_ray_seed`]`(seed, frame,
    /// probe, i)`, into `rays[i]`, as `trace_probe_rays` traces a request; an empty slot gets
    /// probe [`NO_PROBE`]; with `spent` (a buffer whose second `u32` holds the slots of the
    /// budget already spent, the dynamic rays of ADGI's frame) only `limit − spent[1]` slots
    /// are traced, the rest emptied. `rounding[i]` gets the slot's rounding uniform
    /// (`uniform_float(probe_ray_seed(seed, frame, NO_PROBE, i))`). Then
    /// [`GpuProbeCache::record_update_samples`]`(rays, rounding, limit, …)` updates the texels
    /// with the traced samples and skips the empty slots — no read-back in between. `seed` is
    /// the render's seed ([`GpuTracer::start_probes`]).
    ///
    /// # Errors
    /// Before [`GpuTracer::start_probes`] or an upload; when `limit` exceeds the chains'
    /// sample capacity, `rays` or `rounding`; when the device binds fewer than
    /// [`CHAIN_TRACE_STORAGE_BUFFERS`] storage buffers per stage or the pipeline fails.
    pub fn record_chain_rays(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        chains: &GpuProbeChains,
        (rays, rounding): (&GpuBuffer<GpuRaySample>, &GpuBuffer<f32>),
        (limit, spent): (u32, Option<&wgpu::Buffer>),
        frame: u32,
    ) -> Result<()> {
        let probes = &self
            .probes
            .as_ref()
            .ok_or("GpuTracer: no probes started")?
            .guide;
        let scene = self.scene.as_ref().ok_or("GpuTracer: no scene uploaded")?;
        let capacity = chains.samples().len().min(rays.len()).min(rounding.len());
        if limit as usize > capacity {
            return Err(format!(
                "record_chain_rays: {limit} slots, but the chains, rays and rounding hold {capacity}"
            )
            .into());
        }
        let (pipeline, layout) = self.chain_trace_pipeline(probes)?;
        let (x, y) = self.ctx.workgroup_grid(limit, PROBE_GROUP);
        let dispatch = GpuChainTrace {
            limit,
            row: x * PROBE_GROUP,
            seed: probes.gi.seed(),
            frame,
        };
        // A uniform of its own per call, so two calls in one encoder keep their dispatches.
        let dispatch = self.ctx.uniform_buffer("trace_chain_samples", &dispatch);
        let mut buffers = scene_bindings(self.params.raw(), scene).to_vec();
        buffers.extend([
            (12, rays.raw()),
            (14, chains.samples().raw()),
            (15, chains.counters().raw()),
            (16, rounding.raw()),
            (17, dispatch.raw()),
            (22, spent.unwrap_or(probes.no_spent.raw())),
        ]);
        let kernel = ("trace_chain_samples", pipeline, layout);
        record_pass(&self.ctx, encoder, kernel, &buffers, &probes.cache, (x, y));
        Ok(())
    }

    /// `trace_chain_samples` and its layout, built on the first call.
    fn chain_trace_pipeline<'p>(
        &self,
        probes: &'p GpuProbes,
    ) -> Result<&'p (wgpu::ComputePipeline, wgpu::BindGroupLayout)> {
        if let Some(built) = probes.chain_trace.get() {
            return Ok(built);
        }
        self.check_storage_buffers("trace_chain_samples", CHAIN_TRACE_STORAGE_BUFFERS)?;
        let module = self
            .probe_module
            .as_ref()
            .ok_or("GpuTracer: no probe shader")?;
        let layout = chain_trace_layout(self.ctx.device());
        let pipeline = self.pipeline_with(
            module,
            "trace_chain_samples",
            &[&layout, probes.cache.bind_group_layout()],
        )?;
        Ok(probes.chain_trace.get_or_init(|| (pipeline, layout)))
    }

    /// Traces `requests` with `trace_probe_rays` (as a frame traces its probe rays), submitted
    /// and read back: the reference of [`record_chain_rays`](Self::record_chain_rays).
    ///
    /// # Errors
    /// Before [`GpuTracer::start_probes`] or an upload; when `requests` exceed the probes' ray
    /// budget; when the read-back fails.
    pub fn trace_probe_requests(&self, requests: &[GpuProbeRequest]) -> Result<Vec<GpuRaySample>> {
        let scene = self.scene.as_ref().ok_or("GpuTracer: no scene uploaded")?;
        let p = &self
            .probes
            .as_ref()
            .ok_or("GpuTracer: no probes started")?
            .guide;
        if requests.len() > p.requests.len() {
            return Err(format!(
                "trace_probe_requests: {} requests, the budget is {}",
                requests.len(),
                p.requests.len()
            )
            .into());
        }
        let tracer = ProbeTracer {
            ctx: &self.ctx,
            params: self.params.raw(),
            scene,
        };
        let parts = (&p.trace, &p.trace_layout, &p.cache, &p.requests, &p.samples);
        tracer.trace_requests(parts, requests);
        let mut traced = self.ctx.read_back(&p.samples)?;
        traced.truncate(requests.len());
        Ok(traced)
    }

    /// ADGI's frame (`ProbeUpdater::frame` with `UpdatePolicy::Adgi`) on the GPU, one
    /// submission, no read-back; returns the pilot rays traced. In the CPU's order:
    ///
    /// 1. pilot rays (sec. 4.4): every probe's 8, along the CPU's directions with the CPU's
    ///    light seeds (keyed by pattern, probe and octant, so both frames of a pair trace the
    ///    same rays; laid out on the GPU, [`record_pilot_layout`](Self::record_pilot_layout)),
    ///    traced; on the first frame of a pair they also update the texels (N_max of the
    ///    texels); their hits drive f_v, f_r, the temporal gradient and the trigger
    ///    (eq. 11-17) on the second;
    /// 2. the triggers smoothed (eq. 15, 18) and the heuristics words composed with f_c of the
    ///    camera (eq. 10, 19, 20);
    /// 3. dynamic chains (sec. 4.9) on f_d max-pooled into the proxies, each sample expanded
    ///    into `dynamic_rays_per_octant` rays for every probe of its proxy within the dynamic
    ///    budget, `dynamic_share` of the rays after the pilots, traced and averaged with the
    ///    dynamic N_max (none when every f_d is 0: the chains then emit nothing);
    /// 4. the feedback ĝ (eq. 2) from the texels as the dynamic rays left them, the static
    ///    chains (sec. 4.8) on h = exp(min(ĝ/f_s, 1)) f_s, their first samples up to the rays
    ///    left traced and averaged with the texels' N_max.
    fn adgi_frame(&self, frame: u32, camera: Vec3) -> Result<u32> {
        let scene = self.scene.as_ref().ok_or("GpuTracer: no scene uploaded")?;
        let p = &self.probes.as_ref().ok_or("GpuTracer: no probes")?.guide;
        let a = p.adgi.as_ref().ok_or("GpuTracer: no adgi frame")?;
        let (ctx, cache) = (&self.ctx, &p.cache);
        let updater = p.gi.updater();
        let config = updater.config();
        let parts = updater.adgi_parts().ok_or("adgi: no ADGI state")?;
        let seed = p.gi.seed();
        let pilot = config.pilot_schedule.frame(u64::from(frame));
        let tracer = ProbeTracer {
            ctx,
            params: self.params.raw(),
            scene,
        };
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let e = &mut encoder;
        let pilots = self.record_pilot_layout(e, frame)?;
        let pilot_parts = (&p.trace, &p.trace_layout, cache, &p.requests, &p.samples);
        let count = |n| GpuProbeFrame {
            count: n,
            limit: n,
            ..GpuProbeFrame::default()
        };
        tracer.record(e, pilot_parts, count(pilots), None);
        let texel_average = updater.texels().config().moving_average;
        if pilot.updates_caches() {
            let mut rng = probe_ray_seed(seed, frame, u32::MAX, u32::MAX);
            let rounding: Vec<f32> = (0..pilots).map(|_| next_uniform(&mut rng)).collect();
            ctx.write(&a.pilot_rounding, &rounding)?;
            let (hits, u) = (p.samples.raw(), a.pilot_rounding.raw());
            cache.record_update_samples(ctx, e, hits, u, pilots, texel_average)?;
        }
        let phase = if pilot.measures_gradient() {
            PilotPhase::Detect
        } else {
            PilotPhase::Reference
        };
        let (volumes, params) = (&a.volumes, parts.params);
        cache.record_pilot_hits(
            ctx,
            e,
            p.samples.raw(),
            volumes,
            params,
            parts.trigger,
            phase,
        )?;
        a.smoothing.record(ctx, e, cache, config.smoothing)?;
        a.smoothing
            .record_compose(ctx, e, cache, params, camera, a.words.raw())?;
        // Dynamic chains, their rays within `dynamic_share` of the rays after the pilots.
        let non_pilot = (updater.budget() as u32).saturating_sub(pilots);
        let dynamic_budget = (non_pilot as f32 * config.dynamic_share) as u32;
        e.clear_buffer(a.spent.raw(), 0, None);
        let chains = &a.dynamic_chains;
        chains.record_guide(ctx, e, a.words.raw())?;
        chains.record_frame(ctx, e, probe_ray_seed(seed, frame, u32::MAX - 2, 0))?;
        let dispatch = GpuDynamicFrame {
            budget: dynamic_budget,
            rays_per_octant: config.dynamic_rays_per_octant,
            seed,
            frame,
        };
        let dispatch = ctx.uniform_buffer("expand_dynamic_samples", &dispatch);
        let buffers = [
            (14, chains.samples().raw()),
            (15, chains.counters().raw()),
            (16, a.rounding.raw()),
            (18, p.requests.raw()),
            (19, a.spent.raw()),
            (20, a.tables.raw()),
            (21, dispatch.raw()),
        ];
        let kernel = ("expand_dynamic_samples", &a.expand.0, &a.expand.1);
        // 2D, so that more samples than the per-dimension limit of workgroups covers stay valid.
        let groups = ctx.workgroup_grid(u32::try_from(chains.samples().len())?, PROBE_GROUP);
        record_pass(ctx, e, kernel, &buffers, cache, groups);
        let dynamic_parts = (&p.trace, &p.trace_layout, cache, &p.requests, &a.rays);
        let dynamic = GpuProbeFrame {
            limit: dynamic_budget,
            ..GpuProbeFrame::default()
        };
        // The rays written (`spent[1]`) become the dispatch's count on the GPU.
        tracer.record(e, dynamic_parts, dynamic, Some((a.spent.raw(), 4)));
        let (rays, u) = (a.rays.raw(), a.rounding.raw());
        let dynamic_average = config.dynamic_moving_average;
        cache.record_update_samples(ctx, e, rays, u, dynamic_budget, dynamic_average)?;
        // Static chains on the rays left.
        let chains = &a.static_chains;
        chains.record_feedback(ctx, e, cache)?;
        chains.record_guide(ctx, e, a.words.raw())?;
        chains.record_frame(ctx, e, probe_ray_seed(seed, frame, u32::MAX - 3, 0))?;
        let buffers = (&a.rays, &a.rounding);
        self.record_chain_rays(e, chains, buffers, (non_pilot, Some(a.spent.raw())), frame)?;
        cache.record_update_samples(ctx, e, rays, u, non_pilot, texel_average)?;
        ctx.queue().submit([encoder.finish()]);
        Ok(pilots)
    }

    /// Records `lay_out_pilot_rays` (one dispatch): ADGI's pilot requests of frame `frame`
    /// (sec. 4.4; `ProbeUpdater`'s pilot phase: every probe's 8 rays, request `8 probe + o`
    /// along `pilot_direction(o, pilot_uniforms(pilot_seed, pattern, probe, o, 0))` with the
    /// light seed [`request_seed`] of the uniforms of k = 2) into the probe requests, on the GPU
    /// from the updater's pilot seed and the frame's pattern; returns the requests written.
    fn record_pilot_layout(&self, encoder: &mut wgpu::CommandEncoder, frame: u32) -> Result<u32> {
        let p = &self.probes.as_ref().ok_or("GpuTracer: no probes")?.guide;
        let a = p.adgi.as_ref().ok_or("GpuTracer: no adgi frame")?;
        let config = p.gi.updater().config();
        let pilot = config.pilot_schedule.frame(u64::from(frame));
        let layout = GpuPilotLayout::new(config.pilot_seed, pilot.pattern);
        let dispatch = self.ctx.uniform_buffer("lay_out_pilot_rays", &layout);
        let pilots = u32::try_from(8 * p.gi.updater().grid().probe_count())?;
        let kernel = ("lay_out_pilot_rays", &a.lay_out.0, &a.lay_out.1);
        let buffers = [(18, p.requests.raw()), (23, dispatch.raw())];
        let size = self.ctx.workgroup_grid(pilots, PROBE_GROUP);
        record_pass(&self.ctx, encoder, kernel, &buffers, &p.cache, size);
        Ok(pilots)
    }

    /// ADGI's pilot requests of frame `frame` as the GPU frame lays them out (the kernel
    /// `lay_out_pilot_rays`, submitted alone and read back): `8 · probes` requests,
    /// probe-major, for comparison with `ProbeUpdater`'s.
    ///
    /// # Errors
    /// Without `--method adgi` probes started, or when the read-back fails.
    pub fn pilot_requests(&self, frame: u32) -> Result<Vec<GpuProbeRequest>> {
        let p = &self.probes.as_ref().ok_or("GpuTracer: no probes")?.guide;
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let pilots = self.record_pilot_layout(&mut encoder, frame)?;
        self.ctx.queue().submit([encoder.finish()]);
        let mut requests = self.ctx.read_back(&p.requests)?;
        requests.truncate(pilots as usize);
        Ok(requests)
    }

    /// The probe update of frame `frame` before the camera's tiles (the tracer's parameters
    /// already hold the frame's `base`).
    pub(super) fn update_probes(&mut self, frame: u32) -> Result<()> {
        let camera = self.scene()?.camera.position;
        let scene = self.scene.as_ref().ok_or("GpuTracer: no scene uploaded")?;
        let probes = &mut self
            .probes
            .as_mut()
            .ok_or("GpuTracer: no probes started")?
            .guide;
        let tracer = ProbeTracer {
            ctx: &self.ctx,
            params: self.params.raw(),
            scene,
        };
        if probes.gi.updater().policy() == UpdatePolicy::Ddgi {
            return tracer.ddgi_frame(probes, frame);
        }
        if probes.adgi.is_some() {
            let pilots = self.adgi_frame(frame, camera)?;
            let probes = &mut self.probes.as_mut().ok_or("no probes")?.guide;
            probes.adgi.as_mut().ok_or("no adgi")?.pilots = pilots;
            return Ok(());
        }
        let GpuProbes {
            gi,
            cache,
            trace,
            trace_layout,
            requests,
            samples,
            ..
        } = &mut **probes;
        let mut failed = None;
        gi.update(camera, frame, |_, batch, out| {
            let parts = (&*trace, &*trace_layout, &*cache, &*requests, &*samples);
            if let Err(e) = tracer.trace_batch(parts, batch, out) {
                failed.get_or_insert(e);
            }
        })?;
        if let Some(e) = failed {
            return Err(e);
        }
        let texels = &gi.shading().texels;
        cache.upload_words(
            &self.ctx,
            &texels.irradiance_words(),
            &texels.visibility_words(),
        )?;
        probes.rays_last_frame = probes.gi.rays_last_frame();
        Ok(())
    }
}

/// The tracer's parameters (binding 0) and the scene's buffers (1–7), as the probe kernels
/// bind them.
fn scene_bindings<'a>(
    params: &'a wgpu::Buffer,
    s: &'a SceneBuffers,
) -> [(u32, &'a wgpu::Buffer); 8] {
    [
        (0, params),
        (1, s.nodes.raw()),
        (2, s.triangles.raw()),
        (3, s.materials.raw()),
        (4, s.emitters.raw()),
        (5, s.attributes.raw()),
        (6, s.textures.raw()),
        (7, s.texels.raw()),
    ]
}

/// Records one compute pass of `kernel` (label, pipeline, group 0 layout) over `groups`, with
/// `buffers` at group 0 and `cache`'s group at [`GUIDE_GROUP`].
fn record_pass(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    (label, pipeline, layout): (&str, &wgpu::ComputePipeline, &wgpu::BindGroupLayout),
    buffers: &[(u32, &wgpu::Buffer)],
    cache: &GpuProbeCache,
    (x, y): (u32, u32),
) {
    let group = bind_buffers(ctx, label, layout, buffers);
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, &group, &[]);
    pass.set_bind_group(GUIDE_GROUP, cache.bind_group(), &[]);
    pass.dispatch_workgroups(x, y, 1);
}

/// A bind group of `layout` with each `(binding, buffer)` of `buffers`, whole.
fn bind_buffers(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// The pipeline, group 0 layout, cache, requests and samples of `trace_probe_rays`.
type TraceParts<'a> = (
    &'a wgpu::ComputePipeline,
    &'a wgpu::BindGroupLayout,
    &'a GpuProbeCache,
    &'a GpuBuffer<GpuProbeRequest>,
    &'a GpuBuffer<GpuRaySample>,
);

/// The buffers `trace_probe_rays` reads from the tracer.
struct ProbeTracer<'a> {
    ctx: &'a GpuContext,
    params: &'a wgpu::Buffer,
    scene: &'a SceneBuffers,
}

impl ProbeTracer<'_> {
    /// Records `trace_probe_rays` over `dispatch.count` rays of `parts`' buffers (emptying
    /// the slots up to `dispatch.limit`), its dispatch in a uniform of its own; with
    /// `count_from` (a buffer and byte offset) the count is copied from there on the GPU.
    fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        parts: TraceParts<'_>,
        mut dispatch: GpuProbeFrame,
        count_from: Option<(&wgpu::Buffer, u64)>,
    ) {
        let (pipeline, layout, cache, requests, samples) = parts;
        dispatch.limit = dispatch.limit.max(dispatch.count);
        let (x, y) = self.ctx.workgroup_grid(dispatch.limit, PROBE_GROUP);
        dispatch.row = x * PROBE_GROUP;
        let frame = self.ctx.uniform_buffer("trace_probe_rays", &dispatch);
        if let Some((source, offset)) = count_from {
            encoder.copy_buffer_to_buffer(source, offset, frame.raw(), 0, 4);
        }
        let mut buffers = scene_bindings(self.params, self.scene).to_vec();
        buffers.extend([(11, requests.raw()), (12, samples.raw()), (13, frame.raw())]);
        let kernel = ("trace_probe_rays", pipeline, layout);
        record_pass(self.ctx, encoder, kernel, &buffers, cache, (x, y));
    }

    /// DDGI's frame: the frame's rotation and the probes' rounding uniforms from the host
    /// stream (the CPU updater draws the same four rotation uniforms first), every probe's
    /// rays (DDGI's spherical Fibonacci set under the rotation, light seeds
    /// [`probe_ray_seed`]) uploaded, then one submission: the rays traced, copied into the
    /// cache's rays and blended into its words.
    fn ddgi_frame(&self, p: &mut GpuProbes, frame: u32) -> Result<()> {
        let seed = p.gi.seed();
        let mut rng = probe_ray_seed(seed, frame, u32::MAX, u32::MAX);
        let mut u = || next_uniform(&mut rng) - 0.5;
        let rotation = Quat::from_xyzw(u(), u(), u(), u()).normalize();
        let rounding: Vec<f32> = (0..p.rounding.len())
            .map(|_| next_uniform(&mut rng))
            .collect();
        self.ctx.write(&p.rounding, &rounding)?;
        let n = p.gi.updater().config().rays_per_probe;
        let directions: Vec<Vec3> = (0..n)
            .map(|i| rotation * mcg_probe_cache::spherical_fibonacci(i, n))
            .collect();
        let grid = *p.gi.updater().grid();
        let requests: Vec<GpuProbeRequest> = (0..grid.probe_count())
            .flat_map(|probe| {
                let origin = grid.probe_position(grid.probe_coords(probe)).to_array();
                let probe = probe as u32;
                directions
                    .iter()
                    .enumerate()
                    .map(move |(i, d)| GpuProbeRequest {
                        origin,
                        seed: probe_ray_seed(seed, frame, probe, i as u32),
                        direction: d.to_array(),
                        probe,
                    })
            })
            .collect();
        self.ctx
            .queue()
            .write_buffer(p.requests.raw(), 0, bytemuck::cast_slice(&requests));
        let count = requests.len() as u32;
        let dispatch = GpuProbeFrame {
            count,
            ..GpuProbeFrame::default()
        };
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let parts = (&p.trace, &p.trace_layout, &p.cache, &p.requests, &p.samples);
        self.record(&mut encoder, parts, dispatch, None);
        let bytes = u64::from(count) * size_of::<GpuRaySample>() as u64;
        encoder.copy_buffer_to_buffer(p.samples.raw(), 0, p.cache.rays().raw(), 0, bytes);
        p.cache
            .record_blend(self.ctx, &mut encoder, p.rounding.raw())?;
        self.ctx.queue().submit([encoder.finish()]);
        p.rays_last_frame = u64::from(count);
        Ok(())
    }

    /// `requests` uploaded into `parts`' requests, traced into its samples, submitted.
    fn trace_requests(&self, parts: TraceParts<'_>, requests: &[GpuProbeRequest]) {
        self.ctx
            .queue()
            .write_buffer(parts.3.raw(), 0, bytemuck::cast_slice(requests));
        let dispatch = GpuProbeFrame {
            count: requests.len() as u32,
            ..GpuProbeFrame::default()
        };
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.record(&mut encoder, parts, dispatch, None);
        self.ctx.queue().submit([encoder.finish()]);
    }

    /// One batch of the host updater: `batch` uploaded, traced, read back into `out`.
    fn trace_batch(
        &self,
        parts: TraceParts<'_>,
        batch: &[ProbeRayRequest],
        out: &mut [RaySample],
    ) -> Result<()> {
        let requests: Vec<GpuProbeRequest> = batch.iter().map(GpuProbeRequest::from).collect();
        self.trace_requests(parts, &requests);
        let traced = self.ctx.read_back(parts.4)?;
        for (o, s) in out.iter_mut().zip(&traced) {
            o.radiance = s.radiance;
            // The shader's miss distance is f32::MAX (WGSL has no infinity literal).
            o.distance = if s.distance >= f32::MAX {
                f32::INFINITY
            } else {
                s.distance
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe shader parses and validates with naga (no adapter needed): `render` binds
    /// the tracer's 8 storage buffers and the cache's words and table, `trace_probe_rays` the
    /// scene's 7, requests, samples, words and table, `trace_chain_samples` the scene's 7, the
    /// traced samples, the chains' samples and counters, the rounding uniforms, the spent
    /// slots, words and table, `expand_dynamic_samples` the chains' samples and counters, the
    /// rounding uniforms, the requests, the spent slots and its tables, `lay_out_pilot_rays`
    /// the requests; the host structs have the WGSL sizes.
    #[test]
    fn probe_shader_validates_without_an_adapter() {
        let all = super::super::SceneDefs {
            attributes: true,
            alpha_mask: true,
            environment: true,
            environment_map: true,
            portals: false,
        };
        let portals = super::super::SceneDefs {
            environment_map: false,
            portals: true,
            ..all
        };
        naga::front::wgsl::parse_str(&composed_probe_shader(portals).unwrap()).unwrap();
        let source = composed_probe_shader(all).unwrap();
        let module = naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
        let storage = |entry: &str| {
            let index = module
                .entry_points
                .iter()
                .position(|e| e.name == entry)
                .expect("entry point");
            let used = info.get_entry_point(index);
            module
                .global_variables
                .iter()
                .filter(|(h, g)| {
                    !used[*h].is_empty() && matches!(g.space, naga::AddressSpace::Storage { .. })
                })
                .count()
        };
        assert_eq!(storage("render"), 10);
        assert_eq!(storage("trace_probe_rays"), 11);
        assert_eq!(size_of::<GpuProbeRequest>(), 32);
        assert_eq!(size_of::<GpuProbeFrame>(), 16);
        assert_eq!(storage("trace_chain_samples"), 14);
        assert_eq!(storage("expand_dynamic_samples"), 6);
        assert_eq!(size_of::<GpuDynamicFrame>(), 16);
        assert_eq!(storage("lay_out_pilot_rays"), 1);
        assert_eq!(size_of::<GpuPilotLayout>(), 16);
        assert_eq!(size_of::<GpuChainTrace>(), 16);
    }
}
