//! MCMM on the GPU (Dittebrandt et al. 2023): the WGSL module `mcg::mcmm` holds the per-pixel
//! chain operations (Alg. 1-3) and the tile shuffles of TSMIS/SSMIS; this module holds its
//! uniform parameters ([`GpuMcmmParams`]) and, with the `runtime` feature, the host object
//! [`GpuMcmmGuide`]: the double-buffered state buffers, their bind group layout and the bind
//! group of each frame, placed at the group index the renderer chooses.

use bytemuck::{Pod, Zeroable};
use mcg_markov_guide::mcmm::{McmmParams, McmmPrior, ScoreDensity};

use crate::codes;
use crate::types::VmfFitParamsGpu;

#[cfg(feature = "runtime")]
mod guide;
#[cfg(feature = "runtime")]
pub use guide::GpuMcmmGuide;

/// [`McmmParams`] and the image size as the WGSL uniform `McmmParams` of `mcg::mcmm`
/// (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMcmmParams {
    /// The MLE update of Alg. 3 ([`McmmParams::fit`]).
    pub fit: VmfFitParamsGpu,
    /// p_h of Alg. 2 ([`McmmParams::hemisphere_probability`]).
    pub hemisphere_probability: f32,
    /// r_p of a fixed prior (unused by the light-size prior).
    pub prior_mean_cosine: f32,
    /// N_p, the prior's weight in virtual samples (both priors).
    pub prior_weight: f32,
    /// The decay code of a fixed prior (`codes::PRIOR_DECAY_*`).
    pub prior_decay: u32,
    /// `codes::MCMM_PRIOR_FIXED` or `codes::MCMM_PRIOR_LIGHT_SIZE`.
    pub prior_kind: u32,
    /// The emitter radius of the light-size prior (0 for a fixed prior).
    pub prior_radius: f32,
    /// Neighbour candidates of Alg. 1 ([`McmmParams::neighbour_candidates`]).
    pub neighbour_candidates: u32,
    /// Half width of the B-spline window in pixels ([`McmmParams::window_half_width`]).
    pub window_half_width: f32,
    /// `codes::MCMM_SCORE_TECHNIQUE` or `codes::MCMM_SCORE_TILE_MIXTURE`.
    pub score_density: u32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    pad: u32,
}
const _: () = assert!(size_of::<GpuMcmmParams>() == 64);

impl GpuMcmmParams {
    /// The uniform for `params` on a `width × height` image. Validate `params` first
    /// ([`McmmParams::validate`]); this conversion copies the values as they are.
    #[must_use]
    pub fn new(params: &McmmParams, width: u32, height: u32) -> Self {
        let (prior_kind, prior_mean_cosine, prior_weight, prior_decay, prior_radius) =
            match params.prior {
                McmmPrior::Fixed(p) => (
                    codes::MCMM_PRIOR_FIXED,
                    p.mean_cosine,
                    p.weight,
                    codes::prior_decay(p.decay),
                    0.0,
                ),
                McmmPrior::LightSize { radius, weight } => (
                    codes::MCMM_PRIOR_LIGHT_SIZE,
                    0.0,
                    weight,
                    codes::PRIOR_DECAY_SQUARED_COUNT,
                    radius,
                ),
            };
        Self {
            fit: VmfFitParamsGpu::from(&params.fit),
            hemisphere_probability: params.hemisphere_probability,
            prior_mean_cosine,
            prior_weight,
            prior_decay,
            prior_kind,
            prior_radius,
            neighbour_candidates: params.neighbour_candidates,
            window_half_width: params.window_half_width,
            score_density: match params.score_density {
                ScoreDensity::Technique => codes::MCMM_SCORE_TECHNIQUE,
                ScoreDensity::TileMixture => codes::MCMM_SCORE_TILE_MIXTURE,
            },
            width,
            height,
            pad: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcg_vmf::MapPrior;

    #[test]
    fn paper_params_convert_field_by_field() {
        let g = GpuMcmmParams::new(&McmmParams::PAPER, 40, 30);
        assert_eq!(g.hemisphere_probability, 0.2);
        assert_eq!(g.prior_kind, codes::MCMM_PRIOR_FIXED);
        assert_eq!(
            (g.prior_mean_cosine, g.prior_weight),
            (MapPrior::uninformed(0.2).mean_cosine, 0.2)
        );
        assert_eq!((g.neighbour_candidates, g.window_half_width), (5, 45.0));
        assert_eq!(g.score_density, codes::MCMM_SCORE_TECHNIQUE);
        assert_eq!((g.width, g.height), (40, 30));
        let mut p = McmmParams::PAPER;
        p.prior = McmmPrior::LightSize {
            radius: 0.5,
            weight: 3.0,
        };
        p.score_density = ScoreDensity::TileMixture;
        let g = GpuMcmmParams::new(&p, 1, 1);
        assert_eq!(
            (
                g.prior_kind,
                g.prior_radius,
                g.prior_weight,
                g.score_density
            ),
            (
                codes::MCMM_PRIOR_LIGHT_SIZE,
                0.5,
                3.0,
                codes::MCMM_SCORE_TILE_MIXTURE
            )
        );
    }
}
