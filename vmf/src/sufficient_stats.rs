//! Sufficient statistics of the parallax-aware vMF fit shared by MCMM and MCPG, with the MAP
//! prior used to reconstruct a lobe at a shading point.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::mean_cosine::kappa_from_one_minus_mean_cosine;
use crate::{Vmf, math};

/// How the mean cosine r̄ absorbs a new sample direction.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MeanCosineUpdate {
    /// MCMM Alg. 3 lines 15-16: blend the vectors `r̄·μ` and the sample direction `d`, then take
    /// the length, `r̄ ← |mix(w̄ r̄ μ, f d, α)| / w̄'`. This is the mean resultant length, the
    /// maximum-likelihood statistic of the vMF.
    #[default]
    Resultant,
    /// MCPG Alg. 3 line 9: blend the cosine of `d` to the current mean direction,
    /// `r̄ ← mix(w̄ r̄, f (d·μ), α) / w̄'`. Cheaper; can go negative, so r̄ is kept in [−1, 1]
    /// and clamped to ≥ 0 when a lobe is reconstructed.
    Projected,
}

/// Parameters of the maximum-likelihood update (MCMM Alg. 3 lines 11-17, MCPG Alg. 3 lines 4-9).
///
/// The blend factor is α = max(1/N, α_min) after N is incremented and capped at N_max: a true
/// arithmetic mean for the first 1/α_min samples, an exponential moving average after.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitParams {
    /// N_max, the cap on the sample count N (MCMM Alg. 3 line 11: 1024). At least 1.
    pub max_count: u32,
    /// α_min, the smallest blend factor (MCMM Alg. 3 line 12: 0.1; MCPG's engine: 0.01).
    /// Values outside [0, 1] are clamped into it; 0 gives a plain running mean.
    pub alpha_min: f32,
    /// Which mean-cosine update to use.
    pub mean_cosine_update: MeanCosineUpdate,
}

impl FitParams {
    /// The MCMM paper's values: N_max = 1024, α_min = 0.1, resultant mean cosine.
    pub const MCMM: Self = Self {
        max_count: 1024,
        alpha_min: 0.1,
        mean_cosine_update: MeanCosineUpdate::Resultant,
    };

    /// The MCPG authors' engine values (merian-quake, their open-source Quake renderer): N_max = 1024,
    /// α_min = 0.01, projected mean cosine as in MCPG Alg. 3 line 9.
    pub const MCPG: Self = Self {
        max_count: 1024,
        alpha_min: 0.01,
        mean_cosine_update: MeanCosineUpdate::Projected,
    };

    /// A plain running mean over every sample (α = 1/N forever): the unbiased estimator of
    /// a stationary lobe, used to test the fit.
    pub const RUNNING_MEAN: Self = Self {
        max_count: u32::MAX,
        alpha_min: 0.0,
        mean_cosine_update: MeanCosineUpdate::Resultant,
    };
}

impl Default for FitParams {
    /// [`FitParams::MCMM`].
    fn default() -> Self {
        Self::MCMM
    }
}

/// How fast the prior's virtual samples lose weight against the N real ones.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PriorDecay {
    /// `r = (N² r̄ + N_p r_p) / (N² + N_p)`: MCMM Alg. 2 line 6 and MCPG Alg. 2 line 7, so the
    /// prior vanishes quickly after a reset.
    #[default]
    SquaredCount,
    /// `r = (N r̄ + N_p r_p) / (N + N_p)`: the textbook MAP estimate (as in Open PGL).
    Count,
}

/// The MAP prior on the mean cosine (MCMM sec. 5 "Uninformed vs. informed priors").
///
/// The prior is a virtual set of `weight` = N_p samples with mean cosine `mean_cosine` = r_p.
/// Callers whose prior depends on the shading point (MCPG: N_p = 1/|ȳ − x|²) build one per
/// reconstruction, e.g. with [`MapPrior::inverse_square_distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPrior {
    /// r_p, the prior mean cosine, in [0, 1). 0 is the uninformed (uniform) prior.
    pub mean_cosine: f32,
    /// N_p ≥ 0, the number of virtual samples the prior accounts for.
    pub weight: f32,
    /// How the prior decays with the sample count N.
    pub decay: PriorDecay,
}

impl MapPrior {
    /// No prior at all: the lobe is the plain maximum-likelihood fit.
    pub const NONE: Self = Self {
        mean_cosine: 0.0,
        weight: 0.0,
        decay: PriorDecay::SquaredCount,
    };

    /// An uninformed prior r_p = 0 with `weight` virtual samples and the N² decay of the papers.
    #[inline]
    #[must_use]
    pub const fn uninformed(weight: f32) -> Self {
        Self {
            mean_cosine: 0.0,
            weight,
            decay: PriorDecay::SquaredCount,
        }
    }

    /// MCPG's distance prior (sec. 4 "Step 2", Alg. 2 line 7): r_p = 0 and
    /// N_p = max(`min_weight`, `scale` / `distance`²), where `distance` = |ȳ − x| (see
    /// [`SufficientStats::target_distance`]). The paper uses `scale` = 1; the authors' engine
    /// 0.2-0.3 with `min_weight` = 10⁻⁴. A zero distance (or one whose square underflows)
    /// gives an infinite weight, which [`SufficientStats::posterior_mean_cosine`] treats as
    /// "prior only"; any other finite input gives a finite weight (saturating at `f32::MAX`).
    #[inline]
    #[must_use]
    pub fn inverse_square_distance(scale: f32, min_weight: f32, distance: f32) -> Self {
        let squared = distance * distance;
        let weight = scale / squared;
        // Saturate an overflowing quotient, but keep 1/0 = ∞ ("prior only").
        let weight = if squared != 0.0 && weight > f32::MAX {
            f32::MAX
        } else {
            weight
        };
        Self::uninformed(weight.max(min_weight))
    }
}

impl Default for MapPrior {
    /// [`MapPrior::NONE`].
    fn default() -> Self {
        Self::NONE
    }
}

/// Sufficient statistics of a parallax-aware vMF fit: MCMM Table 1 (ȳ, r̄, w̄, N) and MCPG
/// Table 1 (w̄, N, ȳ, r̄), normalised (ȳ and r̄ are means, not weighted sums).
///
/// Samples are target points y (light-source vertices) seen from shading points x with a
/// non-negative weight f (a luminance estimate). The lobe at any shading point x is recovered
/// as μ = (ȳ − x)/|ȳ − x| and κ from r̄ with a MAP prior ([`SufficientStats::to_vmf`]), which is
/// why these statistics can be exchanged between pixels or grid cells (MCMM sec. 5
/// "Sufficient statistics"). Scores, acceptance, time and velocity belong to the chain
/// (mcg-markov-guide), not here.
///
/// r̄ is stored as its complement `one_minus_mean_cosine` = 1 − r̄: concentrated lobes have
/// r̄ ≈ 1 − 1/κ, where f32 spacing (6·10⁻⁸) is coarser than one running-mean step (≈ 1/(κN)),
/// so a stored r̄ would round the updates away and drift (a κ = 1000 fit over 2·10⁴ samples
/// came out at 926). The complement keeps full relative precision there.
///
/// `#[repr(C)]`, 24 bytes: `mean_target`, `weight_sum`, `one_minus_mean_cosine`, `sample_count`.
///
/// # Example
/// ```
/// use mcg_vmf::{FitParams, MapPrior, SufficientStats, glam::Vec3};
/// let x = Vec3::ZERO;
/// let mut stats = SufficientStats::EMPTY;
/// assert!(stats.to_vmf(x, MapPrior::NONE).is_none());
/// for y in [Vec3::new(0.1, 0.0, 5.0), Vec3::new(-0.1, 0.05, 5.0), Vec3::new(0.0, -0.1, 5.0)] {
///     stats.update(x, y, 2.0, &FitParams::MCMM);
/// }
/// // Three samples 0.02 rad apart: the plain fit is very narrow ...
/// let fit = stats.to_vmf(x, MapPrior::NONE).unwrap();
/// assert!(fit.mu().z > 0.999 && fit.kappa() > 1000.0);
/// // ... while 0.2 virtual samples of a uniform prior (r_p = 0) keep it wider while N is small.
/// let map = stats.to_vmf(x, MapPrior::uninformed(0.2)).unwrap();
/// assert!(map.kappa() > 20.0 && map.kappa() < 100.0);
/// ```
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SufficientStats {
    /// ȳ, the weighted mean target point (world space).
    pub mean_target: Vec3,
    /// w̄, the weight sum: a (moving) average of the sample weights f. 0 means empty.
    pub weight_sum: f32,
    /// 1 − r̄, the complement of the weighted mean cosine of the sample directions, in [0, 2]
    /// (in [0, 1] with [`MeanCosineUpdate::Resultant`]). See [`SufficientStats::mean_cosine`].
    pub one_minus_mean_cosine: f32,
    /// N, the number of samples absorbed so far, capped at [`FitParams::max_count`].
    pub sample_count: u32,
}

const _: () = assert!(core::mem::size_of::<SufficientStats>() == 24);

impl Default for SufficientStats {
    /// [`SufficientStats::EMPTY`].
    fn default() -> Self {
        Self::EMPTY
    }
}

impl SufficientStats {
    /// Empty statistics (all zero, so zeroed GPU memory is empty too): no lobe can be
    /// reconstructed. r̄ of empty statistics is meaningless; the first weighted sample
    /// overwrites it.
    pub const EMPTY: Self = Self {
        mean_target: Vec3::ZERO,
        weight_sum: 0.0,
        one_minus_mean_cosine: 0.0,
        sample_count: 0,
    };

    /// `true` when the statistics carry weight (`w̄ > 0`, MCMM sec. 4.1 "valid").
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.weight_sum > 0.0
    }

    /// Absorbs one sample: target point `y` seen from shading point `x` with weight `weight`
    /// (MCMM Alg. 3 lines 11-17; MCPG Alg. 3 lines 4-9).
    ///
    /// With N ← min(N + 1, N_max), α = max(1/N, α_min) and w̄' = mix(w̄, f, α):
    ///
    /// ```text
    /// ȳ' = mix(w̄ ȳ, f y, α) / w̄'                 = (1 − β) ȳ + β y
    /// r̄' = |mix(w̄ r̄ μ, f d, α)| / w̄'             = |(1 − β) r̄ μ + β d|      (Resultant)
    /// r̄' = mix(w̄ r̄, f (d·μ), α) / w̄'             = (1 − β) r̄ + β (d·μ)      (Projected)
    /// ```
    ///
    /// where β = α f / w̄' ∈ [0, 1], μ is the current mean direction from `x` (or `d` when the
    /// statistics are empty) and d = (y − x)/|y − x|. The β forms cannot overflow. r̄ is
    /// updated in complement form, e = 1 − r̄ and t = 1 − d·μ = |d − μ|²/2, so nothing cancels:
    ///
    /// ```text
    /// 1 − r̄'² = (1 − β)² e (2 − e) + 2β(1 − β)(e + t − e t),   e' = (1 − r̄'²) / (1 + r̄')   (Resultant)
    /// e' = (1 − β) e + β t                                                              (Projected)
    /// ```
    ///
    /// A zero weight still counts (N grows, w̄ shrinks, ȳ and r̄ stay), as in the papers.
    /// A sample with a negative, NaN or infinite weight, or a non-finite point, is ignored
    /// and leaves the statistics unchanged; the return value says whether it was absorbed.
    /// `y = x` contributes a zero direction (it lowers r̄).
    #[inline]
    pub fn update(&mut self, x: Vec3, y: Vec3, weight: f32, params: &FitParams) -> bool {
        if !((0.0..f32::INFINITY).contains(&weight) & math::all_finite(x) & math::all_finite(y)) {
            return false;
        }
        let max_count = params.max_count.max(1);
        let count = self.sample_count.saturating_add(1).min(max_count);
        let alpha = (1.0 / count as f32)
            .max(params.alpha_min.clamp(0.0, 1.0))
            .min(1.0);
        // mix(w̄, f, α), bounded by the larger of the two so rounding cannot overflow.
        let weight_sum =
            ((1.0 - alpha) * self.weight_sum + alpha * weight).min(self.weight_sum.max(weight));
        self.sample_count = count;
        if !(weight_sum > 0.0) {
            // Nothing has weight: keep ȳ and r̄ (the papers' 0/0).
            self.weight_sum = 0.0;
            return true;
        }
        let beta = (alpha * weight / weight_sum).min(1.0);
        let direction = math::normalize_robust(y - x).unwrap_or(Vec3::ZERO);
        let mean_direction = if self.weight_sum > 0.0 {
            math::normalize_robust(self.mean_target - x).unwrap_or(direction)
        } else {
            direction
        };
        let e = self.one_minus_mean_cosine;
        self.one_minus_mean_cosine = if direction == Vec3::ZERO {
            // d = 0: r̄' = (1 − β) r̄ (Resultant) or (1 − β) r̄ + β·0 (Projected).
            beta + (1.0 - beta) * e
        } else {
            let t = 0.5 * (direction - mean_direction).length_squared();
            match params.mean_cosine_update {
                MeanCosineUpdate::Resultant => {
                    let e = e.clamp(0.0, 1.0);
                    let keep = 1.0 - beta;
                    let d = (keep * keep * e * (2.0 - e) + 2.0 * beta * keep * (e + t - e * t))
                        .clamp(0.0, 1.0);
                    d / (1.0 + math::sqrt(1.0 - d))
                }
                MeanCosineUpdate::Projected => ((1.0 - beta) * e + beta * t).clamp(0.0, 2.0),
            }
        };
        let mean_target = self.mean_target * (1.0 - beta) + y * beta;
        if math::all_finite(mean_target) {
            self.mean_target = mean_target;
        }
        self.weight_sum = weight_sum;
        true
    }

    /// The weighted mean cosine r̄ = 1 − [`one_minus_mean_cosine`](Self::one_minus_mean_cosine).
    #[inline]
    #[must_use]
    pub fn mean_cosine(&self) -> f32 {
        1.0 - self.one_minus_mean_cosine
    }

    /// Mean direction μ = (ȳ − x)/|ȳ − x| from shading point `x` (MCMM Alg. 2 line 5), or
    /// `None` when the statistics are empty, ȳ coincides with `x` or `x` is not finite.
    /// Unit length to f32 precision however close ȳ is to `x` (and however far).
    #[inline]
    #[must_use]
    pub fn mean_direction(&self, x: Vec3) -> Option<Vec3> {
        if !self.is_valid() {
            return None;
        }
        math::normalize_robust(self.mean_target - x)
    }

    /// Distance |ȳ − x| from shading point `x` to the mean target, the input of distance
    /// priors such as [`MapPrior::inverse_square_distance`]. Accurate however far apart the
    /// points are (|ȳ − x|² is not formed where it would overflow) and saturating at
    /// `f32::MAX`, so finite points give a finite distance.
    #[inline]
    #[must_use]
    pub fn target_distance(&self, x: Vec3) -> f32 {
        math::length_robust(self.mean_target - x)
    }

    /// The MAP mean cosine r = (N² r̄ + N_p r_p)/(N² + N_p) (MCMM Alg. 2 line 6, MCPG Alg. 2
    /// line 7), or with N instead of N² for [`PriorDecay::Count`]. r̄ and r_p are clamped to
    /// [0, 1] first (a NaN r_p counts as 0), so the result is finite whenever N_p is not NaN.
    /// An infinite N_p gives r_p; N = N_p = 0 gives 0.
    #[inline]
    #[must_use]
    pub fn posterior_mean_cosine(&self, prior: MapPrior) -> f32 {
        1.0 - self.posterior_one_minus_mean_cosine(prior)
    }

    /// The inputs of the posterior besides 1 − r̄: (N_eff, N_p, 1 − r_p) with N_eff = N² or N
    /// by the prior's decay, N_p = max(0, weight) and r_p clamped to [0, 1] (NaN → 0).
    #[inline(always)]
    pub(crate) fn posterior_parts(&self, prior: MapPrior) -> (f32, f32, f32) {
        let n = self.sample_count as f32;
        let n_eff = match prior.decay {
            PriorDecay::SquaredCount => n * n,
            PriorDecay::Count => n,
        };
        // `max` maps NaN to 0 (`clamp` would keep it); in-range values pass unchanged.
        #[allow(clippy::manual_clamp)]
        let prior_complement = 1.0 - prior.mean_cosine.max(0.0).min(1.0);
        (n_eff, prior.weight.max(0.0), prior_complement)
    }

    /// 1 − r of [`SufficientStats::posterior_mean_cosine`], computed without cancellation:
    /// (N² (1 − r̄) + N_p (1 − r_p)) / (N² + N_p).
    #[inline]
    fn posterior_one_minus_mean_cosine(&self, prior: MapPrior) -> f32 {
        let (n_eff, prior_weight, prior_complement) = self.posterior_parts(prior);
        if prior_weight == f32::INFINITY {
            return prior_complement;
        }
        let total = n_eff + prior_weight;
        if !(total > 0.0) {
            return 1.0;
        }
        let sample_complement = self.one_minus_mean_cosine.clamp(0.0, 1.0);
        (n_eff * sample_complement + prior_weight * prior_complement) / total
    }

    /// Reconstructs the lobe at shading point `x` (MCMM Alg. 2 lines 5-7, MCPG Alg. 2 lines 6-8):
    /// μ from [`SufficientStats::mean_direction`], r from
    /// [`SufficientStats::posterior_mean_cosine`], κ by Banerjee's approximation
    /// ([`kappa_from_mean_cosine`](crate::kappa_from_mean_cosine), evaluated from 1 − r so that
    /// narrow lobes keep their precision; clamped to [`KAPPA_MAX`](crate::KAPPA_MAX)).
    ///
    /// Returns `None` for empty statistics (w̄ = 0 or N = 0) and when ȳ coincides with `x`.
    #[inline]
    #[must_use]
    pub fn to_vmf(&self, x: Vec3, prior: MapPrior) -> Option<Vmf> {
        if self.sample_count == 0 {
            return None;
        }
        let mu = self.mean_direction(x)?;
        let kappa = kappa_from_one_minus_mean_cosine(self.posterior_one_minus_mean_cosine(prior));
        Some(Vmf::from_unit_mean(mu, kappa))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_sample_sets_the_target() {
        let mut s = SufficientStats::EMPTY;
        assert!(s.update(Vec3::ZERO, Vec3::new(0.0, 0.0, 3.0), 2.0, &FitParams::MCMM));
        assert_eq!(s.sample_count, 1);
        assert_eq!(s.weight_sum, 2.0);
        assert_eq!(s.mean_target, Vec3::new(0.0, 0.0, 3.0));
        assert_eq!(s.mean_cosine(), 1.0);
        let lobe = s.to_vmf(Vec3::ZERO, MapPrior::uninformed(1.0)).unwrap();
        // r = (1·1 + 1·0)/(1 + 1) = 0.5.
        mcg_test_support::assert_close!(lobe.kappa(), crate::kappa_from_mean_cosine(0.5), 1e-6);
        assert_eq!(lobe.mu(), Vec3::Z);
    }

    #[test]
    fn matches_paper_mix_form() {
        // Unnormalised mix form of MCMM Alg. 3 lines 13-16 against the β form.
        let x = Vec3::new(0.2, -0.1, 0.0);
        let ys = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, 2.5, 2.0),
            Vec3::new(0.0, 1.0, 4.0),
            Vec3::new(2.0, 0.0, 1.0),
        ];
        let fs = [1.0_f32, 3.0, 0.5, 2.0];
        let params = FitParams {
            max_count: 2,
            alpha_min: 0.3,
            mean_cosine_update: MeanCosineUpdate::Resultant,
        };
        let mut s = SufficientStats::EMPTY;
        let (mut w, mut yb, mut r, mut n) = (0.0_f32, Vec3::ZERO, 0.0_f32, 0_u32);
        for (y, f) in ys.iter().zip(fs) {
            s.update(x, *y, f, &params);
            n = (n + 1).min(2);
            let a = (1.0 / n as f32).max(0.3);
            let mu = if w > 0.0 {
                (yb - x).normalize()
            } else {
                Vec3::ZERO
            };
            let w_new = w * (1.0 - a) + f * a;
            yb = (w * yb * (1.0 - a) + f * *y * a) / w_new;
            r = ((w * r * mu) * (1.0 - a) + f * (*y - x).normalize() * a).length() / w_new;
            w = w_new;
            mcg_test_support::assert_close!(s.weight_sum, w, 1e-5);
            assert!((s.mean_target - yb).length() < 1e-5);
            mcg_test_support::assert_close!(s.mean_cosine(), r, 1e-5, "{} vs {r}", s.mean_cosine());
        }
    }

    #[test]
    fn bad_samples_are_ignored() {
        let mut s = SufficientStats::EMPTY;
        s.update(Vec3::ZERO, Vec3::X, 1.0, &FitParams::MCPG);
        let before = s;
        for (y, f) in [
            (Vec3::Y, f32::NAN),
            (Vec3::Y, -1.0),
            (Vec3::Y, f32::INFINITY),
            (Vec3::new(f32::NAN, 0.0, 0.0), 1.0),
        ] {
            assert!(!s.update(Vec3::ZERO, y, f, &FitParams::MCPG));
            assert_eq!(s, before);
        }
        // Zero weights on empty stats stay empty and finite.
        let mut e = SufficientStats::EMPTY;
        assert!(e.update(Vec3::ZERO, Vec3::X, 0.0, &FitParams::MCMM));
        assert!(!e.is_valid() && e.to_vmf(Vec3::ZERO, MapPrior::NONE).is_none());
        assert_eq!(e.sample_count, 1);
    }

    #[test]
    fn huge_weights_do_not_overflow() {
        let mut s = SufficientStats::EMPTY;
        for f in [f32::MAX, 1.0, f32::MAX / 2.0] {
            s.update(Vec3::ZERO, Vec3::new(1e30, 0.0, 0.0), f, &FitParams::MCPG);
            assert!(
                s.mean_target.is_finite()
                    && s.weight_sum.is_finite()
                    && s.mean_cosine().is_finite()
            );
        }
    }

    #[test]
    fn tiny_and_huge_offsets_give_unit_mean_directions() {
        // Issue 14 row 3: x = 0 towards (3e-22, 4e-22, 0) gave |μ| = 1.0011 (|ȳ − x|² is
        // subnormal); offsets beyond 1.8·10¹⁹ gave no direction at all.
        for (y, want) in [
            (Vec3::new(3e-22, 4e-22, 0.0), Vec3::new(0.6, 0.8, 0.0)),
            (Vec3::new(0.0, 3e-38, -4e-38), Vec3::new(0.0, 0.6, -0.8)),
            (Vec3::new(3e37, -4e37, 0.0), Vec3::new(0.6, -0.8, 0.0)),
        ] {
            let mut s = SufficientStats::EMPTY;
            assert!(s.update(Vec3::ZERO, y, 1.0, &FitParams::MCMM));
            assert!(s.update(Vec3::ZERO, y, 1.0, &FitParams::MCPG));
            assert!(s.mean_cosine() > 0.999_99, "{s:?}");
            let mu = s.mean_direction(Vec3::ZERO).unwrap();
            mcg_test_support::assert_close!(mu.length(), 1.0, 1e-6, "{y}: {mu}");
            assert!((mu - want).length() < 1e-6, "{y}: {mu}");
            let lobe = s.to_vmf(Vec3::ZERO, MapPrior::uninformed(0.2)).unwrap();
            assert!(lobe.mu().is_normalized(), "{y}: {lobe:?}");
        }
        let s = SufficientStats {
            mean_target: Vec3::X,
            weight_sum: 1.0,
            one_minus_mean_cosine: 0.1,
            sample_count: 3,
        };
        assert_eq!(s.mean_direction(Vec3::new(f32::NAN, 0.0, 0.0)), None);
        assert_eq!(s.mean_direction(Vec3::new(f32::INFINITY, 0.0, 0.0)), None);
    }

    #[test]
    fn prior_forms() {
        let s = SufficientStats {
            mean_target: Vec3::Z,
            weight_sum: 1.0,
            one_minus_mean_cosine: 0.2,
            sample_count: 2,
        };
        let sq = s.posterior_mean_cosine(MapPrior {
            mean_cosine: 0.2,
            weight: 4.0,
            decay: PriorDecay::SquaredCount,
        });
        mcg_test_support::assert_close!(sq, (4.0 * 0.8 + 4.0 * 0.2) / 8.0, 1e-6);
        let lin = s.posterior_mean_cosine(MapPrior {
            mean_cosine: 0.2,
            weight: 4.0,
            decay: PriorDecay::Count,
        });
        mcg_test_support::assert_close!(lin, (2.0 * 0.8 + 4.0 * 0.2) / 6.0, 1e-6);
        let inf = MapPrior::inverse_square_distance(1.0, 1e-4, 0.0);
        assert_eq!(s.posterior_mean_cosine(inf), 0.0);
        assert_eq!(
            MapPrior::inverse_square_distance(0.25, 1e-4, 0.5).weight,
            1.0
        );
        assert_eq!(
            MapPrior::inverse_square_distance(0.25, 1e-4, 1e4).weight,
            1e-4
        );
        // ȳ at the shading point: no direction.
        assert!(s.to_vmf(Vec3::Z, MapPrior::NONE).is_none());
    }
}
