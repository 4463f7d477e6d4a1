//! CPU/GPU parity of `mcg::sampling`: the PCG hash and the uniform-float convention bit for
//! bit, the hash-chained stream, Duff et al.'s frame, and the cosine-weighted hemisphere within
//! the tolerance of WGSL's `sin`/`cos`/`sqrt` (the CPU uses the platform's).
//!
//! The shader is a user's own, composed from `#import mcg::sampling::…` by the plain-WGSL
//! composer. Runs on whatever wgpu adapter exists (lavapipe in CI); skips with a printed
//! reason when there is none, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::sampling::{next_u32, next_uniform, pcg_hash, uniform_float};
use mcg_gpu_backend::{GpuBuffer, shaders};
use mcg_markov_guide::{cosine_hemisphere, cosine_hemisphere_pdf};
use mcg_test_support::assert_close;
use mcg_vmf::Frame;
use rand::RngExt;

mod common;
use common::{gpu_and_rng, random_unit};

const USER_SHADER: &str = r#"
#import mcg::sampling::{
    McgDirectionSample, mcg_cosine_hemisphere_pdf, mcg_cosine_hemisphere_sample,
    mcg_frame_to_world, mcg_pcg_hash, mcg_rng_next, mcg_rng_uniform2, mcg_uniform_float
}

struct Query {
    normal: vec3<f32>,
    seed: u32,
    local: vec3<f32>,
    u_x: f32,
    u_y: f32,
}

struct Result {
    direction: vec3<f32>,
    pdf: f32,
    frame: vec3<f32>,
    pdf_again: f32,
    hash: u32,
    uniform: f32,
    stream_bits: u32,
    stream_u: vec2<f32>,
}

@group(0) @binding(0) var<storage, read> queries: array<Query>;
@group(0) @binding(1) var<storage, read_write> results: array<Result>;

@compute @workgroup_size(64)
fn sampling(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&queries) {
        return;
    }
    let q = queries[i];
    let s = mcg_cosine_hemisphere_sample(q.normal, vec2<f32>(q.u_x, q.u_y));
    var state = q.seed;
    let bits = mcg_rng_next(&state);
    let u = mcg_rng_uniform2(&state);
    results[i] = Result(s.direction, s.pdf, mcg_frame_to_world(q.normal, q.local), mcg_cosine_hemisphere_pdf(q.normal, s.direction), mcg_pcg_hash(q.seed), mcg_uniform_float(q.seed), bits, u);
}
"#;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Query {
    normal: Vec3,
    seed: u32,
    local: Vec3,
    u: Vec2,
    pad: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct Output {
    direction: Vec3,
    pdf: f32,
    frame: Vec3,
    pdf_again: f32,
    hash: u32,
    uniform: f32,
    stream_bits: u32,
    pad0: u32,
    stream_u: Vec2,
    pad1: [u32; 2],
}

/// 8 192 normals (random, the poles ±z incl. the −0 sign rule, the equator), uniforms incl. 0
/// and 1 − 2⁻²⁴, seeds incl. 0 and u32::MAX. Hypotheses: hash, uniform and the stream are
/// integer arithmetic and one exact conversion, so bit for bit; the frame is a few
/// correctly rounded operations that may fuse, so within 8 ε; the hemisphere sample goes
/// through WGSL's `sin`/`cos` (absolute error ≤ 2⁻¹¹ on [−π, π] by the spec; lavapipe's are
/// far better), so within 1e-5 of the CPU's direction and pdf. Broken once on purpose (the
/// uniform from the low 24 bits, `bits & 0xffffffu`): failed.
#[test]
fn sampling_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("sampling_matches_the_cpu", 5) else {
        return;
    };
    let mut queries: Vec<Query> = (0..8192)
        .map(|i| {
            let normal = match i % 10 {
                0 => Vec3::Z,
                1 => -Vec3::Z,
                2 => Vec3::new(0.6, 0.8, -0.0),
                _ => random_unit(&mut rng),
            };
            let u = match i % 7 {
                0 => Vec2::ZERO,
                1 => Vec2::splat(1.0 - 2f32.powi(-24)),
                _ => Vec2::new(rng.random(), rng.random()),
            };
            Query {
                normal,
                seed: rng.random(),
                local: random_unit(&mut rng),
                u,
                pad: [0; 3],
            }
        })
        .collect();
    queries[0].seed = 0;
    queries[1].seed = u32::MAX;
    let source = shaders::compose(USER_SHADER, &[]).unwrap();
    let kernel = ctx.compute_kernel(&source, "sampling").unwrap();
    let input = ctx.storage_buffer("queries", &queries);
    let output: GpuBuffer<Output> = ctx.zeroed_buffer("results", queries.len());
    ctx.dispatch(&kernel, &[input.raw(), output.raw()], queries.len() as u32)
        .unwrap();
    let results = ctx.read_back(&output).unwrap();
    let mut worst = 0.0_f32;
    for (i, (q, r)) in queries.iter().zip(&results).enumerate() {
        assert_eq!(r.hash, pcg_hash(q.seed), "{i}: hash");
        assert_eq!(r.uniform.to_bits(), uniform_float(q.seed).to_bits(), "{i}");
        let mut state = q.seed;
        assert_eq!(r.stream_bits, next_u32(&mut state), "{i}: stream");
        let u = Vec2::new(next_uniform(&mut state), next_uniform(&mut state));
        assert_eq!(r.stream_u, u, "{i}: stream uniforms");
        let frame = Frame::from_normal(q.normal).to_world(q.local);
        assert!(
            (r.frame - frame).length() <= 8.0 * f32::EPSILON,
            "{i}: frame {:?} vs {frame:?}",
            r.frame
        );
        let (w, pdf) = cosine_hemisphere(q.normal, q.u);
        let err = (r.direction - w).length().max((r.pdf - pdf).abs());
        worst = worst.max(err);
        assert!(
            err <= 1e-5,
            "{i}: {:?} {} vs {w:?} {pdf}",
            r.direction,
            r.pdf
        );
        let again = cosine_hemisphere_pdf(q.normal, r.direction);
        assert_close!(r.pdf_again, again, 1e-6, "{i}: pdf");
    }
    println!("cosine hemisphere: largest GPU − CPU difference {worst:.2e}");
}
