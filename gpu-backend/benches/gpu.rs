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
//! - `vmf_pdf`: 262 144 stable pdfs C(κ) e^{−κ|ω − μ|²/2} against the textbook
//!   κ/(2π(1 − e^{−2κ})) e^{κ(μ·ω − 1)}.
//! - `hash_insert`: 262 144 `hashgrid_insert_or_get` (65 536 distinct keys, each 4 times; a
//!   2²⁰-slot table, so after the first iteration every call finds its key: a renderer's
//!   steady state) with the mixing and the xor-primes bucket hash, against a naive unhashed
//!   store (key i writes slot i mod capacity: no hash, no checksum, no probe).
//! - `hash_find`: 262 144 `hashgrid_find` in a 2²⁰-slot table holding 65 536 keys, against a
//!   naive unhashed load (key i reads slot i mod capacity).
//! - `vertex_key`: 262 144 adaptive-grid vertex keys (level from the camera distance with its
//!   jitter, stochastic trilinear vertex, normal class; MCPG sec. 4) against the naive fixed
//!   cell ⌊p/w⌋.
//! - `codec_encode`: 262 144 colours to the ADGI log irradiance word (nearest), LogLuv32 and
//!   R11G11B10, against storing the colour unencoded as `vec4<f32>`.
//!
//! Each iteration is one dispatch and the wait for it (buffers stay on the GPU). On lavapipe
//! these are software numbers: read them as ratios. Without an adapter the benches print why
//! and do nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::IVec3;
use glam::{Vec2, Vec3};
use mcg_gpu_backend::types::{HashgridLevelParams, HashgridTableParams};
use mcg_gpu_backend::types::{TexelParams, TexelUpdate, VmfQuery, VmfSample};
use mcg_gpu_backend::{GpuBuffer, GpuContext, prelude, shaders, wgpu};
use mcg_hashgrid::{BucketHash, CellKey, HashTable};
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

/// Runs each `(bench name, entry point)` of `source` over the same `bindings` in one group.
fn bench_entries(
    c: &mut Criterion,
    ctx: &GpuContext,
    group: &str,
    source: &str,
    entries: &[(&str, &str)],
    bindings: &[&wgpu::Buffer],
    n: u32,
) {
    let kernels: Vec<_> = entries
        .iter()
        .map(|(name, entry)| (*name, ctx.compute_kernel(source, entry).unwrap()))
        .collect();
    let mut g = c.benchmark_group(group);
    for (name, kernel) in &kernels {
        g.bench_function(*name, |b| {
            b.iter(|| ctx.dispatch(kernel, bindings, n).unwrap())
        });
    }
    g.finish();
}

const VMF_PDF: &str = r#"
@group(0) @binding(0) var<storage, read> lobes: array<Vmf>;
@group(0) @binding(1) var<storage, read> queries: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> pdfs: array<f32>;

@compute @workgroup_size(64)
fn stable(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&pdfs) {
        return;
    }
    pdfs[i] = vmf_pdf(lobes[i], queries[i].xyz);
}

// κ/(2π(1 − e^{−2κ})) e^{κ(μ·ω − 1)}: cancels near the peak and at small κ.
@compute @workgroup_size(64)
fn textbook(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&pdfs) {
        return;
    }
    let lobe = lobes[i];
    let k = lobe.kappa;
    pdfs[i] = k / (6.2831855 * (1.0 - exp(-2.0 * k))) * exp(k * (dot(lobe.mu, queries[i].xyz) - 1.0));
}
"#;

fn vmf_pdf(c: &mut Criterion, ctx: &GpuContext) {
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
    let queries: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let w = Vec3::new((i % 13) as f32 - 6.0, 1.0, (i % 5) as f32).normalize();
            [w.x, w.y, w.z, 0.0]
        })
        .collect();
    let lobes = ctx.storage_buffer("lobes", &lobes);
    let queries = ctx.storage_buffer("queries", &queries);
    let pdfs: GpuBuffer<f32> = ctx.zeroed_buffer("pdfs", n);
    bench_entries(
        c,
        ctx,
        "vmf_pdf",
        &[shaders::VMF_MODULE, VMF_PDF].concat(),
        &[
            ("stable_pdf", "stable"),
            ("baseline_textbook_pdf", "textbook"),
        ],
        &[lobes.raw(), queries.raw(), pdfs.raw()],
        n as u32,
    );
}

/// The bindings of `HASH_TABLE` and `HASH_FIND`.
const TABLE_BINDINGS: &str = r#"
@group(0) @binding(0) var<uniform> table: HashgridTable;
@group(0) @binding(1) var<storage, read_write> hashgrid_checksums: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read> keys: array<CellKey>;
@group(0) @binding(3) var<storage, read_write> slots: array<u32>;
"#;

const HASH_TABLE: &str = r#"

// insert-or-get with the table's bucket hash, the checksum and bounded linear probing.
@compute @workgroup_size(64)
fn insert_or_get(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&slots) {
        return;
    }
    let key = keys[i];
    slots[i] = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key)).slot;
}

// Naive: no hash, no checksum, no probing: key i stores its x word at slot i mod capacity.
@compute @workgroup_size(64)
fn unhashed_store(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&slots) {
        return;
    }
    let slot = i % table.capacity;
    atomicStore(&hashgrid_checksums[slot], bitcast<u32>(keys[i].cell.x) | 2u);
    slots[i] = slot;
}
"#;

fn hash_insert(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_u32;
    // 65 536 distinct keys, each inserted 4 times; a 2²⁰-slot table (load 1/16).
    let keys: Vec<CellKey> = (0..n)
        .map(|i| {
            let k = (i % 65_536) as i32;
            CellKey::new(
                IVec3::new(k % 64, (k / 64) % 32, k / 2048),
                (k % 5) as u8,
                0,
            )
        })
        .collect();
    let keys = ctx.storage_buffer("keys", &keys);
    let slots: GpuBuffer<u32> = ctx.zeroed_buffer("slots", n as usize);
    let source = [
        shaders::HASHGRID_MODULE,
        shaders::HASHGRID_TABLE,
        TABLE_BINDINGS,
        HASH_TABLE,
    ]
    .concat();
    let insert = ctx.compute_kernel(&source, "insert_or_get").unwrap();
    let naive = ctx.compute_kernel(&source, "unhashed_store").unwrap();
    let capacity = 1 << 20;
    let mut g = c.benchmark_group("hash_insert");
    for (name, hash) in [
        ("insert_or_get_mix", BucketHash::Mix),
        ("insert_or_get_xor_primes", BucketHash::XorPrimes),
    ] {
        let params = HashgridTableParams::new(capacity, 8, hash).unwrap();
        let table = ctx.uniform_buffer("table", &params);
        let checksums: GpuBuffer<u32> = ctx.zeroed_buffer("checksums", capacity as usize);
        let bindings = [table.raw(), checksums.raw(), keys.raw(), slots.raw()];
        g.bench_function(name, |b| {
            b.iter(|| ctx.dispatch(&insert, &bindings, n).unwrap())
        });
    }
    let params = HashgridTableParams::new(capacity, 8, BucketHash::Mix).unwrap();
    let table = ctx.uniform_buffer("table", &params);
    let checksums: GpuBuffer<u32> = ctx.zeroed_buffer("checksums", capacity as usize);
    let bindings = [table.raw(), checksums.raw(), keys.raw(), slots.raw()];
    g.bench_function("baseline_unhashed_store", |b| {
        b.iter(|| ctx.dispatch(&naive, &bindings, n).unwrap())
    });
    g.finish();
}

const HASH_FIND: &str = r#"

@compute @workgroup_size(64)
fn find(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&slots) {
        return;
    }
    let key = keys[i];
    slots[i] = hashgrid_find(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
}

// Naive: key i reads slot i mod capacity (no hash, no checksum, no probe).
@compute @workgroup_size(64)
fn unhashed_load(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&slots) {
        return;
    }
    slots[i] = atomicLoad(&hashgrid_checksums[i % table.capacity]) ^ bitcast<u32>(keys[i].cell.x);
}
"#;

fn hash_find(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_u32;
    let capacity = 1 << 20;
    // A table holding 65 536 keys (load 1/16), looked up 4 times each.
    let distinct: Vec<CellKey> = (0..65_536)
        .map(|k: i32| CellKey::new(IVec3::new(k % 64, (k / 64) % 32, k / 2048), 3, 1))
        .collect();
    let mut cpu = HashTable::<u32>::new(capacity, 8, BucketHash::Mix).unwrap();
    for k in &distinct {
        let _ = cpu.insert_or_get(k);
    }
    let keys: Vec<CellKey> = (0..n as usize).map(|i| distinct[i % 65_536]).collect();
    let keys = ctx.storage_buffer("keys", &keys);
    let slots: GpuBuffer<u32> = ctx.zeroed_buffer("slots", n as usize);
    let table = ctx.uniform_buffer(
        "table",
        &HashgridTableParams::new(capacity, 8, BucketHash::Mix).unwrap(),
    );
    let checksums = ctx.storage_buffer("checksums", cpu.checksums());
    bench_entries(
        c,
        ctx,
        "hash_find",
        &[
            shaders::HASHGRID_MODULE,
            shaders::HASHGRID_TABLE,
            TABLE_BINDINGS,
            HASH_FIND,
        ]
        .concat(),
        &[
            ("find_mix", "find"),
            ("baseline_unhashed_load", "unhashed_load"),
        ],
        &[table.raw(), checksums.raw(), keys.raw(), slots.raw()],
        n,
    );
}

const VERTEX_KEY: &str = r#"
@group(0) @binding(0) var<uniform> levels: HashgridLevels;
@group(0) @binding(1) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> keys: array<CellKey>;

// Level from the camera distance with its jitter, stochastic trilinear vertex, normal class.
@compute @workgroup_size(64)
fn adaptive(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&keys) {
        return;
    }
    let p = positions[i];
    keys[i] = hashgrid_vertex_key(levels, p.xyz, vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), fract(p.w * 7.0), p.w);
}

// Naive: one fixed width, the cell ⌊p/w⌋, no level, no jitter, no class.
@compute @workgroup_size(64)
fn fixed_floor(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&keys) {
        return;
    }
    keys[i] = CellKey(vec3<i32>(floor(positions[i].xyz / levels.min_width)), 0u);
}
"#;

fn vertex_key(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let positions: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let t = i as f32 / n as f32;
            [
                t * 50.0 - 25.0,
                (i % 97) as f32 * 0.3,
                (i % 13) as f32 + 1.0,
                (i % 1009) as f32 / 1009.0,
            ]
        })
        .collect();
    let positions = ctx.storage_buffer("positions", &positions);
    let keys: GpuBuffer<CellKey> = ctx.zeroed_buffer("keys", n);
    let levels = ctx.uniform_buffer(
        "levels",
        &HashgridLevelParams::from(&mcg_hashgrid::AdaptiveGrid::mcpg()),
    );
    bench_entries(
        c,
        ctx,
        "vertex_key",
        &[shaders::HASHGRID_MODULE, VERTEX_KEY].concat(),
        &[
            ("adaptive_vertex_key", "adaptive"),
            ("baseline_fixed_floor", "fixed_floor"),
        ],
        &[levels.raw(), positions.raw(), keys.raw()],
        n as u32,
    );
}

const CODEC_ENCODE: &str = r#"
@group(0) @binding(0) var<storage, read> values: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> words: array<u32>;
@group(0) @binding(2) var<storage, read_write> floats: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> codec_logluv_tables: array<f32>;

fn uses_all_bindings() {
    _ = arrayLength(&words);
    _ = arrayLength(&floats);
    _ = arrayLength(&codec_logluv_tables);
}

@compute @workgroup_size(64)
fn log_irradiance(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    uses_all_bindings();
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&values) {
        words[i] = codec_irradiance_encode(values[i].xyz, 1u, CodecRounding(CODEC_ROUND_NEAREST, 0.0));
    }
}

@compute @workgroup_size(64)
fn logluv(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    uses_all_bindings();
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&values) {
        words[i] = codec_logluv32_pack(values[i].xyz);
    }
}

@compute @workgroup_size(64)
fn r11g11b10(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    uses_all_bindings();
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&values) {
        words[i] = codec_r11g11b10_pack(values[i].xyz);
    }
}

// Naive: the colour stored as it is, 16 bytes instead of 4.
@compute @workgroup_size(64)
fn vec4_store(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    uses_all_bindings();
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&values) {
        floats[i] = values[i];
    }
}
"#;

fn codec_encode(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let values: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let t = i as f32 / n as f32;
            [t * 20.0, (1.0 - t) * 3.0, (i % 97) as f32 * 0.01, 0.0]
        })
        .collect();
    let values = ctx.storage_buffer("values", &values);
    let words: GpuBuffer<u32> = ctx.zeroed_buffer("words", n);
    let floats: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("floats", n);
    let tables = ctx.storage_buffer("tables", &prelude::logluv_tables());
    bench_entries(
        c,
        ctx,
        "codec_encode",
        &[
            shaders::COLOR_CODEC_MODULE,
            shaders::COLOR_CODEC_LOGLUV,
            CODEC_ENCODE,
        ]
        .concat(),
        &[
            ("log_irradiance_nearest", "log_irradiance"),
            ("logluv32", "logluv"),
            ("r11g11b10", "r11g11b10"),
            ("baseline_vec4_store", "vec4_store"),
        ],
        &[values.raw(), words.raw(), floats.raw(), tables.raw()],
        n as u32,
    );
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
    vmf_pdf(c, &ctx);
    hash_insert(c, &ctx);
    hash_find(c, &ctx);
    vertex_key(c, &ctx);
    codec_encode(c, &ctx);
}

criterion_group!(gpu, benches);
criterion_main!(gpu);
