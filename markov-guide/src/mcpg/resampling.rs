//! Grid resampling: N_mc candidate states, one kept by weighted reservoir sampling (MCPG Alg. 1).

use mcg_vmf::glam::Vec3;
use mcg_vmf::{MapPrior, PriorDecay};

use super::{GridState, McpgParams};
use crate::Reservoir;

/// Which grid a candidate was loaded from (MCPG sec. 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridKind {
    /// The adaptive multi-level grid, whose key holds the normal class: a normal mismatch shows
    /// up as a collision there.
    Adaptive,
    /// The coarse static grid, whose key has no normal: candidates are filtered by the angle
    /// between their lobe and the surface normal instead.
    Static,
}

/// The MAP prior of MCPG Alg. 2 line 7 for a state seen from `x`: r_p = 0 with
/// N_p = max(N_p,min, scale/|ȳ − x|²), decaying with N² (sec. 4, step 2).
#[inline]
#[must_use]
pub fn distance_prior(state: &GridState, x: Vec3, params: &McpgParams) -> MapPrior {
    let d2 = (state.mean_target - x).length_squared();
    let weight = if d2 > 0.0 {
        (params.prior_scale / d2).max(params.prior_min_weight)
    } else {
        f32::INFINITY
    };
    MapPrior {
        mean_cosine: 0.0,
        weight: if weight.is_nan() {
            params.prior_min_weight
        } else {
            weight
        },
        decay: PriorDecay::SquaredCount,
    }
}

/// Prepares a loaded state as a candidate of Alg. 1 (lines 5-7): velocity prediction to time
/// `now` (eq. 10); w̄ ← 0 after a hash collision (`collided`, the checksum did not match); for
/// the static grid, w̄ ← 0 when the lobe direction μ at `x` makes cos(μ, `normal`) ≤
/// `params.static_normal_threshold`. Pass `normal = None` to skip the normal test (single
/// scattering, where the static grid has no threshold).
#[inline]
#[must_use]
pub fn prepare_candidate(
    state: GridState,
    collided: bool,
    grid: GridKind,
    x: Vec3,
    normal: Option<Vec3>,
    now: f32,
    params: &McpgParams,
) -> GridState {
    let mut s = state;
    prepare_in_place(&mut s, collided, grid, x, normal, now, params);
    s
}

/// [`prepare_candidate`] on a state where it lies (the candidate set's storage), so that a
/// vertex's states are not copied from array to array.
#[inline]
pub(crate) fn prepare_in_place(
    s: &mut GridState,
    collided: bool,
    grid: GridKind,
    x: Vec3,
    normal: Option<Vec3>,
    now: f32,
    params: &McpgParams,
) {
    // Prediction never changes validity (it keeps ȳ unless the moved one is finite), so one
    // test serves both.
    let valid = s.is_valid();
    if valid {
        s.predict_valid(now);
    }
    let rejected = collided
        || !valid
        || (grid == GridKind::Static
            && normal.is_some_and(|n| {
                let mu = (s.mean_target - x).normalize_or_zero();
                !(mu.dot(n) > params.static_normal_threshold)
            }));
    if rejected {
        s.weight_sum = 0.0;
    }
}

/// The candidates of one vertex and the one chosen among them (MCPG Alg. 1): up to `N`
/// states, the reservoir choice proportional to w̄, and sum_mc = Σ w̄.
///
/// All offered states are kept, chosen or not, because the estimator's pdf
/// ([`CandidateSet::pdf`]) is a mixture over every accessed state (sec. 4, step 1: "the
/// distribution parameters of all accessed states are retained in memory"). Fixed capacity,
/// no allocation: offers beyond `N` count towards sum_mc and may be chosen, but the set's
/// pdf then needs them too, so [`CandidateSet::offer`] refuses them (returns `false`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CandidateSet<const N: usize> {
    states: [GridState; N],
    len: usize,
    /// Chao's reservoir over the offered indices, weighted by w̄.
    reservoir: Reservoir<usize>,
}

impl<const N: usize> Default for CandidateSet<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> CandidateSet<N> {
    /// An empty set.
    #[inline]
    #[must_use]
    pub const fn new() -> Self {
        Self {
            states: [GridState::EMPTY; N],
            len: 0,
            reservoir: Reservoir::new(),
        }
    }

    /// Offers a prepared candidate ([`prepare_candidate`]) with one uniform (Alg. 1 lines 8-11):
    /// sum_mc += w̄; the candidate is chosen when `u · sum_mc < w̄` ([`Reservoir::offer`]).
    /// Returns `false` (and changes nothing) when the set is full.
    #[inline]
    pub fn offer(&mut self, candidate: GridState, u: f32) -> bool {
        if self.len == N {
            return false;
        }
        self.states[self.len] = candidate;
        self.reservoir
            .offer(self.len, candidate.resampling_weight(), u);
        self.len += 1;
        true
    }

    /// Empties the set (nothing offered, the reservoir reset) and returns the storage of its
    /// states, left as they were: the caller writes every entry (a loaded state or
    /// [`GridState::EMPTY`], so that they are not zeroed first), prepares the candidates there,
    /// then [`offer_stored`](Self::offer_stored)s them in order.
    #[cfg(feature = "std")]
    #[inline]
    pub(crate) fn restart(&mut self) -> &mut [GridState; N] {
        self.len = 0;
        self.reservoir = Reservoir::new();
        &mut self.states
    }

    /// Offers the state already in the storage at the next index (see
    /// [`restart`](Self::restart)), prepared by [`prepare_in_place`]: its w̄ is its
    /// resampling weight (preparation zeroed it for every invalid state).
    #[cfg(feature = "std")]
    #[inline]
    pub(crate) fn offer_stored(&mut self, u: f32) -> bool {
        if self.len == N {
            return false;
        }
        self.reservoir
            .offer(self.len, self.states[self.len].weight_sum, u);
        self.len += 1;
        true
    }

    /// The accessed states, in offer order.
    #[inline]
    #[must_use]
    pub fn states(&self) -> &[GridState] {
        &self.states[..self.len]
    }

    /// The chosen state, `None` when every candidate had w̄ = 0 (Alg. 2 then falls back to
    /// BSDF sampling).
    #[inline]
    #[must_use]
    pub fn selected(&self) -> Option<&GridState> {
        self.selected_index().map(|i| &self.states[i])
    }

    /// Index of the chosen state in [`CandidateSet::states`].
    #[inline]
    #[must_use]
    pub fn selected_index(&self) -> Option<usize> {
        self.reservoir.selected().copied()
    }

    /// sum_mc = Σ w̄ over the accessed states.
    #[inline]
    #[must_use]
    pub const fn weight_sum(&self) -> f32 {
        self.reservoir.weight_sum()
    }

    /// The mean candidate score sum_mc / N_mc of the acceptance test (eq. 8), with N_mc the
    /// number of accessed states.
    #[inline]
    #[must_use]
    pub fn mean_weight(&self) -> f32 {
        if self.len == 0 {
            0.0
        } else {
            self.weight_sum() / self.len as f32
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use mcg_vmf::{FitParams, SufficientStats};

    pub(crate) fn state_towards(target: Vec3, weight: f32) -> GridState {
        let mut stats = SufficientStats::EMPTY;
        stats.update(Vec3::ZERO, target, weight, &FitParams::MCPG);
        GridState::from_stats(&stats, 0.0, Vec3::ZERO)
    }

    #[test]
    fn collisions_and_static_normal_mismatches_zero_the_weight() {
        let p = McpgParams::PAPER;
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 1.0);
        let keep = prepare_candidate(
            s,
            false,
            GridKind::Static,
            Vec3::ZERO,
            Some(Vec3::Z),
            0.0,
            &p,
        );
        assert_eq!(keep.weight_sum, 1.0);
        let below = prepare_candidate(
            s,
            false,
            GridKind::Static,
            Vec3::ZERO,
            Some(-Vec3::Z),
            0.0,
            &p,
        );
        assert_eq!(below.weight_sum, 0.0);
        // The adaptive grid does not test the normal (its key does).
        let adaptive = prepare_candidate(
            s,
            false,
            GridKind::Adaptive,
            Vec3::ZERO,
            Some(-Vec3::Z),
            0.0,
            &p,
        );
        assert_eq!(adaptive.weight_sum, 1.0);
        let collided = prepare_candidate(s, true, GridKind::Adaptive, Vec3::ZERO, None, 0.0, &p);
        assert_eq!(collided.weight_sum, 0.0);
    }

    #[test]
    fn reservoir_keeps_all_states_and_picks_by_weight() {
        let n = 200;
        let mut counts = [0u32; 3];
        for a in 0..n {
            for b in 0..n {
                let mut set = CandidateSet::<4>::new();
                set.offer(state_towards(Vec3::Z, 1.0), 0.5);
                set.offer(
                    state_towards(Vec3::X + Vec3::Z, 3.0),
                    (a as f32 + 0.5) / n as f32,
                );
                set.offer(GridState::EMPTY, 0.0);
                set.offer(
                    state_towards(Vec3::Y + Vec3::Z, 4.0),
                    (b as f32 + 0.5) / n as f32,
                );
                assert_eq!(set.states().len(), 4);
                assert_eq!(set.weight_sum(), 8.0);
                assert_eq!(set.mean_weight(), 2.0);
                let i = set.selected_index().unwrap();
                counts[[0, 1, 9, 2][i]] += 1;
                assert!(!set.offer(GridState::EMPTY, 0.0));
            }
        }
        for (k, w) in [1.0, 3.0, 4.0].iter().enumerate() {
            let p = counts[k] as f32 / (n * n) as f32;
            mcg_test_support::assert_close!(p, w / 8.0, 0.01, "candidate {k}");
        }
        assert_eq!(CandidateSet::<2>::new().selected(), None);
    }

    #[test]
    fn distance_prior_follows_inverse_square() {
        let p = McpgParams::PAPER;
        let s = state_towards(Vec3::new(0.0, 0.0, 2.0), 1.0);
        assert_eq!(distance_prior(&s, Vec3::ZERO, &p).weight, 0.25);
        let far = state_towards(Vec3::new(0.0, 0.0, 1000.0), 1.0);
        assert_eq!(distance_prior(&far, Vec3::ZERO, &p).weight, 1e-4);
        assert_eq!(
            distance_prior(&s, Vec3::new(0.0, 0.0, 2.0), &p).weight,
            f32::INFINITY
        );
    }
}
