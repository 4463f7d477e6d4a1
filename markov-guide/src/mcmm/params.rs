//! The constants of MCMM, with the paper's defaults.

use mcg_vmf::{FitParams, MapPrior, PriorDecay};

use crate::error::ParamsError;

/// Every constant of MCMM (Dittebrandt et al. 2023), paper defaults in [`McmmParams::PAPER`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McmmParams {
    /// Probability of a hemisphere (cosine or BSDF) sample although the state holds a valid
    /// lobe (Alg. 2 line 2: 0.2; vkdt uses 0.125). This is the defensive technique of appendix A.
    pub hemisphere_probability: f32,
    /// The maximum-likelihood update (Alg. 3 lines 11-16): N_max = 1024, α_min = 0.1, and the
    /// resultant-length mean cosine of lines 15-16.
    pub fit: FitParams,
    /// The MAP prior of the mean cosine (Alg. 2 line 6; sec. 5 "Uninformed vs. informed
    /// priors"): by default uninformed, r_p = 0 with N_p = 0.2 virtual samples, decaying with N².
    pub prior: McmmPrior,
    /// Neighbour states offered to the reservoir of Alg. 1 per iteration (vkdt: 5).
    pub neighbour_candidates: u32,
    /// Half width in pixels of the B-spline window the neighbours are drawn from (sec. 4.1:
    /// a 91 × 91 window at 1920 × 1080, so 45).
    pub window_half_width: f32,
    /// Which density divides the score f of Alg. 3 line 1 (the paper: the chain's own
    /// technique, [`ScoreDensity::Technique`]).
    pub score_density: ScoreDensity,
}

/// The density p(ω) in the score f = lum(L_e f_r)/p(ω) that drives acceptance (Alg. 3) and
/// neighbour resampling (Alg. 1). The score only steers the chains: the SMIS estimators of the
/// image are the same, and unbiased, with either choice.
///
/// The paper divides by the pdf of the technique that drew ω, "to make f a coarse estimator
/// for the pixel contribution" (sec. 4.1, stage 3). With several small lights that coarse
/// estimator favours the wrong states: a hemisphere sample that hits a light the chain's lobe
/// does not cover scores p_h⁻¹ π/cos θ times the light's radiance, 10²–10³ times what a lobe
/// sample of the same light scores, so such fresh one-sample states win every acceptance and
/// every resampling, the written states S_c stay young (N = 1–6 samples in our measurements on
/// the toy scene's `ToyScene::eight_lights`) and guiding is barely
/// better than cosine sampling there.
///
/// [`ScoreDensity::TileMixture`] divides by the mixture density of all chains of the tile at
/// that step, (1/n) Σⱼ p(ω | tⱼ) — the denominator of the spatial SMIS estimator (eq. 9), so
/// the score *is* the pixel's one-sample SSMIS estimate. This is the importance weight of
/// population Monte Carlo, which the paper names as its model for Alg. 1: a light that many
/// lobes of the tile already cover scores low, one that none covers scores high, and a
/// population whose mixture is proportional to the integrand scores the same everywhere, so
/// acceptance stops discarding the states' learning. Measured on eight lights (SSMIS,
/// 32 × 32 pixels, the paper's 45-pixel window): variance 0.12–0.20 of cosine sampling against
/// 0.60–0.68 with the paper's score; on one light 0.007–0.009 against 0.021–0.027. It costs n pdf evaluations
/// per sample, which SSMIS spends anyway for its estimate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ScoreDensity {
    /// p(ω | S), the defensive mixture of the state that drew ω (MCMM Alg. 2-3 as written).
    #[default]
    Technique,
    /// (1/n) Σⱼ p(ω | tⱼ) over the n chains of the tile at this step (the SSMIS denominator,
    /// eq. 9): the score is the pixel's one-sample SSMIS estimate. An extension of the paper.
    TileMixture,
}

impl McmmParams {
    /// The paper's constants.
    pub const PAPER: Self = Self {
        hemisphere_probability: 0.2,
        fit: FitParams::MCMM,
        prior: McmmPrior::Fixed(MapPrior::uninformed(0.2)),
        neighbour_candidates: 5,
        window_half_width: 45.0,
        score_density: ScoreDensity::Technique,
    };

    /// Checks that probabilities lie in [0, 1], lengths are finite and non-negative and that at
    /// least one neighbour candidate is drawn.
    ///
    /// # Errors
    /// The first [`ParamsError`] found.
    pub fn validate(&self) -> Result<(), ParamsError> {
        if !(0.0..=1.0).contains(&self.hemisphere_probability) {
            return Err(ParamsError::ProbabilityOutOfRange {
                parameter: "hemisphere_probability",
                value: self.hemisphere_probability,
            });
        }
        let out_of_range =
            |parameter, value| ParamsError::NotFiniteNonNegative { parameter, value };
        if !(self.window_half_width >= 0.0 && self.window_half_width.is_finite()) {
            return Err(out_of_range("window_half_width", self.window_half_width));
        }
        if !(0.0..=1.0).contains(&self.fit.alpha_min) {
            return Err(out_of_range("fit.alpha_min", self.fit.alpha_min));
        }
        self.prior.check()?;
        if self.neighbour_candidates == 0 {
            return Err(ParamsError::NoCandidates {
                parameter: "neighbour_candidates",
            });
        }
        Ok(())
    }
}

/// The prior of MCMM's lobe fit (MCMM sec. 5, "Uninformed vs. informed priors").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum McmmPrior {
    /// The same prior for every lobe; the paper's Falcor scenes use the uninformed r_p = 0.
    Fixed(MapPrior),
    /// An informed prior from a known emitter size (the paper's Quake scenes, where every light
    /// is about one unit across): r_p is the mean cosine of directions spread uniformly over the
    /// cone a sphere of `radius` subtends at the lobe's target distance d,
    /// 1 − r_p = (1 − cos θ)/2 with sin θ = radius/d (r_p = 0 when d ≤ radius), with `weight`
    /// virtual samples decaying with N². Lobes start as wide as the light, however few samples
    /// they hold.
    LightSize {
        /// Emitter radius, in scene units.
        radius: f32,
        /// N_p, the prior's weight in virtual samples.
        weight: f32,
    },
}

impl McmmPrior {
    /// The MAP prior for a lobe whose mean target is `distance` away from the shading point.
    #[inline]
    #[must_use]
    pub fn at_distance(&self, distance: f32) -> MapPrior {
        match *self {
            McmmPrior::Fixed(prior) => prior,
            McmmPrior::LightSize { radius, weight } => {
                let sin = if distance > radius {
                    radius / distance
                } else {
                    1.0
                };
                // 1 − cos θ = sin²θ/(1 + cos θ), without cancellation for small θ.
                let cos = crate::math::sqrt((1.0 - sin * sin).max(0.0));
                let one_minus_cos = sin * sin / (1.0 + cos);
                MapPrior {
                    mean_cosine: 1.0 - 0.5 * one_minus_cos,
                    weight,
                    decay: PriorDecay::SquaredCount,
                }
            }
        }
    }

    /// The first field out of range, as a [`ParamsError::NotFiniteNonNegative`].
    fn check(&self) -> Result<(), ParamsError> {
        let out_of_range =
            |parameter, value| ParamsError::NotFiniteNonNegative { parameter, value };
        match *self {
            McmmPrior::Fixed(prior) => {
                if !(prior.weight >= 0.0) {
                    return Err(out_of_range("prior.weight", prior.weight));
                }
                if !(-1.0..=1.0).contains(&prior.mean_cosine) {
                    return Err(out_of_range("prior.mean_cosine", prior.mean_cosine));
                }
            }
            McmmPrior::LightSize { radius, weight } => {
                if !(radius >= 0.0 && radius.is_finite()) {
                    return Err(out_of_range("prior.radius", radius));
                }
                if !(weight >= 0.0 && weight.is_finite()) {
                    return Err(out_of_range("prior.weight", weight));
                }
            }
        }
        Ok(())
    }
}

impl Default for McmmParams {
    /// [`McmmParams::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn paper_defaults_validate_and_bad_values_do_not() {
        assert_eq!(McmmParams::PAPER.validate(), Ok(()));
        assert_eq!(McmmParams::PAPER.score_density, ScoreDensity::Technique);
        assert_eq!(McmmParams::default(), McmmParams::PAPER);
        let mut p = McmmParams::PAPER;
        p.hemisphere_probability = f32::NAN;
        assert!(matches!(
            p.validate(),
            Err(ParamsError::ProbabilityOutOfRange {
                parameter: "hemisphere_probability",
                value
            }) if value.is_nan()
        ));
        let mut p = McmmParams::PAPER;
        p.window_half_width = -1.0;
        assert_eq!(
            p.validate(),
            Err(ParamsError::NotFiniteNonNegative {
                parameter: "window_half_width",
                value: -1.0
            })
        );
        let mut p = McmmParams::PAPER;
        p.prior = McmmPrior::LightSize {
            radius: 1.0,
            weight: -2.0,
        };
        assert_eq!(
            p.validate().unwrap_err().to_string(),
            "parameter prior.weight = -2 is not finite, non-negative and in range"
        );
        let mut p = McmmParams::PAPER;
        p.neighbour_candidates = 0;
        assert_eq!(
            p.validate(),
            Err(ParamsError::NoCandidates {
                parameter: "neighbour_candidates"
            })
        );
    }
}
