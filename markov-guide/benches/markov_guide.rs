//! Criterion benchmarks of mcg-markov-guide, each group with its baseline, per operation (a
//! batch of [`BATCH`] operations per iteration; criterion reports time per element):
//!
//! - `mcmm_update`: MCMM Alg. 3 ([`mcmm::update`]: acceptance, reset, MLE update, copy) vs the
//!   bare MLE step ([`SufficientStats::update`]) it wraps.
//! - `mcpg_resampling`: MCPG Alg. 1 with N_mc = 5 from real hash tables ([`GridEnsemble::load`],
//!   [`prepare_candidate`], [`CandidateSet::offer`]) vs the same reservoir over five states read
//!   from a plain array (no hashing, no probing).
//! - `lobe_reconstruction`: a lobe from sufficient statistics at a shading point with MCPG's
//!   distance prior ([`GridState::lobe`], Alg. 2 lines 6-8) vs [`Vmf::new`] from a given μ and κ.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mcg_markov_guide::glam::Vec3;
use mcg_markov_guide::mcg_vmf::{FitParams, SufficientStats, Vmf};
use mcg_markov_guide::mcmm::{McmmParams, PixelState, update};
use mcg_markov_guide::mcpg::{
    CandidateSet, GridEnsemble, GridKind, GridState, GridUniforms, McpgParams, distance_prior,
    prepare_candidate,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

const BATCH: usize = 1024;

fn random_vec3(rng: &mut Pcg64Mcg, scale: f32) -> Vec3 {
    Vec3::new(
        rng.random::<f32>() - 0.5,
        rng.random::<f32>() - 0.5,
        rng.random::<f32>(),
    ) * scale
}

fn warm_stats(rng: &mut Pcg64Mcg) -> SufficientStats {
    let mut s = SufficientStats::EMPTY;
    for _ in 0..8 {
        s.update(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 3.0) + random_vec3(rng, 0.3),
            1.0 + rng.random::<f32>(),
            &FitParams::MCMM,
        );
    }
    s
}

fn bench_mcmm_update(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let params = McmmParams::PAPER;
    let inputs: Vec<(PixelState, Vec3, f32, bool, f32)> = (0..BATCH)
        .map(|_| {
            let state = PixelState {
                stats: warm_stats(&mut rng),
                score: rng.random::<f32>() * 4.0,
            };
            (
                state,
                Vec3::new(0.0, 0.0, 3.0) + random_vec3(&mut rng, 0.4),
                rng.random::<f32>() * 4.0,
                rng.random::<f32>() < 0.2,
                rng.random(),
            )
        })
        .collect();
    let mut g = c.benchmark_group("mcmm_update");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("mle_step_baseline", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(state, x2, f, _, _) in black_box(&inputs) {
                let mut s = state.stats;
                s.update(Vec3::ZERO, x2, f, &params.fit);
                acc += s.weight_sum;
            }
            acc
        })
    });
    g.bench_function("alg3_update", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(state, x2, f, hemisphere, u) in black_box(&inputs) {
                let (mut s, mut current) = (state, state);
                update(
                    &mut s,
                    &mut current,
                    Vec3::ZERO,
                    x2,
                    f,
                    hemisphere,
                    u,
                    &params,
                );
                acc += current.stats.weight_sum;
            }
            acc
        })
    });
    g.finish();
}

fn bench_mcpg_resampling(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(2);
    let params = McpgParams::PAPER;
    let camera = Vec3::new(0.0, -3.0, 3.0);
    let mut grids = GridEnsemble::new(1 << 16, 4099, params.adaptive_probability).unwrap();
    // Fill the grids around a 1 × 1 patch of the plane, as a warmed-up renderer would.
    for _ in 0..20_000 {
        let x = random_vec3(&mut rng, 1.0) * Vec3::new(1.0, 1.0, 0.0);
        let u = GridUniforms {
            grid: rng.random(),
            level: rng.random(),
            corner: rng.random(),
        };
        let state = GridState::from_stats(&warm_stats(&mut rng), 0.0, Vec3::ZERO);
        grids.store(x, Vec3::Z, camera, &u, state);
    }
    let points: Vec<(Vec3, [GridUniforms; 5], [f32; 5])> = (0..BATCH)
        .map(|_| {
            let x = random_vec3(&mut rng, 1.0) * Vec3::new(1.0, 1.0, 0.0);
            let u = core::array::from_fn(|_| GridUniforms {
                grid: rng.random(),
                level: rng.random(),
                corner: rng.random(),
            });
            (x, u, core::array::from_fn(|_| rng.random()))
        })
        .collect();
    let plain: Vec<GridState> = (0..BATCH * 5)
        .map(|_| GridState::from_stats(&warm_stats(&mut rng), 0.0, Vec3::ZERO))
        .collect();
    let mut g = c.benchmark_group("mcpg_resampling");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("array_reservoir_baseline", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for (i, (_, _, us)) in black_box(&points).iter().enumerate() {
                let mut set = CandidateSet::<5>::new();
                for k in 0..5 {
                    set.offer(plain[i * 5 + k], us[k]);
                }
                acc += set.weight_sum();
            }
            acc
        })
    });
    g.bench_function("alg1_hash_grids", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(x, ref grid_u, ref us) in black_box(&points) {
                let mut set = CandidateSet::<5>::new();
                for k in 0..5 {
                    let (state, collided, grid, _) = grids.load(x, Vec3::Z, camera, &grid_u[k]);
                    let candidate =
                        prepare_candidate(state, collided, grid, x, Some(Vec3::Z), 1.0, &params);
                    set.offer(candidate, us[k]);
                }
                acc += set.weight_sum();
            }
            acc
        })
    });
    g.finish();
    let _ = GridKind::Static;
}

fn bench_lobe_reconstruction(c: &mut Criterion) {
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    let params = McpgParams::PAPER;
    let states: Vec<(GridState, Vec3)> = (0..BATCH)
        .map(|_| {
            (
                GridState::from_stats(&warm_stats(&mut rng), 0.0, Vec3::ZERO),
                random_vec3(&mut rng, 0.5) * Vec3::new(1.0, 1.0, 0.0),
            )
        })
        .collect();
    let given: Vec<(Vec3, f32)> = states
        .iter()
        .map(|(s, x)| {
            let lobe = s.lobe(*x, distance_prior(s, *x, &params)).unwrap();
            (lobe.mu() * 2.0, lobe.kappa())
        })
        .collect();
    let mut g = c.benchmark_group("lobe_reconstruction");
    g.throughput(Throughput::Elements(BATCH as u64));
    g.bench_function("vmf_new_baseline", |b| {
        b.iter(|| {
            black_box(&given)
                .iter()
                .map(|&(mu, k)| Vmf::new(mu, k).unwrap().kappa())
                .sum::<f32>()
        })
    });
    g.bench_function("from_sufficient_statistics", |b| {
        b.iter(|| {
            black_box(&states)
                .iter()
                .map(|(s, x)| {
                    s.lobe(*x, distance_prior(s, *x, &params))
                        .map_or(0.0, |l| l.kappa())
                })
                .sum::<f32>()
        })
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_mcmm_update,
    bench_mcpg_resampling,
    bench_lobe_reconstruction
);
criterion_main!(benches);
