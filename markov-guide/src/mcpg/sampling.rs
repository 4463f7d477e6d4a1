//! Technique choice and the estimator's pdf over the accessed states (MCPG Alg. 2, eq. 6-7).

use mcg_smis::Technique;
use mcg_vmf::Vmf;
use mcg_vmf::glam::{Vec2, Vec3};

use crate::{cosine_hemisphere, cosine_hemisphere_pdf};

use super::{CandidateSet, GridState, McpgParams, distance_prior};

/// The technique MCPG Alg. 2 picked for one sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleChoice {
    /// BSDF (or cosine, or phase-function) sampling by the renderer (Alg. 2 line 3); the state
    /// carried into Alg. 3 is then the empty state (line 4).
    Bsdf,
    /// The chosen state's lobe at the shading point (Alg. 2 lines 6-9).
    Lobe(Vmf),
}

/// MCPG Alg. 2 lines 1-9: BSDF sampling when no state was chosen (all w̄ = 0) or with
/// probability p_bsdf (`u < p_bsdf`), otherwise the chosen state's lobe at `x` with the
/// distance prior ([`distance_prior`]). Returns the technique and the state Alg. 3 continues
/// from (the chosen state, or [`GridState::EMPTY`] after a BSDF choice).
#[inline]
#[must_use]
pub fn choose_technique(
    selected: Option<&GridState>,
    x: Vec3,
    u: f32,
    params: &McpgParams,
) -> (SampleChoice, GridState) {
    let Some(state) = selected else {
        return (SampleChoice::Bsdf, GridState::EMPTY);
    };
    if u < params.bsdf_probability {
        return (SampleChoice::Bsdf, GridState::EMPTY);
    }
    match state.lobe(x, distance_prior(state, x, params)) {
        Some(lobe) => (SampleChoice::Lobe(lobe), *state),
        None => (SampleChoice::Bsdf, GridState::EMPTY),
    }
}

impl<const N: usize> CandidateSet<N> {
    /// The density of the direction ω that Alg. 1-2 sample at `x` given the accessed states,
    /// the denominator of MCPG's estimators (eq. 6 per vertex, eq. 7):
    ///
    /// ```text
    /// p(ω | S) = p_bsdf·p_b(ω) + (1 − p_bsdf) · Σ_{s∈S} (w̄_s / Σw̄) · V(ω | μ_s(x), κ_s(x))     (Σw̄ > 0)
    /// p(ω | S) = p_b(ω)                                                                       (Σw̄ = 0)
    /// ```
    ///
    /// `bsdf_pdf` is p_b(ω), the renderer's BSDF (or cosine, or phase-function) density.
    ///
    /// Eq. 7 writes the denominator as Σ_{s∈S} p(ω | s), the balance-heuristic sum of SMIS over
    /// the accessed states. Alg. 1 picks a state with probability w̄_s/Σw̄, not uniformly, and
    /// every state is loaded before ω is drawn, so the exact density of ω given S is the
    /// w̄-weighted mixture above; with it, f(ω)/p(ω | S) is unbiased for any S, and the BSDF
    /// term covers the integrand's support wherever p_b does (MCMM appendix A). A state whose
    /// lobe cannot be built at `x` is one Alg. 2 would answer with BSDF sampling, so its share
    /// goes to p_b.
    #[inline]
    #[must_use]
    pub fn pdf(&self, x: Vec3, w: Vec3, bsdf_pdf: f32, params: &McpgParams) -> f32 {
        let total = self.weight_sum();
        if !(total > 0.0) {
            return bsdf_pdf;
        }
        let mut lobes = 0.0;
        for s in self.states() {
            let weight = s.resampling_weight();
            if weight > 0.0 {
                let share = weight / total;
                lobes += share
                    * match s.lobe(x, distance_prior(s, x, params)) {
                        Some(lobe) => lobe.pdf(w),
                        None => bsdf_pdf,
                    };
            }
        }
        let p = params.bsdf_probability;
        p * bsdf_pdf + (1.0 - p) * lobes
    }
}

/// The sampling technique of one path vertex with a Lambertian (cosine) BSDF: the vertex's
/// accessed states with Alg. 2's choice, as an [`mcg_smis::Technique`] whose density is
/// [`CandidateSet::pdf`]. A forward path tracer needs no more than that density: it multiplies
/// its throughput by f·|cos θ|/p at every vertex, which is MCPG eq. 6.
/// `mcg_smis::path_estimate` over one such technique per vertex computes the same product for
/// a path stored as a whole (in linear time).
///
/// The uniform is `(u_choice, u_direction)`: `u_choice` is Alg. 2's ξ against p_bsdf.
#[derive(Clone, Copy, Debug)]
pub struct CosineVertexTechnique<'a, const N: usize> {
    set: &'a CandidateSet<N>,
    x: Vec3,
    normal: Vec3,
    params: &'a McpgParams,
}

impl<'a, const N: usize> CosineVertexTechnique<'a, N> {
    /// The technique of the vertex at `x` with unit normal `normal` and accessed states `set`.
    #[inline]
    #[must_use]
    pub const fn new(
        set: &'a CandidateSet<N>,
        x: Vec3,
        normal: Vec3,
        params: &'a McpgParams,
    ) -> Self {
        Self {
            set,
            x,
            normal,
            params,
        }
    }
}

impl<const N: usize> Technique for CosineVertexTechnique<'_, N> {
    type Sample = Vec3;
    type Uniform = (f32, Vec2);

    #[inline]
    fn pdf(&self, w: &Vec3) -> f32 {
        self.set.pdf(
            self.x,
            *w,
            cosine_hemisphere_pdf(self.normal, *w),
            self.params,
        )
    }

    #[inline]
    fn sample(&self, (u_choice, u): (f32, Vec2)) -> Vec3 {
        match choose_technique(self.set.selected(), self.x, u_choice, self.params).0 {
            SampleChoice::Lobe(lobe) => lobe.sample(u),
            SampleChoice::Bsdf => cosine_hemisphere(self.normal, u).0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcpg::resampling::tests::state_towards;

    #[test]
    fn empty_sets_fall_back_to_the_bsdf() {
        let p = McpgParams::PAPER;
        let (t, s) = choose_technique(None, Vec3::ZERO, 0.9, &p);
        assert_eq!((t, s), (SampleChoice::Bsdf, GridState::EMPTY));
        let set = CandidateSet::<5>::new();
        assert_eq!(set.pdf(Vec3::ZERO, Vec3::Z, 0.3, &p), 0.3);
    }

    #[test]
    fn pdf_is_the_weighted_mixture() {
        let p = McpgParams::PAPER;
        let mut set = CandidateSet::<5>::new();
        let a = state_towards(Vec3::new(0.0, 0.0, 2.0), 1.0);
        let b = state_towards(Vec3::new(2.0, 0.0, 2.0), 3.0);
        set.offer(a, 0.5);
        set.offer(b, 0.5);
        let w = Vec3::new(0.3, 0.1, 1.0).normalize();
        let va = a
            .lobe(Vec3::ZERO, distance_prior(&a, Vec3::ZERO, &p))
            .unwrap()
            .pdf(w);
        let vb = b
            .lobe(Vec3::ZERO, distance_prior(&b, Vec3::ZERO, &p))
            .unwrap()
            .pdf(w);
        let want = 0.1 * 0.2 + 0.9 * (0.25 * va + 0.75 * vb);
        let got = set.pdf(Vec3::ZERO, w, 0.2, &p);
        mcg_test_support::assert_close!(got, want, 1e-5 * want);
        let (t, s) = choose_technique(set.selected(), Vec3::ZERO, 0.5, &p);
        assert!(matches!(t, SampleChoice::Lobe(_)));
        assert_eq!(s, *set.selected().unwrap());
        assert_eq!(
            choose_technique(set.selected(), Vec3::ZERO, 0.05, &p).0,
            SampleChoice::Bsdf
        );
    }
}
