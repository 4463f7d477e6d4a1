//! CPU/GPU parity of ADGI's pilot-ray uniforms (sec. 4.4): `mcg::adgi_chains`'
//! `adgi_hash_uniform` and `adgi_pilot_uniforms` against `mcg_probe_cache`'s `hash_uniform` and
//! `ProbeUpdater::pilot_uniforms`, bit for bit.
//!
//! The shader is a user's own, composed from `#import mcg::adgi_chains::…` by the plain-WGSL
//! composer. Runs on whatever wgpu adapter exists (lavapipe in CI); skips with a printed
//! reason when there is none, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).

use mcg_gpu_backend::{GpuBuffer, shaders};
use mcg_probe_cache::{ProbeUpdater, hash_uniform};
use rand::RngExt;

mod common;
use common::gpu_and_rng;

const USER_SHADER: &str = r#"
#import mcg::adgi_chains::{adgi_hash_uniform, adgi_pilot_uniforms}

struct Query {
    seed: vec2<u32>,
    pattern: vec2<u32>,
    counter: vec2<u32>,
    probe: u32,
    octant: u32,
    k: u32,
    pad: u32,
}

@group(0) @binding(0) var<storage, read> queries: array<Query>;
@group(0) @binding(1) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn pilots(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&queries) {
        return;
    }
    let q = queries[i];
    let u = adgi_pilot_uniforms(q.seed, q.pattern, q.probe, q.octant, q.k);
    results[i] = vec4<f32>(u, adgi_hash_uniform(q.counter), 0.0);
}
"#;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    seed: [u32; 2],
    pattern: [u32; 2],
    counter: [u32; 2],
    probe: u32,
    octant: u32,
    k: u32,
    pad: u32,
}

/// A u64 as WGSL's `vec2<u32>(low, high)`.
fn words(v: u64) -> [u32; 2] {
    [v as u32, (v >> 32) as u32]
}

/// 8 192 queries: seeds, patterns and counters random over all 64 bits, small (the renderer's:
/// a u32 seed, pattern = frame / 2) and at the wrap (u64::MAX, 2³² − 1, 2³²); probes up to
/// 2²⁹ − 1 (the largest whose `(8 probe + octant) << 3` the WGSL twin carries into the high
/// word); k ∈ {0, 1, 2, 3}. Hypothesis: integer hashing and one exact conversion (24 bits
/// times 2⁻²⁴), so bit for bit. Broken once on purpose (the carry of `adgi_u64_add` dropped):
/// failed at query 0 (seed 2³², probe 2²⁹ − 4).
#[test]
fn pilot_uniforms_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("pilot_uniforms_match_the_cpu", 41) else {
        return;
    };
    let edges = [0, 1, u64::from(u32::MAX), 1 << 32, u64::MAX, u64::MAX - 1];
    let wide = |rng: &mut rand_pcg::Pcg64, i: usize| match i % 4 {
        0 => edges[rng.random_range(0..edges.len())],
        1 => u64::from(rng.random::<u32>()),
        2 => rng.random_range(0..1000),
        _ => rng.random(),
    };
    let queries: Vec<(u64, u64, u64, usize, usize, u64)> = (0..8192)
        .map(|i| {
            let probe = match i % 5 {
                0 => (1 << 29) - 1 - rng.random_range(0..4),
                1 => rng.random_range(0..1 << 29),
                _ => rng.random_range(0..4096),
            };
            let (seed, pattern) = (wide(&mut rng, i), wide(&mut rng, i / 4));
            let counter = wide(&mut rng, i / 16);
            (seed, pattern, counter, probe, i % 8, (i / 8 % 4) as u64)
        })
        .collect();
    let gpu_queries: Vec<Query> = queries
        .iter()
        .map(|&(seed, pattern, counter, probe, octant, k)| Query {
            seed: words(seed),
            pattern: words(pattern),
            counter: words(counter),
            probe: probe as u32,
            octant: octant as u32,
            k: k as u32,
            pad: 0,
        })
        .collect();
    let source = shaders::compose(USER_SHADER, &[]).unwrap();
    let kernel = ctx.compute_kernel(&source, "pilots").unwrap();
    let input = ctx.storage_buffer("queries", &gpu_queries);
    let output: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("results", queries.len());
    ctx.dispatch(&kernel, &[input.raw(), output.raw()], queries.len() as u32)
        .unwrap();
    let results = ctx.read_back(&output).unwrap();
    for (i, (&(seed, pattern, counter, probe, o, k), r)) in queries.iter().zip(&results).enumerate()
    {
        let u = ProbeUpdater::pilot_uniforms(seed, pattern, probe, o, k);
        let want = [u.x, u.y, hash_uniform(counter)].map(f32::to_bits);
        let got = [r[0], r[1], r[2]].map(f32::to_bits);
        assert_eq!(
            got, want,
            "{i}: seed {seed:#x} pattern {pattern:#x} probe {probe} octant {o} k {k} \
             counter {counter:#x}"
        );
    }
}
