//! Kernel benchmarks, each group with its naive WGSL baseline in the same run:
//!
//! - `texel_update`: 65 536 moving-average updates of 1 024 packed irradiance texels with the
//!   compare-and-swap loop, against a plain `vec4<f32>` store of the sample (no average, no
//!   atomics): the price of the packed atomic texel.
//! - `vmf_sample`: 262 144 `vmf_sample_with_pdf` calls with the stable sampler, against the
//!   textbook sampler `cos θ = 1 + ln(ξ + (1 − ξ) e^{−2κ})/κ` with built-in `sin`/`cos` and
//!   the textbook pdf (which loses precision near the peak and overflows nothing only
//!   because κ ≤ 200 here).
//!
//! Each iteration is one dispatch and the wait for it (buffers stay on the GPU). On lavapipe
//! these are software numbers: read them as ratios. Without an adapter the benches print why
//! and do nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use mcg_gpu_backend::types::{TexelParams, TexelUpdate, VmfQuery, VmfSample};
use mcg_gpu_backend::{GpuBuffer, GpuContext, shaders};
use mcg_vmf::Vmf;

const NAIVE_STORE: &str = r#"
struct TexelUpdate {
    sample: vec3<f32>,
    texel: u32,
}
@group(0) @binding(0) var<storage, read_write> texels: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> updates: array<TexelUpdate>;
@compute @workgroup_size(64)
fn naive_store(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&updates) {
        return;
    }
    let up = updates[i];
    texels[up.texel] = vec4<f32>(up.sample, 1.0);
}
"#;

const TEXTBOOK_SAMPLER: &str = r#"
@group(0) @binding(0) var<storage, read> lobes: array<Vmf>;
@group(0) @binding(1) var<storage, read> queries: array<VmfQuery>;
@group(0) @binding(2) var<storage, read_write> pdfs: array<f32>;
@group(0) @binding(3) var<storage, read_write> samples: array<VmfSample>;
struct VmfQuery {
    direction: vec3<f32>,
    uniforms: vec2<f32>,
}
@compute @workgroup_size(64)
fn textbook(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&pdfs) {
        return;
    }
    let lobe = lobes[i];
    let u = queries[i].uniforms;
    let k = lobe.kappa;
    let cos_theta = 1.0 + log(u.y + (1.0 - u.y) * exp(-2.0 * k)) / k;
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = 6.2831855 * u.x;
    let w = vmf_frame_to_world(lobe.mu, vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta));
    let pdf = k / (6.2831855 * (1.0 - exp(-2.0 * k))) * exp(k * (cos_theta - 1.0));
    pdfs[i] = pdf;
    samples[i] = VmfSample(w, pdf);
}

@compute @workgroup_size(64)
fn stable(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&pdfs) {
        return;
    }
    let s = vmf_sample_with_pdf(lobes[i], queries[i].uniforms);
    pdfs[i] = s.pdf;
    samples[i] = s;
}
"#;

fn texel_update(c: &mut Criterion, ctx: &GpuContext) {
    let n = 65_536_u32;
    let updates: Vec<TexelUpdate> = (0..n)
        .map(|k| TexelUpdate {
            sample: Vec3::new((k % 97) as f32 * 0.1, (k % 13) as f32, 0.5),
            texel: (k.wrapping_mul(2_654_435_761) >> 22) % 1024,
        })
        .collect();
    let updates = ctx.storage_buffer("updates", &updates);
    let packed = ctx
        .compute_kernel(shaders::kernels::COLOR_CODEC_TEXELS, "codec_texel_updates")
        .unwrap();
    let words: GpuBuffer<u32> = ctx.zeroed_buffer("words", 1024);
    let params = ctx.uniform_buffer(
        "params",
        &TexelParams {
            max_count: 63,
            rounding_mode: 1,
            rounding_u: 0.0,
            word_layout: 0,
        },
    );
    let naive = ctx.compute_kernel(NAIVE_STORE, "naive_store").unwrap();
    let plain: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("plain", 1024);
    let mut g = c.benchmark_group("texel_update");
    g.bench_function("packed_atomic_moving_average", |b| {
        b.iter(|| {
            ctx.dispatch(&packed, &[words.raw(), updates.raw(), params.raw()], n)
                .unwrap()
        })
    });
    g.bench_function("baseline_plain_vec4_store", |b| {
        b.iter(|| {
            ctx.dispatch(&naive, &[plain.raw(), updates.raw()], n)
                .unwrap()
        })
    });
    g.finish();
}

fn vmf_sample(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let lobes: Vec<Vmf> = (0..n)
        .map(|i| {
            Vmf::new(
                Vec3::new(0.3, (i % 7) as f32 - 3.0, 1.0),
                0.5 + (i % 200) as f32,
            )
            .unwrap()
        })
        .collect();
    let queries: Vec<VmfQuery> = (0..n)
        .map(|i| {
            VmfQuery::new(
                Vec3::Z,
                Vec2::new((i % 1009) as f32 / 1009.0, (i % 997) as f32 / 997.0),
            )
        })
        .collect();
    let lobes = ctx.storage_buffer("lobes", &lobes);
    let queries = ctx.storage_buffer("queries", &queries);
    let pdfs: GpuBuffer<f32> = ctx.zeroed_buffer("pdfs", n);
    let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
    let source = [shaders::VMF_MODULE, TEXTBOOK_SAMPLER].concat();
    let stable = ctx.compute_kernel(&source, "stable").unwrap();
    let textbook = ctx.compute_kernel(&source, "textbook").unwrap();
    let bindings = [lobes.raw(), queries.raw(), pdfs.raw(), samples.raw()];
    let mut g = c.benchmark_group("vmf_sample");
    g.bench_function("stable_sample_with_pdf", |b| {
        b.iter(|| ctx.dispatch(&stable, &bindings, n as u32).unwrap())
    });
    g.bench_function("baseline_textbook_sampler", |b| {
        b.iter(|| ctx.dispatch(&textbook, &bindings, n as u32).unwrap())
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => {
            eprintln!("skipping the GPU benches: {e}");
            return;
        }
    };
    eprintln!(
        "adapter: {} ({:?})",
        ctx.adapter_info().name,
        ctx.adapter_info().device_type
    );
    texel_update(c, &ctx);
    vmf_sample(c, &ctx);
}

criterion_group!(gpu, benches);
criterion_main!(gpu);
