//! CPU/GPU parity of ADGI's guiding function, Metropolis probe chains and trigger smoothing:
//! `GpuProbeChains` and `GpuTriggerSmoothing` against `mcg_probe_cache`'s `GuidingFunction`,
//! `ProxyGrid::max_pool`, `ProbeChains` and `spatial_smoothing`, for the same inputs and the
//! same uniforms (`chain_step_uniforms`).
//!
//! Bit for bit: the guide's tables (decoded heuristics, max-pooled proxies), the guiding values
//! of the dynamic form (h = f) and the smoothed triggers. Within WGSL's accuracy: the static
//! form's `exp` (WGSL spec, "Floating Point Accuracy": 3 + 2|x| ULP, |x| ≤ 1 here) and the
//! chains' positions and directions, whose proposals go through `log`, `sqrt`, `sin` and `cos`
//! (Φ⁻¹ of the walk, the direction of (cos θ, φ)). The guide is piecewise constant per cell
//! and octant, so those last-bit differences change no decision unless a state lies within
//! them of a cell or octant boundary: every accept/reject, restart and emitted (cell, octant)
//! is compared exactly.

mod common;

use std::collections::BTreeSet;

use glam::{UVec3, Vec3};
use mcg_color_codec::Heuristics;
use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::guides::adgi::{
    GpuChainState, GpuGuideQuery, GpuProbeChains, GpuTriggerSmoothing, chain_step_uniforms,
};
use mcg_markov_guide::FrameSchedule;
use mcg_probe_cache::guiding_function::decode_field;
use mcg_probe_cache::heuristics::encode;
use mcg_probe_cache::temporal_gradient::spatial_smoothing;
use mcg_probe_cache::{
    ChainKind, GuideParams, GuidingFunction, HeuristicField, ProbeChains, ProbeGrid, ProxyGrid,
    SmoothingKernel,
};
use rand::RngExt;
use rand_pcg::Pcg64;

/// Heuristics words per probe and octant: `hot(coords, octant)` gives f_s and f_d's scale;
/// f_v random; a tenth of the octants zero.
fn words(grid: &ProbeGrid, rng: &mut Pcg64, hot: impl Fn(UVec3, usize) -> f32) -> Vec<u32> {
    (0..grid.probe_count() * 8)
        .map(|i| {
            let (probe, o) = (i / 8, i % 8);
            let scale = if rng.random_range(0..10) == 0 {
                0.0
            } else {
                hot(grid.probe_coords(probe), o)
            };
            let h = Heuristics {
                f_v: rng.random(),
                f_s: scale * rng.random_range(0.2f32..1.0),
                f_d: scale * rng.random_range(0.0f32..1.0),
                flags: rng.random_range(0..64),
            };
            encode(h).0
        })
        .collect()
}

fn heuristic_words(w: &[u32]) -> Vec<mcg_color_codec::HeuristicsWord> {
    w.iter()
        .map(|&x| mcg_color_codec::HeuristicsWord(x))
        .collect()
}

/// The guiding function of both forms on a 7 × 5 × 4 grid (its proxies partly filled on the
/// upper faces): the GPU's table (f_s per probe; f_d max-pooled into 3 × 2 × 2 proxies) is
/// the CPU's `decode_field` + `max_pool` within 3 ULP (the decode's division), and h(p, ω)
/// at 2 000 points (a fifth outside the grid, some zero or NaN directions) with feedback ĝ
/// (NaN, negative, 0, large among it) is `GuidingFunction::guiding_value` within 3 ULP for
/// the dynamic form (h = f) and 10 ULP (plus WGSL's `exp` bound) for the static form's
/// exp(min(ĝ/f, 1)) f. Lavapipe: the table and the dynamic form bit for bit, the static
/// form 4 ULP at worst.
#[test]
fn guiding_values_match_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("guiding_values_match_the_cpu", 30) else {
        return;
    };
    let grid = common::adgi_grid();
    let w = words(&grid, &mut rng, |c, o| {
        if (c.x + o as u32).is_multiple_of(3) {
            0.3
        } else {
            1.0
        }
    });
    let queries: Vec<(Vec3, Vec3)> = (0..2000)
        .map(|i| {
            let lo = Vec3::new(-1.6, -0.1, -0.8);
            let hi = Vec3::new(2.8, 4.2, 4.2);
            let p = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
            let d = match i % 97 {
                0 => Vec3::ZERO,
                1 => Vec3::NAN,
                _ => common::random_unit(&mut rng) * rng.random_range(0.5f32..2.0),
            };
            (p, d)
        })
        .collect();
    let gpu_queries: Vec<GpuGuideQuery> = queries
        .iter()
        .map(|&(p, d)| GpuGuideQuery::new(p, d))
        .collect();
    for kind in [ChainKind::Static, ChainKind::Dynamic] {
        let (cells, field, params) = match kind {
            ChainKind::Static => (
                ProxyGrid::probes(grid),
                HeuristicField::Static,
                GuideParams::STATIC,
            ),
            ChainKind::Dynamic => (
                ProxyGrid::adgi(grid),
                HeuristicField::Dynamic,
                GuideParams::DYNAMIC,
            ),
        };
        let chains = ProbeChains::new(cells, kind, 4, FrameSchedule::DEFAULT, || [0.5; 5]).unwrap();
        let gpu = GpuProbeChains::new(ctx, &chains, params).unwrap();
        // CPU tables.
        let mut per_probe = vec![0.0; grid.probe_count() * 8];
        decode_field(&heuristic_words(&w), field, &mut per_probe).unwrap();
        let mut table = vec![0.0; cells.table_len()];
        cells.max_pool(&per_probe, &mut table).unwrap();
        let feedback: Vec<f32> = (0..cells.table_len())
            .map(|i| match i % 23 {
                0 => f32::NAN,
                1 => -0.5,
                2 => 0.0,
                3 => 1e30,
                _ => rng.random_range(0.0f32..0.8),
            })
            .collect();
        gpu.guide_from_words(ctx, &w).unwrap();
        gpu.write_feedback(ctx, &feedback).unwrap();
        let got_table = gpu.read_guide_table(ctx).unwrap();
        // The decode divides a code by its field's maximum: within 2.5 ULP in WGSL, so 3 ULP
        // (an NVIDIA H200 differed; lavapipe matches bit for bit).
        for (i, (&g, &c)) in got_table.iter().zip(&table).enumerate() {
            let e = common::ulps(g, c);
            assert!(
                e <= 3,
                "{kind:?}: guide table entry {i}: GPU {g} CPU {c} ({e} ULP)"
            );
        }
        assert!(table.iter().filter(|&&x| x > 0.0).count() > table.len() / 2);
        let h = GuidingFunction::new(cells, &table, Some(&feedback), params).unwrap();
        let got = gpu.guide_values(ctx, &gpu_queries).unwrap();
        let mut worst = 0;
        let mut positive = 0;
        for (&(p, d), &g) in queries.iter().zip(&got) {
            let c = h.guiding_value(p, d);
            let e = common::ulps(g, c);
            worst = worst.max(e);
            positive += usize::from(c > 0.0);
            // The table's 3 ULP; then WGSL's exp, within 3 + 2|x| ULP (x ≤ cap = 1), the
            // CPU's within 1, and the product with f rounding once more: 7 ULP more. The
            // dynamic form has no exp.
            let bound = if kind == ChainKind::Static { 10 } else { 3 };
            assert!(
                e <= bound,
                "{kind:?} h({p}, {d}): GPU {g} CPU {c} ({e} ULP)"
            );
        }
        assert!(positive > 800, "{kind:?}: {positive} positive values");
        println!("{kind:?}: worst {worst} ULP over {} queries", queries.len());
    }
}

/// One chain as the CPU runs it alone, from `state`, with its own uniforms.
fn single_chain(
    cells: ProxyGrid,
    kind: ChainKind,
    state: mcg_probe_cache::ProbeChainState,
) -> ProbeChains {
    let mut c = ProbeChains::new(cells, kind, 1, FrameSchedule::DEFAULT, || [0.5; 5]).unwrap();
    c.states_mut()[0] = state;
    c
}

/// Chain states equal to f32 tolerance: positions within 10⁻⁴ spacing, z and φ (mod 2π) within
/// 10⁻⁴, h within 2 ULP·8 (the static form's exp).
fn assert_state_close(g: &GpuChainState, c: &mcg_probe_cache::ProbeChainState, what: &str) {
    let dp = (g.position - Vec3::new(c.x[0], c.x[1], c.x[2]))
        .abs()
        .max_element();
    let dz = (g.z - c.x[3]).abs();
    let dphi = (g.phi - c.x[4]).abs();
    let dphi = dphi.min(core::f32::consts::TAU - dphi);
    assert!(
        dp < 1e-4 && dz < 1e-4 && dphi < 1e-4 && common::ulps(g.target_value, c.target) <= 16,
        "{what}: GPU {g:?} CPU {c:?}"
    );
}

/// Runs `frames` frames of `count` chains of `kind` on the GPU and on the CPU (all chains
/// together, and each chain alone) with the same uniforms and checks, every frame: the frame's
/// counters equal the CPU's; per chain the restart, the number of accepted steps and every
/// accept/reject of the emitted steps (a rejected step repeats the previous position) equal
/// the CPU chain's, and the states agree to f32 tolerance; the emitted samples (static: per
/// chain, in step order; dynamic: the set of (proxy, octant), each once) equal the CPU's.
/// Returns the totals (proposals, accepted, restarts, emitted).
#[allow(clippy::too_many_arguments)]
fn run_chains(
    ctx: &GpuContext,
    grid: ProbeGrid,
    kind: ChainKind,
    params: GuideParams,
    w: &[u32],
    feedback: Option<Vec<f32>>,
    count: usize,
    frames: u32,
    rng: &mut Pcg64,
) -> [u32; 4] {
    let cells = match kind {
        ChainKind::Static => ProxyGrid::probes(grid),
        ChainKind::Dynamic => ProxyGrid::adgi(grid),
    };
    let field = match kind {
        ChainKind::Static => HeuristicField::Static,
        ChainKind::Dynamic => HeuristicField::Dynamic,
    };
    let mut cpu = ProbeChains::new(cells, kind, count, FrameSchedule::DEFAULT, || {
        core::array::from_fn(|_| rng.random())
    })
    .unwrap();
    let mut singles: Vec<ProbeChains> = cpu
        .states()
        .iter()
        .map(|s| single_chain(cells, kind, *s))
        .collect();
    let gpu = GpuProbeChains::new(ctx, &cpu, params).unwrap();
    gpu.guide_from_words(ctx, w).unwrap();
    let mut per_probe = vec![0.0; grid.probe_count() * 8];
    decode_field(&heuristic_words(w), field, &mut per_probe).unwrap();
    let mut table = vec![0.0; cells.table_len()];
    cells.max_pool(&per_probe, &mut table).unwrap();
    if let Some(f) = &feedback {
        gpu.write_feedback(ctx, f).unwrap();
    }
    let guide = GuidingFunction::new(cells, &table, feedback.as_deref(), params).unwrap();
    let (k, m) = (
        FrameSchedule::DEFAULT.burn_in() as usize,
        FrameSchedule::DEFAULT.iterations() as usize,
    );
    let mut totals = [0u32; 4];
    for frame in 0..frames {
        let seed = 0x9e37_79b9u32.wrapping_mul(frame + 1);
        gpu.step_frame(ctx, seed).unwrap();
        let cpu_samples = cpu
            .step_frame_parallel(&guide, |j, d| chain_step_uniforms(seed, j as u32, d), 1)
            .to_vec();
        let stats = cpu.stats();
        let gpu_stats = gpu.read_stats(ctx).unwrap();
        assert_eq!(gpu_stats, stats, "frame {frame}: counters");
        totals[0] += stats.proposals;
        totals[1] += stats.accepted;
        totals[2] += stats.restarts;
        totals[3] += stats.emitted;
        let states = gpu.read_states(ctx).unwrap();
        let mut samples = gpu.read_samples(ctx).unwrap();
        samples.sort_by_key(|s| (s.chain, s.step));
        for (j, single) in singles.iter_mut().enumerate() {
            let what = format!("{kind:?} frame {frame} chain {j}");
            let own = single
                .step_frame_parallel(&guide, |_, d| chain_step_uniforms(seed, j as u32, d), 1)
                .to_vec();
            let g = &states[j];
            assert_eq!(g.restarted, single.stats().restarts, "{what}: restart");
            assert_eq!(
                g.accepted.count_ones(),
                single.stats().accepted,
                "{what}: accepted"
            );
            assert_state_close(g, &single.states()[0], &what);
            assert_state_close(g, &cpu.states()[j], &what);
            if kind == ChainKind::Static {
                let mine: Vec<_> = samples.iter().filter(|s| s.chain == j as u32).collect();
                assert_eq!(mine.len(), own.len(), "{what}: samples");
                for (i, (gs, cs)) in mine.iter().zip(&own).enumerate() {
                    let c = gs.to_cpu(&grid);
                    assert_eq!(
                        (c.cell, c.probe, c.octant),
                        (cs.cell, cs.probe, cs.octant),
                        "{what}: sample {i}"
                    );
                    assert!(
                        (c.position - cs.position).abs().max_element() < 1e-4,
                        "{what}: sample {i}"
                    );
                    assert!(
                        (c.direction - cs.direction).abs().max_element() < 1e-4,
                        "{what}: sample {i}"
                    );
                }
                // The accept/reject of each emitted step after the first: did the state move?
                let steps: Vec<u32> = mine.iter().map(|s| s.step).collect();
                for (a, b) in mine.iter().zip(mine.iter().skip(1)) {
                    if b.step != a.step + 1 {
                        continue;
                    }
                    let moved = a.position != b.position;
                    assert_eq!(
                        g.accepted >> b.step & 1 == 1,
                        moved,
                        "{what}: step {}",
                        b.step
                    );
                }
                assert!(steps.iter().all(|&s| (k as u32..m as u32).contains(&s)));
            }
        }
        if kind == ChainKind::Dynamic {
            let got: BTreeSet<(u32, u32)> = samples.iter().map(|s| (s.cell, s.octant)).collect();
            let want: BTreeSet<(u32, u32)> = cpu_samples
                .iter()
                .map(|s| (s.cell, u32::from(s.octant)))
                .collect();
            assert_eq!(
                got.len(),
                samples.len(),
                "frame {frame}: a (proxy, octant) twice"
            );
            assert_eq!(got, want, "frame {frame}: emitted (proxy, octant)");
        }
    }
    totals
}

/// Static chains (sec. 4.8): 48 chains, 40 frames of M = 8 (K = 2) — 320 steps each — on a
/// 6 × 4 × 4 grid whose f_s vanishes for x ≥ 4 (chains started there restart), with feedback
/// ĝ: every decision and sample equals the CPU's (see `run_chains`).
#[test]
fn static_chains_match_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("static_chains_match_the_cpu", 31) else {
        return;
    };
    let grid = ProbeGrid::new(
        Vec3::new(0.0, -1.0, 0.5),
        Vec3::new(0.5, 0.5, 0.75),
        UVec3::new(6, 4, 4),
    )
    .unwrap();
    let w = words(&grid, &mut rng, |c, o| match (c.x, o) {
        (4.., _) => 0.0,
        (_, 0..=3) => 1.0,
        _ => 0.25,
    });
    let feedback: Vec<f32> = (0..grid.probe_count() * 8)
        .map(|_| rng.random_range(0.0f32..0.6))
        .collect();
    let [proposals, accepted, restarts, emitted] = run_chains(
        ctx,
        grid,
        ChainKind::Static,
        GuideParams::STATIC,
        &w,
        Some(feedback),
        48,
        40,
        &mut rng,
    );
    println!(
        "static: {proposals} proposals, {accepted} accepted, {restarts} restarts, {emitted} samples"
    );
    assert_eq!(proposals, 48 * 40 * 8);
    assert!(
        accepted > proposals / 10 && accepted < proposals * 9 / 10,
        "{accepted}"
    );
    assert!(restarts > 0, "no chain restarted");
}

/// Dynamic chains (sec. 4.9): 32 chains, 30 frames on a 9 × 7 × 6 grid (3 × 3 × 2 proxies, the
/// upper ones partial), f_d non-zero in part of the grid, α = 0: the counters, decisions,
/// states and the deduplicated (proxy, octant) set of every frame equal the CPU's.
#[test]
fn dynamic_chains_match_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("dynamic_chains_match_the_cpu", 32) else {
        return;
    };
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::new(9, 7, 6)).unwrap();
    let w = words(&grid, &mut rng, |c, o| {
        if c.y < 3 && o % 2 == 0 {
            1.0
        } else if c.z > 3 {
            0.4
        } else {
            0.0
        }
    });
    let [proposals, accepted, restarts, emitted] = run_chains(
        ctx,
        grid,
        ChainKind::Dynamic,
        GuideParams::DYNAMIC,
        &w,
        None,
        32,
        30,
        &mut rng,
    );
    println!(
        "dynamic: {proposals} proposals, {accepted} accepted, {restarts} restarts, {emitted} samples"
    );
    assert!(accepted > proposals / 20, "{accepted}");
    assert!(emitted > 30 * 4, "{emitted}");
}

/// The triggers' smoothing on a 7 × 5 × 4 grid: trigger states with NaN, ±∞, huge and
/// negative values mixed in, smoothed with ADGI's kernel (r = 2, octants), r = 1 without
/// octants, r = 0 with octants, and a radius past the grid: f_Δv and f_Δr equal
/// `spatial_smoothing`'s bit for bit.
#[test]
fn trigger_smoothing_matches_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("trigger_smoothing_matches_the_cpu", 33) else {
        return;
    };
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(7, 5, 4)).unwrap();
    let gpu_cache = common::adgi_cache(ctx, grid);
    let n = grid.probe_count() * 8;
    let value = |rng: &mut Pcg64| match rng.random_range(0..60) {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => f32::NEG_INFINITY,
        3 => 3e38,
        4 => -0.25,
        _ => rng.random::<f32>() * rng.random::<f32>(),
    };
    let state: Vec<[f32; 4]> = (0..n)
        .map(|_| [rng.random(), rng.random(), value(&mut rng), value(&mut rng)])
        .collect();
    ctx.write(gpu_cache.pilot_state(), &state).unwrap();
    let smoothing = GpuTriggerSmoothing::new(ctx, &gpu_cache);
    let (tv, tr): (Vec<f32>, Vec<f32>) = state.iter().map(|s| (s[2], s[3])).unzip();
    for kernel in [
        SmoothingKernel::ADGI,
        SmoothingKernel {
            spatial_radius: 1,
            directional: false,
        },
        SmoothingKernel {
            spatial_radius: 0,
            directional: true,
        },
        SmoothingKernel {
            spatial_radius: 9,
            directional: true,
        },
    ] {
        let (gv, gr) = smoothing.smooth(ctx, &gpu_cache, kernel).unwrap();
        for (input, got, what) in [(&tv, &gv, "f_Δv"), (&tr, &gr, "f_Δr")] {
            let (mut out, mut scratch) = (vec![0.0; n], vec![0.0; n]);
            spatial_smoothing(&grid, kernel, input, &mut out, &mut scratch).unwrap();
            let first = got
                .iter()
                .zip(&out)
                .position(|(a, b)| a.to_bits() != b.to_bits());
            assert_eq!(
                first.map(|i| (i, got[i], out[i])),
                None,
                "{kernel:?} {what}: (index, GPU, CPU)"
            );
            assert!(out.iter().any(|&x| x > 0.01) && out.iter().all(|x| x.is_finite()));
        }
    }
}
