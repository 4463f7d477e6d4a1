//! Property tests of mcg-markov-guide: chain states never become NaN or infinite, whatever the
//! renderer hands back — zero, huge, infinite or NaN radiance, coincident points, points far
//! away, degenerate normals — through every transition of MCMM (Alg. 1-3) and MCPG (Alg. 1-3,
//! discard, velocity prediction). Removing the score sanitisation of `mcmm::update` fails the first
//! property at once (a NaN score is stored).

use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcg_smis::Technique;
use mcg_markov_guide::mcmm::{self, CosineChainTechnique, McmmParams, PixelState};
use mcg_markov_guide::mcpg::{self, CandidateSet, GridKind, GridState, McpgParams, Observation};
use proptest::prelude::*;

/// Radiance values a broken renderer may produce.
fn radiance() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(f32::INFINITY),
        Just(f32::NAN),
        Just(-1.0f32),
        Just(f32::MAX),
        Just(f32::MIN_POSITIVE),
        0.0f32..1.0e6,
    ]
}

/// Points: ordinary, coincident with the shading point (the origin), huge, non-finite.
fn point() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        Just(Vec3::ZERO),
        Just(Vec3::splat(f32::NAN)),
        Just(Vec3::new(f32::INFINITY, 0.0, 1.0)),
        Just(Vec3::new(1.0e30, -1.0e30, 1.0e30)),
        (-10.0f32..10.0, -10.0f32..10.0, -10.0f32..10.0).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
    ]
}

/// Normals: ordinary, zero, non-finite, not unit length.
fn normal() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        Just(Vec3::Z),
        Just(Vec3::ZERO),
        Just(Vec3::splat(f32::NAN)),
        Just(Vec3::new(0.0, 0.0, 1.0e-30)),
        Just(Vec3::new(3.0, 4.0, 0.0)),
    ]
}

fn finite_stats(s: &mcg_markov_guide::mcg_vmf::SufficientStats) -> bool {
    s.mean_target.is_finite()
        && s.weight_sum.is_finite()
        && s.weight_sum >= 0.0
        && s.one_minus_mean_cosine.is_finite()
}

fn finite_grid_state(s: &GridState) -> bool {
    finite_stats(&s.stats()) && s.time.is_finite() && s.velocity().is_finite()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// MCMM: a chain driven for 8 iterations by arbitrary results stays finite, and so does
    /// every technique density built from it.
    #[test]
    fn mcmm_states_stay_finite(
        steps in proptest::collection::vec((radiance(), point(), normal(), any::<bool>(), 0.0f32..1.0, 0.0f32..1.0), 1..8),
        x in point(),
    ) {
        let params = McmmParams::PAPER;
        let (mut s, mut c) = (PixelState::EMPTY, PixelState::EMPTY);
        for (f, x2, n, hemisphere, u, v) in steps {
            let neighbour = c;
            s = mcmm::collaborative_discovery(s, [(neighbour, u)]);
            let technique = CosineChainTechnique::new(&s, x, n, &params);
            let (w, _) = technique.sample_with_branch(u, Vec2::new(v, u));
            let pdf = technique.pdf(&w);
            prop_assert!(pdf >= 0.0 || pdf.is_nan(), "pdf {pdf}");
            mcmm::update(&mut s, &mut c, x, x2, f, hemisphere, v, &params);
            for state in [s, c] {
                prop_assert!(finite_stats(&state.stats), "{state:?}");
                prop_assert!(state.score.is_finite() && state.score >= 0.0, "{state:?}");
            }
        }
    }

    /// MCPG: candidates, technique choice, pdf, transition and discard with arbitrary results
    /// keep every stored state finite, and the candidate pdf is never negative or NaN for a
    /// finite BSDF pdf.
    #[test]
    fn mcpg_states_stay_finite(
        steps in proptest::collection::vec((radiance(), point(), point(), 0.0f32..1.0, 0.0f32..1.0, -1.0f32..5.0), 1..8),
        x in point(),
        n in normal(),
    ) {
        let params = McpgParams::PAPER;
        let mut stored = GridState::EMPTY;
        for (i, (f, next, next_previous, u, v, frame_time)) in steps.into_iter().enumerate() {
            let now = i as f32;
            let mut set = CandidateSet::<5>::new();
            for k in 0..5 {
                let grid = if k % 2 == 0 { GridKind::Adaptive } else { GridKind::Static };
                let c = mcpg::prepare_candidate(stored, k == 4, grid, x, Some(n), now, &params);
                prop_assert!(finite_grid_state(&c), "{c:?}");
                set.offer(c, u);
            }
            let (choice, state) = mcpg::choose_technique(set.selected(), x, v, &params);
            let w = match choice {
                mcpg::SampleChoice::Lobe(lobe) => lobe.sample(Vec2::new(u, v)),
                mcpg::SampleChoice::Bsdf => Vec3::Z,
            };
            let pdf = set.pdf(x, w, 0.3, &params);
            prop_assert!(pdf >= 0.0, "pdf {pdf}");
            let observation = Observation { x, next, next_previous, estimate: f, now, frame_time };
            match mcpg::update(&state, set.mean_weight(), &observation, u, &params) {
                Some(new) => {
                    prop_assert!(finite_grid_state(&new), "{new:?}");
                    stored = new;
                }
                None => {
                    if mcpg::should_discard(&state, x, w, f, now, &params) {
                        stored.weight_sum = 0.0;
                    }
                }
            }
        }
    }
}
