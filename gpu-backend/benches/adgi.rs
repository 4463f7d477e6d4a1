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
use mcg_probe_cache::{BlendWeights, ProbeGrid, QueryConfig, TexelConfig};
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

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("skipping the ADGI benches: {e}");
            return;
        }
    };
    let ctx = &ctx;
    eprintln!("adapter: {:?}", ctx.adapter_info());
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(16, 8, 16)).unwrap();
    let config = ProbeCacheConfig {
        grid,
        texels: TexelConfig::ADGI,
        query: QueryConfig::ADGI_RADIANCE,
        blend: BlendWeights::DDGI,
        rays_per_probe: RAYS_PER_PROBE,
    };
    let cache = GpuProbeCache::new(ctx, &config).unwrap();
    let probes = grid.probe_count() as u32;
    eprintln!(
        "bytes per probe: ADGI words {}, RGBA32F + RG32F {}, 16-byte texels in both maps {}",
        cache.bytes_per_probe(),
        16 * 64 + 8 * 256,
        16 * (64 + 256)
    );
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
    let uniforms: Vec<f32> = (0..RAYS).map(|i| (i as f32 * 0.618_034) % 1.0).collect();
    let ray_buffer = ctx.storage_buffer("rays", &rays);
    let uniform_buffer = ctx.storage_buffer("uniforms", &uniforms);
    let probe_uniforms = ctx.storage_buffer("probe uniforms", &uniforms[..probes as usize]);
    // Fill the words, then the float texels with their decoded values.
    for _ in 0..4 {
        cache
            .update_samples(ctx, &rays, &uniforms, MovingAverage::STATIC)
            .unwrap();
    }
    ctx.write(cache.rays(), &rays[..(probes * RAYS_PER_PROBE) as usize])
        .unwrap();
    let (irr, vis) = cache.read_words(ctx).unwrap();
    let float_irr: Vec<[f32; 4]> = irr
        .iter()
        .map(|&w| {
            IrradianceLayout::ADGI
                .decode(IrradianceWord(w))
                .extend(1.0)
                .to_array()
        })
        .collect();
    let float_vis: Vec<[f32; 2]> = vis
        .iter()
        .map(|&w| VisibilityLayout::ADGI.decode(VisibilityWord(w)).to_array())
        .collect();
    let float_irr = ctx.storage_buffer("float irradiance", &float_irr);
    let float_vis = ctx.storage_buffer("float visibility", &float_vis);
    let queries: Vec<GpuIrradianceQuery> = (0..QUERIES)
        .map(|_| {
            let (n, u) = direction();
            let (v, w) = direction();
            let x = Vec3::new(15.0 * u, 7.0 * w, 15.0 * (u * 7.3 + w * 3.1).fract());
            GpuIrradianceQuery::new(x, n, v)
        })
        .collect();
    let query_buffer = ctx.storage_buffer("queries", &queries);
    let results: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("results", QUERIES as usize);

    // The float-texel baseline: the cache's buffers plus the float texels at group 0, the
    // inputs at group 1.
    let device = ctx.device();
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
    let float_group = |cache: &GpuProbeCache| {
        group(
            device,
            &float_layout,
            &[
                (0, cache.params_buffer().raw()),
                (1, cache.words().raw()),
                (2, cache.texel_table().raw()),
                (3, cache.rays().raw()),
                (4, float_irr.raw()),
                (5, float_vis.raw()),
            ],
        )
    };
    // The same words read as DDGI's irradiance texels (4 bilinear taps per probe instead of
    // the cosine convolution over 36 texels).
    let ddgi_cache = GpuProbeCache::new(
        ctx,
        &ProbeCacheConfig {
            query: QueryConfig::DDGI,
            ..config
        },
    )
    .unwrap();
    ddgi_cache.upload_words(ctx, &irr, &vis).unwrap();
    let float_groups = [float_group(&cache), float_group(&ddgi_cache)];
    let input_group = |count: u32| {
        let step = ctx.uniform_buffer(
            "step",
            &GpuStepParams {
                count,
                ..GpuStepParams::default()
            },
        );
        let g = group(
            device,
            &input_layout,
            &[
                (0, ray_buffer.raw()),
                (2, step.raw()),
                (3, query_buffer.raw()),
                (4, results.raw()),
            ],
        );
        (g, step)
    };
    let (ray_inputs, _ray_step) = input_group(RAYS);
    let (query_inputs, _query_step) = input_group(QUERIES);
    let wait = || device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    let baseline = |pipeline: &wgpu::ComputePipeline,
                    float_group: &wgpu::BindGroup,
                    inputs: &wgpu::BindGroup,
                    count: u32| {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, float_group, &[]);
            pass.set_bind_group(1, inputs, &[]);
            pass.dispatch_workgroups(count / 64, 1, 1);
        }
        ctx.queue().submit([encoder.finish()]);
        wait();
    };
    let recorded = |record: &dyn Fn(&mut wgpu::CommandEncoder)| {
        let mut encoder = device.create_command_encoder(&Default::default());
        record(&mut encoder);
        ctx.queue().submit([encoder.finish()]);
        wait();
    };

    let mut g = c.benchmark_group("adgi_update_per_ray");
    g.sample_size(20);
    g.bench_function("adgi_cas", |b| {
        b.iter(|| {
            recorded(&|e| {
                cache
                    .record_update_samples(
                        ctx,
                        e,
                        ray_buffer.raw(),
                        uniform_buffer.raw(),
                        RAYS,
                        MovingAverage::STATIC,
                    )
                    .unwrap();
            });
        });
    });
    g.bench_function("rgba32f_store", |b| {
        b.iter(|| baseline(&store, &float_groups[0], &ray_inputs, RAYS));
    });
    g.bench_function("ddgi_blend", |b| {
        b.iter(|| recorded(&|e| cache.record_blend(ctx, e, probe_uniforms.raw()).unwrap()));
    });
    g.finish();

    let mut g = c.benchmark_group("adgi_query");
    g.sample_size(20);
    for (name, cache, floats) in [
        ("radiance", &cache, &float_groups[0]),
        ("irradiance", &ddgi_cache, &float_groups[1]),
    ] {
        g.bench_function(format!("adgi_words_{name}"), |b| {
            b.iter(|| {
                recorded(&|e| {
                    cache
                        .record_query(ctx, e, query_buffer.raw(), results.raw(), QUERIES)
                        .unwrap();
                });
            });
        });
        g.bench_function(format!("rgba32f_rg32f_{name}"), |b| {
            b.iter(|| baseline(&query, floats, &query_inputs, QUERIES));
        });
    }
    g.finish();
}

criterion_group!(adgi, benches);
criterion_main!(adgi);
