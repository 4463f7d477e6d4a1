//! MCMM Fig. 16 in miniature: adaptive Markov chains whose lobes follow their own samples,
//! estimated with TSMIS (cyclic shift, MCMM eq. 8) and SSMIS (xor permutation, MCMM eq. 9),
//! are unbiased with the shuffle and biased without it.
//!
//! Setup ([`mcg_tests::AdaptiveTile`]): a tile of 8 lanes (pixels); lane l integrates its own
//! function `0.2 + 4 e^{−|x − b_l|/0.02}` on [0, 1) with b_l = 0.3 + 0.05 l (each pixel sees
//! its own light). Each lane holds one chain state, the centre c of a lobe
//! `0.2 · U(0, 1) + 0.8 · Laplace(c, 0.02)` (MCMM's defensive probability 0.2, so every
//! technique covers [0, 1)). A chain samples its lobe and moves the lobe to the sample with
//! probability min(1, f(x)/score) (MCMM Alg. 3), so its next lobe depends on its own sample.
//!
//! - TSMIS: 4 steps per frame; lane l evaluates 4-sample SMIS over the 4 (lobe, sample) pairs
//!   it saw. With a cyclic shift by one lane after each step these pairs come from 4 different
//!   chains; without it they come from one chain, whose lobe at step k + 1 sits on its sample
//!   of step k, inflating that sample's denominator: biased low.
//! - SSMIS: each step, lane l samples the state it holds after a uniformly random xor
//!   permutation and evaluates one-sample SMIS over the tile's 8 lobes. Without the
//!   permutation a lane always samples its own chain, which has adapted to its own pixel's
//!   light; the selection is then not uniform given the lobes: biased high.
//!
//! Hypothesis per scheme: the mean over independent tiles of the lane-averaged estimate equals
//! the lane-averaged exact integral. Each tile runs 4 warm-up frames and then 12 measured
//! frames (estimates within a tile are correlated through the chains, so a tile is one
//! observation); 6 000 independent tiles. Threshold 5σ; seed fixed per scheme.

use mcg_tests::{
    AdaptiveTile, Decorrelation, RunningStats, TILE, ZTestResult, assert_z_test, lane_integral,
    seeded_rng, z_test,
};

const TILES: usize = 6_000;
const WARM_UP: usize = 4;
const FRAMES: usize = 12;

fn run(scheme: Decorrelation, seed: u64) -> RunningStats {
    let mut rng = seeded_rng(seed);
    let mut stats = RunningStats::new();
    for _ in 0..TILES {
        let mut tile = AdaptiveTile::new(&mut rng);
        let mut scratch = [0.0; TILE];
        for _ in 0..WARM_UP {
            tile.frame(scheme, &mut rng, &mut scratch);
        }
        let mut sums = [0.0; TILE];
        for _ in 0..FRAMES {
            tile.frame(scheme, &mut rng, &mut sums);
        }
        stats.push(sums.iter().sum::<f64>() / (TILE * FRAMES) as f64);
    }
    stats
}

fn expected() -> f64 {
    (0..TILE).map(lane_integral).sum::<f64>() / TILE as f64
}

/// The schemes with their fixed seeds, shuffled ones first ([`Decorrelation::ALL`]'s order).
const SEEDS: [(Decorrelation, u64); 4] = [
    (Decorrelation::TsmisShuffled, 0x5316_0001),
    (Decorrelation::SsmisShuffled, 0x5316_0002),
    (Decorrelation::TsmisUnshuffled, 0x5316_0003),
    (Decorrelation::SsmisUnshuffled, 0x5316_0004),
];

/// Runs every scheme whose [`Decorrelation::is_shuffled`] is `shuffled` with its seed, prints
/// its z-test against [`expected`] and yields the scheme, its statistics and the z-test.
fn measure(shuffled: bool) -> impl Iterator<Item = (Decorrelation, RunningStats, ZTestResult)> {
    SEEDS
        .into_iter()
        .filter(move |(scheme, _)| scheme.is_shuffled() == shuffled)
        .map(|(scheme, seed)| {
            let stats = run(scheme, seed);
            let r = z_test(&stats, expected());
            eprintln!(
                "{}: mean {:.6} expected {:.6} z {:+.2}",
                scheme.label(),
                r.mean,
                r.expected,
                r.z
            );
            (scheme, stats, r)
        })
}

#[test]
fn shuffled_tsmis_and_ssmis_are_unbiased() {
    for (scheme, stats, _) in measure(true) {
        let r = assert_z_test(scheme.label(), &stats, expected(), 5.0);
        // The test can see a bias of 2 % of the integral.
        assert!(r.standard_error < 0.004 * expected(), "{r:?}");
    }
}

#[test]
fn unshuffled_estimators_are_biased() {
    for (scheme, _, r) in measure(false) {
        assert!(
            r.z.abs() > 5.0,
            "{}: no detectable bias, {r:?}",
            scheme.label()
        );
    }
}
