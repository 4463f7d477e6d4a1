//! Section "GPU backend": the WGSL twins run on this machine's wgpu adapter and are held to
//! the CPU crates' answers, as the parity tests of `mcg-gpu-backend` do.
//!
//! Without an adapter the section says why and shows nothing else.

use std::time::Instant;

use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::types::VmfQuery;
use mcg_gpu_backend::{CodecKernels, GpuHashTable, HashgridKernels, VmfKernels};
use mcg_hashgrid::{BucketHash, CellKey, ConcurrentTable, HashTable, checksum, hash_mix};
use mcg_vmf::Vmf;
use mcg_vmf::glam::{IVec3, Vec2, Vec3};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Context;
use crate::Result;
use crate::report::{Section, Table};

/// Builds the section.
pub fn build(ctx: &Context<'_>) -> Result<Section> {
    let mut section = Section::new("gpu-backend", "GPU backend: WGSL twins in parity");
    section.paragraph(
        "`mcg-gpu-backend` ships every primitive as WGSL (vMF lobes, hash-grid keys and tables, \
         packed colour words) with constants generated from the Rust crates. Here the twins run \
         on this machine's wgpu adapter and their results are compared with the CPU crates on \
         the same inputs: hashes, table contents and packed words must match bit for bit; vMF \
         densities go through the GPU's exp and log and are compared by relative error.",
    );
    let gpu = match GpuContext::new() {
        Ok(gpu) => gpu,
        Err(e) => {
            section.paragraph(&format!("Skipped: {e}."));
            return Ok(section);
        }
    };
    let info = gpu.adapter_info();
    section.paragraph(&format!(
        "Adapter: {} ({:?}, {:?}). On a software adapter (lavapipe) the timings are CPU \
         numbers, shown only as orders of magnitude.",
        info.name, info.backend, info.device_type
    ));
    let n = (ctx.config.samples / 4).clamp(4_096, 262_144);
    let mut rng = Pcg64Mcg::seed_from_u64(ctx.config.seed);
    let mut table = Table::new(
        "CPU/GPU parity on this adapter",
        [
            "check",
            "inputs",
            "result",
            "GPU time (incl. upload, read-back)",
        ],
    );

    table.push_row(vmf_pdf_row(&gpu, &mut rng, n)?);
    for row in hashgrid_rows(&gpu, &mut rng, n)? {
        table.push_row(row);
    }
    table.push_row(logluv_row(&gpu, &mut rng, n)?);
    section.table(table);
    section.paragraph(
        "The full parity suites (`cargo test -p mcg-gpu-backend --test gpu --test twins`) add \
         sampling, reconstruction from sufficient statistics, products, convolutions and \
         mixtures, all bucket hashes, static-grid keys and jittered vertices, table outcomes \
         one by one including the full table, eviction by age, every packed colour word \
         (LogLuv32 over every luminance boundary and every code), the concurrent moving average \
         of shared texels, and the MCPG grid and MCMM pixel states.",
    );
    Ok(section)
}

/// One table row: `check`, `inputs`, `result`, `GPU time`.
type Row = [String; 4];

/// vMF densities of `n` lobes on the GPU against the CPU, by relative error.
fn vmf_pdf_row(gpu: &GpuContext, rng: &mut Pcg64Mcg, n: usize) -> Result<Row> {
    let lobes: Vec<Vmf> = (0..n)
        .map(|i| {
            let mu = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                0.5,
            );
            Vmf::new(mu, [0.1_f32, 3.0, 50.0, 1e4][i % 4]).expect("valid lobe")
        })
        .collect();
    let queries: Vec<VmfQuery> = lobes
        .iter()
        .map(|l| {
            let u = Vec2::new(rng.random(), rng.random());
            VmfQuery::new(l.sample(u), u)
        })
        .collect();
    let kernels = VmfKernels::new();
    let t = Instant::now();
    let (pdfs, _) = kernels.pdf_and_sample(gpu, &lobes, &queries)?;
    let dt = t.elapsed();
    let worst = lobes
        .iter()
        .zip(&queries)
        .zip(&pdfs)
        .map(|((l, q), g)| {
            let c = f64::from(l.pdf(q.direction));
            (f64::from(*g) - c).abs() / c.max(1e-30)
        })
        .fold(0.0_f64, f64::max);
    Ok([
        "vMF pdf, κ ∈ {0.1, 3, 50, 10⁴}".to_owned(),
        n.to_string(),
        format!("largest relative error {worst:.1e}"),
        format!("{:.1} ms", dt.as_secs_f64() * 1e3),
    ])
}

/// Racing inserts into a GPU table against the CPU's key set, and the bucket hash and
/// checksum bit for bit.
fn hashgrid_rows(gpu: &GpuContext, rng: &mut Pcg64Mcg, n: usize) -> Result<[Row; 2]> {
    let keys: Vec<CellKey> = (0..n)
        .map(|_| {
            let c = IVec3::new(
                rng.random_range(-50..50),
                rng.random_range(-50..50),
                rng.random_range(-50..50),
            );
            CellKey::new(c, rng.random_range(0..8), rng.random_range(0..6))
        })
        .collect();
    let capacity = (2 * n as u32).next_power_of_two();
    let empty = HashTable::<u32>::new(capacity, 32, BucketHash::Mix)?;
    let table_gpu = GpuHashTable::upload(gpu, &empty)?;
    let t = Instant::now();
    let outcomes = table_gpu.insert_or_get(gpu, &keys)?;
    let dt = t.elapsed();
    let words = table_gpu.read_checksums(gpu)?;
    let cpu = ConcurrentTable::new(capacity, 32, BucketHash::Mix)?;
    for k in &keys {
        let _ = cpu.insert_or_get(k);
    }
    let mut a: Vec<u32> = words.iter().copied().filter(|&w| w > 1).collect();
    let mut b: Vec<u32> = cpu
        .into_checksums()
        .into_iter()
        .filter(|&w| w > 1)
        .collect();
    a.sort_unstable();
    b.sort_unstable();
    let slots_ok = keys
        .iter()
        .zip(&outcomes)
        .filter(|(k, o)| o.slot().is_some_and(|s| words[s as usize] == checksum(k)))
        .count();
    let inserts = [
        "racing insert-or-get: same key set as the CPU".to_owned(),
        format!("{n} inserts, {} distinct keys", b.len()),
        format!(
            "{}; {slots_ok}/{n} outcomes point at their checksum",
            if a == b { "identical" } else { "DIFFERENT" }
        ),
        format!("{:.1} ms", dt.as_secs_f64() * 1e3),
    ];

    let hash_kernels = HashgridKernels::new();
    hash_kernels.hashes(gpu, &keys[..1])?; // builds the pipeline outside the timing
    let t = Instant::now();
    let hashes = hash_kernels.hashes(gpu, &keys)?;
    let dt = t.elapsed();
    let same = keys
        .iter()
        .zip(&hashes)
        .filter(|(k, h)| h[1] == hash_mix(k) && h[3] == checksum(k))
        .count();
    let hashes_row = [
        "pcg4d bucket hash and checksum, bit for bit".to_owned(),
        n.to_string(),
        format!("{same}/{n} identical"),
        format!("{:.1} ms", dt.as_secs_f64() * 1e3),
    ];
    Ok([inserts, hashes_row])
}

/// LogLuv32: the CPU encodes in f64, the GPU decides the same codes exactly in f32.
fn logluv_row(gpu: &GpuContext, rng: &mut Pcg64Mcg, n: usize) -> Result<Row> {
    let colours: Vec<Vec3> = (0..n)
        .map(|_| {
            let base = rng.random_range(-40.0..40.0_f32);
            Vec3::from_array([0; 3].map(|_| (base + rng.random_range(-6.0..6.0_f32)).exp2()))
        })
        .collect();
    let words: Vec<u32> = (0..n).map(|_| rng.random()).collect();
    let codec_kernels = CodecKernels::new();
    codec_kernels.logluv(gpu, &colours[..1], &words[..1])?; // builds the pipeline
    let t = Instant::now();
    let reads = codec_kernels.logluv(gpu, &colours, &words)?;
    let dt = t.elapsed();
    let same = colours
        .iter()
        .zip(&reads)
        .filter(|(c, r)| r.packed[0] == mcg_color_codec::LogLuv32::pack_xyz(**c))
        .count();
    Ok([
        "LogLuv32 words (f64 on the CPU, exact f32 on the GPU), bit for bit".to_owned(),
        n.to_string(),
        format!("{same}/{n} identical"),
        format!("{:.1} ms", dt.as_secs_f64() * 1e3),
    ])
}
