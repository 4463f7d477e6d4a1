//! The GPU probe cache's cost against DDGI's float texels, on a 16 × 8 × 16 grid (2 048 probes,
//! ADGI's 8 × 8 + 16 × 16 texel maps):
//!
//! - group `adgi_update_per_ray`: 131 072 rays at random probes and directions; `adgi_cas` is
//!   ADGI's per-sample update (`GpuProbeCache::record_update_samples`: texel lookup, log decode,
//!   moving average, log encode, compare-and-swap, for both words), `rgba32f_store` the same
//!   lookup with plain stores into RGBA32F + RG32F texels; `ddgi_blend` is DDGI's blend of 64
//!   rays per probe into every interior texel (`record_blend`, 131 072 rays as well).
//! - group `adgi_query`: 65 536 irradiance queries (8 probes, Chebyshev visibility with
//!   bilinear moments) reading the packed words (`adgi_words_*`, `record_query`) against the
//!   same query built with `MCG_ADGI_FLOAT_TEXELS`, reading RGBA32F + RG32F texels holding the
//!   decoded values (`rgba32f_rg32f_*`); `_radiance` reads ADGI's radiance texels (cosine
//!   convolution over the 36 interior texels per probe), `_irradiance` DDGI's irradiance texels
//!   (4 bilinear taps per probe).
//!
//! Each iteration is one submission and the wait for it; on lavapipe read the ratios. Without
//! an adapter the bench prints why and does nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{UVec3, Vec3};
use mcg_color_codec::{
    IrradianceLayout, IrradianceWord, MovingAverage, VisibilityLayout, VisibilityWord,
};
use mcg_gpu_backend::guides::adgi::{
    GpuIrradianceQuery, GpuProbeCache, GpuRaySample, GpuStepParams, ProbeCacheConfig,
};
use mcg_gpu_backend::shaders::{self, defs};
use mcg_gpu_backend::{GpuBuffer, GpuContext, wgpu};
use mcg_probe_cache::{ProbeGrid, QueryConfig};
use rand::{RngExt, SeedableRng};

const KERNEL: &str = include_str!("adgi_baseline.wgsl");
const RAYS: u32 = 1 << 17;
const QUERIES: u32 = 1 << 16;
const RAYS_PER_PROBE: u32 = 64;

fn storage(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: if read_only {
                wgpu::BufferBindingType::Storage { read_only: true }
            } else {
                wgpu::BufferBindingType::Storage { read_only: false }
            },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<_> = buffers
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout,
        entries: &entries,
    })
}

/// The float-texel baseline's layouts (group 0: the cache's buffers plus the float texels;
/// group 1: the inputs) and its two pipelines.
struct Baseline {
    float_layout: wgpu::BindGroupLayout,
    input_layout: wgpu::BindGroupLayout,
    store: wgpu::ComputePipeline,
    query: wgpu::ComputePipeline,
}

/// Everything the two bench groups dispatch: the caches, the input buffers, the baseline.
struct Fixture {
    ctx: GpuContext,
    cache: GpuProbeCache,
    ddgi_cache: GpuProbeCache,
    ray_buffer: GpuBuffer<GpuRaySample>,
    uniform_buffer: GpuBuffer<f32>,
    probe_uniforms: GpuBuffer<f32>,
    query_buffer: GpuBuffer<GpuIrradianceQuery>,
    results: GpuBuffer<[f32; 4]>,
    baseline: Baseline,
    float_groups: [wgpu::BindGroup; 2],
    ray_inputs: wgpu::BindGroup,
    query_inputs: wgpu::BindGroup,
    _float_texels: (GpuBuffer<[f32; 4]>, GpuBuffer<[f32; 2]>),
    _steps: [GpuBuffer<GpuStepParams>; 2],
}

/// The random rays (at random probes) and queries, drawn in this order from one seeded rng.
fn random_inputs(probes: u32) -> (Vec<GpuRaySample>, Vec<GpuIrradianceQuery>) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
    let mut direction = || {
        let z: f32 = rng.random::<f32>() * 2.0 - 1.0;
        let phi: f32 = rng.random::<f32>() * core::f32::consts::TAU;
        let r = (1.0 - z * z).max(0.0).sqrt();
        (
            Vec3::new(r * phi.cos(), r * phi.sin(), z),
            rng.random::<f32>(),
        )
    };
    let rays: Vec<GpuRaySample> = (0..RAYS)
        .map(|i| {
            let (d, u) = direction();
            GpuRaySample {
                direction: d,
                distance: 0.2 + 2.0 * u,
                radiance: Vec3::new(u, 0.5 * u, 0.25),
                probe: i % probes,
            }
        })
        .collect();
    let queries: Vec<GpuIrradianceQuery> = (0..QUERIES)
        .map(|_| {
            let (n, u) = direction();
            let (v, w) = direction();
            let x = Vec3::new(15.0 * u, 7.0 * w, 15.0 * (u * 7.3 + w * 3.1).fract());
            GpuIrradianceQuery::new(x, n, v)
        })
        .collect();
    (rays, queries)
}

/// The words decoded into RGBA32F irradiance and RG32F visibility texels.
fn float_texels(irr: &[u32], vis: &[u32]) -> (Vec<[f32; 4]>, Vec<[f32; 2]>) {
    let float_irr = irr
        .iter()
        .map(|&w| {
            IrradianceLayout::ADGI
                .decode(IrradianceWord(w))
                .extend(1.0)
                .to_array()
        })
        .collect();
    let float_vis = vis
        .iter()
        .map(|&w| VisibilityLayout::ADGI.decode(VisibilityWord(w)).to_array())
        .collect();
    (float_irr, float_vis)
}

/// The float-texel baseline's shader, layouts and pipelines.
fn baseline_pipelines(device: &wgpu::Device) -> Baseline {
    let mut defs_float = GpuProbeCache::shader_defs(0).to_vec();
    defs_float.push((defs::ADGI_FLOAT_TEXELS, 1));
    let source = shaders::compose(KERNEL, &defs_float).unwrap();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("adgi baseline"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let float_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("adgi float texels"),
        entries: &[
            uniform(0),
            storage(1, false),
            storage(2, true),
            storage(3, true),
            storage(4, false),
            storage(5, false),
        ],
    });
    let input_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("adgi bench inputs"),
        entries: &[
            storage(0, true),
            uniform(2),
            storage(3, true),
            storage(4, false),
        ],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("adgi baseline"),
        bind_group_layouts: &[Some(&float_layout), Some(&input_layout)],
        immediate_size: 0,
    });
    let pipeline = |entry: &str| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            cache: None,
        })
    };
    let (store, query) = (pipeline("store_rgba32f"), pipeline("query_rgba32f"));
    Baseline {
        float_layout,
        input_layout,
        store,
        query,
    }
}

/// The baseline's group 0 for `cache`: its buffers and the float texels.
fn float_group(
    device: &wgpu::Device,
    baseline: &Baseline,
    cache: &GpuProbeCache,
    float_irr: &GpuBuffer<[f32; 4]>,
    float_vis: &GpuBuffer<[f32; 2]>,
) -> wgpu::BindGroup {
    group(
        device,
        &baseline.float_layout,
        &[
            (0, cache.params_buffer().raw()),
            (1, cache.words().raw()),
            (2, cache.texel_table().raw()),
            (3, cache.rays().raw()),
            (4, float_irr.raw()),
            (5, float_vis.raw()),
        ],
    )
}

/// Fills `cache`'s words with four rounds of `rays` and its rays buffer with the first
/// ones; returns the irradiance and visibility words.
fn fill(
    ctx: &GpuContext,
    cache: &GpuProbeCache,
    rays: &[GpuRaySample],
    uniforms: &[f32],
    probes: u32,
) -> (Vec<u32>, Vec<u32>) {
    for _ in 0..4 {
        cache
            .update_samples(ctx, rays, uniforms, MovingAverage::STATIC)
            .unwrap();
    }
    ctx.write(cache.rays(), &rays[..(probes * RAYS_PER_PROBE) as usize])
        .unwrap();
    cache.read_words(ctx).unwrap()
}

/// The baseline's group 1 (rays, step of `count` threads, queries, results) and its step.
fn input_group(
    ctx: &GpuContext,
    baseline: &Baseline,
    [rays, queries, results]: [&wgpu::Buffer; 3],
    count: u32,
) -> (wgpu::BindGroup, GpuBuffer<GpuStepParams>) {
    let step = ctx.uniform_buffer(
        "step",
        &GpuStepParams {
            count,
            ..GpuStepParams::default()
        },
    );
    let inputs = [(0, rays), (2, step.raw()), (3, queries), (4, results)];
    (group(ctx.device(), &baseline.input_layout, &inputs), step)
}

impl Fixture {
    /// The fixture on the default adapter, or `None` (after saying why) without one.
    fn new() -> Option<Self> {
        let ctx = match GpuContext::new() {
            Ok(ctx) => ctx,
            Err(e) => {
                eprintln!("skipping the ADGI benches: {e}");
                return None;
            }
        };
        eprintln!("adapter: {:?}", ctx.adapter_info());
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(16, 8, 16)).unwrap();
        let config = ProbeCacheConfig {
            query: QueryConfig::ADGI_RADIANCE,
            ..ProbeCacheConfig::adgi(grid, RAYS_PER_PROBE)
        };
        let cache = GpuProbeCache::new(&ctx, &config).unwrap();
        let probes = grid.probe_count() as u32;
        eprintln!(
            "bytes per probe: ADGI words {}, RGBA32F + RG32F {}, 16-byte texels in both maps {}",
            cache.bytes_per_probe(),
            16 * 64 + 8 * 256,
            16 * (64 + 256)
        );
        let (rays, queries) = random_inputs(probes);
        let uniforms: Vec<f32> = (0..RAYS).map(|i| (i as f32 * 0.618_034) % 1.0).collect();
        let ray_buffer = ctx.storage_buffer("rays", &rays);
        let uniform_buffer = ctx.storage_buffer("uniforms", &uniforms);
        let probe_uniforms = ctx.storage_buffer("probe uniforms", &uniforms[..probes as usize]);
        // Fill the words, then the float texels with their decoded values.
        let (irr, vis) = fill(&ctx, &cache, &rays, &uniforms, probes);
        let (float_irr, float_vis) = float_texels(&irr, &vis);
        let float_irr = ctx.storage_buffer("float irradiance", &float_irr);
        let float_vis = ctx.storage_buffer("float visibility", &float_vis);
        let query_buffer = ctx.storage_buffer("queries", &queries);
        let results: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("results", QUERIES as usize);
        let device = ctx.device();
        let baseline = baseline_pipelines(device);
        // The same words read as DDGI's irradiance texels (4 bilinear taps per probe instead
        // of the cosine convolution over 36 texels).
        let ddgi_config = ProbeCacheConfig {
            query: QueryConfig::DDGI,
            ..config
        };
        let ddgi_cache = GpuProbeCache::new(&ctx, &ddgi_config).unwrap();
        ddgi_cache.upload_words(&ctx, &irr, &vis).unwrap();
        let float_groups = [&cache, &ddgi_cache]
            .map(|c| float_group(device, &baseline, c, &float_irr, &float_vis));
        let buffers = [ray_buffer.raw(), query_buffer.raw(), results.raw()];
        let (ray_inputs, ray_step) = input_group(&ctx, &baseline, buffers, RAYS);
        let (query_inputs, query_step) = input_group(&ctx, &baseline, buffers, QUERIES);
        Some(Self {
            _float_texels: (float_irr, float_vis),
            _steps: [ray_step, query_step],
            ctx,
            cache,
            ddgi_cache,
            ray_buffer,
            uniform_buffer,
            probe_uniforms,
            query_buffer,
            results,
            baseline,
            float_groups,
            ray_inputs,
            query_inputs,
        })
    }

    /// Submits one dispatch of a baseline pipeline over `count` threads and waits for it.
    fn dispatch_baseline(
        &self,
        pipeline: &wgpu::ComputePipeline,
        float_group: &wgpu::BindGroup,
        inputs: &wgpu::BindGroup,
        count: u32,
    ) {
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, float_group, &[]);
            pass.set_bind_group(1, inputs, &[]);
            pass.dispatch_workgroups(count / 64, 1, 1);
        }
        self.submit(encoder);
    }

    /// Submits what `record` records and waits for it.
    fn recorded(&self, record: &dyn Fn(&mut wgpu::CommandEncoder)) {
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&Default::default());
        record(&mut encoder);
        self.submit(encoder);
    }

    /// Submits `encoder`'s commands and waits for the device.
    fn submit(&self, encoder: wgpu::CommandEncoder) {
        self.ctx.queue().submit([encoder.finish()]);
        self.ctx
            .device()
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
}

/// Group `adgi_update_per_ray`: ADGI's update, the RGBA32F store, DDGI's blend.
fn bench_update(c: &mut Criterion, f: &Fixture) {
    let ctx = &f.ctx;
    let mut g = c.benchmark_group("adgi_update_per_ray");
    g.sample_size(20);
    g.bench_function("adgi_cas", |b| {
        b.iter(|| {
            f.recorded(&|e| {
                f.cache
                    .record_update_samples(
                        ctx,
                        e,
                        f.ray_buffer.raw(),
                        f.uniform_buffer.raw(),
                        RAYS,
                        MovingAverage::STATIC,
                    )
                    .unwrap();
            });
        });
    });
    g.bench_function("rgba32f_store", |b| {
        b.iter(|| f.dispatch_baseline(&f.baseline.store, &f.float_groups[0], &f.ray_inputs, RAYS));
    });
    g.bench_function("ddgi_blend", |b| {
        b.iter(|| {
            f.recorded(&|e| {
                f.cache
                    .record_blend(ctx, e, f.probe_uniforms.raw())
                    .unwrap()
            })
        });
    });
    g.finish();
}

/// Group `adgi_query`: the words' query against the float texels', radiance and irradiance.
fn bench_query(c: &mut Criterion, f: &Fixture) {
    let ctx = &f.ctx;
    let mut g = c.benchmark_group("adgi_query");
    g.sample_size(20);
    for (name, cache, floats) in [
        ("radiance", &f.cache, &f.float_groups[0]),
        ("irradiance", &f.ddgi_cache, &f.float_groups[1]),
    ] {
        g.bench_function(format!("adgi_words_{name}"), |b| {
            b.iter(|| {
                f.recorded(&|e| {
                    cache
                        .record_query(ctx, e, f.query_buffer.raw(), f.results.raw(), QUERIES)
                        .unwrap();
                });
            });
        });
        g.bench_function(format!("rgba32f_rg32f_{name}"), |b| {
            b.iter(|| f.dispatch_baseline(&f.baseline.query, floats, &f.query_inputs, QUERIES));
        });
    }
    g.finish();
}

/// Both groups on one fixture (nothing without an adapter).
fn benches(c: &mut Criterion) {
    let Some(fixture) = Fixture::new() else {
        return;
    };
    bench_update(c, &fixture);
    bench_query(c, &fixture);
}

criterion_group!(adgi, benches);
criterion_main!(adgi);
