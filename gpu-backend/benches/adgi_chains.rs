//! ADGI's probe chains on the GPU against the uniform pilot-ray directions, on a 16 × 8 × 16
//! grid (2 048 probes), one group `adgi_chain_step_per_direction`, 16 384 directions each:
//!
//! - `static_chains`: one frame of 2 048 static chains (one per probe) of M = 8 steps, K = 0
//!   (`GpuProbeChains::record_frame`: per step Φ⁻¹ of five uniforms, folding, nearest probe,
//!   octant, the guide's table and `exp` of eq. 2, the acceptance test, the sample appended
//!   through the atomic counter) — 16 384 proposals;
//! - `dynamic_chains`: the same on the 6 × 3 × 6 virtual proxies (α = 0, each (proxy, octant)
//!   claimed once);
//! - `uniform_pilot_directions`: the baseline, one stratified uniform direction per probe and
//!   octant from host uniforms (`GpuProbeCache::record_pilot_rays`, sec. 4.4) — 16 384
//!   directions, what a renderer spends to pick probe-ray directions without guiding.
//!
//! Each iteration is one submission and the wait for it; on lavapipe read the ratios. Without
//! an adapter the bench prints why and does nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{UVec3, Vec3};
use mcg_color_codec::Heuristics;
use mcg_gpu_backend::guides::adgi::{GpuProbeCache, GpuProbeChains, ProbeCacheConfig};
use mcg_gpu_backend::{GpuBuffer, GpuContext, wgpu};
use mcg_markov_guide::FrameSchedule;
use mcg_probe_cache::{ChainKind, ClipVolumes, GuideParams, ProbeChains, ProbeGrid, ProxyGrid};
use rand::{RngExt, SeedableRng};

/// Everything the group dispatches.
struct Fixture {
    ctx: GpuContext,
    cache: GpuProbeCache,
    chains: [GpuProbeChains; 2],
    pilot_uniforms: GpuBuffer<f32>,
    pilot_out: GpuBuffer<[f32; 4]>,
    volumes: ClipVolumes,
}

impl Fixture {
    fn new() -> Option<Self> {
        let ctx = match GpuContext::new() {
            Ok(ctx) => ctx,
            Err(e) => {
                println!("adgi_chains bench skipped: {e}");
                return None;
            }
        };
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::new(16, 8, 16)).unwrap();
        let cache = GpuProbeCache::new(&ctx, &ProbeCacheConfig::adgi(grid, 1)).unwrap();
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let n = grid.probe_count() * 8;
        // Heuristics: a third of the octants zero, the rest random.
        let words: Vec<u32> = (0..n)
            .map(|_| {
                let on = rng.random_range(0..3) != 0;
                let f = |r: f32| if on { r } else { 0.0 };
                let h = Heuristics {
                    f_v: rng.random(),
                    f_s: f(rng.random()),
                    f_d: f(rng.random()),
                    flags: 0,
                };
                mcg_probe_cache::heuristics::encode(h).0
            })
            .collect();
        let schedule = FrameSchedule::new(8, 0).unwrap();
        let chains = [
            (
                ProxyGrid::probes(grid),
                ChainKind::Static,
                GuideParams::STATIC,
            ),
            (
                ProxyGrid::adgi(grid),
                ChainKind::Dynamic,
                GuideParams::DYNAMIC,
            ),
        ]
        .map(|(cells, kind, guide)| {
            let cpu = ProbeChains::new(cells, kind, grid.probe_count(), schedule, || {
                core::array::from_fn(|_| rng.random())
            })
            .unwrap();
            let gpu = GpuProbeChains::new(&ctx, &cpu, guide).unwrap();
            gpu.guide_from_words(&ctx, &words).unwrap();
            let feedback: Vec<f32> = (0..cells.table_len()).map(|_| rng.random()).collect();
            gpu.write_feedback(&ctx, &feedback).unwrap();
            // Two frames so the chains sit in the support.
            gpu.step_frame(&ctx, 1).unwrap();
            gpu.step_frame(&ctx, 2).unwrap();
            gpu
        });
        let uniforms: Vec<f32> = (0..2 * n).map(|_| rng.random()).collect();
        let pilot_uniforms = ctx.storage_buffer("pilot uniforms", &uniforms);
        let pilot_out = ctx.zeroed_buffer("pilot directions", n);
        // V_in and V_out around the whole grid: every probe traces.
        let view = glam::camera::rh::view::look_at_mat4(
            Vec3::new(4.0, 2.0, -20.0),
            Vec3::new(4.0, 2.0, 4.0),
            Vec3::Y,
        );
        let proj = glam::camera::rh::proj::directx::perspective(1.5, 1.0, 0.1, 100.0);
        let (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(10.0));
        let volumes = ClipVolumes::from_camera(proj * view, (lo, hi), 1.0, (lo, hi)).unwrap();
        Some(Self {
            ctx,
            cache,
            chains,
            pilot_uniforms,
            pilot_out,
            volumes,
        })
    }

    /// Records with `record`, submits and waits.
    fn run(&self, record: impl FnOnce(&mut wgpu::CommandEncoder)) {
        let mut e = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        record(&mut e);
        self.ctx.queue().submit([e.finish()]);
        self.ctx
            .device()
            .poll(wgpu::PollType::wait_indefinitely())
            .unwrap();
    }
}

fn benches(c: &mut Criterion) {
    let Some(f) = Fixture::new() else {
        return;
    };
    let ctx = &f.ctx;
    let mut g = c.benchmark_group("adgi_chain_step_per_direction");
    g.sample_size(20);
    let mut seed = 3u32;
    for (name, chains) in [
        ("static_chains", &f.chains[0]),
        ("dynamic_chains", &f.chains[1]),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                seed = seed.wrapping_add(1);
                f.run(|e| chains.record_frame(ctx, e, seed).unwrap());
            });
        });
    }
    g.bench_function("uniform_pilot_directions", |b| {
        b.iter(|| {
            f.run(|e| {
                f.cache
                    .record_pilot_rays(
                        ctx,
                        e,
                        f.pilot_uniforms.raw(),
                        &f.volumes,
                        f.pilot_out.raw(),
                    )
                    .unwrap();
            });
        });
    });
    g.finish();
}

criterion_group!(adgi_chains, benches);
criterion_main!(adgi_chains);
