//! The single-scattering variant of MCPG (sec. 4, "Extension to Single Scattering").
//!
//! Three changes, none to the state: the BSDF is replaced by the volume's phase function (pass
//! its density as `bsdf_pdf` to [`CandidateSet::pdf`](super::CandidateSet::pdf) and sample it
//! for [`SampleChoice::Bsdf`](super::SampleChoice::Bsdf)); the adaptive grid's key folds in the
//! reverse camera direction instead of the surface normal, jittered by a cosine lobe
//! ([`jittered_view_direction`]) so that neighbouring view directions share states — pass it
//! where a surface vertex passes its normal (the `normal` of
//! [`GridEnsemble::load`](super::GridEnsemble::load) and `store`, whose key class is
//! `mcg_hashgrid::normal_class` of it); and the
//! static grid has no normal threshold (pass `normal = None` to
//! [`prepare_candidate`](super::prepare_candidate)).

use mcg_vmf::glam::{Vec2, Vec3};

use crate::cosine_hemisphere;

/// The direction whose class goes into the adaptive grid's key at a volume vertex: the reverse
/// camera direction −`view` (unit, from the camera towards the vertex) jittered by a
/// cosine-weighted lobe around it, from two uniforms.
#[inline]
#[must_use]
pub fn jittered_view_direction(view: Vec3, u: Vec2) -> Vec3 {
    cosine_hemisphere(-view, u).0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_stays_around_the_reverse_view() {
        let view = Vec3::new(0.0, 1.0, 0.0);
        for i in 0..16 {
            let u = Vec2::new((i as f32 + 0.5) / 16.0, (i as f32 * 0.618).fract());
            let d = jittered_view_direction(view, u);
            assert!(d.dot(-view) >= 0.0 && (d.length() - 1.0).abs() < 1e-5);
        }
        assert!((jittered_view_direction(view, Vec2::ZERO) + view).length() < 1e-6);
    }
}
