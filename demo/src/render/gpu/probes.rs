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
//! - **`adgi`, `adgi-refill`:** the decisions run on the host. mcg-probe-cache's
//!   `ProbeUpdater` (the same object and seed as `--device cpu`: pilot rays, temporal trigger,
//!   heuristics, dynamic and static Metropolis chains, refill) asks for its batches of rays;
//!   each batch is uploaded, traced by `trace_probe_rays` on the GPU and read back, and the
//!   updater updates its texels on the host. The convolved irradiance texels are then uploaded
//!   into the cache for the camera's query. (The GPU twins of those steps exist in
//!   `mcg_gpu_backend::guides::adgi`, but not yet the heuristics-composing and ĝ-feedback
//!   kernels that would chain them into a frame without the host.)
//!
//! The camera's `render` shades each first hit with its emission, one light sample and
//! albedo/π · `adgi_irradiance_at` — the CPU's conventions ([`super::super::probe_gi`]), so
//! both devices agree in expectation (`ddgi`: the same rotations, other light-sample seeds;
//! `adgi`: the same rays and seeds, traced in f32 on either device).

use bytemuck::{Pod, Zeroable};
use glam::{Quat, Vec3};
use mcg_gpu_backend::guides::adgi::{GpuProbeCache, GpuRaySample, ProbeCacheConfig};
use mcg_gpu_backend::sampling::next_uniform;
use mcg_gpu_backend::{GpuBuffer, GpuContext, wgpu};
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

/// Invocations per workgroup of `trace_probe_rays`.
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
    /// Padding to 16 bytes.
    pub pad: [u32; 2],
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
    frame: GpuBuffer<GpuProbeFrame>,
    rounding: GpuBuffer<f32>,
    rays_last_frame: u64,
}

/// The tracer's WGSL for the probe methods: `render` and `trace_probe_rays` with
/// [`PROBE_GI_DEF`], `mcg::adgi` at [`GUIDE_GROUP`] (`mcg::mcpg` and `mcg::mcmm` at unused
/// groups).
///
/// # Errors
/// When composition fails (an unknown import).
pub fn composed_probe_shader() -> Result<String> {
    let mut defs = guide_defs(UNUSED_GROUP, MCMM_UNUSED_GROUP, GUIDE_GROUP);
    defs.push((PROBE_GI_DEF, 1));
    Ok(mcg_gpu_backend::shaders::compose(super::SHADER, &defs)?)
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
        let config = ProbeCacheConfig {
            grid,
            texels: *gi.updater().texels().config(),
            query: gi.shading().query,
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
            return Ok(());
        }
        let ctx = &self.ctx;
        let cache = GpuProbeCache::new(ctx, &config)?;
        if self.probe_module.is_none() {
            self.probe_module = Some(self.module("mcg-demo probe gi", composed_probe_shader()?));
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
            frame: ctx.uniform_buffer("mcg-demo probe frame", &GpuProbeFrame::default()),
            rounding: ctx.zeroed_buffer("mcg-demo probe rounding", grid.probe_count()),
            gi,
            cache,
            trace,
            trace_layout,
            rays_last_frame: 0,
        });
        self.probes = Some(Guided {
            guide: probes,
            pipeline,
            layout,
        });
        Ok(())
    }

    /// Probe rays traced in the last frame of a probe method (`None` before one).
    #[must_use]
    pub fn probe_rays_last_frame(&self) -> Option<u64> {
        self.probes.as_ref().map(|p| p.guide.rays_last_frame)
    }

    /// The probe cache of a probe method ([`GpuTracer::start_probes`]), e.g. to read its
    /// words.
    #[must_use]
    pub fn probe_cache(&self) -> Option<&GpuProbeCache> {
        self.probes.as_ref().map(|p| &p.guide.cache)
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
        if probes.gi.updater().policy() == mcg_probe_cache::UpdatePolicy::Ddgi {
            return tracer.ddgi_frame(probes, frame);
        }
        let GpuProbes {
            gi,
            cache,
            trace,
            trace_layout,
            requests,
            samples,
            frame: frame_buffer,
            ..
        } = &mut **probes;
        let mut failed = None;
        gi.update(camera, frame, |_, batch, out| {
            let parts = (&*trace, &*trace_layout, &*cache, &*requests, &*samples);
            if let Err(e) = tracer.trace_batch(parts, frame_buffer, batch, out) {
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
    /// Records `trace_probe_rays` over `dispatch.count` rays of `probes`' buffers.
    fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        parts: TraceParts<'_>,
        frame: &GpuBuffer<GpuProbeFrame>,
        mut dispatch: GpuProbeFrame,
    ) {
        let (pipeline, layout, cache, requests, samples) = parts;
        let groups = dispatch.count.div_ceil(PROBE_GROUP).max(1);
        let x = groups.min(
            self.ctx
                .device()
                .limits()
                .max_compute_workgroups_per_dimension,
        );
        dispatch.row = x * PROBE_GROUP;
        self.ctx
            .queue()
            .write_buffer(frame.raw(), 0, bytemuck::bytes_of(&dispatch));
        let s = self.scene;
        let buffers = [
            (0, self.params),
            (1, s.nodes.raw()),
            (2, s.triangles.raw()),
            (3, s.materials.raw()),
            (4, s.emitters.raw()),
            (5, s.uvs.raw()),
            (6, s.textures.raw()),
            (7, s.texels.raw()),
            (11, requests.raw()),
            (12, samples.raw()),
            (13, frame.raw()),
        ];
        let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .map(|&(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        let group = self
            .ctx
            .device()
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("trace_probe_rays"),
                layout,
                entries: &entries,
            });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("trace_probe_rays"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.set_bind_group(GUIDE_GROUP, cache.bind_group(), &[]);
        pass.dispatch_workgroups(x, groups.div_ceil(x), 1);
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
        self.record(&mut encoder, parts, &p.frame, dispatch);
        let bytes = u64::from(count) * size_of::<GpuRaySample>() as u64;
        encoder.copy_buffer_to_buffer(p.samples.raw(), 0, p.cache.rays().raw(), 0, bytes);
        p.cache
            .record_blend(self.ctx, &mut encoder, p.rounding.raw())?;
        self.ctx.queue().submit([encoder.finish()]);
        p.rays_last_frame = u64::from(count);
        Ok(())
    }

    /// One batch of the host updater: `batch` uploaded, traced, read back into `out`.
    fn trace_batch(
        &self,
        parts: TraceParts<'_>,
        frame: &GpuBuffer<GpuProbeFrame>,
        batch: &[ProbeRayRequest],
        out: &mut [RaySample],
    ) -> Result<()> {
        let requests: Vec<GpuProbeRequest> = batch.iter().map(GpuProbeRequest::from).collect();
        self.ctx
            .queue()
            .write_buffer(parts.3.raw(), 0, bytemuck::cast_slice(&requests));
        let dispatch = GpuProbeFrame {
            count: batch.len() as u32,
            ..GpuProbeFrame::default()
        };
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.record(&mut encoder, parts, frame, dispatch);
        self.ctx.queue().submit([encoder.finish()]);
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
    /// scene's 7, requests, samples, words and table; the host structs have the WGSL sizes.
    #[test]
    fn probe_shader_validates_without_an_adapter() {
        let source = composed_probe_shader().unwrap();
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
    }
}
