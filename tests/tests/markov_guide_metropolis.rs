//! Statistical suite of ADGI's Metropolis random walk (mcg-markov-guide, ADGI Alg. 1 and 5):
//! the walk's samples follow its target.

use mcg_markov_guide::{FrameSchedule, MetropolisChain, RandomWalk, StepUniforms};
use mcg_tests::{assert_chi_square, seeded_rng};
use rand::RngExt;

/// Bins per axis of the unit square.
const BINS: usize = 12;

/// A bimodal target on the unit square: a constant floor, a bump at (0.25, 0.3) and a tighter,
/// brighter one at (0.7, 0.75); zero outside the square.
fn target(x: &[f32; 2]) -> f32 {
    if !(0.0..1.0).contains(&x[0]) || !(0.0..1.0).contains(&x[1]) {
        return 0.0;
    }
    let bump = |cx: f32, cy: f32, s: f32| {
        (-((x[0] - cx).powi(2) + (x[1] - cy).powi(2)) / (2.0 * s * s)).exp()
    };
    0.3 + 2.0 * bump(0.25, 0.3, 0.12) + 4.0 * bump(0.7, 0.75, 0.07)
}

/// The target's probability of each bin, by a 40 × 40 midpoint rule inside every bin.
fn bin_probabilities() -> Vec<f64> {
    let sub = 40;
    let mut p = vec![0.0; BINS * BINS];
    for by in 0..BINS {
        for bx in 0..BINS {
            let mut s = 0.0;
            for j in 0..sub {
                for i in 0..sub {
                    let x = (bx as f64 + (i as f64 + 0.5) / sub as f64) / BINS as f64;
                    let y = (by as f64 + (j as f64 + 0.5) / sub as f64) / BINS as f64;
                    s += target(&[x as f32, y as f32]) as f64;
                }
            }
            p[by * BINS + bx] = s;
        }
    }
    let total: f64 = p.iter().sum();
    p.iter().map(|v| v / total).collect()
}

/// H₀: the positions of independent chains follow the normalised target. 20 000 chains, each
/// started uniformly in the square and run for 30 frames of the default schedule (8 steps, 2
/// discarded; σ = 0.15), so each has taken 240 steps and forgotten its start; the final
/// position of each chain is one sample, so samples are independent. Chi-square over 12 × 12
/// bins at α = 0.001. Accepting every proposal (no Metropolis test) fails it with X² ≈ 9900 on
/// 143 degrees of freedom.
#[test]
fn random_walk_follows_its_target() {
    let walk = RandomWalk::new([0.15, 0.15]).unwrap();
    let schedule = FrameSchedule::DEFAULT;
    let mut rng = seeded_rng(0xAD61_0001);
    let chains = 20_000;
    let mut counts = vec![0u64; BINS * BINS];
    for _ in 0..chains {
        let mut chain = MetropolisChain::new([rng.random::<f32>(), rng.random::<f32>()]);
        let mut last = chain.x;
        for _frame in 0..30 {
            walk.run_frame(
                &mut chain,
                schedule,
                target,
                || StepUniforms {
                    proposal: [rng.random(), rng.random()],
                    accept: rng.random(),
                },
                |x| last = *x,
            );
        }
        let bx = ((last[0] * BINS as f32) as usize).min(BINS - 1);
        let by = ((last[1] * BINS as f32) as usize).min(BINS - 1);
        counts[by * BINS + bx] += 1;
    }
    let expected: Vec<f64> = bin_probabilities()
        .iter()
        .map(|p| p * chains as f64)
        .collect();
    assert_chi_square(
        "Metropolis random walk on a bimodal 2-D target",
        &counts,
        &expected,
        0.001,
    );
}
