//! CPU/GPU parity of `mcg::markov`: MCPG grid states and MCMM pixel states, read and written.
//!
//! Runs on whatever wgpu adapter exists (lavapipe in CI); every test skips with a printed
//! reason when there is no adapter, and fails instead when `MCG_REQUIRE_GPU=1` (CI sets it).
//! Hashes, checksums, table outcomes, packed words and states must match bit for bit; the
//! vMF lobes go through `exp` and `log`, which WGSL only bounds loosely, so they are compared
//! within tolerances derived from WGSL's precision rules (see `common::tolerance`).

use glam::Vec3;
use mcg_gpu_backend::MarkovKernels;
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_markov_guide::mcmm::PixelState;
use mcg_test_support::assert_close;
use mcg_vmf::{FitParams, MapPrior, PriorDecay, SufficientStats, Vmf};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;

mod common;
use common::{EPS, gpu_and_rng, random_unit};

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

/// MCMM pixel states built on the CPU and uploaded as they are (`Pod`, 28 bytes): validity,
/// resampling score and sample count bit for bit, and the lobe at a shading point with a
/// fixed prior: "no lobe" exactly where the CPU says `None`, μ within 64 ε and κ within
/// 64 ε relative (arithmetic only, as in the reconstruction test of `tests/parity_vmf.rs`), on 4 096
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
        found += usize::from(assert_same_lobe(i, s.lobe(x, prior), r.lobe));
    }
    assert!(found > 2500, "{found} lobes");
}

/// The velocities the f16 packing must round like `half`: ties to even at every exponent
/// (normal and subnormal), the subnormal/normal boundary, the largest half, values beyond it,
/// signed zeros, and non-finite components (the whole velocity stores 0).
fn f16_edge_velocities() -> Vec<Vec3> {
    let mut out = Vec::new();
    for e in -26..16 {
        let base = 2f32.powi(e);
        for m in [
            1.0,
            1.0 + 2f32.powi(-11),
            1.0 + 3.0 * 2f32.powi(-11),
            1.5,
            1.999,
        ] {
            let v = base * m;
            out.push(Vec3::new(v, -v, v * 0.75));
        }
    }
    let boundary = 2f32.powi(-14);
    out.extend([
        Vec3::new(
            boundary * (1.0 - 2f32.powi(-12)),
            boundary * (1.0 - 2f32.powi(-11)),
            65504.0,
        ),
        Vec3::new(65519.0, -65520.0, 1e9),
        Vec3::new(-0.0, 0.0, 5.960_464_5e-8),
        Vec3::new(2.980_232_2e-8, 8.940_697e-8, 1e-30),
        Vec3::new(f32::NAN, 1.0, 2.0),
        Vec3::new(1.0, f32::INFINITY, 2.0),
    ]);
    out
}

/// Grid states packed on the GPU (`markov_grid_state_pack`) equal `GridState::from_stats` bit
/// for bit, and pixel states equal `PixelState { stats, score }`: 4 096 random statistics
/// (counts up to 70 000, past the u16 clamp) with random velocities, plus every velocity of
/// [`f16_edge_velocities`]. Hypothesis: the f16 rounding is exact integer arithmetic and the
/// rest is copying, so nothing may differ. Broken once on purpose (rounding ties away from
/// zero, `+ 0x1000u` instead of the ties-to-even increment): failed.
#[test]
fn grid_and_pixel_states_written_on_the_gpu_match_the_cpu() {
    use mcg_gpu_backend::types::MarkovGridWrite;
    use mcg_markov_guide::mcpg::GridState;
    let Some((ctx, mut rng)) = gpu_and_rng("grid_states_written_on_the_gpu", 71) else {
        return;
    };
    let mut writes: Vec<MarkovGridWrite> = (0..4096)
        .map(|i| {
            let mut stats = SufficientStats::EMPTY;
            for _ in 0..(i % 20) {
                stats.update(
                    Vec3::ZERO,
                    random_unit(&mut rng) * 3.0 + Vec3::Z * 5.0,
                    rng.random(),
                    &FitParams::MCPG,
                );
            }
            stats.sample_count = rng.random_range(0..70_000);
            let velocity = random_unit(&mut rng) * 10f32.powf(rng.random_range(-9.0..6.0));
            MarkovGridWrite {
                stats,
                time: rng.random_range(0.0..1e4),
                velocity,
            }
        })
        .collect();
    let edges = f16_edge_velocities();
    let n_random = writes.len();
    let stats = writes[7].stats;
    writes.extend(edges.iter().map(|&velocity| MarkovGridWrite {
        stats,
        time: 1.0,
        velocity,
    }));
    let (grid, pixel) = MarkovKernels::new().write_states(ctx, &writes).unwrap();
    for (i, w) in writes.iter().enumerate() {
        let cpu = GridState::from_stats(&w.stats, w.time, w.velocity);
        assert_eq!(
            bytemuck::bytes_of(&grid[i]),
            bytemuck::bytes_of(&cpu),
            "{i} (random below {n_random}): velocity {:?} → GPU {:?}, CPU {:?}",
            w.velocity,
            grid[i].velocity(),
            cpu.velocity()
        );
        let cpu = PixelState {
            stats: w.stats,
            score: w.time,
        };
        assert_eq!(
            bytemuck::bytes_of(&pixel[i]),
            bytemuck::bytes_of(&cpu),
            "{i}"
        );
    }
}

/// Grid states queried on the GPU: `is_valid` and `resampling_weight` bit for bit,
/// `predicted(now)` (MCPG eq. 10) bit for bit (the product is kept from fusing with the sum),
/// and the lobe at a shading point within 64 ε (μ) and 64 ε relative (κ), "no lobe" exactly
/// where the CPU says `None`; 4 096 states incl. empty, infinite-weight, NaN-target and
/// coincident-target ones, with velocities up to 10³ and times on both sides of `now`. Broken
/// once on purpose (prediction with `now + time` instead of `now − time`): failed.
#[test]
fn grid_state_queries_match_the_cpu() {
    use mcg_gpu_backend::types::MarkovGridQuery;
    use mcg_markov_guide::mcpg::GridState;
    let Some((ctx, mut rng)) = gpu_and_rng("grid_state_queries_match_the_cpu", 73) else {
        return;
    };
    let x = Vec3::new(0.1, 0.2, -0.3);
    let now = 37.25;
    let states: Vec<GridState> = (0..4096)
        .map(|i| {
            let mut stats = SufficientStats::EMPTY;
            for _ in 0..(i % 25) {
                stats.update(
                    x,
                    random_unit(&mut rng) * 2.0 + Vec3::Y * 5.0,
                    rng.random_range(0.0..3.0),
                    &FitParams::MCPG,
                );
            }
            match i % 37 {
                0 => stats.weight_sum = f32::INFINITY,
                1 => stats.mean_target = Vec3::new(f32::NAN, 0.0, 0.0),
                2 => stats.mean_target = x,
                _ => {}
            }
            let velocity = random_unit(&mut rng) * rng.random_range(0.0..1e3);
            GridState::from_stats(&stats, rng.random_range(0.0..80.0), velocity)
        })
        .collect();
    let prior = MapPrior {
        mean_cosine: 0.3,
        weight: 0.2,
        decay: PriorDecay::Count,
    };
    let reads = MarkovKernels::new()
        .grid_state_queries(ctx, &states, &MarkovGridQuery::new(x, now, prior))
        .unwrap();
    let mut found = 0;
    for (i, s) in states.iter().enumerate() {
        let r = reads[i];
        assert_eq!(
            (r.is_valid, r.resampling_weight),
            (s.is_valid(), s.resampling_weight()),
            "{i}"
        );
        assert_eq!(
            bytemuck::bytes_of(&r.predicted),
            bytemuck::bytes_of(&s.predicted(now)),
            "{i}: predicted {:?} vs {:?}",
            r.predicted.mean_target,
            s.predicted(now).mean_target
        );
        found += usize::from(assert_same_lobe(i, s.lobe(x, prior), r.lobe));
    }
    assert!(found > 3000, "{found} lobes");
}

/// The GPU's lobe of state `i` against the CPU's: "no lobe" exactly where the CPU says `None`,
/// else μ within 64 ε and κ within 64 ε relative (arithmetic only, no `exp`/`log`). Returns
/// whether there was a lobe.
fn assert_same_lobe(i: usize, cpu: Option<Vmf>, gpu: Option<(Vec3, f32)>) -> bool {
    match (cpu, gpu) {
        (None, None) => false,
        (Some(lobe), Some((mu, kappa))) => {
            assert!((mu - lobe.mu()).length() <= 64.0 * f32::EPSILON, "{i}: μ");
            let k = f64::from(lobe.kappa());
            assert_close!(f64::from(kappa), k, 64.0 * EPS * k.max(1e-30), "{i}: κ");
            true
        }
        (cpu, gpu) => panic!("{i}: CPU lobe {cpu:?}, GPU lobe {gpu:?}"),
    }
}
