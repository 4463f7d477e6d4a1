//! The constants of MCPG, with the paper's defaults.

use mcg_vmf::FitParams;

use crate::error::ParamsError;

/// Every constant of MCPG (Alber et al. 2025), defaults in [`McpgParams::PAPER`]: the paper's
/// values where it gives them, the authors' engine's otherwise (merian-quake), and the engine's
/// discard rule, which our tracking tests need ([`DiscardRule`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McpgParams {
    /// N_mc, the candidates loaded per vertex in Alg. 1 (5).
    pub candidates: u32,
    /// Probability that a candidate is loaded from the adaptive grid rather than the static one
    /// (sec. 4, step 1: p_adaptive = 0.7).
    pub adaptive_probability: f32,
    /// p_bsdf, the probability of a BSDF (or cosine, or phase-function) sample although a
    /// valid state was resampled (Alg. 2 line 2). The paper calls it "low"; the authors' engine
    /// uses 0.1-0.15; 0.1 here.
    pub bsdf_probability: f32,
    /// The MLE update of Alg. 3: N_max 1024, α_min 0.01, r̄ as the mean projected cosine (l. 9).
    pub fit: FitParams,
    /// Prior weight N_p = `prior_scale` / |ȳ − x|² with r_p = 0 (sec. 4, step 2: scale 1) ...
    pub prior_scale: f32,
    /// ... and never below this (the authors' engine: 10⁻⁴), so a far target keeps a prior.
    pub prior_min_weight: f32,
    /// Static-grid candidates whose lobe direction μ makes cos(μ, n) ≤ this with the surface
    /// normal are rejected (sec. 4, step 1; the paper gives no value, ours is 0: the lobe must
    /// point above the surface).
    pub static_normal_threshold: f32,
    /// The discard heuristic's thresholds (sec. 5).
    pub discard: DiscardRule,
}

/// When a rejected lobe sample discards the state it came from (MCPG sec. 5, "Discarding Light
/// Sources"). Both forms also require T ≠ now (the state was not updated at this time).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DiscardRule {
    /// The paper's text: f_mc ≤ `ratio`·w̄ ("significantly smaller"; the code of the paper's era
    /// used 0.5) and μᵀω > r, r the MAP mean cosine of Alg. 2 line 7. On small lights this
    /// discards live states whenever a sample from the inner half of a lobe misses.
    Paper {
        /// The estimate ratio below which the light counts as gone.
        ratio: f32,
    },
    /// The authors' engine (merian-quake): f_mc ≤ `ratio`·w̄ (10⁻³) and ω·μ ≥ 0.9 + 0.1·r̄: only a
    /// sample very close to the lobe's axis can discard it.
    Engine {
        /// The estimate ratio below which the light counts as gone.
        ratio: f32,
    },
}

impl McpgParams {
    /// The paper's constants.
    pub const PAPER: Self = Self {
        candidates: 5,
        adaptive_probability: 0.7,
        bsdf_probability: 0.1,
        fit: FitParams::MCPG,
        prior_scale: 1.0,
        prior_min_weight: 1.0e-4,
        static_normal_threshold: 0.0,
        discard: DiscardRule::Engine { ratio: 1.0e-3 },
    };

    /// The constants for a scene measured in units `s` times the paper's (Quake units; s =
    /// scene units per Quake unit): the prior scale N_p·d² is an area, so it becomes
    /// `prior_scale · s²`; every other constant is dimensionless and stays. Lengths of the
    /// grids scale with s too ([`GuideConfig::for_scene`](super::GuideConfig::for_scene)).
    /// A non-finite or non-positive `s` returns the constants unchanged.
    #[must_use]
    pub fn scaled(self, s: f32) -> Self {
        let mut p = self;
        if s > 0.0 && s.is_finite() {
            p.prior_scale *= s * s;
        }
        p
    }

    /// Checks probabilities, weights and counts.
    ///
    /// # Errors
    /// The first [`ParamsError`] found. N_max must fit the state's 16-bit count.
    pub fn validate(&self) -> Result<(), ParamsError> {
        for (parameter, value) in [
            ("adaptive_probability", self.adaptive_probability),
            ("bsdf_probability", self.bsdf_probability),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(ParamsError::ProbabilityOutOfRange { parameter, value });
            }
        }
        let (DiscardRule::Paper { ratio } | DiscardRule::Engine { ratio }) = self.discard;
        for (parameter, value) in [
            ("prior_scale", self.prior_scale),
            ("prior_min_weight", self.prior_min_weight),
            ("discard.ratio", ratio),
        ] {
            if !(value >= 0.0 && value.is_finite()) {
                return Err(ParamsError::NotFiniteNonNegative { parameter, value });
            }
        }
        let out_of_range =
            |parameter, value| ParamsError::NotFiniteNonNegative { parameter, value };
        if !(self.static_normal_threshold.abs() <= 1.0) {
            let value = self.static_normal_threshold;
            return Err(out_of_range("static_normal_threshold", value));
        }
        if !(0.0..=1.0).contains(&self.fit.alpha_min) {
            return Err(out_of_range("fit.alpha_min", self.fit.alpha_min));
        }
        if self.fit.max_count > u16::MAX as u32 {
            return Err(out_of_range("fit.max_count", self.fit.max_count as f32));
        }
        if self.candidates == 0 {
            return Err(ParamsError::NoCandidates {
                parameter: "candidates",
            });
        }
        if self.fit.max_count == 0 {
            return Err(ParamsError::NoCandidates {
                parameter: "fit.max_count",
            });
        }
        Ok(())
    }
}

impl Default for McpgParams {
    /// [`McpgParams::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_defaults_validate_and_bad_values_do_not() {
        assert_eq!(McpgParams::PAPER.validate(), Ok(()));
        let mut p = McpgParams::PAPER;
        p.adaptive_probability = 1.5;
        assert_eq!(
            p.validate(),
            Err(ParamsError::ProbabilityOutOfRange {
                parameter: "adaptive_probability",
                value: 1.5
            })
        );
        let mut p = McpgParams::PAPER;
        p.prior_scale = f32::NAN;
        assert!(matches!(
            p.validate(),
            Err(ParamsError::NotFiniteNonNegative {
                parameter: "prior_scale",
                value
            }) if value.is_nan()
        ));
        let mut p = McpgParams::PAPER;
        p.fit.max_count = 70_000;
        assert_eq!(
            p.validate(),
            Err(ParamsError::NotFiniteNonNegative {
                parameter: "fit.max_count",
                value: 70_000.0
            })
        );
        let mut p = McpgParams::PAPER;
        p.candidates = 0;
        assert_eq!(
            p.validate(),
            Err(ParamsError::NoCandidates {
                parameter: "candidates"
            })
        );
    }
}
