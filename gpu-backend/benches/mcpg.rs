//! The GPU MCPG guide's cost (group `mcpg_vertex`): 65 536 invocations, one path vertex each
//! (a shading point on a plane under one sphere light), guided by `mcg::mcpg` (begin, sample
//! with the exact pdf, an analytic trace, finish) against the same kernel without the finish
//! (`unfinished`: the finish's cost is the difference), the same kernel with cosine
//! sampling, against a kernel that only finds and reads the N_mc candidates' states as
//! `mcpg_begin` does (`reads`: the memory reads no implementation of MCPG Alg. 1 avoids, a
//! floor under `guided`), and against the same dispatch of a kernel that only writes its
//! output (`launch`: what all pay before any sampling, to read the ratio net of it); and the
//! per-frame pass alone (`end_frame`: cache fold, eviction of both grids and the cache, frame
//! advance) on the guide's tables (2¹⁶ adaptive, 2¹² static, 2¹² cache slots). The guide is
//! trained for 8 frames first, and keeps training: the steady state of a renderer. Each
//! iteration is one submission and the wait for it; on lavapipe read the ratios. Without an
//! adapter the bench prints why and does nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use mcg_gpu_backend::guides::mcpg::GpuMcpgGuide;
use mcg_gpu_backend::{GpuBuffer, GpuContext, GuidedKernel, shaders, storage_entry, wgpu};
use mcg_markov_guide::mcpg::GuideConfig;

const KERNEL: &str = include_str!("mcpg_vertex.wgsl");
const VERTICES: u32 = 1 << 16;

fn config() -> GuideConfig {
    let mut c = GuideConfig::for_scene(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 3.5))
        .for_camera(60f32.to_radians(), 256);
    c.adaptive_capacity = 1 << 16;
    c.static_capacity = 1 << 12;
    if let Some(cache) = &mut c.cache {
        cache.capacity = 1 << 12;
    }
    c
}

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("skipping the MCPG benches: {e}");
            return;
        }
    };
    let ctx = &ctx;
    eprintln!("adapter: {:?}", ctx.adapter_info());
    let mut guide = GpuMcpgGuide::new(ctx, &config()).unwrap();
    guide.set_camera(ctx, Vec3::new(0.0, -2.0, 3.0));
    let memory = guide.memory();
    eprintln!("memory: {memory:?}");
    let device = ctx.device();
    let source = shaders::compose(KERNEL, &GpuMcpgGuide::shader_defs(1)).unwrap();
    let kernel = GuidedKernel::from_wgsl(
        ctx,
        "mcpg vertex",
        source,
        &[storage_entry(0, false)],
        guide.bind_group_layout(),
    );
    let guided = kernel.pipeline(ctx, "guided_vertex");
    let unfinished = kernel.pipeline(ctx, "unfinished_vertex");
    let cosine = kernel.pipeline(ctx, "cosine_vertex");
    let reads = kernel.pipeline(ctx, "reads_vertex");
    let launch = kernel.pipeline(ctx, "launch_vertex");
    let estimates: GpuBuffer<f32> = ctx.zeroed_buffer("estimates", VERTICES as usize);
    let io = kernel.io_bind_group(ctx, &[estimates.raw()]);
    let run = |pipeline: &wgpu::ComputePipeline, guide: &GpuMcpgGuide| {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &io, &[]);
            pass.set_bind_group(1, guide.bind_group(), &[]);
            pass.dispatch_workgroups(VERTICES / 64, 1, 1);
        }
        ctx.queue().submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    };
    for _ in 0..8 {
        run(&guided, &guide);
        guide.end_frame(ctx).unwrap();
    }
    let mut g = c.benchmark_group("mcpg_vertex");
    g.sample_size(20);
    g.bench_function("guided", |b| b.iter(|| run(&guided, &guide)));
    g.bench_function("unfinished", |b| b.iter(|| run(&unfinished, &guide)));
    g.bench_function("cosine", |b| b.iter(|| run(&cosine, &guide)));
    g.bench_function("reads", |b| b.iter(|| run(&reads, &guide)));
    g.bench_function("launch", |b| b.iter(|| run(&launch, &guide)));
    g.bench_function("end_frame", |b| {
        b.iter(|| {
            guide.end_frame(ctx).unwrap();
            device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
        });
    });
    g.finish();
}

criterion_group!(mcpg, benches);
criterion_main!(mcpg);
