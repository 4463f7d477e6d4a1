//! Screen-space Markov chain mixture models (MCMM, Dittebrandt et al. 2023): one chain per
//! pixel whose state is the sufficient statistics of a vMF lobe (Table 1), moved each iteration
//! by collaborative discovery (Alg. 1), sampling (Alg. 2) and acceptance plus maximum-likelihood
//! update (Alg. 3).
//!
//! One iteration for pixel p, with S the tentative state and S_c the current one:
//! 1. [`collaborative_discovery`]: resample S from neighbour states of the previous frame.
//! 2. [`choose_technique`]: hemisphere (cosine or BSDF) or the lobe of S; the renderer samples
//!    ω, traces to x₂ and computes f = lum(L_e f_r)/p(ω) (p per [`ScoreDensity`]).
//! 3. [`update()`]: acceptance min(1, f/S_c.f), reset after a hemisphere sample, MLE update.
//!
//! The SMIS estimator over a tile of chains (eq. 8, 9) takes its pdfs from [`technique_pdf`].

mod params;
mod resampling;
mod sampling;
mod state;
mod update;

pub use params::{McmmParams, McmmPrior, ScoreDensity};
pub use resampling::{bspline_offset, collaborative_discovery, resample_neighbour};
pub use sampling::{CosineChainTechnique, SampleChoice, choose_technique, technique_pdf};
pub use state::PixelState;
#[cfg(feature = "std")]
pub use state::PixelStateBuffers;
pub use update::update;
