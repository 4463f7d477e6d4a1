//! Property tests of mcg-markov-guide: chain states never become NaN or infinite, whatever the
//! renderer hands back — zero, huge, infinite or NaN radiance, coincident points, points far
//! away, degenerate normals — through every transition of MCMM (Alg. 1-3) and MCPG (Alg. 1-3,
//! discard, velocity prediction). Removing the score sanitisation of `mcmm::update` fails the first
//! property at once (a NaN score is stored).

use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcg_smis::Technique;
use mcg_markov_guide::mcmm::{self, CosineChainTechnique, McmmParams, PixelState};
use mcg_markov_guide::mcpg::{self, CandidateSet, GridKind, GridState, McpgParams, Observation};
use mcg_markov_guide::{
    FrameSchedule, MetropolisChain, RandomWalk, Reservoir, StepUniforms, cosine_hemisphere,
    cosine_hemisphere_pdf, standard_normal_from_uniform,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform, any_vec3};

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
    #![proptest_config(support::proptest_config(512, 0x7E57_0005))]

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

proptest! {
    #![proptest_config(support::proptest_config(1024, 0x7E57_00A5))]

    /// MCPG's transition with an adversarial time, frame time or mean weight never stores NaN
    /// or ∞ (issue 14 row 9: a NaN `now` was stored as T).
    #[test]
    fn mcpg_transitions_reject_bad_times(
        now in any_f32(), frame_time in any_f32(), mean_weight in any_f32(),
        estimate in radiance(), next in point(), u in any_uniform(),
    ) {
        let params = McpgParams::PAPER;
        let observation = Observation {
            x: Vec3::ZERO, next, next_previous: Vec3::new(0.1, 0.0, 2.0), estimate, now, frame_time,
        };
        let state = GridState::from_stats(&GridState::EMPTY.stats(), now, Vec3::splat(frame_time));
        prop_assert!(finite_grid_state(&state), "{state:?}");
        if let Some(new) = mcpg::update(&state, mean_weight, &observation, u, &params) {
            prop_assert!(finite_grid_state(&new), "{new:?}");
            prop_assert!(now.is_finite() && new.time == now);
        }
        let _ = mcpg::should_discard(&state, Vec3::ZERO, Vec3::Z, estimate, now, &params);
        prop_assert!(finite_grid_state(&state.predicted(now)));
    }

    /// Sampling helpers and the reservoir never return NaN for finite input, and the
    /// reservoir's sum never leaves the f32 range (issue 14 rows 10, 12).
    #[test]
    fn helpers_are_finite(
        u in (any_f32(), any_f32()), n in any_vec3(),
        offers in proptest::collection::vec((any_f32(), any_uniform()), 1..12),
    ) {
        let (w, pdf) = cosine_hemisphere(Vec3::new(0.3, -0.4, 0.866).normalize(), Vec2::new(u.0, u.1));
        prop_assert!(w.is_finite() && (w.length() - 1.0).abs() < 1e-5, "{u:?}: {w}");
        prop_assert!(pdf.is_finite() && pdf >= 0.0);
        if let Some(n) = n.try_normalize() {
            prop_assert!(cosine_hemisphere_pdf(n, w).is_finite());
        }
        for x in [u.0, u.1] {
            let z = standard_normal_from_uniform(x);
            prop_assert!(z.is_finite() && z.abs() < 5.7, "{x}: {z}");
        }
        let mut r = Reservoir::new();
        for (i, (weight, u)) in offers.into_iter().enumerate() {
            let taken = r.offer(i, weight, u);
            prop_assert!(r.weight_sum().is_finite() && r.weight_sum() >= 0.0);
            if taken {
                prop_assert_eq!(r.selected(), Some(&i));
            }
            if weight > 0.0 && weight.is_finite() && u == 0.0 {
                prop_assert!(taken, "a positive weight with u = 0 is always taken");
            }
        }
    }

    /// Random walks reject step sizes whose proposals could overflow, and a finite chain stays
    /// finite (issue 14 row 11).
    #[test]
    fn walks_stay_finite(
        steps in [any_f32(), any_f32()], x in [any_f32(), any_f32()],
        uniforms in proptest::collection::vec(([any_f32(), any_f32()], any_f32()), 1..16),
        iterations in any_u32(), burn_in in any_u32(),
    ) {
        let walk = match RandomWalk::new(steps) {
            Ok(w) => w,
            Err(e) => {
                prop_assert!(steps.iter().any(|&s| !(s > 0.0 && s <= RandomWalk::<2>::STEP_MAX)), "{e:?}");
                return Ok(());
            }
        };
        let start = x.map(|c| if c.is_finite() { c } else { 0.0 });
        let mut chain = MetropolisChain::new(start);
        for (proposal, accept) in &uniforms {
            let p = walk.propose(&chain.x, proposal);
            prop_assert!(p.iter().all(|c| c.is_finite()), "{chain:?} {proposal:?}: {p:?}");
            walk.step(&mut chain, |_| 1.0, &StepUniforms { proposal: *proposal, accept: *accept });
            prop_assert!(chain.x.iter().all(|c| c.is_finite()) && chain.target.is_finite());
        }
        if let Ok(schedule) = FrameSchedule::new(iterations.min(64), burn_in) {
            let mut k = 0;
            let emitted = walk.run_frame(&mut chain, schedule, |x| x[0].abs().min(1.0), || {
                k += 1;
                StepUniforms { proposal: uniforms[k % uniforms.len()].0, accept: 0.5 }
            }, |x| assert!(x.iter().all(|c| c.is_finite())));
            prop_assert!(emitted <= iterations.min(64));
        }
    }

    /// Pixel state buffers report sizes they cannot hold instead of aborting (issue 14).
    #[test]
    fn pixel_buffers_validate(width in prop_oneof![0u32..64, (1u32 << 31)..=u32::MAX], height in prop_oneof![0u32..64, (1u32 << 31)..=u32::MAX]) {
        match mcmm::PixelStateBuffers::new(width, height) {
            Ok(b) => prop_assert!(width < 64 && height < 64 && b.width() == width),
            Err(e) => prop_assert!(width > i32::MAX as u32 || height > i32::MAX as u32, "{e:?}"),
        }
    }
}
