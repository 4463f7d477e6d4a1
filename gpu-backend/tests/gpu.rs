//! CPU/GPU parity on whatever wgpu adapter exists (lavapipe in CI): the same inputs fed to
//! the CPU crates and to the WGSL twins. Every test skips with a printed reason when there
//! is no adapter, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).
//!
//! Hashes, checksums, table outcomes and packed words must match bit for bit. The vMF lobes
//! go through `exp` and `log`, which WGSL only bounds loosely, so they are compared within
//! tolerances derived from WGSL's precision rules (see `common::tolerance`).

use glam::{IVec3, Vec2, Vec3};
use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::kernels::{
    CodecKernels, GpuHashTable, GpuTexels, HashgridKernels, MarkovKernels, VmfKernels,
};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_gpu_backend::types::{
    HashgridLevelParams, HashgridTableParams, HashgridVertexQuery, TexelParams, TexelUpdate,
    VmfQuery, VmfStatsQuery, VmfUpdate,
};
use mcg_hashgrid::{
    AdaptiveGrid, BucketHash, CellKey, ConcurrentTable, HashTable, Insert, checksum, hash_mix,
    hash_mix_coherent, hash_xor_primes, normal_class, stochastic_trilinear,
};
use mcg_vmf::{FitParams, MapPrior, PriorDecay, SufficientStats, Vmf};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

mod common;
use common::{EPS, KAPPAS, gpu_and_rng, random_key, random_unit, tolerance};

/// vMF pdf and `sample_with_pdf` on 22 × 512 lobes, queries and uniform pairs (fixed seed),
/// incl. uniforms 0 and 1 − ε: every GPU value within the [`tolerance`] of the CPU's.
/// Reports the largest error as a fraction of its tolerance. Broken once on purpose (the
/// WGSL pdf used `exp(-lobe.kappa * distance_squared)`, dropping the ½): failed.
#[test]
fn vmf_pdf_and_samples_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_pdf_and_samples_match_the_cpu", 7) else {
        return;
    };
    let mut lobes = Vec::new();
    let mut queries = Vec::new();
    for &kappa in &KAPPAS {
        for j in 0..512 {
            let lobe = Vmf::new(random_unit(&mut rng), kappa).unwrap();
            // Directions near the mean (where the pdf is large) and anywhere.
            let w = if j % 2 == 0 {
                lobe.sample(Vec2::new(rng.random(), rng.random()))
            } else {
                random_unit(&mut rng)
            };
            let u = match j {
                0 => Vec2::ZERO,
                1 => Vec2::splat(1.0 - f32::EPSILON / 2.0),
                _ => Vec2::new(rng.random(), rng.random()),
            };
            lobes.push(lobe);
            queries.push(VmfQuery::new(w, u));
        }
    }
    let kernels = VmfKernels::new(ctx).unwrap();
    let (pdfs, samples) = kernels.pdf_and_sample(ctx, &lobes, &queries).unwrap();
    let (mut worst_pdf, mut worst_dir, mut worst_spdf) = (0.0_f64, 0.0_f64, 0.0_f64);
    for i in 0..lobes.len() {
        let (lobe, q) = (lobes[i], queries[i]);
        let kappa = f64::from(lobe.kappa());
        // pdf
        let cpu = f64::from(lobe.pdf(q.direction));
        let exponent = 0.5 * kappa * f64::from((q.direction - lobe.mu()).length_squared());
        // WGSL may flush subnormals: exp(·) below f32::MIN_POSITIVE may become 0 before the
        // multiplication by C(κ).
        let flush = f64::from(lobe.normalization()) * 2.0 * f64::from(f32::MIN_POSITIVE);
        let tol = tolerance::pdf(kappa, exponent) * cpu + flush;
        let err = (f64::from(pdfs[i]) - cpu).abs();
        assert!(
            err <= tol,
            "pdf κ = {kappa}, ω = {}: GPU {} CPU {cpu}, tolerance {tol}",
            q.direction,
            pdfs[i]
        );
        worst_pdf = worst_pdf.max(err / tol);
        // sample
        let (w, p) = lobe.sample_with_pdf(q.uniforms);
        let r = f64::from(lobe.mu().dot(w)) - 1.0;
        let dr = tolerance::cos_theta_minus_one(kappa, f64::from(q.uniforms.y), r);
        let tol_dir = tolerance::direction(dr);
        let g = samples[i];
        let err_dir = f64::from((g.direction - w).length());
        assert!(
            err_dir <= tol_dir,
            "sample κ = {kappa}, u = {}: GPU {} CPU {w}, |Δ| {err_dir} > {tol_dir}",
            q.uniforms,
            g.direction
        );
        worst_dir = worst_dir.max(err_dir / tol_dir);
        let tol_p =
            (tolerance::normalization(kappa) + tolerance::exp_of_product(kappa * r) + kappa * dr)
                * f64::from(p)
                + flush;
        let err_p = (f64::from(g.pdf) - f64::from(p)).abs();
        assert!(
            err_p <= tol_p,
            "sample pdf κ = {kappa}, u = {}: GPU {} CPU {p}, tolerance {tol_p}",
            q.uniforms,
            g.pdf
        );
        worst_spdf = worst_spdf.max(err_p / tol_p);
    }
    println!(
        "vMF parity on {} ({} lobes): largest error / tolerance: pdf {worst_pdf:.3}, \
         sample direction {worst_dir:.3}, sample pdf {worst_spdf:.3}",
        ctx.adapter_info().name,
        lobes.len()
    );
}

/// Reconstruction from sufficient statistics (MCMM/MCPG Alg. 2), products and the mean
/// cosine round trip on 2 000 fits (fixed seed): μ within 64 ε, κ within 64 ε relative (no
/// exp/log on that path: only +, −, ×, ÷ and sqrt), "no lobe" exactly where the CPU says
/// `None`; product scale within the tolerance of its three C(κ) and one exp; A₃(κ) within
/// the error of its expm1. Broken once on purpose (N instead of N² in the WGSL posterior):
/// failed.
#[test]
fn vmf_reconstruction_and_products_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_reconstruction_and_products_match_the_cpu", 11)
    else {
        return;
    };
    let mut stats = Vec::new();
    let mut queries = Vec::new();
    for i in 0..2000 {
        let x = Vec3::new(rng.random(), rng.random(), rng.random());
        let mut s = SufficientStats::EMPTY;
        let light = Vec3::new(
            rng.random_range(-5.0..5.0),
            4.0,
            rng.random_range(-5.0..5.0),
        );
        let spread = [0.01_f32, 0.3, 3.0][i % 3];
        let params = if i % 2 == 0 {
            FitParams::MCMM
        } else {
            FitParams::MCPG
        };
        for _ in 0..(i % 40) {
            let y = light + random_unit(&mut rng) * spread * rng.random::<f32>();
            s.update(x, y, rng.random_range(0.0..2.0), &params);
        }
        if i % 97 == 0 {
            s.mean_target = x; // ȳ = x: no lobe.
        }
        let prior = MapPrior {
            mean_cosine: [0.0, 0.3][i % 2],
            weight: [0.0, 0.2, 1.0, f32::INFINITY][i % 4],
            decay: if i % 5 == 0 {
                PriorDecay::Count
            } else {
                PriorDecay::SquaredCount
            },
        };
        let other = Vmf::new(random_unit(&mut rng), KAPPAS[i % KAPPAS.len()]).unwrap();
        let kappa = KAPPAS[(i / 3) % KAPPAS.len()];
        stats.push(s);
        queries.push(VmfStatsQuery::new(x, prior, other, kappa));
    }
    let results = VmfKernels::new(ctx)
        .unwrap()
        .stats(ctx, &stats, &queries)
        .unwrap();
    let mut lobes = 0;
    for (i, (s, q)) in stats.iter().zip(&queries).enumerate() {
        let prior = MapPrior {
            mean_cosine: q.prior_mean_cosine,
            weight: q.prior_weight,
            decay: if q.prior_decay == 1 {
                PriorDecay::Count
            } else {
                PriorDecay::SquaredCount
            },
        };
        let g = results[i];
        match s.to_vmf(q.shading_point, prior) {
            None => assert_eq!(g.reconstructed[3], -1.0, "{i}: GPU found a lobe, CPU none"),
            Some(lobe) => {
                lobes += 1;
                let mu = Vec3::from_slice(&g.reconstructed[..3]);
                assert!(
                    (mu - lobe.mu()).length() <= 64.0 * f32::EPSILON,
                    "{i}: μ {mu} vs {}",
                    lobe.mu()
                );
                let k = f64::from(lobe.kappa());
                assert!(
                    (f64::from(g.reconstructed[3]) - k).abs() <= 64.0 * EPS * k,
                    "{i}: κ {} vs {k}",
                    g.reconstructed[3]
                );
                // Product with `other`, from the CPU's lobe.
                let (p, scale) = lobe.product(&q.other);
                let pk = f64::from(p.kappa());
                assert!(
                    (f64::from(g.product[3]) - pk).abs() <= 64.0 * EPS * pk.max(1.0),
                    "{i}: product κ"
                );
                let pmu = Vec3::from_slice(&g.product[..3]);
                assert!(
                    (pmu - p.mu()).length() <= 1e-4,
                    "{i}: product μ {pmu} vs {}",
                    p.mu()
                );
                let exponent = pk - k - f64::from(q.other.kappa());
                let tol = tolerance::normalization(k)
                    + tolerance::normalization(f64::from(q.other.kappa()))
                    + tolerance::normalization(pk)
                    + tolerance::exp_of_product(exponent.min(0.0))
                    // κ' − κ₀ − κ₁ cancels: its absolute error is a few ε of the κs.
                    + 64.0 * EPS * (k + pk)
                    + 8.0 * EPS;
                let err = (f64::from(g.product_scale) - f64::from(scale)).abs();
                assert!(
                    err <= tol * f64::from(scale) + 1e-30,
                    "{i}: scale {} vs {scale}",
                    g.product_scale
                );
            }
        }
        let kappa = q.kappa;
        let a = mcg_vmf::mean_cosine_from_kappa(kappa);
        let kd = f64::from(kappa);
        let tol = tolerance::mean_cosine(kd);
        assert!(
            (f64::from(g.mean_cosine) - f64::from(a)).abs() <= tol,
            "A₃({kappa}): {} vs {a}",
            g.mean_cosine
        );
        // Banerjee's κ of the GPU's own A₃ (arithmetic only) matches the CPU's of the same r.
        let kb = mcg_vmf::kappa_from_mean_cosine(g.mean_cosine);
        assert!(
            (f64::from(g.kappa_back) - f64::from(kb)).abs() <= 64.0 * EPS * f64::from(kb).max(1.0),
            "κ(A₃) {} vs {kb}",
            g.kappa_back
        );
    }
    assert!(lobes > 1500, "{lobes} lobes");
}

/// One `SufficientStats::update` (MCMM Alg. 3, MCPG Alg. 3) from 4 096 states (fits of
/// 0..40 samples, both mean-cosine updates, incl. rejected negative and infinite weights and
/// y = x): N exact; w̄ within 8 ε relative (three roundings of positive terms and the 2.5-ULP
/// division 1/N); ȳ within 16 ε (|ȳ| + |y|); 1 − r̄ within 32 ε (√(2t) + e + t) + 400 ε²,
/// where t = 1 − d·μ: the normalisations of d and μ (sqrt and division, ≤ 5 ULP each)
/// perturb |d − μ| by ≤ 16 ε, and the remaining products and the final division add a few ε
/// of e and t. Broken once on purpose (β = α instead of αf/w̄'): failed.
#[test]
fn vmf_stats_update_matches_the_cpu() {
    let Some(ctx) = gpu_or_skip("vmf_stats_update_matches_the_cpu") else {
        return;
    };
    let kernels = VmfKernels::new(ctx).unwrap();
    for params in [FitParams::MCMM, FitParams::MCPG] {
        let mut rng = Pcg64::seed_from_u64(23);
        let mut stats = Vec::new();
        let mut updates = Vec::new();
        for i in 0..4096 {
            let x = Vec3::new(rng.random(), rng.random(), rng.random());
            let light = Vec3::new(
                rng.random_range(-5.0..5.0),
                6.0,
                rng.random_range(-5.0..5.0),
            );
            let spread = [0.001_f32, 0.1, 2.0][i % 3];
            let mut s = SufficientStats::EMPTY;
            for _ in 0..(i % 40) {
                s.update(
                    x,
                    light + random_unit(&mut rng) * spread,
                    rng.random_range(0.0..2.0),
                    &params,
                );
            }
            let y = match i % 50 {
                0 => x,
                _ => light + random_unit(&mut rng) * spread,
            };
            let weight = match i % 97 {
                0 => -1.0,
                1 => f32::INFINITY,
                2 => 0.0,
                _ => rng.random_range(0.0..2.0),
            };
            stats.push(s);
            updates.push(VmfUpdate {
                x,
                weight,
                y,
                _pad: 0.0,
            });
        }
        let gpu = kernels
            .update_stats(ctx, &stats, &updates, &params)
            .unwrap();
        for i in 0..stats.len() {
            let before = stats[i];
            let u = updates[i];
            let mut cpu = before;
            cpu.update(u.x, u.y, u.weight, &params);
            let g = gpu[i];
            assert_eq!(g.sample_count, cpu.sample_count, "{i}");
            let w = f64::from(cpu.weight_sum);
            assert!(
                (f64::from(g.weight_sum) - w).abs() <= 8.0 * EPS * w,
                "{i}: w̄ {} vs {w}",
                g.weight_sum
            );
            let scale = f64::from(before.mean_target.length() + u.y.length());
            assert!(
                f64::from((g.mean_target - cpu.mean_target).length()) <= 16.0 * EPS * scale,
                "{i}: ȳ {} vs {}",
                g.mean_target,
                cpu.mean_target
            );
            let d = (u.y - u.x).normalize_or_zero();
            let mu = if before.weight_sum > 0.0 {
                (before.mean_target - u.x).try_normalize().unwrap_or(d)
            } else {
                d
            };
            let t = 0.5 * f64::from((d - mu).length_squared());
            let e = f64::from(before.one_minus_mean_cosine);
            let tol = 32.0 * EPS * ((2.0 * t).sqrt() + e + t) + 400.0 * EPS * EPS;
            let c = f64::from(cpu.one_minus_mean_cosine);
            assert!(
                (f64::from(g.one_minus_mean_cosine) - c).abs() <= tol,
                "{i}: 1 − r̄ {} vs {c} (tolerance {tol})",
                g.one_minus_mean_cosine
            );
        }
    }
}

/// Every bucket hash and the checksum, bit for bit, on 20 000 keys incl. extreme coordinates;
/// the stochastic trilinear vertex and normal class bit for bit; the adaptive level equal
/// wherever the CPU's level is not within 10⁻³ of a rounding boundary (the GPU's `log` may
/// differ there). Broken once on purpose (the WGSL pcg4d without its xorshift): failed.
#[test]
fn hashes_checksums_and_vertices_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("hashes_checksums_and_vertices_match_the_cpu", 5) else {
        return;
    };
    let mut keys: Vec<CellKey> = (0..20_000).map(|_| random_key(&mut rng)).collect();
    for c in [i32::MIN, -1, 0, 1, i32::MAX] {
        keys.push(
            CellKey::new(IVec3::new(c, c.wrapping_neg(), c / 3), 255, 255).with_extra(u16::MAX),
        );
    }
    let grid = AdaptiveGrid::mcpg();
    let levels = HashgridLevelParams::from(&grid);
    let queries: Vec<HashgridVertexQuery> = (0..keys.len())
        .map(|_| HashgridVertexQuery {
            position: Vec3::new(
                rng.random_range(-1e3..1e3),
                rng.random_range(-1e3..1e3),
                rng.random_range(-1e3..1e3),
            ) * [1e-3, 1.0, 1e3][rng.random_range(0..3)],
            xi_level: rng.random(),
            normal: random_unit(&mut rng),
            u_corner: rng.random(),
            camera: Vec3::new(rng.random(), rng.random(), rng.random()) * 100.0,
            _pad: 0.0,
        })
        .collect();
    let kernels = HashgridKernels::new();
    let hashes = kernels.hashes(ctx, &keys).unwrap();
    for (k, h) in keys.iter().zip(&hashes) {
        let cpu = [
            hash_xor_primes(k),
            hash_mix(k),
            hash_mix_coherent(k),
            checksum(k),
        ];
        assert_eq!(*h, cpu, "key {k:?}");
    }
    let vertex_keys = kernels.vertex_keys(ctx, &levels, &queries).unwrap();
    let mut level_checked = 0;
    for (q, g) in queries.iter().zip(&vertex_keys) {
        assert_eq!(
            g.cell,
            stochastic_trilinear(q.position, q.u_corner),
            "{q:?}"
        );
        assert_eq!(g.class, normal_class(q.normal), "{q:?}");
        let d = q.camera.distance(q.position);
        let w = grid.target_width(d).max(grid.params().min_width);
        let x = f64::from((w / grid.params().min_width).ln() * levels.levels_per_ln) + 0.5;
        if (x - x.round()).abs() > 1e-3 {
            assert_eq!(u32::from(g.level), grid.level(d, q.xi_level), "{q:?}");
            level_checked += 1;
        }
    }
    assert!(level_checked > queries.len() * 99 / 100);
}

fn table_params_cases() -> Vec<(u32, u32, BucketHash)> {
    let mut cases = Vec::new();
    for hash in BucketHash::ALL {
        cases.push((64, 8, hash)); // power of two: mask
        cases.push((61, 4, hash)); // prime: modulo
    }
    cases
}

/// Serial inserts on the GPU give the CPU's outcomes one by one (`Found`, `Inserted` with
/// the same slot, `Full`), for tables that fill up (100 inserts into 61 or 64 slots), both
/// slot indexers and all bucket hashes; the final checksum arrays are equal. Lookups on a
/// table built on the CPU (with tombstones from removals) and uploaded as is give the CPU's
/// `find`. Broken once on purpose (the WGSL probe stopped at tombstones like at empty
/// slots): failed.
#[test]
fn serial_table_operations_match_the_cpu_outcome_by_outcome() {
    let Some((ctx, mut rng)) = gpu_and_rng(
        "serial_table_operations_match_the_cpu_outcome_by_outcome",
        3,
    ) else {
        return;
    };
    for (capacity, probes, hash) in table_params_cases() {
        let keys: Vec<CellKey> = (0..100).map(|_| random_key(&mut rng)).collect();
        let keys: Vec<CellKey> = keys.iter().chain(&keys[..20]).copied().collect();
        let mut cpu = HashTable::<u32>::new(capacity, probes, hash).unwrap();
        // A few tombstones first.
        for k in &keys[..10] {
            cpu.insert_or_get(k);
        }
        for k in &keys[..10] {
            if rng.random_bool(0.5) {
                cpu.remove(k);
            }
        }
        let gpu = GpuHashTable::upload(ctx, &cpu).unwrap();
        assert_eq!(
            gpu.params(),
            HashgridTableParams::new(capacity, probes, hash).unwrap()
        );
        // Lookups on the uploaded table.
        let found = gpu.find(ctx, &keys).unwrap();
        for (k, f) in keys.iter().zip(&found) {
            assert_eq!(
                *f,
                cpu.find(k),
                "find {k:?} in ({capacity}, {probes}, {hash:?})"
            );
        }
        let outcomes = gpu.insert_or_get_serial(ctx, &keys).unwrap();
        let mut full = 0;
        for (k, g) in keys.iter().zip(&outcomes) {
            let c = cpu.insert_or_get(k);
            assert_eq!(*g, c, "insert {k:?} in ({capacity}, {probes}, {hash:?})");
            full += usize::from(c == Insert::Full);
        }
        assert!(full > 0, "the table should fill up");
        assert_eq!(gpu.read_checksums(ctx).unwrap(), cpu.checksums());
    }
}

/// 65 536 invocations insert keys drawn from 20 000 distinct ones (each inserted ≈ 3 times,
/// racing on the same slots) into a 65 536-slot table, and into a 40 009-slot (prime) one:
/// the GPU table ends with exactly the CPU's key set (as checksums), each key in one slot, one
/// `Inserted` per distinct key, and every outcome's slot holds its key's checksum. Broken
/// once on purpose (the WGSL claim used a plain store instead of the compare-and-swap):
/// racing invocations both reported `Inserted` for one key and the test failed.
#[test]
fn concurrent_inserts_end_with_the_cpu_key_set() {
    let Some((ctx, mut rng)) = gpu_and_rng("concurrent_inserts_end_with_the_cpu_key_set", 9) else {
        return;
    };
    let distinct: Vec<CellKey> = {
        let mut set = std::collections::HashSet::new();
        while set.len() < 20_000 {
            set.insert(random_key(&mut rng));
        }
        let mut v: Vec<CellKey> = set.into_iter().collect();
        v.sort_by_key(|k| k.words());
        v
    };
    let keys: Vec<CellKey> = (0..65_536)
        .map(|_| distinct[rng.random_range(0..distinct.len())])
        .collect();
    for (capacity, hash) in [(65_536, BucketHash::Mix), (40_009, BucketHash::Mix)] {
        let empty = HashTable::<u32>::new(capacity, 32, hash).unwrap();
        let gpu = GpuHashTable::upload(ctx, &empty).unwrap();
        let outcomes = gpu.insert_or_get(ctx, &keys).unwrap();
        let words = gpu.read_checksums(ctx).unwrap();
        let cpu = ConcurrentTable::new(capacity, 32, hash).unwrap();
        for k in &keys {
            assert!(cpu.insert_or_get(k).slot().is_some());
        }
        let mut cpu_set: Vec<u32> = cpu
            .into_checksums()
            .into_iter()
            .filter(|&w| w > 1)
            .collect();
        let mut gpu_set: Vec<u32> = words.iter().copied().filter(|&w| w > 1).collect();
        cpu_set.sort_unstable();
        gpu_set.sort_unstable();
        let used: std::collections::HashSet<CellKey> = keys.iter().copied().collect();
        assert_eq!(gpu_set.len(), used.len(), "each key in exactly one slot");
        assert_eq!(gpu_set, cpu_set, "same key set as the CPU");
        let mut inserted = 0;
        for (k, o) in keys.iter().zip(&outcomes) {
            let slot = o.slot().expect("no insert may fail at this load");
            assert_eq!(words[slot as usize], checksum(k), "{k:?}");
            inserted += usize::from(o.is_inserted());
        }
        assert_eq!(inserted, used.len(), "one Inserted per distinct key");
    }
}

/// R11G11B10, RGB9E5, gamma-5 R10G10B10A2, and the ADGI irradiance (log codec with
/// round-down, nearest and stochastic rounding; count field), visibility and heuristics
/// words bit for bit, and their decoded
/// values exactly, on 50 000 colours over 2⁻³⁰..2¹⁷ (log-uniform), negatives, zeros,
/// overflow, infinities and the rounding ties of the float formats. Broken once on purpose
/// (round-half-up instead of half-even in the WGSL ufloat): failed.
#[test]
fn packed_colour_words_match_the_cpu_bit_for_bit() {
    let Some(ctx) = gpu_or_skip("packed_colour_words_match_the_cpu_bit_for_bit") else {
        return;
    };
    use mcg_color_codec::{
        ColorCodec, Gamma5R10G10B10A2, Heuristics, HeuristicsLayout, IrradianceLayout, R11G11B10,
        Rgb9E5, Rounding, VisibilityLayout,
    };
    let mut rng = Pcg64::seed_from_u64(13);
    let mut values: Vec<[f32; 4]> = (0..50_000)
        .map(|_| {
            let mut v = [0.0_f32; 4];
            for x in v.iter_mut().take(3) {
                *x = (rng.random_range(-30.0_f32..17.0)).exp2();
            }
            v[3] = rng.random();
            v
        })
        .collect();
    let specials = [
        0.0,
        -0.0,
        -1.0,
        1.0,
        65024.0,
        65025.0,
        1e9,
        f32::INFINITY,
        f32::NEG_INFINITY,
        6.1035156e-5,
        1.0 + 1.0 / 128.0,
        1.0 + 3.0 / 128.0,
        1e-40,
    ];
    for &a in &specials {
        for &b in &specials {
            values.push([a, b, 1.5, 0.5]);
        }
    }
    let reads = CodecKernels::new().pack_unpack(ctx, &values).unwrap();
    let irr = IrradianceLayout::ADGI;
    for (i, (v, read)) in values.iter().zip(&reads).enumerate() {
        let rgb = Vec3::new(v[0], v[1], v[2]);
        let count = i as u32 % 64;
        let cpu = [
            R11G11B10::pack(rgb),
            Rgb9E5::pack(rgb),
            Gamma5R10G10B10A2.encode(rgb),
            irr.encode(rgb, count, Rounding::Down).0,
        ];
        assert_eq!(
            read.formats, cpu,
            "R11G11B10, RGB9E5, gamma-5, irradiance (down) of {rgb}"
        );
        let nearest = irr.encode(rgb, count, Rounding::Nearest).0;
        let stochastic = irr.encode(rgb, count, Rounding::Stochastic(v[3])).0;
        let vis = VisibilityLayout::ADGI;
        let moments = Vec2::new(v[0], v[1]);
        let vis_nearest = vis.encode(moments, count, Rounding::Nearest);
        let vis_stochastic = vis.encode(moments, count, Rounding::Stochastic(v[3]));
        assert_eq!(
            read.rounded[2..],
            [vis_nearest.0, vis_stochastic.0],
            "visibility of {moments}, u = {}",
            v[3]
        );
        assert_eq!(
            read.decoded[5][..2],
            vis.decode(vis_nearest).to_array(),
            "visibility decode of {moments}"
        );
        assert_eq!(
            read.rounded[..2],
            [nearest, stochastic],
            "irradiance of {rgb}, u = {}",
            v[3]
        );
        let h = Heuristics {
            f_v: v[0].min(1.0),
            f_s: v[1].min(1.0),
            f_d: v[2].min(1.0),
            flags: count,
        };
        let heu = HeuristicsLayout::ADGI;
        let h_nearest = heu.encode_with(h, Rounding::Nearest);
        let h_stochastic = heu.encode_with(h, Rounding::Stochastic(v[3]));
        assert_eq!(
            read.heuristics[..2],
            [h_nearest.0, h_stochastic.0],
            "heuristics of {h:?}"
        );
        let hd = heu.decode(h_nearest);
        assert_eq!(
            read.decoded[6],
            [hd.f_v, hd.f_s, hd.f_d, hd.flags as f32],
            "heuristics decode of {h:?}"
        );
        let cpu_decoded = [
            R11G11B10::unpack(cpu[0]),
            Rgb9E5::unpack(cpu[1]),
            Gamma5R10G10B10A2.decode(cpu[2]),
            irr.decode(cpu[3].into()),
            irr.decode(nearest.into()),
        ];
        for (k, d) in cpu_decoded.iter().enumerate() {
            assert_eq!(read.decoded[k][..3], d.to_array(), "decode {k} of {rgb}");
        }
    }
}

/// ≈ 65 000 invocations fold samples into 1 056 shared irradiance texels with the
/// compare-and-swap loop, a texel's updates in consecutive invocations (racing). Hypothesis:
/// the result is one that some serial order of the updates gives. With one sample value per
/// texel every order gives the same word, so each texel must equal the CPU's word after the
/// same number of serial updates, and its count exactly that number (1..=62, below N_max)
/// or N_max = 63; the same for visibility words (N_max = 10). Then 65 536 distinct samples
/// into 64 irradiance texels: counts N_max, values within
/// the samples' range (± one quantum). Broken once on purpose (an `atomicStore` of the
/// update instead of the compare-and-swap): lost updates gave counts below the number of
/// updates and the test failed.
#[test]
fn concurrent_texel_updates_match_a_serial_order() {
    let Some(ctx) = gpu_or_skip("concurrent_texel_updates_match_a_serial_order") else {
        return;
    };
    use mcg_color_codec::{IrradianceLayout, IrradianceWord, MovingAverage, Rounding};
    let layout = IrradianceLayout::ADGI;
    let average = MovingAverage::STATIC;
    let mut rng = Pcg64::seed_from_u64(17);
    // 1 024 texels with 1..=62 updates each (below N_max = 63, so every lost update shows in
    // the count) and 32 texels with 1 024 updates each; a texel's updates are consecutive
    // invocations, so they race within and across workgroups.
    let counts: Vec<u32> = (0..1056_u32)
        .map(|t| if t < 1024 { 1 + t % 62 } else { 1024 })
        .collect();
    let texels = counts.len() as u32;
    let per_texel: Vec<Vec3> = (0..texels)
        .map(|_| {
            Vec3::new(
                rng.random_range(0.0..20.0),
                rng.random_range(0.0..2.0),
                rng.random_range(0.0..0.1),
            )
        })
        .collect();
    let mut updates = Vec::new();
    for (t, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            updates.push(TexelUpdate {
                sample: per_texel[t],
                texel: t as u32,
            });
        }
    }
    // Irradiance words (N_max = 63, static) and visibility words (moments = the sample's xy,
    // N_max = 10, dynamic): the GPU's texels after the racing updates, and the CPU's word and
    // count after n serial updates.
    use mcg_color_codec::{VisibilityLayout, VisibilityWord};
    let vis = VisibilityLayout::ADGI;
    let dynamic = MovingAverage::DYNAMIC;
    type Serial<'a> = Box<dyn Fn(u32, Vec3) -> (u32, u32) + 'a>;
    let serial_irradiance: Serial = Box::new(|n, x| {
        let w = (0..n).fold(0, |w, _| average.update(&layout, w, x, Rounding::Nearest));
        (w, layout.count(IrradianceWord(w)))
    });
    let serial_visibility: Serial = Box::new(|n, x| {
        let m = Vec2::new(x.x, x.y);
        let w = (0..n).fold(0, |w, _| dynamic.update(&vis, w, m, Rounding::Nearest));
        (w, vis.count(VisibilityWord(w)))
    });
    for (word_layout, max_count, serial) in [
        (0, average.max_count(), serial_irradiance),
        (1, dynamic.max_count(), serial_visibility),
    ] {
        let params = TexelParams {
            max_count,
            rounding_mode: 1,
            rounding_u: 0.0,
            word_layout,
        };
        let words = GpuTexels::upload(ctx, &vec![0; texels as usize]).unwrap();
        words.update(ctx, &updates, &params).unwrap();
        let gpu = words.read(ctx).unwrap();
        for t in 0..texels as usize {
            let n = counts[t];
            let (cpu, count) = serial(n, per_texel[t]);
            assert_eq!(count, n.min(max_count), "layout {word_layout}, texel {t}");
            assert_eq!(
                gpu[t], cpu,
                "layout {word_layout}, texel {t} after {n} equal updates"
            );
        }
    }
    // Distinct samples: exact counts, values within the samples' range.
    let updates: Vec<TexelUpdate> = (0..65_536_u32)
        .map(|k| TexelUpdate {
            sample: Vec3::splat(rng.random_range(1.0..2.0)),
            texel: k % 64,
        })
        .collect();
    let words = GpuTexels::upload(ctx, &[0; 64]).unwrap();
    let params = TexelParams {
        max_count: average.max_count(),
        rounding_mode: 1,
        rounding_u: 0.0,
        word_layout: 0,
    };
    words.update(ctx, &updates, &params).unwrap();
    for w in words.read(ctx).unwrap() {
        let w = IrradianceWord(w);
        assert_eq!(layout.count(w), average.max_count());
        let v = layout.decode(w);
        assert!(v.min_element() >= 0.97 && v.max_element() <= 2.03, "{v}");
    }
}

/// MCPG grid states built on the CPU and uploaded as they are: the GPU reads the same
/// velocity (three f16, exactly), sample count and sufficient statistics, bit for bit, on
/// 4 096 states incl. saturated and zero velocities. Broken once on purpose (velocity z read
/// from the high half of the last word): failed.
#[test]
fn grid_states_read_the_same_on_the_gpu() {
    let Some(ctx) = gpu_or_skip("grid_states_read_the_same_on_the_gpu") else {
        return;
    };
    use mcg_markov_guide::mcpg::GridState;
    let mut rng = Pcg64::seed_from_u64(19);
    let states: Vec<GridState> = (0..4096)
        .map(|i| {
            let mut s = SufficientStats::EMPTY;
            for _ in 0..(i % 50) {
                s.update(
                    Vec3::ZERO,
                    random_unit(&mut rng) * 3.0 + Vec3::Z * 5.0,
                    rng.random(),
                    &FitParams::MCPG,
                );
            }
            let v = match i % 4 {
                0 => Vec3::ZERO,
                1 => Vec3::splat(1e9),
                _ => random_unit(&mut rng) * rng.random_range(0.0..100.0),
            };
            GridState::from_stats(&s, rng.random(), v)
        })
        .collect();
    let reads = MarkovKernels::new().grid_states(ctx, &states).unwrap();
    for (i, s) in states.iter().enumerate() {
        let v = s.velocity();
        let r = reads[i];
        assert_eq!(
            (r.velocity, r.sample_count),
            (v, s.sample_count()),
            "state {i}"
        );
        assert_eq!(r.stats, s.stats(), "state {i}");
    }
}

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
