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
//!   steady state) with the mixing and the xor-primes bucket hash, and the age-tracked
//!   insert-and-touch (mix), against a naive unhashed store (key i writes slot i mod
//!   capacity: no hash, no checksum, no probe).
//! - `hash_find`: 262 144 `hashgrid_find` in a 2²⁰-slot table holding 65 536 keys, against a
//!   naive unhashed load (key i reads slot i mod capacity).
//! - `vertex_key`: 262 144 adaptive-grid vertex keys (level from the camera distance with its
//!   jitter, stochastic trilinear vertex, normal class; MCPG sec. 4), static-grid vertex keys
//!   and jittered vertices against the naive fixed cell ⌊p/w⌋.
//! - `codec_encode`: 262 144 colours to the ADGI log irradiance word (nearest), LogLuv32,
//!   R11G11B10, RGB9E5, gamma-5 R10G10B10A2, the visibility word (xy) and the heuristics word
//!   (clamped to 1), against storing the colour unencoded as `vec4<f32>`.
//!
//! - `texel_update` also folds the same updates into 13/13 + 6 visibility words
//!   (`packed_atomic_visibility`), against the same plain store.
//! - `vmf_stats_update`: 262 144 `vmf_stats_update` (weighted running means of ȳ and of the
//!   mean cosine, N_max, α_min) against a plain running mean of the unit directions.
//! - `vmf_reconstruct`: 262 144 `vmf_from_sufficient_stats` with the MAP prior (MCMM Alg. 2)
//!   against Banerjee's κ of the sample mean cosine without the prior.
//! - `vmf_product`: 262 144 `vmf_product` (normalisations in the stable form, scale with
//!   e^{κ' − κ_a − κ_b}) against the textbook product with C(κ) = κ/(4π sinh κ) (κ ≤ 50 here,
//!   so sinh does not overflow).
//! - `vmf_convolve`: 262 144 `vmf_convolve` (A₃ products and the exact inverse by Newton)
//!   against the plain harmonic rule κ' = κ κ_k/(κ + κ_k).
//! - `vmf_mixture`: 262 144 `VmfMixture<4>` pdfs and `sample_with_pdf` against the sum of
//!   four textbook pdfs and a linear CDF walk with the textbook sampler.
//! - `hash_evict`: eviction of stale cells in a 2¹⁸-slot age-tracked table (about 100 000
//!   keys over 16 frames, max_age 7: the two passes, tombstones and the trim) against a
//!   plain clear of stale slots; each iteration first restores the checksum array (4 ×
//!   2¹⁸ bytes written, in both arms).
//! - `markov_state`: 262 144 MCPG grid states read on the GPU (f16 velocity, count,
//!   statistics, and the lobe reconstructed with the prior) and MCMM pixel-state lobes,
//!   against reading a plain `vec4<f32>` lobe.
//! - `codec_decode`: 262 144 words decoded as the log irradiance word, LogLuv32 and
//!   R11G11B10, against loading an unencoded `vec4<f32>`.
//!
//! Each iteration is one dispatch and the wait for it (buffers stay on the GPU). On lavapipe
//! these are software numbers: read them as ratios. Without an adapter the benches print why
//! and do nothing.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::IVec3;
use glam::{Vec2, Vec3};
use mcg_gpu_backend::shaders::{self, Module, kernels};
use mcg_gpu_backend::types::{
    HashgridAgeParams, HashgridLevelParams, HashgridTableParams, TexelParams, TexelUpdate,
    VmfFitParamsGpu, VmfQuery, VmfSample, VmfUpdate, pack_mixtures,
};
use mcg_gpu_backend::{GpuBuffer, GpuContext, wgpu};
use mcg_hashgrid::{BucketHash, CellKey, HashTable};
use mcg_markov_guide::mcmm::PixelState;
use mcg_markov_guide::mcpg::GridState;
use mcg_vmf::{FitParams, SufficientStats, Vmf, VmfMixture};

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
fn textbook_at(i: u32) {
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

fn stable_at(i: u32) {
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
        .compute_kernel(
            &kernels::plain(kernels::COLOR_CODEC_TEXELS),
            "codec_texel_updates",
        )
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
    let naive = ctx
        .compute_kernel(&kernels::plain(NAIVE_STORE), "naive_store")
        .unwrap();
    let plain: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("plain", 1024);
    let mut g = c.benchmark_group("texel_update");
    g.bench_function("packed_atomic_moving_average", |b| {
        b.iter(|| {
            ctx.dispatch(&packed, &[words.raw(), updates.raw(), params.raw()], n)
                .unwrap()
        })
    });
    let visibility: GpuBuffer<u32> = ctx.zeroed_buffer("visibility words", 1024);
    let visibility_params = ctx.uniform_buffer(
        "params",
        &TexelParams {
            max_count: 63,
            rounding_mode: 1,
            rounding_u: 0.0,
            word_layout: 1,
        },
    );
    g.bench_function("packed_atomic_visibility", |b| {
        b.iter(|| {
            ctx.dispatch(
                &packed,
                &[visibility.raw(), updates.raw(), visibility_params.raw()],
                n,
            )
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
    let source = [
        &lib(&[Module::Vmf, Module::Dispatch]),
        TEXTBOOK_SAMPLER,
        &entry_points("pdfs", &["textbook", "stable"]),
    ]
    .concat();
    let stable = ctx
        .compute_kernel(&kernels::plain(&source), "stable")
        .unwrap();
    let textbook = ctx
        .compute_kernel(&kernels::plain(&source), "textbook")
        .unwrap();
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
        .map(|(name, entry)| {
            (
                *name,
                ctx.compute_kernel(&kernels::plain(source), entry).unwrap(),
            )
        })
        .collect();
    let mut g = c.benchmark_group(group);
    for (name, kernel) in &kernels {
        g.bench_function(*name, |b| {
            b.iter(|| ctx.dispatch(kernel, bindings, n).unwrap())
        });
    }
    g.finish();
}

/// One WGSL compute entry point `entry`: one invocation per element, which runs `prologue`
/// and then `statement` for element `i` when `i < arrayLength(&guard)`.
/// The library's plain WGSL for `modules` (and what they import), with the kernels' bindings:
/// the hash words at binding 1, the LogLuv tables at binding 3.
fn lib(modules: &[Module]) -> String {
    shaders::wgsl(modules, kernels::KERNEL_DEFS).unwrap()
}

fn per_element_entry(entry: &str, prologue: &str, guard: &str, statement: &str) -> String {
    format!(
        "
@compute @workgroup_size(64)
fn {entry}(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {{
    {prologue}
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&{guard}) {{
        {statement}
    }}
}}
"
    )
}

/// WGSL compute entry points, one per `(entry, statement)`: each runs `uses_all_bindings()`
/// (so every entry point of a group binds the same buffers) and then `statement` once per
/// element `i < arrayLength(&guard)`.
fn per_element_entries(guard: &str, entries: &[(&str, &str)]) -> String {
    entries
        .iter()
        .map(|(entry, statement)| {
            per_element_entry(entry, "uses_all_bindings();", guard, statement)
        })
        .collect()
}

/// WGSL compute entry points `name`, one per name, that call the group's function
/// `name_at(i: u32)` once per element `i < arrayLength(&guard)`.
fn entry_points(guard: &str, names: &[&str]) -> String {
    names
        .iter()
        .map(|name| per_element_entry(name, "", guard, &format!("{name}_at(i);")))
        .collect()
}

/// [`entry_points`] that first call the group's `uses_all_bindings()`, for groups where some
/// `name_at` leaves a binding unused (every entry point of a group binds the same buffers).
fn all_binding_entry_points(guard: &str, names: &[&str]) -> String {
    names
        .iter()
        .map(|name| {
            per_element_entry(
                name,
                "uses_all_bindings();",
                guard,
                &format!("{name}_at(i);"),
            )
        })
        .collect()
}

const VMF_PDF: &str = r#"
@group(0) @binding(0) var<storage, read> lobes: array<Vmf>;
@group(0) @binding(1) var<storage, read> queries: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> pdfs: array<f32>;

fn stable_at(i: u32) {
    pdfs[i] = vmf_pdf(lobes[i], queries[i].xyz);
}

// κ/(2π(1 − e^{−2κ})) e^{κ(μ·ω − 1)}: cancels near the peak and at small κ.
fn textbook_at(i: u32) {
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
        &[
            &lib(&[Module::Vmf, Module::Dispatch]),
            VMF_PDF,
            &entry_points("pdfs", &["stable", "textbook"]),
        ]
        .concat(),
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
// Binding 1: `mcg_hashgrid_words` (mcg::hashgrid_table).
@group(0) @binding(2) var<storage, read> keys: array<HashgridCellKey>;
@group(0) @binding(3) var<storage, read_write> slots: array<u32>;
"#;

const HASH_TABLE: &str = r#"

// insert-or-get with the table's bucket hash, the checksum and bounded linear probing.
fn insert_or_get_at(i: u32) {
    let key = keys[i];
    slots[i] = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key)).slot;
}

// Naive: no hash, no checksum, no probing: key i stores its x word at slot i mod capacity.
fn unhashed_store_at(i: u32) {
    let slot = i % table.capacity;
    atomicStore(&mcg_hashgrid_words[slot], bitcast<u32>(keys[i].cell.x) | 2u);
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
        &lib(&[Module::HashgridTable, Module::Dispatch]),
        TABLE_BINDINGS,
        HASH_TABLE,
        &entry_points("slots", &["insert_or_get", "unhashed_store"]),
    ]
    .concat();
    let insert = ctx
        .compute_kernel(&kernels::plain(&source), "insert_or_get")
        .unwrap();
    let naive = ctx
        .compute_kernel(&kernels::plain(&source), "unhashed_store")
        .unwrap();
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
    // The age-tracked insert: insert-or-get (mix), then the slot touched in the frame.
    let touch = ctx
        .compute_kernel(
            &kernels::plain(kernels::HASHGRID_AGES),
            "hashgrid_insert_touch",
        )
        .unwrap();
    let aged = ctx.uniform_buffer("aged table", &params.at_offsets(0, capacity));
    let words: GpuBuffer<u32> = ctx.zeroed_buffer("words", 2 * capacity as usize);
    let age_params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(1, 0));
    let counter: GpuBuffer<u32> = ctx.zeroed_buffer("counter", 1);
    let bindings = [
        aged.raw(),
        words.raw(),
        age_params.raw(),
        counter.raw(),
        keys.raw(),
    ];
    g.bench_function("insert_or_get_touch_mix", |b| {
        b.iter(|| ctx.dispatch(&touch, &bindings, n).unwrap())
    });
    g.finish();
}

const HASH_FIND: &str = r#"

fn find_at(i: u32) {
    let key = keys[i];
    slots[i] = hashgrid_find(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
}

// Naive: key i reads slot i mod capacity (no hash, no checksum, no probe).
fn unhashed_load_at(i: u32) {
    slots[i] = atomicLoad(&mcg_hashgrid_words[i % table.capacity]) ^ bitcast<u32>(keys[i].cell.x);
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
            &lib(&[Module::HashgridTable, Module::Dispatch]),
            TABLE_BINDINGS,
            HASH_FIND,
            &entry_points("slots", &["find", "unhashed_load"]),
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
@group(0) @binding(2) var<storage, read_write> keys: array<HashgridCellKey>;

// Level from the camera distance with its jitter, stochastic trilinear vertex, normal class.
fn adaptive_at(i: u32) {
    let p = positions[i];
    keys[i] = hashgrid_vertex_key(levels, p.xyz, vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), fract(p.w * 7.0), p.w);
}

// The static grid's vertex key (stochastic trilinear corner of p/w, MCPG sec. 4).
fn static_grid_at(i: u32) {
    let p = positions[i];
    keys[i] = hashgrid_static_vertex_key(levels.min_width, p.xyz, p.w);
}

// The jittered vertex of p/w.
fn jittered_at(i: u32) {
    let p = positions[i];
    keys[i] = HashgridCellKey(hashgrid_jittered_vertex(p.xyz / levels.min_width, fract(p.www * vec3<f32>(3.0, 5.0, 7.0))), 0u);
}

// Naive: one fixed width, the cell ⌊p/w⌋, no level, no jitter, no class.
fn fixed_floor_at(i: u32) {
    keys[i] = HashgridCellKey(vec3<i32>(floor(positions[i].xyz / levels.min_width)), 0u);
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
        &[
            &lib(&[Module::Hashgrid, Module::Dispatch]),
            VERTEX_KEY,
            &entry_points(
                "keys",
                &["adaptive", "static_grid", "jittered", "fixed_floor"],
            ),
        ]
        .concat(),
        &[
            ("adaptive_vertex_key", "adaptive"),
            ("static_grid_vertex_key", "static_grid"),
            ("jittered_vertex", "jittered"),
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
// Binding 3: `mcg_codec_logluv_tables` (mcg::color_codec_logluv).

fn uses_all_bindings() {
    _ = arrayLength(&words);
    _ = arrayLength(&floats);
    _ = arrayLength(&mcg_codec_logluv_tables);
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
    let tables = ctx.storage_buffer("tables", &shaders::constants::logluv_tables());
    bench_entries(
        c,
        ctx,
        "codec_encode",
        &[
            &lib(&[Module::ColorCodecLogluv, Module::Dispatch]),
            CODEC_ENCODE,
            &per_element_entries(
                "values",
                &[
                    ("log_irradiance", "words[i] = codec_irradiance_encode(values[i].xyz, 1u, CodecRounding(CODEC_ROUND_NEAREST, 0.0));"),
                    ("logluv", "words[i] = codec_logluv32_pack(values[i].xyz);"),
                    ("r11g11b10", "words[i] = codec_r11g11b10_pack(values[i].xyz);"),
                    ("rgb9e5", "words[i] = codec_rgb9e5_pack(values[i].xyz);"),
                    ("gamma5", "words[i] = codec_gamma5_pack(values[i].xyz);"),
                    ("visibility", "words[i] = codec_visibility_encode(values[i].xy, 1u, CodecRounding(CODEC_ROUND_NEAREST, 0.0));"),
                    ("heuristics", "words[i] = codec_heuristics_encode(min(values[i].xyz, vec3<f32>(1.0)), 1u, CodecRounding(CODEC_ROUND_NEAREST, 0.0));"),
                    // Naive: the colour stored as it is, 16 bytes instead of 4.
                    ("vec4_store", "floats[i] = values[i];"),
                ],
            ),
        ]
        .concat(),
        &[
            ("log_irradiance_nearest", "log_irradiance"),
            ("logluv32", "logluv"),
            ("r11g11b10", "r11g11b10"),
            ("rgb9e5", "rgb9e5"),
            ("gamma5_r10g10b10a2", "gamma5"),
            ("visibility_nearest", "visibility"),
            ("heuristics_nearest", "heuristics"),
            ("baseline_vec4_store", "vec4_store"),
        ],
        &[values.raw(), words.raw(), floats.raw(), tables.raw()],
        n as u32,
    );
}

/// `n` lobes with κ in [0.5, `max_kappa`) and directions spread over the sphere.
fn bench_lobes(n: usize, max_kappa: f32) -> Vec<Vmf> {
    (0..n)
        .map(|i| {
            let mu = Vec3::new(0.3, (i % 7) as f32 - 3.0, 1.0 - (i % 3) as f32);
            Vmf::new(mu, 0.5 + (i as f32 * 0.618).fract() * (max_kappa - 0.5)).unwrap()
        })
        .collect()
}

const VMF_STATS_UPDATE: &str = r#"
// Naive: a plain running mean of the unit directions (no weights, no mean cosine, no N_max).
@compute @workgroup_size(64)
fn running_mean(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&updates) || fit.max_count == 0u {
        return;
    }
    var s = stats[i];
    let u = updates[i];
    let n = f32(s.sample_count) + 1.0;
    let m = vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z);
    let next = m + (normalize(u.y - u.x) - m) / n;
    s.mean_target_x = next.x;
    s.mean_target_y = next.y;
    s.mean_target_z = next.z;
    s.sample_count += 1u;
    stats[i] = s;
}
"#;

fn vmf_stats_update(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let updates: Vec<VmfUpdate> = (0..n)
        .map(|i| {
            VmfUpdate::new(
                Vec3::new(0.1, 0.2, -0.3),
                Vec3::new((i % 13) as f32 - 6.0, 4.0, (i % 5) as f32),
                0.1 + (i % 17) as f32,
            )
        })
        .collect();
    let stats: GpuBuffer<SufficientStats> = ctx.zeroed_buffer("stats", n);
    let updates = ctx.storage_buffer("updates", &updates);
    let fit = ctx.uniform_buffer("fit", &VmfFitParamsGpu::from(&FitParams::MCMM));
    bench_entries(
        c,
        ctx,
        "vmf_stats_update",
        &[kernels::VMF_UPDATE, VMF_STATS_UPDATE].concat(),
        &[
            ("stats_update", "vmf_update"),
            ("baseline_running_mean_direction", "running_mean"),
        ],
        &[stats.raw(), updates.raw(), fit.raw()],
        n as u32,
    );
}

/// Bindings of the lobe operations (`vmf_reconstruct`, `vmf_product`, `vmf_convolve`).
const VMF_OPS: &str = r#"
@group(0) @binding(0) var<storage, read> stats: array<VmfSufficientStats>;
@group(0) @binding(1) var<storage, read> a: array<Vmf>;
@group(0) @binding(2) var<storage, read> b: array<Vmf>;
@group(0) @binding(3) var<storage, read_write> out: array<vec4<f32>>;

fn uses_all_bindings() {
    _ = arrayLength(&stats);
    _ = arrayLength(&a);
    _ = arrayLength(&b);
}

// MCMM Alg. 2 lines 5-7: ȳ − x normalised, κ of the MAP mean cosine.
fn map_reconstruct_at(i: u32) {
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    _ = vmf_from_sufficient_stats(stats[i], vec3<f32>(0.1, 0.2, -0.3), VmfMapPrior(0.2, 0.5, 0u), &lobe);
    out[i] = vec4<f32>(lobe.mu, lobe.kappa);
}

// Naive: Banerjee's κ = r(3 − r²)/(1 − r²) of the sample mean cosine, no prior, no guards.
fn banerjee_no_prior_at(i: u32) {
    let s = stats[i];
    let mu = normalize(vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z) - vec3<f32>(0.1, 0.2, -0.3));
    let r = 1.0 - s.one_minus_mean_cosine;
    out[i] = vec4<f32>(mu, r * (3.0 - r * r) / (1.0 - r * r));
}

fn product_at(i: u32) {
    var p: Vmf;
    let scale = vmf_product(a[i], b[i], &p);
    out[i] = vec4<f32>(p.mu * scale, p.kappa);
}

// Naive: C(κ) = κ/(4π sinh κ), scale = C(κ_a) C(κ_b)/C(κ').
fn textbook_c(kappa: f32) -> f32 {
    return kappa / (12.566371 * sinh(kappa));
}

fn textbook_product_at(i: u32) {
    let m = a[i].mu * a[i].kappa + b[i].mu * b[i].kappa;
    let kappa = length(m);
    let scale = textbook_c(a[i].kappa) * textbook_c(b[i].kappa) / textbook_c(kappa);
    out[i] = vec4<f32>(m / kappa * scale, kappa);
}

fn convolve_at(i: u32) {
    let c = vmf_convolve(a[i], b[i].kappa);
    out[i] = vec4<f32>(c.mu, c.kappa);
}

// Naive: κ' = κ κ_k/(κ + κ_k).
fn harmonic_at(i: u32) {
    let k = a[i].kappa;
    let kk = b[i].kappa;
    out[i] = vec4<f32>(a[i].mu, k * kk / (k + kk));
}
"#;

/// The groups `vmf_reconstruct`, `vmf_product` and `vmf_convolve` over the same buffers.
fn vmf_ops(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let x = Vec3::new(0.1, 0.2, -0.3);
    let stats: Vec<SufficientStats> = (0..n)
        .map(|i| {
            let mut s = SufficientStats::EMPTY;
            for k in 0..(1 + i % 4) {
                let y = Vec3::new(((i + k) % 13) as f32 - 6.0, 4.0, ((i + 3 * k) % 5) as f32);
                s.update(x, y, 0.5 + k as f32, &FitParams::MCMM);
            }
            s
        })
        .collect();
    let stats = ctx.storage_buffer("stats", &stats);
    let a = ctx.storage_buffer("a", &bench_lobes(n, 50.0));
    let mut b_lobes = bench_lobes(n, 50.0);
    b_lobes.rotate_left(1);
    let b = ctx.storage_buffer("b", &b_lobes);
    let out: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("out", n);
    let source = [
        &lib(&[Module::Vmf, Module::Dispatch]),
        VMF_OPS,
        &all_binding_entry_points(
            "out",
            &[
                "map_reconstruct",
                "banerjee_no_prior",
                "product",
                "textbook_product",
                "convolve",
                "harmonic",
            ],
        ),
    ]
    .concat();
    let bindings = [stats.raw(), a.raw(), b.raw(), out.raw()];
    for (group, entries) in [
        (
            "vmf_reconstruct",
            [
                ("map_reconstruct", "map_reconstruct"),
                ("baseline_banerjee_no_prior", "banerjee_no_prior"),
            ],
        ),
        (
            "vmf_product",
            [
                ("stable_product", "product"),
                ("baseline_textbook_sinh_product", "textbook_product"),
            ],
        ),
        (
            "vmf_convolve",
            [
                ("convolve_exact_inverse", "convolve"),
                ("baseline_harmonic_kappa", "harmonic"),
            ],
        ),
    ] {
        bench_entries(c, ctx, group, &source, &entries, &bindings, n as u32);
    }
}

/// Entry points appended to the kernel module `kernels::VMF_MIXTURE` (K = 4, bindings
/// `mixtures`, `queries`, `samples`, `choices`); each writes its result to `samples`.
const VMF_MIXTURE: &str = r#"
fn uses_all_bindings() {
    _ = arrayLength(&choices);
}

fn mixture_pdf_at(i: u32) {
    samples[i] = VmfSample(queries[i].direction, vmf_mixture_pdf(mixtures[i], queries[i].direction));
}

// Naive: Σ w κ/(2π(1 − e^{−2κ})) e^{κ(μ·ω − 1)}.
fn textbook_mixture_pdf(m: VmfMixture, w: vec3<f32>) -> f32 {
    var pdf = 0.0;
    for (var k = 0u; k < VMF_MIXTURE_K; k += 1u) {
        let lobe = m.lobes[k];
        pdf += m.weights[k] * lobe.kappa / (6.2831855 * (1.0 - exp(-2.0 * lobe.kappa))) * exp(lobe.kappa * (dot(lobe.mu, w) - 1.0));
    }
    return pdf;
}

fn textbook_pdf_sum_at(i: u32) {
    samples[i] = VmfSample(queries[i].direction, textbook_mixture_pdf(mixtures[i], queries[i].direction));
}

fn mixture_sample_at(i: u32) {
    samples[i] = vmf_mixture_sample_with_pdf(mixtures[i], queries[i].uniforms);
}

// Naive: a linear CDF walk, the textbook sampler, the textbook pdf sum.
fn linear_cdf_walk_at(i: u32) {
    let m = mixtures[i];
    let u = queries[i].uniforms;
    var k = 0u;
    var start = 0.0;
    for (; k + 1u < VMF_MIXTURE_K; k += 1u) {
        if u.x < start + m.weights[k] {
            break;
        }
        start += m.weights[k];
    }
    let lobe = m.lobes[k];
    let uy = (u.x - start) / m.weights[k];
    let kappa = lobe.kappa;
    let cos_theta = 1.0 + log(uy + (1.0 - uy) * exp(-2.0 * kappa)) / kappa;
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = 6.2831855 * u.y;
    let w = vmf_frame_to_world(lobe.mu, vec3<f32>(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta));
    samples[i] = VmfSample(w, textbook_mixture_pdf(m, w));
}
"#;

fn vmf_mixture(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let lobes = bench_lobes(4 * n, 200.0);
    let mixtures: Vec<VmfMixture<4>> = lobes
        .chunks_exact(4)
        .enumerate()
        .map(|(i, l)| {
            let w = (i % 5) as f32;
            VmfMixture::new([l[0], l[1], l[2], l[3]], [1.0, w, 0.5, 2.0 - w * 0.3]).unwrap()
        })
        .collect();
    let queries: Vec<VmfQuery> = (0..n)
        .map(|i| {
            let w = Vec3::new((i % 13) as f32 - 6.0, 1.0, (i % 5) as f32).normalize();
            VmfQuery::new(
                w,
                Vec2::new((i % 1009) as f32 / 1009.0, (i % 997) as f32 / 997.0),
            )
        })
        .collect();
    let mixtures = ctx.storage_buffer("mixtures", &pack_mixtures(&mixtures));
    let queries = ctx.storage_buffer("queries", &queries);
    let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
    let choices: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("choices", n);
    bench_entries(
        c,
        ctx,
        "vmf_mixture",
        &[
            kernels::VMF_MIXTURE,
            VMF_MIXTURE,
            &all_binding_entry_points(
                "samples",
                &[
                    "mixture_pdf",
                    "textbook_pdf_sum",
                    "mixture_sample",
                    "linear_cdf_walk",
                ],
            ),
        ]
        .concat(),
        &[
            ("mixture_pdf", "mixture_pdf"),
            ("baseline_textbook_pdf_sum", "textbook_pdf_sum"),
            ("mixture_sample_with_pdf", "mixture_sample"),
            ("baseline_linear_cdf_walk_textbook", "linear_cdf_walk"),
        ],
        &[mixtures.raw(), queries.raw(), samples.raw(), choices.raw()],
        n as u32,
    );
}

const PLAIN_CLEAR: &str = r#"
struct Table {
    capacity: u32,
}
struct AgeParams {
    frame: u32,
    max_age: u32,
}
@group(0) @binding(0) var<uniform> table: Table;
// The table's words: checksums, then ages (`mcg_hashgrid_words` of the library's kernel).
@group(0) @binding(1) var<storage, read_write> words: array<u32>;
@group(0) @binding(2) var<uniform> age_params: AgeParams;

// Naive: one pass, stale slots set empty (no tombstones, so probe runs may break; no count).
@compute @workgroup_size(64)
fn plain_clear(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = id.x + id.y * groups.x * 64u;
    if slot < table.capacity && age_params.frame - words[table.capacity + slot] > age_params.max_age {
        words[slot] = 0u;
    }
}
"#;

fn hash_evict(c: &mut Criterion, ctx: &GpuContext) {
    let capacity = 1_u32 << 18;
    let mut cpu = HashTable::<u32>::new(capacity, 16, BucketHash::Mix)
        .unwrap()
        .with_age_tracking();
    for k in 0..100_000_i32 {
        if k % 6250 == 0 {
            cpu.advance_frame();
        }
        let key = CellKey::new(IVec3::new(k % 64, (k / 64) % 64, k / 4096), 2, 0);
        let _ = cpu.insert_or_get(&key);
    }
    let initial = [cpu.checksums(), cpu.ages()].concat();
    let table = ctx.uniform_buffer(
        "table",
        &HashgridTableParams::new(capacity, 16, BucketHash::Mix)
            .unwrap()
            .at_offsets(0, capacity),
    );
    let words = ctx.storage_buffer("words", &initial);
    let params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(cpu.frame(), 7));
    let counter: GpuBuffer<u32> = ctx.zeroed_buffer("counter", 1);
    let kernel =
        |source: &str, entry: &str| ctx.compute_kernel(&kernels::plain(source), entry).unwrap();
    let (evict, trim) = (
        kernel(kernels::HASHGRID_AGES, "hashgrid_evict"),
        kernel(kernels::HASHGRID_AGES, "hashgrid_trim"),
    );
    let clear = kernel(PLAIN_CLEAR, "plain_clear");
    let bindings = [table.raw(), words.raw(), params.raw(), counter.raw()];
    let mut g = c.benchmark_group("hash_evict");
    g.bench_function("evict_and_trim", |b| {
        b.iter(|| {
            ctx.write(&words, &initial).unwrap();
            ctx.dispatch(&evict, &bindings, capacity).unwrap();
            ctx.dispatch(&trim, &bindings[..2], capacity).unwrap();
        })
    });
    g.bench_function("baseline_plain_clear", |b| {
        b.iter(|| {
            ctx.write(&words, &initial).unwrap();
            ctx.dispatch(&clear, &bindings[..3], capacity).unwrap();
        })
    });
    g.finish();
}

const MARKOV_STATE: &str = r#"
@group(0) @binding(0) var<storage, read> grid_states: array<MarkovGridState>;
@group(0) @binding(1) var<storage, read> pixel_states: array<MarkovPixelState>;
@group(0) @binding(2) var<storage, read> plain: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> out: array<vec4<f32>>;

fn uses_all_bindings() {
    _ = arrayLength(&grid_states);
    _ = arrayLength(&pixel_states);
    _ = arrayLength(&plain);
}

// MCPG: the cell's velocity, count and statistics, and its lobe with the prior.
fn grid_state_at(i: u32) {
    let s = grid_states[i];
    let x = vec3<f32>(0.1, 0.2, -0.3) + markov_grid_state_velocity(s) * 1e-3;
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    _ = vmf_from_sufficient_stats(markov_grid_state_stats(s), x, VmfMapPrior(0.2, 0.5, 0u), &lobe);
    out[i] = vec4<f32>(lobe.mu, lobe.kappa);
}

// MCMM: the pixel's lobe at x with the prior (`PixelState::lobe`).
fn pixel_state_at(i: u32) {
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    _ = markov_pixel_state_lobe(pixel_states[i], vec3<f32>(0.1, 0.2, -0.3), VmfMapPrior(0.2, 0.5, 0u), &lobe);
    out[i] = vec4<f32>(lobe.mu, lobe.kappa);
}

// Naive: the lobe stored as a plain vec4 (μ, κ).
fn plain_lobe_at(i: u32) {
    out[i] = plain[i];
}
"#;

fn markov_state(c: &mut Criterion, ctx: &GpuContext) {
    let n = 262_144_usize;
    let x = Vec3::new(0.1, 0.2, -0.3);
    let stats: Vec<SufficientStats> = (0..n)
        .map(|i| {
            let mut s = SufficientStats::EMPTY;
            let y = Vec3::new((i % 13) as f32 - 6.0, 4.0, (i % 5) as f32);
            s.update(x, y, 1.0, &FitParams::MCPG);
            s.update(x, y + Vec3::X, 0.5, &FitParams::MCPG);
            s
        })
        .collect();
    let grid: Vec<GridState> = stats
        .iter()
        .enumerate()
        .map(|(i, s)| GridState::from_stats(s, 0.0, Vec3::new((i % 7) as f32, 0.0, 1.0)))
        .collect();
    let pixels: Vec<PixelState> = stats
        .iter()
        .map(|&stats| PixelState { stats, score: 1.0 })
        .collect();
    let plain: Vec<[f32; 4]> = bench_lobes(n, 50.0)
        .iter()
        .map(|l| l.mu().extend(l.kappa()).to_array())
        .collect();
    let grid = ctx.storage_buffer("grid states", &grid);
    let pixels = ctx.storage_buffer("pixel states", &pixels);
    let plain = ctx.storage_buffer("plain lobes", &plain);
    let out: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("out", n);
    bench_entries(
        c,
        ctx,
        "markov_state",
        &[
            &lib(&[Module::Markov, Module::Dispatch]),
            MARKOV_STATE,
            &all_binding_entry_points("out", &["grid_state", "pixel_state", "plain_lobe"]),
        ]
        .concat(),
        &[
            ("mcpg_grid_state_lobe", "grid_state"),
            ("mcmm_pixel_state_lobe", "pixel_state"),
            ("baseline_plain_vec4_lobe", "plain_lobe"),
        ],
        &[grid.raw(), pixels.raw(), plain.raw(), out.raw()],
        n as u32,
    );
}

const CODEC_DECODE: &str = r#"
@group(0) @binding(0) var<storage, read> words: array<u32>;
@group(0) @binding(1) var<storage, read> plain: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;
// Binding 3: `mcg_codec_logluv_tables` (mcg::color_codec_logluv).

fn uses_all_bindings() {
    _ = arrayLength(&words);
    _ = arrayLength(&plain);
    _ = arrayLength(&mcg_codec_logluv_tables);
}
"#;

fn codec_decode(c: &mut Criterion, ctx: &GpuContext) {
    use mcg_color_codec::{ColorCodec, LogLuv32, R11G11B10};
    let n = 262_144_usize;
    let values: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = i as f32 / n as f32;
            Vec3::new(t * 20.0, (1.0 - t) * 3.0, (i % 97) as f32 * 0.01)
        })
        .collect();
    // Half R11G11B10, half LogLuv32 words; every decoder reads them all (any 32 bits are a
    // valid irradiance word).
    let words: Vec<u32> = values
        .iter()
        .enumerate()
        .map(|(i, &v)| match i % 2 {
            0 => R11G11B10.encode(v),
            _ => LogLuv32.encode(v),
        })
        .collect();
    let plain: Vec<[f32; 4]> = values.iter().map(|v| v.extend(1.0).to_array()).collect();
    let words = ctx.storage_buffer("words", &words);
    let plain = ctx.storage_buffer("plain", &plain);
    let out: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("out", n);
    let tables = ctx.storage_buffer("tables", &shaders::constants::logluv_tables());
    bench_entries(
        c,
        ctx,
        "codec_decode",
        &[
            &lib(&[Module::ColorCodecLogluv, Module::Dispatch]),
            CODEC_DECODE,
            &per_element_entries(
                "out",
                &[
                    (
                        "log_irradiance",
                        "out[i] = vec4<f32>(codec_irradiance_decode(words[i]), 1.0);",
                    ),
                    (
                        "logluv",
                        "out[i] = vec4<f32>(codec_logluv32_unpack(words[i]), 1.0);",
                    ),
                    (
                        "r11g11b10",
                        "out[i] = vec4<f32>(codec_r11g11b10_unpack(words[i]), 1.0);",
                    ),
                    // Naive: the colour loaded unencoded, 16 bytes instead of 4.
                    ("vec4_load", "out[i] = plain[i];"),
                ],
            ),
        ]
        .concat(),
        &[
            ("log_irradiance", "log_irradiance"),
            ("logluv32", "logluv"),
            ("r11g11b10", "r11g11b10"),
            ("baseline_vec4_load", "vec4_load"),
        ],
        &[words.raw(), plain.raw(), out.raw(), tables.raw()],
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
    vmf_stats_update(c, &ctx);
    vmf_ops(c, &ctx);
    vmf_mixture(c, &ctx);
    hash_evict(c, &ctx);
    markov_state(c, &ctx);
    codec_decode(c, &ctx);
}

criterion_group!(gpu, benches);
criterion_main!(gpu);
