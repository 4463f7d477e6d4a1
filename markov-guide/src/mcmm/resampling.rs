//! Collaborative discovery: weighted resampling of neighbour states (MCMM Alg. 1).

use mcg_vmf::glam::Vec2;

use super::PixelState;

/// A screen offset drawn from a degree-5 B-spline kernel with support ±`half_width` pixels
/// (MCMM sec. 4.1, Alg. 1 line 4).
///
/// Per axis the offset is `half_width/3 · (Σ₆ uᵢ − 3)`: the sum of six uniforms follows the
/// Irwin-Hall distribution of order 6, which is the degree-5 cardinal B-spline (Shirley et al.
/// 2005, cited as SSA05 in the paper). `u[0..6]` drive x, `u[6..12]` drive y. The paper's text says "the
/// sum of four random numbers", which is a degree-3 spline; its degree-5 statement and the
/// authors' vkdt code (`15·(Σ₆ u − 3)`, ±45 px) agree on six, which is what we use.
#[inline]
#[must_use]
pub fn bspline_offset(u: &[f32; 12], half_width: f32) -> Vec2 {
    let sx: f32 = u[0..6].iter().sum();
    let sy: f32 = u[6..12].iter().sum();
    Vec2::new(sx - 3.0, sy - 3.0) * (half_width / 3.0)
}

/// One step of Alg. 1 (lines 4-10): offers neighbour state `candidate` to the reservoir held in
/// `state` with running score sum `sum`. The candidate replaces `state` when the state is
/// invalid or when `u < s_q/(s_q + sum)`, where s_q = score(S_q) = S_q.f. Returns whether it did.
///
/// Invalid candidates (w̄ = 0, non-finite values, negative scores) are skipped: they neither
/// replace the state nor add to the sum.
#[inline]
pub fn resample_neighbour(
    state: &mut PixelState,
    sum: &mut f32,
    candidate: PixelState,
    u: f32,
) -> bool {
    if !candidate.is_valid() {
        return false;
    }
    let score = candidate.resampling_score();
    let total = *sum + score;
    let take = !state.is_valid() || u * total < score;
    if take {
        *state = candidate;
    }
    *sum = total;
    take
}

/// Alg. 1 over a list of neighbour candidates: starts the reservoir at the pixel's own
/// (shuffled) state with sum = score(S) (line 2) and offers each `(candidate, u)` pair in turn.
///
/// The renderer loads the candidates (Alg. 1 line 4: the previous frame's state at the
/// motion-corrected pixel `p + offset + motion`, offset from [`bspline_offset`]; see
/// [`PixelStateBuffers::neighbour`](super::PixelStateBuffers::neighbour)) and passes one uniform
/// per candidate. Off-screen candidates are simply not passed. The paper's loop condition "until
/// score(S) > 0" is met by offering a fixed number of candidates
/// ([`McmmParams::neighbour_candidates`](super::McmmParams::neighbour_candidates), 5 in vkdt).
///
/// # Example
/// ```
/// use mcg_markov_guide::mcmm::{PixelState, collaborative_discovery};
/// use mcg_markov_guide::glam::Vec3;
/// let mut bright = PixelState::EMPTY;
/// bright.stats.weight_sum = 1.0;
/// bright.stats.sample_count = 4;
/// bright.stats.mean_target = Vec3::Z;
/// bright.score = 9.0;
/// // An empty pixel takes the first valid neighbour it is offered.
/// let s = collaborative_discovery(PixelState::EMPTY, [(bright, 0.99)]);
/// assert_eq!(s, bright);
/// ```
#[must_use]
pub fn collaborative_discovery<I>(state: PixelState, candidates: I) -> PixelState
where
    I: IntoIterator<Item = (PixelState, f32)>,
{
    let mut state = state;
    let mut sum = state.resampling_score();
    for (candidate, u) in candidates {
        resample_neighbour(&mut state, &mut sum, candidate, u);
    }
    state
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcg_vmf::glam::Vec3;

    fn state(score: f32) -> PixelState {
        let mut s = PixelState::EMPTY;
        s.stats.weight_sum = 1.0;
        s.stats.sample_count = 1;
        s.stats.mean_target = Vec3::new(score, 0.0, 1.0);
        s.score = score;
        s
    }

    #[test]
    fn offset_has_the_spline_support_and_mean() {
        assert_eq!(bspline_offset(&[0.5; 12], 45.0), Vec2::ZERO);
        assert_eq!(bspline_offset(&[0.0; 12], 45.0), Vec2::splat(-45.0));
        let mut u = [0.0; 12];
        u[..6].fill(1.0);
        assert_eq!(bspline_offset(&u, 45.0), Vec2::new(45.0, -45.0));
    }

    #[test]
    fn selection_is_proportional_to_score() {
        // Own state score 1, neighbours 2 and 3: each of the three is kept with probability
        // score/6. Enumerate both uniforms on a grid.
        let n = 300;
        let mut counts = [0u32; 3];
        for a in 0..n {
            for b in 0..n {
                let ua = (a as f32 + 0.5) / n as f32;
                let ub = (b as f32 + 0.5) / n as f32;
                let s = collaborative_discovery(state(1.0), [(state(2.0), ua), (state(3.0), ub)]);
                counts[s.score as usize - 1] += 1;
            }
        }
        for (i, c) in counts.iter().enumerate() {
            let p = *c as f32 / (n * n) as f32;
            mcg_test_support::assert_close!(p, (i as f32 + 1.0) / 6.0, 0.005, "{i}: {p}");
        }
    }

    #[test]
    fn invalid_candidates_are_skipped_and_invalid_states_replaced() {
        let mut bad = state(5.0);
        bad.score = f32::NAN;
        assert_eq!(
            collaborative_discovery(state(1.0), [(bad, 0.0)]),
            state(1.0)
        );
        assert_eq!(
            collaborative_discovery(PixelState::EMPTY, [(state(0.5), 0.999)]),
            state(0.5)
        );
        // A valid state with score 0 is replaced by any valid candidate with score > 0 ...
        assert_eq!(
            collaborative_discovery(state(0.0), [(state(2.0), 0.999)]),
            state(2.0)
        );
        // ... and a zero-score candidate never replaces a valid state.
        assert_eq!(
            collaborative_discovery(state(1.0), [(state(0.0), 0.0)]),
            state(1.0)
        );
    }
}
