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
    /// N_c, the sample count from which a chain's lobe gets its whole mixture share — mcg's
    /// extension of Alg. 2; 0 (the default) is the paper's. A state with N < N_c samples
    /// lends the part 1 − N/N_c of its share to the scatter technique
    /// ([`McpgParams::young_share`]), and a scatter sample drawn while it is the chosen state
    /// continues its chain instead of restarting from the empty state (Alg. 2 line 4). The
    /// density stays the exact mixture the samples are drawn from, so the estimator stays
    /// unbiased.
    ///
    /// Where it pays: with the paper's rule a chain of one sample gets 90 % of the choices at
    /// once, and in a path tracer's rooms many such chains point at whatever dim surface one
    /// sample found, while the light they miss is reached through the 10 % scatter share with
    /// 10× the weight. In mcg-demo's renderer (128², 8 spp × 64 frames, CPU, seeds 1-6) N_c = 16
    /// lowered the relative MSE on the room lit from behind a panel (3 bounces, with the
    /// irradiance cache) from 0.030-0.041 (mean 0.036) to 0.028-0.030, and its largest
    /// per-frame error from up to 30 to at most 8; on the room of 24 small lights (direct
    /// light, no cache, 64², 4 spp) from 1.60-1.91 to 0.41-0.46, where the paper's chains
    /// degrade over the frames. 8 and 32 gave the same as 16 within noise.
    ///
    /// Neutral in the crate's `guided_room` example (20 Lambertian quads, 128², seeds 1-2):
    /// per-frame MSE 0.556 and 0.483 against 0.530 and 0.507, frame 1 worse.
    ///
    /// Where it does not: few samples per state and one small light that a lucky sample
    /// finds — e.g. 8 points on a plane under a light of radius 0.25, 8 frames × 64 samples
    /// each — there the first chain is right and trusting it at once pays: the guided
    /// variance after training was 2-50× that of the paper's rule.
    pub confidence_samples: f32,
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
        confidence_samples: 0.0,
    };

    /// The part of a state's mixture share that goes to the scatter technique under
    /// [`confidence_samples`](Self::confidence_samples) = N_c: max(0, 1 − N·(1/N_c)) for a
    /// state with N ≥ 1 samples; 0 when N_c = 0 (the paper) or N = 0. Below 1 for every
    /// valid N_c (≥ 1), so a young lobe keeps a share. The GPU twin multiplies by the same
    /// f32 reciprocal.
    #[inline]
    #[must_use]
    pub fn young_share(&self, sample_count: u32) -> f32 {
        if !(self.confidence_samples > 0.0) || sample_count == 0 {
            return 0.0;
        }
        (1.0 - sample_count as f32 * (1.0 / self.confidence_samples)).max(0.0)
    }

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
        let n_c = self.confidence_samples;
        if !(n_c == 0.0 || (1.0..=65535.0).contains(&n_c)) {
            return Err(out_of_range("confidence_samples", n_c));
        }
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
        for bad in [0.5, -1.0, 70_000.0, f32::NAN, f32::INFINITY] {
            let mut p = McpgParams::PAPER;
            p.confidence_samples = bad;
            assert!(
                matches!(
                    p.validate(),
                    Err(ParamsError::NotFiniteNonNegative {
                        parameter: "confidence_samples",
                        ..
                    })
                ),
                "{bad}"
            );
        }
    }

    /// The young share falls linearly from 1 − 1/N_c at N = 1 to 0 at N = N_c, is 0 for the
    /// paper (N_c = 0) and for N = 0, and never reaches 1.
    #[test]
    fn young_share_falls_to_zero_at_the_confidence_count() {
        let mut p = McpgParams::PAPER;
        assert_eq!(p.young_share(1), 0.0);
        p.confidence_samples = 16.0;
        assert_eq!(p.young_share(0), 0.0);
        assert_eq!(p.young_share(1), 1.0 - 1.0 / 16.0);
        assert_eq!(p.young_share(8), 0.5);
        assert_eq!(p.young_share(16), 0.0);
        assert_eq!(p.young_share(1024), 0.0);
        p.confidence_samples = 1.0;
        assert_eq!(p.young_share(1), 0.0);
    }
}
