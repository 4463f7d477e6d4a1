//! State transition, maximum-likelihood update and the discard heuristic (MCPG Alg. 3, sec. 5).

use mcg_vmf::glam::Vec3;

use super::{CandidateSet, DiscardRule, GridState, McpgParams, distance_prior};

/// What the renderer observed for one guided sample, the inputs of MCPG Alg. 3.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// hit.x, the shading point the direction was sampled at.
    pub x: Vec3,
    /// hit_next.x, the traced vertex.
    pub next: Vec3,
    /// hit_next.x_prev, where that vertex was in the previous frame (from the renderer's motion
    /// data; equal to `next` for static geometry).
    pub next_previous: Vec3,
    /// f_mc = lum(⟨L_i(hit.x, ω)⟩_SMIS), eq. 7 (Alg. 3 line 1).
    pub estimate: f32,
    /// T, the current time.
    pub now: f32,
    /// T − T_prev, the time since the previous frame (the denominator of eq. 9).
    pub frame_time: f32,
}

impl Observation {
    /// An observation in a static scene: hit_next did not move (x_prev = x, so v = 0) and
    /// frames are one time unit apart.
    #[inline]
    #[must_use]
    pub const fn static_scene(x: Vec3, next: Vec3, estimate: f32, now: f32) -> Self {
        Self {
            x,
            next,
            next_previous: next,
            estimate,
            now,
            frame_time: 1.0,
        }
    }
}

/// [`update`] from the candidates themselves: continues from the chosen candidate after a lobe
/// sample (`lobe_sampled`), from the empty state after a BSDF sample (Alg. 2 line 4), with the
/// set's mean weight, so that the caller cannot pass the wrong state.
#[inline]
#[must_use]
pub fn update_from<const N: usize>(
    set: &CandidateSet<N>,
    lobe_sampled: bool,
    observation: &Observation,
    u: f32,
    params: &McpgParams,
) -> Option<GridState> {
    let state = match (lobe_sampled, set.selected()) {
        (true, Some(s)) => *s,
        _ => GridState::EMPTY,
    };
    update(&state, set.mean_weight(), observation, u, params)
}

/// MCPG Alg. 3: acceptance against the mean candidate score (eq. 8), then the MLE update.
///
/// `state` is the state Alg. 2 continued from ([`choose_technique`](super::choose_technique):
/// the chosen state, or empty after a BSDF sample); `mean_weight` is sum_mc/N_mc
/// ([`CandidateSet::mean_weight`](super::CandidateSet::mean_weight)); `u` one uniform.
/// Accepts when `u < f_mc/(sum_mc/N_mc)`; then N ← min(N + 1, N_max), α = max(1/N, α_min),
/// w̄, ȳ, r̄ move towards (f_mc, hit_next.x, d·μ) (lines 4-9), T ← now (line 10) and
/// v ← (hit_next.x − hit_next.x_prev)/(T − T_prev) (line 11, eq. 9). Returns the state to
/// store ("grid.store", line 12) — at a freshly chosen level and corner — or `None` when the
/// transition was rejected.
///
/// Bad input never poisons a state: an estimate that is NaN, infinite or negative, or a `now`
/// that is NaN or infinite, is never accepted; non-finite points leave the statistics
/// unchanged; a zero or non-finite frame time (or velocity) stores v = 0.
#[inline]
#[must_use]
pub fn update(
    state: &GridState,
    mean_weight: f32,
    observation: &Observation,
    u: f32,
    params: &McpgParams,
) -> Option<GridState> {
    let f = observation.estimate;
    if !(0.0..f32::INFINITY).contains(&f) || !observation.now.is_finite() {
        return None;
    }
    // u < f/(sum/N) ⇔ u·(sum/N) < f; an empty neighbourhood (mean 0) accepts any f > 0.
    let mean_weight = crate::math::finite_non_negative_or_zero(mean_weight);
    if !(f > 0.0 && u * mean_weight < f) {
        return None;
    }
    let mut stats = state.stats();
    stats.update(observation.x, observation.next, f, &params.fit);
    let velocity = if observation.frame_time > 0.0 && observation.frame_time.is_finite() {
        (observation.next - observation.next_previous) / observation.frame_time
    } else {
        Vec3::ZERO
    };
    Some(GridState::from_stats(&stats, observation.now, velocity))
}

/// The discard heuristic of MCPG sec. 5, for a lobe sample whose transition was rejected:
/// `true` when the state's light seems gone, so the caller should zero w̄ of the slot the state
/// was read from ([`GridState::weight_sum`] = 0).
///
/// All three must hold: the new estimate is small, f_mc ≤ ratio·w̄; the state was not updated
/// at this time (T ≠ now); and ω points at the state's target (the light would have been hit
/// were it still there): μᵀω > r with r the MAP mean cosine of Alg. 2 line 7
/// ([`DiscardRule::Paper`]), or ω·μ ≥ 0.9 + 0.1·r̄ ([`DiscardRule::Engine`]).
#[inline]
#[must_use]
pub fn should_discard(
    state: &GridState,
    x: Vec3,
    w: Vec3,
    estimate: f32,
    now: f32,
    params: &McpgParams,
) -> bool {
    if !state.is_valid() || state.time == now {
        return false;
    }
    let estimate = if estimate >= 0.0 { estimate } else { 0.0 };
    let (DiscardRule::Paper { ratio } | DiscardRule::Engine { ratio }) = params.discard;
    if !(estimate <= ratio * state.weight_sum) {
        return false;
    }
    let Some(mu) = (state.mean_target - x).try_normalize() else {
        return false;
    };
    let threshold = match params.discard {
        DiscardRule::Paper { .. } => state
            .stats()
            .posterior_mean_cosine(distance_prior(state, x, params)),
        DiscardRule::Engine { .. } => 0.9 + 0.1 * state.stats().mean_cosine(),
    };
    match params.discard {
        DiscardRule::Paper { .. } => mu.dot(w) > threshold,
        DiscardRule::Engine { .. } => mu.dot(w) >= threshold,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcpg::resampling::tests::state_towards;

    fn observation(estimate: f32) -> Observation {
        Observation {
            x: Vec3::ZERO,
            next: Vec3::new(0.0, 0.0, 2.0),
            next_previous: Vec3::new(-0.1, 0.0, 2.0),
            estimate,
            now: 3.0,
            frame_time: 0.5,
        }
    }

    #[test]
    fn acceptance_against_mean_candidate_score() {
        let p = McpgParams::PAPER;
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 2.0);
        // f = 1 against mean 4: accepted iff u < 0.25.
        assert!(update(&s, 4.0, &observation(1.0), 0.24, &p).is_some());
        assert!(update(&s, 4.0, &observation(1.0), 0.26, &p).is_none());
        let new = update(&GridState::EMPTY, 0.0, &observation(1.0), 0.99, &p).unwrap();
        assert_eq!(new.sample_count(), 1);
        assert_eq!(new.time, 3.0);
        assert!((new.velocity() - Vec3::new(0.2, 0.0, 0.0)).length() < 1e-4);
        assert_eq!(new.mean_target, Vec3::new(0.0, 0.0, 2.0));
    }

    #[test]
    fn adversarial_observations_never_poison() {
        let p = McpgParams::PAPER;
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 2.0);
        for f in [f32::NAN, f32::INFINITY, -1.0, 0.0] {
            assert!(update(&s, 1.0, &observation(f), 0.0, &p).is_none());
        }
        let mut o = observation(f32::MAX);
        o.next = Vec3::new(1e30, 0.0, 1e30);
        o.frame_time = 0.0;
        let new = update(&s, f32::NAN, &o, 0.0, &p).unwrap();
        assert!(new.is_valid() && new.velocity() == Vec3::ZERO);
        assert!(new.one_minus_mean_cosine.is_finite());
        o.next = Vec3::splat(f32::NAN);
        let new = update(&s, 1.0, &o, 0.0, &p).unwrap();
        assert!(new.mean_target.is_finite());
        // Issue 14 row 9: a NaN or infinite `now` was stored as T.
        for now in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut o = observation(1.0);
            o.now = now;
            assert!(update(&s, 1.0, &o, 0.0, &p).is_none(), "{now}");
            assert_eq!(GridState::from_stats(&s.stats(), now, Vec3::ZERO).time, 0.0);
        }
    }

    #[test]
    fn update_from_continues_from_the_right_state() {
        let p = McpgParams::PAPER;
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 2.0);
        let mut set = CandidateSet::<2>::new();
        set.offer(s, 0.0);
        let o = Observation::static_scene(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), 1.0, 3.0);
        assert_eq!(o.next_previous, o.next);
        let lobe = update_from(&set, true, &o, 0.0, &p).unwrap();
        assert_eq!(lobe, update(&s, set.mean_weight(), &o, 0.0, &p).unwrap());
        assert_eq!(lobe.sample_count(), 2);
        let bsdf = update_from(&set, false, &o, 0.0, &p).unwrap();
        assert_eq!(bsdf.sample_count(), 1);
    }

    #[test]
    fn discard_needs_all_three_conditions() {
        let p = McpgParams::PAPER;
        let mut s = state_towards(Vec3::new(0.0, 0.0, 2.0), 2.0);
        s.time = 1.0;
        let towards = Vec3::Z;
        assert!(should_discard(&s, Vec3::ZERO, towards, 0.0, 2.0, &p));
        assert!(!should_discard(&s, Vec3::ZERO, towards, 0.0, 1.0, &p)); // updated now
        assert!(!should_discard(&s, Vec3::ZERO, towards, 1.5, 2.0, &p)); // estimate not small
        assert!(!should_discard(&s, Vec3::ZERO, Vec3::X, 0.0, 2.0, &p)); // looked elsewhere
        assert!(!should_discard(
            &GridState::EMPTY,
            Vec3::ZERO,
            towards,
            0.0,
            2.0,
            &p
        ));
    }
}
