//! CPU/GPU parity of the second set of twins: the vMF mixture and convolution, the static-grid
//! key and the jittered vertex, the age counter (eviction of stale cells), MCMM's pixel state.
//! Skips without an adapter (fails with `MCG_REQUIRE_GPU=1`), like `tests/gpu.rs`.

use glam::{Vec2, Vec3};
use mcg_gpu_backend::kernels::{
    CodecKernels, GpuHashTable, HashgridKernels, MarkovKernels, VmfKernels, VmfMixtureKernel,
};
use mcg_gpu_backend::prelude;
use mcg_gpu_backend::types::{HashgridJitterQuery, VmfQuery, mixture_stride_floats, pack_mixtures};
use mcg_hashgrid::{BucketHash, CellKey, HashTable, StaticGrid, jittered_vertex};
use mcg_markov_guide::mcmm::PixelState;
use mcg_vmf::{FitParams, MapPrior, PriorDecay, SufficientStats, Vmf, VmfMixture};
use rand::RngExt;

/// The shift of frame and ages in the wrap-around run of the eviction test: frames 0..12
/// become u32::MAX − 5 .. 6, wrapping past 0.
const WRAP_SHIFT: u32 = u32::MAX - 5;

mod common;
use common::{EPS, KAPPAS, gpu_and_rng, random_key, random_unit, tolerance};

/// `VmfMixture<4>` pdf, component choice and `sample_with_pdf` on 8 192 mixtures (fixed seed;
/// κ from the switch-point list, weights with zeros, uniforms incl. 0 and 1 − ε/2).
/// Hypotheses: the component index and the rescaled uniform are bit-exact (only +, −, one
/// division and comparisons, all correctly rounded on lavapipe); the pdf is within
/// Σ wᵢ Vᵢ(ω) tolᵢ + 4ε of the CPU's, tolᵢ = `tolerance::pdf` of each lobe; the sampled
/// direction within `tolerance::direction` of the CPU's sample of the chosen lobe with the
/// same uniforms; the sample's pdf within the pdf tolerance of the CPU's mixture pdf at the
/// GPU's direction. Broken once on purpose (the WGSL select rescaled with `u / weight`
/// instead of `(u − start)/weight`): failed.
#[test]
fn vmf_mixture_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_mixture_matches_the_cpu", 29) else {
        return;
    };
    let n = 8192;
    let mut mixtures = Vec::with_capacity(n);
    let mut queries = Vec::with_capacity(n);
    for i in 0..n {
        let lobes = [0; 4].map(|_| {
            Vmf::new(
                random_unit(&mut rng),
                KAPPAS[rng.random_range(0..KAPPAS.len())],
            )
            .unwrap()
        });
        let mut weights = [0; 4].map(|_| rng.random_range(0.0..3.0_f32));
        if i % 3 == 0 {
            weights[rng.random_range(0..4)] = 0.0;
        }
        weights[i % 4] += 0.1;
        mixtures.push(VmfMixture::new(lobes, weights).unwrap());
        let u = match i % 64 {
            0 => Vec2::ZERO,
            1 => Vec2::splat(1.0 - f32::EPSILON / 2.0),
            _ => Vec2::new(rng.random(), rng.random()),
        };
        queries.push(VmfQuery::new(random_unit(&mut rng), u));
    }
    let evals = VmfMixtureKernel::<4>::new(ctx)
        .unwrap()
        .eval(ctx, &mixtures, &queries)
        .unwrap();
    // The pdf tolerance of the mixture at `w`: each lobe's tolerance, weighted.
    let pdf_tolerance = |m: &VmfMixture<4>, w: Vec3| -> f64 {
        let mut tol = 0.0;
        for (lobe, &weight) in m.lobes().iter().zip(m.weights()) {
            let kappa = f64::from(lobe.kappa());
            let exponent = 0.5 * kappa * f64::from((w - lobe.mu()).length_squared());
            let flush = f64::from(lobe.normalization()) * 2.0 * f64::from(f32::MIN_POSITIVE);
            tol += f64::from(weight)
                * (tolerance::pdf(kappa, exponent) * f64::from(lobe.pdf(w)) + flush);
        }
        tol + 4.0 * EPS * f64::from(m.pdf(w))
    };
    let (mut worst_pdf, mut worst_dir) = (0.0_f64, 0.0_f64);
    for i in 0..n {
        let (m, q) = (&mixtures[i], queries[i]);
        let (index, u) = m.select(q.uniforms.x);
        let e = evals[i];
        assert_eq!(
            (e.component, e.u.to_bits()),
            (index, u.to_bits()),
            "{i}: component choice of u = {}",
            q.uniforms.x
        );
        let cpu = f64::from(m.pdf(q.direction));
        let tol = pdf_tolerance(m, q.direction);
        let gpu_pdf = e.pdf;
        let err = (f64::from(gpu_pdf) - cpu).abs();
        assert!(err <= tol, "{i}: pdf GPU {gpu_pdf} CPU {cpu} (tol {tol})");
        worst_pdf = worst_pdf.max(err / tol);
        let lobe = m.lobes()[index];
        let w = lobe.sample(Vec2::new(u, q.uniforms.y));
        assert_eq!(w, m.sample(q.uniforms), "the CPU reuses the uniform");
        let kappa = f64::from(lobe.kappa());
        let r = f64::from(lobe.mu().dot(w)) - 1.0;
        let dr = tolerance::cos_theta_minus_one(kappa, f64::from(q.uniforms.y), r);
        let tol_dir = tolerance::direction(dr);
        let g = e.sample;
        let err_dir = f64::from((g.direction - w).length());
        assert!(
            err_dir <= tol_dir,
            "{i}: sample GPU {} CPU {w} (tol {tol_dir})",
            g.direction
        );
        worst_dir = worst_dir.max(err_dir / tol_dir);
        let at = f64::from(m.pdf(g.direction));
        let tol_p = pdf_tolerance(m, g.direction);
        assert!(
            (f64::from(g.pdf) - at).abs() <= tol_p,
            "{i}: sample pdf GPU {} CPU {at}",
            g.pdf
        );
    }
    println!(
        "mixture parity ({n} mixtures of 4): choices bit-exact; largest error / tolerance: \
         pdf {worst_pdf:.3}, direction {worst_dir:.3}"
    );
}

/// `Vmf::convolve` and `kappa_from_mean_cosine_exact` on 4 096 lobes × kernels and 4 096 mean
/// cosines in (0, 1) (fixed seed, κ from the switch-point list, r dense near 0 and 1).
/// Hypothesis: μ is copied bit for bit and κ' agrees within the propagated error of the
/// inputs' A₃ on the GPU: |Δκ'| ≤ (ΔA(κ) A(κ_k) + A(κ) ΔA(κ_k) + ΔA(κ') + 4ε)/A₃'(κ') +
/// 4·10⁻⁷ κ' (the two Newton stops), ΔA = `tolerance::mean_cosine`, and the same for the
/// inverse alone (ΔA(κ') + 2ε over the slope). Broken once on purpose (the WGSL inverse
/// returned Banerjee's approximation without Newton steps): failed.
#[test]
fn vmf_convolution_matches_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_convolution_matches_the_cpu", 31) else {
        return;
    };
    let n = 4096;
    let lobes: Vec<Vmf> = (0..n)
        .map(|i| Vmf::new(random_unit(&mut rng), KAPPAS[i % KAPPAS.len()]).unwrap())
        .collect();
    let params: Vec<[f32; 2]> = (0..n)
        .map(|i| {
            let kernel = match i % 5 {
                0 => -1.0,
                1 => KAPPAS[(i / 5) % KAPPAS.len()],
                _ => 10f32.powf(rng.random_range(-3.0..5.0)),
            };
            let r = match i % 3 {
                0 => rng.random::<f32>(),
                1 => 1.0 - 10f32.powf(rng.random_range(-7.0..0.0)),
                _ => 10f32.powf(rng.random_range(-8.0..0.0)),
            };
            [kernel, r]
        })
        .collect();
    let (kernel_kappas, mean_cosines): (Vec<f32>, Vec<f32>) =
        params.iter().map(|&[k, r]| (k, r)).unzip();
    let (convolved, kappas) = VmfKernels::new(ctx)
        .unwrap()
        .convolve(ctx, &lobes, &kernel_kappas, &mean_cosines)
        .unwrap();
    let a = |k: f64| f64::from(mcg_vmf::mean_cosine_from_kappa(k as f32));
    // dA₃/dκ in f64: 1/κ² − 1/sinh²κ (series near 0).
    let slope = |k: f64| {
        if k < 1e-3 {
            1.0 / 3.0 - k * k / 15.0
        } else {
            1.0 / (k * k) - 1.0 / k.sinh().powi(2)
        }
    };
    let (mut worst_conv, mut worst_inv) = (0.0_f64, 0.0_f64);
    for i in 0..n {
        let [kk, r] = params[i];
        let cpu = lobes[i].convolve(kk);
        let g = convolved[i];
        assert_eq!(g.mu(), cpu.mu(), "{i}: μ");
        let (k, kk, k2) = (
            f64::from(lobes[i].kappa()),
            f64::from(kk.max(0.0)),
            f64::from(cpu.kappa()),
        );
        let da = tolerance::mean_cosine(k) * a(kk)
            + a(k) * tolerance::mean_cosine(kk)
            + tolerance::mean_cosine(k2)
            + 4.0 * EPS;
        let tol = (da / slope(k2).max(1e-300)).min(1e7) + 4e-7 * k2 + 1e-30;
        let err = (f64::from(g.kappa()) - k2).abs();
        assert!(
            err <= tol,
            "{i}: κ {k} ⊛ {kk}: GPU {} CPU {k2} (tol {tol})",
            g.kappa()
        );
        worst_conv = worst_conv.max(err / tol);
        let cpu = f64::from(mcg_vmf::kappa_from_mean_cosine_exact(r));
        let tol = ((tolerance::mean_cosine(cpu) + 2.0 * EPS) / slope(cpu).max(1e-300)).min(1e7)
            + 4e-7 * cpu
            + 1e-30;
        let err = (f64::from(kappas[i]) - cpu).abs();
        assert!(
            err <= tol,
            "{i}: κ(r = {r}): GPU {} CPU {cpu} (tol {tol})",
            kappas[i]
        );
        worst_inv = worst_inv.max(err / tol);
    }
    println!(
        "convolution parity ({n}): largest error / tolerance: convolved κ {worst_conv:.3}, \
         exact inverse {worst_inv:.3}"
    );
}

/// `StaticGrid::vertex_key` and `jittered_vertex` on 20 000 positions over 10⁻³..10⁶ scene
/// units with three cell widths (25, 0.37, 3), uniforms incl. 0, 1 − ε/2, 1, negatives and the ties u = 1 − f:
/// keys and vertices bit for bit. Broken once on purpose (the WGSL jittered vertex compared
/// u > 1 − f instead of ≥): failed.
#[test]
fn static_keys_and_jittered_vertices_match_the_cpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("static_keys_and_jittered_vertices_match_the_cpu", 37)
    else {
        return;
    };
    let specials = [0.0, 1.0 - f32::EPSILON / 2.0, 1.0, -0.5, 0.5];
    let queries: Vec<HashgridJitterQuery> = (0..20_000)
        .map(|i| {
            let scale = [1e-3_f32, 1.0, 1e3, 1e6][i % 4];
            let position = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * scale;
            // Exact multiples of the width too (fraction 0).
            let width = [25.0_f32, 0.37, 3.0][i % 3];
            let position = if i % 17 == 0 {
                (position / width).round() * width
            } else {
                position
            };
            let mut u = [rng.random(), rng.random(), rng.random(), rng.random()];
            if i % 11 == 0 {
                u[i % 4] = specials[(i / 11) % specials.len()];
            }
            // Ties of the jitter: u = 1 − f exactly (f = k/8), where ⌊q + u⌋ steps up.
            let (position, u) = if i % 23 == 0 {
                let k = (i / 23 % 7 + 1) as f32;
                let p = position.floor() + Vec3::splat(k / 8.0);
                (p, [u[0], 1.0 - k / 8.0, 1.0 - k / 8.0, 1.0 - k / 8.0])
            } else {
                (position, u)
            };
            HashgridJitterQuery {
                position,
                u_corner: u[0],
                u_jitter: Vec3::new(u[1], u[2], u[3]),
                width,
            }
        })
        .collect();
    let (keys, jittered) = HashgridKernels::new()
        .static_vertices(ctx, &queries)
        .unwrap();
    for (i, q) in queries.iter().enumerate() {
        let grid = StaticGrid::new(q.width).unwrap();
        assert_eq!(keys[i], grid.vertex_key(q.position, q.u_corner), "{q:?}");
        let v = jittered_vertex(q.position, q.u_jitter);
        assert_eq!(jittered[i], v, "{q:?}");
    }
}

/// The age counter. (1) Serial insert-and-touch on the GPU of 120 keys (a third already in
/// the table) into an age-tracked `HashTable` uploaded as is gives the CPU's checksums and
/// ages slot for slot and the same number of `Inserted`. (2) Eviction: tables of 2 048 slots
/// filled over 12 frames (each frame a random subset touched, some keys removed, so
/// tombstones exist), evicted on the GPU in two passes with max_age 0, 3, 7 and 100 end with
/// the CPU's checksum array after `evict_older_than` (tombstones trimmed alike) and the same
/// count, for both slot indexers (mask and modulo); and again for max_age 3 and 7 with frame
/// and ages shifted by `WRAP_SHIFT` (frame wrapped past u32::MAX to 6, ages on both sides of
/// the wrap): the wrapping rule frame − age > max_age gives the same result. All through
/// `GpuHashTable::{insert_or_get_touch_serial, evict_older_than, insert_or_get_touch}`. (3) 4 096
/// racing insert-and-touch invocations leave every key's slot aged to the frame and no other
/// slot changed. Broken once on purpose (the WGSL trim cleared a tombstone followed by any
/// non-occupied slot without walking the run): the checksum arrays differed and the test
/// failed. Broken once more (the WGSL staleness test without wrapping,
/// `frame >= age && frame − age > max_age`): the wrapped run evicted 484 instead of 782 and
/// the test failed.
#[test]
fn age_counter_evicts_the_cpu_cells() {
    let Some((ctx, mut rng)) = gpu_and_rng("age_counter_evicts_the_cpu_cells", 41) else {
        return;
    };
    for capacity in [2048_u32, 2039] {
        let hash = BucketHash::Mix;
        let mut cpu = HashTable::<u32>::new(capacity, 16, hash)
            .unwrap()
            .with_age_tracking();
        let pool: Vec<CellKey> = (0..1500).map(|_| random_key(&mut rng)).collect();
        for frame in 0..12 {
            for k in &pool {
                if rng.random_bool([0.3, 0.05][frame % 2]) {
                    cpu.insert_or_get(k);
                }
            }
            for k in &pool[..40] {
                if rng.random_bool(0.1) {
                    cpu.remove(k);
                }
            }
            cpu.advance_frame();
        }
        // (1) serial insert-and-touch, slot for slot.
        {
            let keys: Vec<CellKey> = pool[..40]
                .iter()
                .copied()
                .chain((0..80).map(|_| random_key(&mut rng)))
                .collect();
            let mut after = cpu.clone();
            let inserted = keys
                .iter()
                .filter(|k| after.insert_or_get(k).is_inserted())
                .count();
            let gpu = GpuHashTable::upload(ctx, &cpu).unwrap();
            let ages = ctx.storage_buffer("ages", cpu.ages());
            let gpu_inserted = gpu
                .insert_or_get_touch_serial(ctx, &ages, &keys, cpu.frame())
                .unwrap();
            assert_eq!(gpu.read_checksums(ctx).unwrap(), after.checksums());
            assert_eq!(ctx.read_back(&ages).unwrap(), after.ages());
            assert_eq!(gpu_inserted as usize, inserted);
        }
        // (2) eviction in two passes (`GpuHashTable::evict_older_than`).
        // Run once as is and once with frame and ages shifted by `WRAP_SHIFT` (wrapping): the
        // shifted ages straddle u32::MAX and the frame has wrapped past 0, and the documented
        // rule (frame − age > max_age, wrapping) gives the CPU's result on the unshifted
        // table, whose frame cannot be set.
        for (max_age, shift) in [
            (0, 0),
            (3, 0),
            (7, 0),
            (100, 0),
            (3, WRAP_SHIFT),
            (7, WRAP_SHIFT),
        ] {
            let mut after = cpu.clone();
            let evicted = after.evict_older_than(max_age);
            let gpu = GpuHashTable::upload(ctx, &cpu).unwrap();
            let shifted: Vec<u32> = cpu.ages().iter().map(|a| a.wrapping_add(shift)).collect();
            let ages = ctx.storage_buffer("ages", &shifted);
            let frame = cpu.frame().wrapping_add(shift);
            assert_eq!(
                gpu.evict_older_than(ctx, &ages, frame, max_age).unwrap(),
                evicted,
                "evicted, max_age {max_age}, frame {frame}"
            );
            assert_eq!(
                gpu.read_checksums(ctx).unwrap(),
                after.checksums(),
                "checksums after eviction, capacity {capacity}, max_age {max_age}, frame {frame}"
            );
            if shift != 0 {
                assert!(frame < cpu.frame() && shifted.iter().any(|&a| a > frame));
            }
            if max_age == 3 {
                assert!(evicted > 0 && after.tombstones() < cpu.tombstones() + evicted);
            }
        }
        // (3) racing insert-and-touch.
        {
            let keys: Vec<CellKey> = (0..4096)
                .map(|_| pool[rng.random_range(0..pool.len())])
                .collect();
            let gpu = GpuHashTable::upload(ctx, &cpu).unwrap();
            let ages = ctx.storage_buffer("ages", cpu.ages());
            let frame = cpu.frame().wrapping_add(1);
            gpu.insert_or_get_touch(ctx, &ages, &keys, frame).unwrap();
            let words = gpu.read_checksums(ctx).unwrap();
            let gpu_ages = ctx.read_back(&ages).unwrap();
            let wanted: std::collections::HashSet<u32> =
                keys.iter().map(mcg_hashgrid::checksum).collect();
            for slot in 0..capacity as usize {
                if wanted.contains(&words[slot]) {
                    assert_eq!(gpu_ages[slot], frame, "slot {slot} not touched");
                } else {
                    assert_eq!(words[slot], cpu.checksums()[slot], "slot {slot}");
                    assert_eq!(gpu_ages[slot], cpu.ages()[slot], "slot {slot}");
                }
            }
        }
    }
}

/// MCMM pixel states built on the CPU and uploaded as they are (`Pod`, 28 bytes): validity,
/// resampling score and sample count bit for bit, and the lobe at a shading point with a
/// fixed prior: "no lobe" exactly where the CPU says `None`, μ within 64 ε and κ within
/// 64 ε relative (arithmetic only, as in the reconstruction test of `tests/gpu.rs`), on 4 096
/// states incl. empty, negative-score and infinite ones. Broken once on purpose (the WGSL
/// validity check without the score's sign): failed.
#[test]
fn pixel_states_read_the_same_on_the_gpu() {
    let Some((ctx, mut rng)) = gpu_and_rng("pixel_states_read_the_same_on_the_gpu", 43) else {
        return;
    };
    let x = Vec3::new(0.1, 0.2, -0.3);
    let states: Vec<PixelState> = (0..4096)
        .map(|i| {
            let mut stats = SufficientStats::EMPTY;
            for _ in 0..(i % 30) {
                stats.update(
                    x,
                    random_unit(&mut rng) * 2.0 + Vec3::Y * 5.0,
                    rng.random_range(0.0..3.0),
                    &FitParams::MCMM,
                );
            }
            let score = match i % 13 {
                0 => -1.0,
                1 => f32::INFINITY,
                2 => 0.0,
                _ => rng.random_range(0.0..10.0),
            };
            if i % 29 == 0 {
                stats.weight_sum = f32::INFINITY;
            }
            if i % 31 == 0 {
                stats.mean_target = x;
            }
            PixelState { stats, score }
        })
        .collect();
    let prior = MapPrior {
        mean_cosine: 0.2,
        weight: 0.5,
        decay: PriorDecay::SquaredCount,
    };
    let reads = MarkovKernels::new()
        .pixel_states(ctx, &states, x, prior)
        .unwrap();
    let mut found = 0;
    for (i, s) in states.iter().enumerate() {
        let r = reads[i];
        assert_eq!(
            (r.resampling_score, r.is_valid),
            (s.resampling_score(), s.is_valid()),
            "{i}: {s:?}"
        );
        assert_eq!(r.sample_count, s.stats.sample_count as f32, "{i}");
        match (s.lobe(x, prior), r.lobe) {
            (None, None) => {}
            (Some(lobe), Some((mu, kappa))) => {
                found += 1;
                assert!((mu - lobe.mu()).length() <= 64.0 * f32::EPSILON, "{i}: μ");
                let k = f64::from(lobe.kappa());
                assert!(
                    (f64::from(kappa) - k).abs() <= 64.0 * EPS * k.max(1e-30),
                    "{i}: κ {kappa} vs {k}"
                );
            }
            (cpu, gpu) => panic!("{i}: CPU lobe {cpu:?}, GPU lobe {gpu:?}"),
        }
    }
    assert!(found > 2500, "{found} lobes");
}

/// `VmfMixtureKernel::<K>` for K = 1 and 3 (the kernel's `VMF_MIXTURE_K` replaced on the
/// host): on 512 mixtures each (fixed seed, κ in [0.5, 50], weights in (0.1, 3)), the
/// component and the rescaled uniform equal the CPU's bit for bit and the pdf is within
/// 10⁻⁴ relative (κ ≤ 50 keeps `tolerance::pdf` below 10⁻⁴, see the K = 4 test). A wrong K
/// misreads the packed layout and fails. Broken once on purpose (the host left K at 4):
/// failed.
#[test]
fn vmf_mixture_kernel_takes_any_k() {
    let Some((ctx, mut rng)) = gpu_and_rng("vmf_mixture_kernel_takes_any_k", 53) else {
        return;
    };
    fn check<const K: usize>(ctx: &mcg_gpu_backend::GpuContext, rng: &mut impl rand::Rng) {
        let mixtures: Vec<VmfMixture<K>> = (0..512)
            .map(|_| {
                let lobes = [0; K]
                    .map(|_| Vmf::new(random_unit(rng), rng.random_range(0.5..50.0)).unwrap());
                VmfMixture::new(lobes, [0; K].map(|_| rng.random_range(0.1..3.0))).unwrap()
            })
            .collect();
        let queries: Vec<VmfQuery> = (0..512)
            .map(|_| VmfQuery::new(random_unit(rng), Vec2::new(rng.random(), rng.random())))
            .collect();
        let evals = VmfMixtureKernel::<K>::new(ctx)
            .unwrap()
            .eval(ctx, &mixtures, &queries)
            .unwrap();
        for ((m, q), e) in mixtures.iter().zip(&queries).zip(&evals) {
            let (index, u) = m.select(q.uniforms.x);
            assert_eq!(
                (e.component, e.u.to_bits()),
                (index, u.to_bits()),
                "K = {K}"
            );
            let cpu = m.pdf(q.direction);
            assert!(
                (e.pdf - cpu).abs() <= 1e-4 * cpu + 1e-30,
                "K = {K}: pdf GPU {} CPU {cpu}",
                e.pdf
            );
        }
    }
    check::<1>(ctx, &mut rng);
    check::<3>(ctx, &mut rng);
}

/// Empty inputs: `GpuHashTable::{insert_or_get, insert_or_get_serial, find,
/// insert_or_get_touch, insert_or_get_touch_serial}` with no keys return nothing and leave
/// the checksum and age arrays as the CPU table has them (the kernels' buffers are padded to
/// one zeroed element, which must not be read as a key). Broken once on purpose (the early
/// return for no keys removed from `GpuHashTable::run`): the serial insert wrote the zero
/// key and the test failed.
#[test]
fn empty_key_lists_change_nothing() {
    let Some((ctx, _)) = gpu_and_rng("empty_key_lists_change_nothing", 0) else {
        return;
    };
    let mut cpu = HashTable::<u32>::new(64, 8, BucketHash::Mix)
        .unwrap()
        .with_age_tracking();
    let _ = cpu.insert_or_get(&CellKey::new(glam::IVec3::ONE, 1, 0));
    let gpu = GpuHashTable::upload(ctx, &cpu).unwrap();
    let ages = ctx.storage_buffer("ages", cpu.ages());
    assert!(gpu.insert_or_get_serial(ctx, &[]).unwrap().is_empty());
    assert!(gpu.insert_or_get(ctx, &[]).unwrap().is_empty());
    assert!(gpu.find(ctx, &[]).unwrap().is_empty());
    assert_eq!(
        gpu.insert_or_get_touch_serial(ctx, &ages, &[], 5).unwrap(),
        0
    );
    assert_eq!(gpu.insert_or_get_touch(ctx, &ages, &[], 5).unwrap(), 0);
    assert_eq!(gpu.read_checksums(ctx).unwrap(), cpu.checksums());
    assert_eq!(ctx.read_back(&ages).unwrap(), cpu.ages());
}

/// `pack_mixtures` writes the layout the WGSL struct has for K = 4 (checked against naga in
/// `tests/wgsl.rs` for K = 1..=5): lobes, then weights, then padding.
#[test]
fn packed_mixtures_have_the_wgsl_layout() {
    let m = VmfMixture::new(
        [
            Vmf::new(Vec3::X, 1.0).unwrap(),
            Vmf::new(Vec3::Y, 2.0).unwrap(),
        ],
        [1.0, 3.0],
    )
    .unwrap();
    let packed = pack_mixtures(&[m, m]);
    assert_eq!(mixture_stride_floats(2), 12);
    assert_eq!(packed.len(), 24);
    assert_eq!(
        packed[..12],
        [1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 2.0, 0.25, 0.75, 0.0, 0.0]
    );
}

/// LogLuv32 (`pack_xyz`, `encode`, `unpack_xyz`, `decode`) bit for bit. Encode: 65 536
/// luminance boundaries (Y = 2ᵉ·T[k] and the float below it for every exponent e of the
/// range and every log₂ step k, so every Le boundary is crossed), 40 000 colours
/// log-uniform over 2⁻⁷⁰..2⁷⁰ per component (saturated and near-grey chromaticities), the
/// luminance bounds ± one ulp, zeros, negatives, NaN and infinities. Decode: every Le code
/// (0..2¹⁵) with random chromaticities, with and without the sign bit. Hypothesis: words and
/// decoded values equal the CPU's exactly (the decoder's `exp2` is the CPU's, table-driven, and
/// its divisions are correctly rounded on lavapipe). Broken once on purpose (the chroma
/// candidate not corrected by the exact sign test): words differed and the test failed.
#[test]
fn logluv32_matches_the_cpu_bit_for_bit() {
    let Some((ctx, mut rng)) = gpu_and_rng("logluv32_matches_the_cpu_bit_for_bit", 47) else {
        return;
    };
    use mcg_color_codec::{ColorCodec, LogLuv32};
    let log2_steps = &prelude::logluv_tables()[..256];
    let mut values: Vec<[f32; 4]> = Vec::new();
    for e in -64..64_i32 {
        for &t in log2_steps {
            for m in [t, f32::from_bits(t.to_bits() - 1)] {
                let y = m * 2f32.powi(e);
                let x = y * rng.random_range(0.0..2.0_f32);
                let z = y * rng.random_range(0.0..2.0_f32);
                values.push([x, y, z, 0.0]);
            }
        }
    }
    for _ in 0..40_000 {
        let mut v = [0.0; 4];
        let base = rng.random_range(-70.0..70.0_f32);
        for c in v.iter_mut().take(3) {
            *c = (base + rng.random_range(-8.0..8.0_f32)).exp2();
        }
        values.push(v);
    }
    let specials = [
        0.0,
        -1.0,
        1.0,
        f32::NAN,
        f32::INFINITY,
        1.837_197_6e19,
        1.837_197_7e19,
        1.837_197_5e19,
        5.413_676_9e-20,
        5.413_677e-20,
        5.413_676_8e-20,
        1e-30,
        3e38,
    ];
    for &a in &specials {
        for &b in &specials {
            for &c in &[0.0, 1.0, 1e30, f32::INFINITY] {
                values.push([a, b, c, 0.0]);
            }
        }
    }
    let mut words: Vec<u32> = (0..1u32 << 15)
        .map(|le| (le << 16) | rng.random_range(0..1u32 << 16))
        .collect();
    words.extend((0..2000).map(|_| rng.random::<u32>() | (1 << 31)));
    while words.len() < values.len() {
        words.push(rng.random());
    }
    values.resize(words.len(), [0.0; 4]);
    let colours: Vec<Vec3> = values.iter().map(|v| Vec3::from_slice(&v[..3])).collect();
    let reads = CodecKernels::new().logluv(ctx, &colours, &words).unwrap();
    for (i, ((&v, &w), read)) in colours.iter().zip(&words).zip(&reads).enumerate() {
        assert_eq!(
            read.packed,
            [LogLuv32::pack_xyz(v), LogLuv32.encode(v)],
            "{i}: pack of {v:?}"
        );
        assert_eq!(
            read.xyz,
            LogLuv32::unpack_xyz(w),
            "{i}: unpack_xyz of {w:#010x}"
        );
        assert_eq!(read.rgb, LogLuv32.decode(w), "{i}: decode of {w:#010x}");
    }
}
