//! The host side: a headless, featureless context; a context on the renderer's own device;
//! length errors; two hash tables side by side in one shader.
//!
//! Runs on whatever wgpu adapter exists (lavapipe in CI); every test skips with a printed
//! reason when there is no adapter, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::types::{HashgridTableParams, VmfQuery};
use mcg_gpu_backend::{GpuBuffer, GpuContext, VmfKernels};
use mcg_hashgrid::{BucketHash, CellKey, HashTable, Insert};
use mcg_test_support::assert_close;
use mcg_vmf::Vmf;

mod common;
use common::{gpu_and_rng, random_key};

/// The context reports its adapter; `GpuContext::new` asks for no features.
#[test]
fn context_is_headless_and_featureless() {
    let Some(ctx) = gpu_or_skip("context_is_headless_and_featureless") else {
        return;
    };
    let info = ctx.adapter_info();
    println!(
        "adapter: {} ({:?}, {:?})",
        info.name, info.backend, info.device_type
    );
    assert_eq!(ctx.device().features(), wgpu_features_empty());
    let _: &GpuContext = ctx;
}

fn wgpu_features_empty() -> mcg_gpu_backend::wgpu::Features {
    mcg_gpu_backend::wgpu::Features::empty()
}

/// `GpuContext::from_device` runs the crate's host types on a device the renderer made with
/// plain wgpu calls (here: the shared context's own device and queue, cloned), and length
/// mismatches come back as `GpuError::LengthMismatch` instead of panics.
#[test]
fn host_types_run_on_the_renderers_own_device() {
    use mcg_gpu_backend::GpuError;
    let Some(shared) = gpu_or_skip("host_types_run_on_the_renderers_own_device") else {
        return;
    };
    let ctx = GpuContext::from_device(shared.device().clone(), shared.queue().clone()).unwrap();
    assert!(ctx.adapter().is_none());
    assert_eq!(ctx.adapter_info().name, shared.adapter_info().name);
    let lobes = [Vmf::new(Vec3::Z, 10.0).unwrap(); 3];
    let queries = [VmfQuery::new(Vec3::Z, Vec2::new(0.25, 0.5)); 3];
    let kernels = VmfKernels::new();
    let (pdfs, _) = kernels.pdf_and_sample(&ctx, &lobes, &queries).unwrap();
    let cpu = lobes[0].pdf(Vec3::Z);
    assert_close!(pdfs[0], cpu, 1e-4 * cpu);
    assert_eq!(
        kernels.pdf_and_sample(&ctx, &lobes, &queries[..2]),
        Err(GpuError::LengthMismatch {
            expected: 3,
            found: 2
        })
    );
    let buffer: mcg_gpu_backend::GpuBuffer<u32> = ctx.zeroed_buffer("words", 4);
    assert_eq!(
        ctx.write(&buffer, &[1, 2, 3]),
        Err(GpuError::LengthMismatch {
            expected: 4,
            found: 3
        })
    );
}

/// A user's shader (composed by naga_oil from `#import mcg::hashgrid_table::…`) holds two
/// tables side by side in the one `mcg_hashgrid_words` array — an adaptive grid of 256 slots
/// (xor-primes hash, power-of-two mask) at offset 0 and a static grid of 97 slots (mix hash,
/// modulo) after it — and inserts the same 600 keys into both, serially. Hypothesis: both
/// regions end bit for bit as two separate CPU `HashTable`s after the same inserts, and every
/// outcome is the CPU's (a table descriptor whose offset were ignored would make the second
/// table overwrite the first).
#[test]
fn two_tables_share_one_words_array_in_a_users_shader() {
    use mcg_gpu_backend::naga_oil::compose::{Composer, NagaModuleDescriptor, ShaderDefValue};
    use mcg_gpu_backend::shaders::{self, defs};
    let Some((ctx, mut rng)) = gpu_and_rng("two_tables_share_one_words_array", 97) else {
        return;
    };
    let user = r#"
#import mcg::hashgrid::{HashgridCellKey, HashgridTable, hashgrid_checksum, hashgrid_home_slot}
#import mcg::hashgrid_table::hashgrid_insert_or_get

@group(0) @binding(0) var<storage, read> tables: array<HashgridTable, 2>;
@group(0) @binding(2) var<storage, read> keys: array<HashgridCellKey>;
@group(0) @binding(3) var<storage, read_write> results: array<vec4<u32>>;

@compute @workgroup_size(64)
fn two_tables(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x != 0u {
        return;
    }
    for (var i = 0u; i < arrayLength(&keys); i += 1u) {
        let key = keys[i];
        let a = hashgrid_insert_or_get(tables[0], hashgrid_home_slot(tables[0], key), hashgrid_checksum(key));
        let b = hashgrid_insert_or_get(tables[1], hashgrid_home_slot(tables[1], key), hashgrid_checksum(key));
        results[i] = vec4<u32>(a.slot, a.outcome, b.slot, b.outcome);
    }
}
"#;
    let mut composer = Composer::default();
    shaders::add_to_composer(&mut composer).unwrap();
    let module = composer
        .make_naga_module(NagaModuleDescriptor {
            source: user,
            file_path: "two_tables.wgsl",
            shader_defs: [
                (defs::HASHGRID_GROUP.to_string(), ShaderDefValue::UInt(0)),
                (defs::HASHGRID_BINDING.to_string(), ShaderDefValue::UInt(1)),
            ]
            .into(),
            ..Default::default()
        })
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&composer)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .unwrap();
    let wgsl =
        naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
            .unwrap();
    let kernel = ctx.compute_kernel(&wgsl, "two_tables").unwrap();

    let (cap_a, cap_b) = (256, 97);
    let mut cpu_a = HashTable::<u32>::new(cap_a, 8, BucketHash::XorPrimes).unwrap();
    let mut cpu_b = HashTable::<u32>::new(cap_b, 8, BucketHash::Mix).unwrap();
    let params = [
        HashgridTableParams::new(cap_a, 8, BucketHash::XorPrimes).unwrap(),
        HashgridTableParams::new(cap_b, 8, BucketHash::Mix)
            .unwrap()
            .at_offsets(cap_a, 0),
    ];
    let keys: Vec<CellKey> = (0..600).map(|_| random_key(&mut rng)).collect();
    let tables = ctx.storage_buffer("tables", &params);
    let words: GpuBuffer<u32> = ctx.zeroed_buffer("words", (cap_a + cap_b) as usize);
    let keys_buffer = ctx.storage_buffer("keys", &keys);
    let results: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("results", keys.len());
    ctx.dispatch(
        &kernel,
        &[tables.raw(), words.raw(), keys_buffer.raw(), results.raw()],
        1,
    )
    .unwrap();
    let results = ctx.read_back(&results).unwrap();
    let words = ctx.read_back(&words).unwrap();
    let outcome = |slot, code| mcg_gpu_backend::codes::insert(slot, code).unwrap();
    let (mut full_a, mut full_b) = (0, 0);
    for (key, r) in keys.iter().zip(&results) {
        let (a, b) = (cpu_a.insert_or_get(key), cpu_b.insert_or_get(key));
        assert_eq!(outcome(r[0], r[1]), a, "{key:?} in table a");
        assert_eq!(outcome(r[2], r[3]), b, "{key:?} in table b");
        full_a += usize::from(a == Insert::Full);
        full_b += usize::from(b == Insert::Full);
    }
    assert_eq!(&words[..cap_a as usize], cpu_a.checksums());
    assert_eq!(&words[cap_a as usize..], cpu_b.checksums());
    // The keys overfill the small table, so both the inserted and the full paths ran.
    assert!(
        full_b > 0 && full_a < full_b,
        "full: a {full_a}, b {full_b}"
    );
}
