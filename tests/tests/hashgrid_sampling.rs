//! Random decisions of the hash grid: stochastic trilinear corner frequencies, the
//! jittered-cell alternative, the level's monotonicity in distance and its geometric jitter.

use glam::{IVec3, Vec2, Vec3};
use mcg_hashgrid::{
    AdaptiveGrid, LevelParams, cell_and_fraction, geometric_jitter, geometric_jitter_probability,
    jittered_vertex, stochastic_trilinear, trilinear_weights,
};
use mcg_tests::{assert_chi_square, seeded_rng};
use rand::RngExt;

const ALPHA: f64 = 0.001;

/// Fractional positions in the cell: generic, near a face, on a face (zero-weight corners), at
/// a vertex, near the centre.
const POSITIONS: [[f32; 3]; 5] = [
    [0.23, 0.61, 0.87],
    [0.02, 0.5, 0.97],
    [0.0, 0.4, 0.7],
    [0.0, 0.0, 0.0],
    [0.5, 0.49, 0.51],
];

fn corner_index(q: Vec3, v: glam::IVec3) -> usize {
    let d = v - q.floor().as_ivec3();
    assert!(
        d.cmpge(glam::IVec3::ZERO).all() && d.cmple(glam::IVec3::ONE).all(),
        "{v} not a corner of {q}"
    );
    (d.x + 2 * d.y + 4 * d.z) as usize
}

/// Expected counts from the trilinear weights (f64); corners of zero weight must get no sample.
fn check_corners(label: &str, f: Vec3, counts: &[u64; 8], n: usize) {
    let w: [f64; 8] = std::array::from_fn(|i| {
        let x = if i & 1 != 0 {
            f.x as f64
        } else {
            1.0 - f.x as f64
        };
        let y = if i & 2 != 0 {
            f.y as f64
        } else {
            1.0 - f.y as f64
        };
        let z = if i & 4 != 0 {
            f.z as f64
        } else {
            1.0 - f.z as f64
        };
        x * y * z
    });
    for (i, (&c, &wi)) in counts.iter().zip(&w).enumerate() {
        if wi == 0.0 {
            assert_eq!(c, 0, "{label}: corner {i} has weight 0 but {c} samples");
        }
    }
    let (obs, exp): (Vec<u64>, Vec<f64>) = counts
        .iter()
        .zip(&w)
        .filter(|&(_, &wi)| wi > 0.0)
        .map(|(&c, &wi)| (c, wi * n as f64))
        .unzip();
    if obs.len() > 1 {
        let r = assert_chi_square(label, &obs, &exp, ALPHA);
        println!(
            "{label}: X² = {:.2}, df = {}, p = {:.3}",
            r.statistic, r.degrees_of_freedom, r.p_value
        );
    } else {
        assert_eq!(obs[0], n as u64);
    }
}

/// Draws 10⁶ corners with `pick(q)` at each of [`POSITIONS`] in the cell at (−3, 7, 1000)
/// and checks their counts against the trilinear weights ([`check_corners`]).
fn check_sampler(name: &str, mut pick: impl FnMut(Vec3) -> IVec3) {
    const N: usize = 1_000_000;
    for f in POSITIONS {
        let q = Vec3::new(-3.0, 7.0, 1000.0) + Vec3::from_array(f);
        let (_, frac) = cell_and_fraction(q);
        let mut counts = [0_u64; 8];
        for _ in 0..N {
            counts[corner_index(q, pick(q))] += 1;
        }
        check_corners(&format!("{name} at {q}"), frac, &counts, N);
    }
}

/// H₀: `stochastic_trilinear(q, u)` returns corner c with probability W(c) (trilinear weight).
/// Chi-square over the corners of positive weight, n = 10⁶ uniforms per position, 5 positions
/// (incl. faces with zero-weight corners, which must never be picked), α = 0.001, seed
/// 0x4847_0001. The cell sits at (−3, 7, 1000) so the floor of negative coordinates is
/// exercised. A walk that swapped two weights (e.g. used f for the lower corner on one axis)
/// changes the counts by ~10⁵.
#[test]
fn stochastic_trilinear_matches_the_weights() {
    let mut rng = seeded_rng(0x4847_0001);
    check_sampler("stochastic trilinear", |q| {
        stochastic_trilinear(q, rng.random::<f32>())
    });
    for f in POSITIONS {
        let (_, frac) = cell_and_fraction(Vec3::new(-3.0, 7.0, 1000.0) + Vec3::from_array(f));
        let w = trilinear_weights(frac);
        mcg_tests::assert_close!(w.iter().sum::<f32>(), 1.0, 1e-6);
    }
}

/// H₀: `jittered_vertex(q, u)` returns corner c with probability W(c). Same positions, n, α;
/// seed 0x4847_0002.
#[test]
fn jittered_vertex_matches_the_weights() {
    let mut rng = seeded_rng(0x4847_0002);
    check_sampler("jittered vertex", |q| {
        jittered_vertex(q, Vec3::new(rng.random(), rng.random(), rng.random()))
    });
}

/// The target level is non-decreasing in distance over 200 000 log-spaced distances from 10⁻³
/// to 10⁶ for the default and two other parameter sets, covers every level it passes, and the
/// jittered level is never below the target.
#[test]
fn level_is_monotone_in_distance() {
    let sets = [
        LevelParams::MCPG,
        LevelParams {
            power: 3f32.sqrt(),
            steps: 1,
            // √3 per level: the coarsest width stays finite up to level 168
            // (`AdaptiveGrid::new` rejects more, `GridError::CoarsestWidthNotFinite`).
            max_level: 160,
            ..LevelParams::MCPG
        },
        LevelParams {
            tan_half_angle: 0.002,
            steps: 6,
            max_level: 40,
            ..LevelParams::MCPG
        },
    ];
    for p in sets {
        let g = AdaptiveGrid::new(p).unwrap();
        let mut last = 0;
        for i in 0..200_000 {
            let d = 1e-3 * 10f32.powf(9.0 * i as f32 / 200_000.0);
            let l = g.target_level(d);
            assert!(l >= last, "{p:?}: level {l} at d = {d} below {last}");
            assert!(
                l <= last + 1,
                "{p:?}: level jumps from {last} to {l} at d = {d}"
            );
            assert!(g.level(d, 0.9) >= l);
            last = l;
        }
        assert!(last > 10);
    }
}

/// Exact: over all 2²⁴ uniforms ξ = i·2⁻²⁴ (what 24-bit f32 generators produce), the jitter
/// equals k for exactly 2²⁴ · 2^−(k+1) of them (k < 24) and 24 for one.
#[test]
fn jitter_probabilities_are_exact_on_the_uniform_grid() {
    let mut counts = [0_u64; 26];
    for i in 0..(1_u32 << 24) {
        counts[geometric_jitter(i as f32 * 2f32.powi(-24)) as usize] += 1;
    }
    for (k, &c) in counts.iter().enumerate() {
        let want = (geometric_jitter_probability(k as u32) * 2f64.powi(24)).round() as u64;
        assert_eq!(c, want, "k = {k}");
    }
}

/// H₀: the jittered level minus the target level is geometric with P(k) = 2^−(k+1). Chi-square
/// over k (tail bins merged to ≥ 5 expected), n = 10⁶ levels at distances drawn log-uniformly
/// in [1, 10⁴] (targets below max_level − 30, so no clamping), α = 0.001, seed 0x4847_0003.
/// Using ⌈·⌉ instead of ⌊·⌋ would put no mass at k = 0.
#[test]
fn level_jitter_is_geometric() {
    const N: usize = 1_000_000;
    let g = AdaptiveGrid::mcpg();
    let mut rng = seeded_rng(0x4847_0003);
    let mut counts = vec![0_u64; 25];
    for _ in 0..N {
        let u: Vec2 = Vec2::new(rng.random(), rng.random());
        let d = 10f32.powf(4.0 * u.x);
        counts[(g.level(d, u.y) - g.target_level(d)) as usize] += 1;
    }
    let expected: Vec<f64> = (0..25)
        .map(|k| geometric_jitter_probability(k) * N as f64)
        .collect();
    let r = assert_chi_square("level jitter", &counts, &expected, ALPHA);
    println!(
        "level jitter: X² = {:.2}, df = {}, p = {:.3}",
        r.statistic, r.degrees_of_freedom, r.p_value
    );
}
