//! Acceptance and maximum-likelihood update of a pixel's chain (MCMM Alg. 3).

use mcg_vmf::glam::Vec3;

use super::{McmmParams, PixelState};

/// MCMM Alg. 3: the Metropolis-style acceptance of the tentative state `tentative` (S) against
/// the current state `current` (S_c), then the maximum-likelihood update of S with the new
/// sample. Returns whether S was accepted.
///
/// Inputs: the shading point `x1`, the traced vertex `x2`, the score `f = lum(L_e f_r)/p(ω)`
/// (line 1, computed by the renderer, with p as [`McmmParams::score_density`] says), whether ω
/// came from the hemisphere technique, and one uniform `u`.
///
/// 1. a = min(1, f / S_c.f); accept when f > 0 and (S_c invalid or u < a) (lines 2-4).
/// 2. On acceptance after a hemisphere sample, S is reset to {0} (line 6): the new light starts
///    a new lobe. S.f ← f.
/// 3. S absorbs (x2, f) with N ← min(N + 1, N_max), α = max(1/N, α_min) (lines 11-17, see
///    [`SufficientStats::update`](mcg_vmf::SufficientStats::update)); zero-contribution
///    samples count too and narrow the lobe, as the paper notes.
/// 4. On acceptance S_c ← S. The listing copies S into S_c (line 9) before the update of lines
///    11-17; we copy after it, so the state written out holds the sample that made it win
///    (copying first would write an empty state after every accepted hemisphere sample).
///
/// Bad input never poisons a state: a score that is NaN, infinite or negative is treated as 0
/// (never accepted; the MLE step counts it as a zero-weight sample), and non-finite points
/// leave S unchanged.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn update(
    tentative: &mut PixelState,
    current: &mut PixelState,
    x1: Vec3,
    x2: Vec3,
    f: f32,
    from_hemisphere: bool,
    u: f32,
    params: &McmmParams,
) -> bool {
    let f = crate::math::finite_non_negative_or_zero(f);
    // u < f/S_c.f, written as u·S_c.f < f so that S_c.f = 0 accepts any f > 0.
    let accepted = f > 0.0 && (!current.is_valid() || u * current.score < f);
    if accepted {
        if from_hemisphere {
            *tentative = PixelState::EMPTY;
        }
        tentative.score = f;
    }
    tentative.stats.update(x1, x2, f, &params.fit);
    if accepted {
        *current = *tentative;
    }
    accepted
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hemisphere_hit_resets_and_wins() {
        let p = McmmParams::PAPER;
        let mut s = PixelState::EMPTY;
        s.stats
            .update(Vec3::ZERO, Vec3::new(5.0, 0.0, 1.0), 1.0, &p.fit);
        s.score = 1.0;
        let mut c = s;
        let light = Vec3::new(0.0, 0.0, 3.0);
        assert!(update(
            &mut s,
            &mut c,
            Vec3::ZERO,
            light,
            4.0,
            true,
            0.5,
            &p
        ));
        assert_eq!(s.stats.sample_count, 1);
        assert_eq!(s.stats.mean_target, light);
        assert_eq!(c, s);
        assert_eq!(c.score, 4.0);
    }

    #[test]
    fn acceptance_probability_is_the_score_ratio() {
        let p = McmmParams::PAPER;
        let mut c = PixelState::EMPTY;
        c.stats.update(Vec3::ZERO, Vec3::Z, 4.0, &p.fit);
        c.score = 4.0;
        // f = 1 against S_c.f = 4: accepted iff u < 1/4.
        for (u, want) in [(0.24, true), (0.26, false)] {
            let mut s = c;
            let mut cur = c;
            assert_eq!(
                update(&mut s, &mut cur, Vec3::ZERO, Vec3::Z, 1.0, false, u, &p),
                want
            );
            assert_eq!(s.stats.sample_count, 2); // the MLE step runs either way
            assert_eq!(cur.stats.sample_count, if want { 2 } else { 1 });
        }
    }

    #[test]
    fn adversarial_scores_never_poison() {
        let p = McmmParams::PAPER;
        for f in [
            f32::NAN,
            f32::INFINITY,
            -3.0,
            0.0,
            f32::MAX,
            f32::MIN_POSITIVE,
        ] {
            let mut s = PixelState::EMPTY;
            let mut c = PixelState::EMPTY;
            for (i, x2) in [
                Vec3::Z,
                Vec3::ZERO,
                Vec3::splat(f32::NAN),
                Vec3::new(1e30, 0.0, 1.0),
            ]
            .into_iter()
            .enumerate()
            {
                update(&mut s, &mut c, Vec3::ZERO, x2, f, i % 2 == 0, 0.3, &p);
                for st in [s, c] {
                    assert!(
                        st.stats.weight_sum.is_finite() && st.stats.weight_sum >= 0.0,
                        "{f} {st:?}"
                    );
                    assert!(st.stats.mean_target.is_finite(), "{f} {st:?}");
                    assert!(st.score.is_finite());
                    assert!(st.stats.one_minus_mean_cosine.is_finite());
                }
            }
        }
    }
}
