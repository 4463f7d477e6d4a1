//! Choice of the sampling technique and the per-chain pdf (MCMM Alg. 2 and appendix A).

use mcg_smis::Technique;
use mcg_vmf::Vmf;
use mcg_vmf::glam::{Vec2, Vec3};

use crate::{cosine_hemisphere, cosine_hemisphere_pdf};

use super::{McmmParams, PixelState};

/// The technique Alg. 2 picked for one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleChoice {
    /// An independent hemisphere sample: cosine or BSDF sampling, chosen by the renderer
    /// (Alg. 2 line 3). Resets the lobe when it is accepted (Alg. 3 line 6).
    Hemisphere,
    /// The state's lobe, reconstructed with the prior at the shading point (Alg. 2 lines 5-8).
    Lobe(Vmf),
}

/// MCMM Alg. 2 lines 1-9: a hemisphere sample when the state is invalid or with probability
/// `params.hemisphere_probability` (`u` < p_h), otherwise the state's lobe at shading point `x`.
///
/// A state whose lobe cannot be reconstructed at `x` (ȳ = x) falls back to the hemisphere too.
/// The renderer then samples ω from the technique ([`Vmf::sample`] or its own cosine/BSDF
/// sampler) with fresh uniforms.
#[inline]
#[must_use]
pub fn choose_technique(state: &PixelState, x: Vec3, u: f32, params: &McmmParams) -> SampleChoice {
    if u < params.hemisphere_probability {
        return SampleChoice::Hemisphere;
    }
    match state.lobe_with(x, &params.prior) {
        Some(lobe) => SampleChoice::Lobe(lobe),
        None => SampleChoice::Hemisphere,
    }
}

/// The density p(ω | S) with which chain state `state` samples ω at shading point `x`:
/// the defensive mixture p_h·p_hemi(ω) + (1 − p_h)·V(ω | μ, κ) for a state with a lobe, and
/// p_hemi(ω) for one without (the two branches of [`choose_technique`]).
///
/// `hemisphere_pdf` is the renderer's cosine or BSDF pdf at ω. These are the technique
/// densities p(ω | t_j) of the SMIS estimators (MCMM eq. 8, 9); because every technique keeps
/// the hemisphere branch, their sum is positive wherever the integrand is, which is what
/// appendix A needs for unbiasedness.
#[inline]
#[must_use]
pub fn technique_pdf(
    state: &PixelState,
    x: Vec3,
    w: Vec3,
    hemisphere_pdf: f32,
    params: &McmmParams,
) -> f32 {
    match state.lobe_with(x, &params.prior) {
        Some(lobe) => {
            let p = params.hemisphere_probability;
            p * hemisphere_pdf + (1.0 - p) * lobe.pdf(w)
        }
        None => hemisphere_pdf,
    }
}

/// One chain's technique with cosine hemisphere sampling as the defensive branch: the
/// [`mcg_smis::Technique`] that MCMM's SMIS estimators (eq. 8, 9) sum over.
///
/// Its density is [`technique_pdf`] with p_hemi(ω) = max(0, n·ω)/π; its uniform is
/// `(u_select, u)`, `u_select` choosing the branch as [`choose_technique`] does. Build it from
/// the state the sample is drawn from, before [`update`](super::update()) changes that state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CosineChainTechnique {
    lobe: Option<Vmf>,
    normal: Vec3,
    hemisphere_probability: f32,
}

impl CosineChainTechnique {
    /// The technique of chain state `state` at shading point `x` with unit normal `normal`.
    #[inline]
    #[must_use]
    pub fn new(state: &PixelState, x: Vec3, normal: Vec3, params: &McmmParams) -> Self {
        Self {
            lobe: state.lobe_with(x, &params.prior),
            normal,
            hemisphere_probability: params.hemisphere_probability,
        }
    }

    /// The lobe, `None` when the technique is the hemisphere alone.
    #[inline]
    #[must_use]
    pub const fn lobe(&self) -> Option<Vmf> {
        self.lobe
    }

    /// Samples ω and reports whether the hemisphere branch was taken.
    #[inline]
    #[must_use]
    pub fn sample_with_branch(&self, u_select: f32, u: Vec2) -> (Vec3, bool) {
        match self.lobe {
            Some(lobe) if !(u_select < self.hemisphere_probability) => (lobe.sample(u), false),
            _ => (cosine_hemisphere(self.normal, u).0, true),
        }
    }
}

impl Technique for CosineChainTechnique {
    type Sample = Vec3;
    type Uniform = (f32, Vec2);

    #[inline]
    fn pdf(&self, w: &Vec3) -> f32 {
        let hemisphere = cosine_hemisphere_pdf(self.normal, *w);
        match self.lobe {
            Some(lobe) => {
                let p = self.hemisphere_probability;
                p * hemisphere + (1.0 - p) * lobe.pdf(*w)
            }
            None => hemisphere,
        }
    }

    #[inline]
    fn sample(&self, (u_select, u): (f32, Vec2)) -> Vec3 {
        self.sample_with_branch(u_select, u).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcg_vmf::{FitParams, SufficientStats};

    fn lit_state() -> PixelState {
        let mut stats = SufficientStats::EMPTY;
        stats.update(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), 3.0, &FitParams::MCMM);
        PixelState { stats, score: 3.0 }
    }

    #[test]
    fn invalid_states_use_the_hemisphere() {
        let p = McmmParams::PAPER;
        assert_eq!(
            choose_technique(&PixelState::EMPTY, Vec3::ZERO, 0.9, &p),
            SampleChoice::Hemisphere
        );
        assert_eq!(
            technique_pdf(&PixelState::EMPTY, Vec3::ZERO, Vec3::Z, 0.3, &p),
            0.3
        );
        // ȳ = x: no lobe.
        let s = lit_state();
        assert_eq!(
            choose_technique(&s, Vec3::new(0.0, 0.0, 2.0), 0.9, &p),
            SampleChoice::Hemisphere
        );
    }

    #[test]
    fn valid_states_mix_defensively() {
        let p = McmmParams::PAPER;
        let s = lit_state();
        assert_eq!(
            choose_technique(&s, Vec3::ZERO, 0.1, &p),
            SampleChoice::Hemisphere
        );
        let SampleChoice::Lobe(lobe) = choose_technique(&s, Vec3::ZERO, 0.5, &p) else {
            panic!("expected a lobe");
        };
        assert_eq!(lobe.mu(), Vec3::Z);
        let pdf = technique_pdf(&s, Vec3::ZERO, Vec3::Z, 0.3, &p);
        mcg_test_support::assert_close!(pdf, (0.2 * 0.3 + 0.8 * lobe.pdf(Vec3::Z)), 1e-4 * pdf);
        // The smis technique agrees with technique_pdf for the cosine hemisphere.
        let t = CosineChainTechnique::new(&s, Vec3::ZERO, Vec3::Z, &p);
        let w = Vec3::new(0.2, 0.1, 0.9).normalize();
        let want = technique_pdf(&s, Vec3::ZERO, w, cosine_hemisphere_pdf(Vec3::Z, w), &p);
        mcg_test_support::assert_close!(t.pdf(&w), want, 1e-6 * want);
        assert!(!t.sample_with_branch(0.5, Vec2::new(0.3, 0.3)).1);
        assert!(t.sample_with_branch(0.1, Vec2::new(0.3, 0.3)).1);
    }
}
