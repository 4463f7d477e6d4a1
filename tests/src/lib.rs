//! # mcg-tests: the shared statistics harness of mcg
//!
//! The statistical suites of every mcg crate live in this package's `tests/` folder and share
//! the small harness in this library, so that each suite states a hypothesis, a sample size, a
//! threshold and a seed, and nothing else.
//!
//! | item | what it tests | typical use |
//! |---|---|---|
//! | [`ks_test`], [`assert_ks`], [`KsResult`] | one-sample Kolmogorov-Smirnov against an analytic CDF | 1-D marginals of samplers (cos θ, φ) |
//! | [`chi_square_test`], [`assert_chi_square`], [`ChiSquareResult`] | chi-square goodness of fit over bins, small bins merged | samplers against their pdf on a binned sphere |
//! | [`SphereBins`] | equal-area bins on S², bin probabilities of a pdf by quadrature | the bins of the chi-square test |
//! | [`RunningStats`], [`z_test()`], [`assert_z_test`] | z-test of a sample mean (Welford mean and variance) | estimators against analytic integrals |
//! | [`GaussLegendre`], [`integrate_sphere`], [`graded_theta_breaks`] | f64 reference quadrature on an interval and on S² | normalisation and product integrals |
//! | [`vmf_pdf`], [`vmf_one_minus_cos_cdf`], [`one_minus_cos`], [`vmf_mean_cosine`], … | f64 reference formulas of the vMF lobe | every suite that tests vMF code |
//! | [`LineTechnique`], [`SphereTechnique`], [`line_integrands`], [`sphere_integrands`], [`AdaptiveTile`], [`convergence_run`], [`fig1_estimate`], [`variance_with_error`], … | techniques, integrands with closed-form integrals, MCMM Fig. 16 and MMIS Fig. 1 in miniature | the `smis_*` suites and the demo's smis section |
//! | [`plane_keys`], [`line_keys`], [`sphere_shell_keys`], [`floor_view_keys`], [`occupancy`] | structured grid-key streams and bucket counts | hash-grid occupancy and checksum suites |
//! | [`Experiment`], [`ExperimentConfig`], [`UpdatePolicy`], [`Run`], [`frames_to_error`] | ADGI (and its refill extension) vs uniform DDGI at equal ray budget on the two-room door scene, errors against the reference | the `probe_cache_adgi` suite and the demo's probe-cache section |
//! | [`seeded_rng`], [`uniform_vec2`], [`uniform_sphere_direction`] | deterministic random numbers | every suite, one fixed seed per test |
//! | [`assert_close!`], [`proptest_config`], [`hit_room`] | from `mcg-test-support` (the crates' own tests use it too): tolerance assertions that print both values, the fixed-seed proptest configuration, the key streams' box room | every suite; the demo's hash-grid section |
//!
//! ## Conventions
//! - Every test uses a fixed seed, so a suite either passes or fails, every time.
//! - Significance levels are stated by the caller; the vMF suites use α = 0.001 (or 5σ for
//!   z-tests). Thresholds come from the test's own statistics and are never tuned to pass.
//! - Reference computations are in f64; the code under test is evaluated at f32 inputs, its
//!   f32 outputs accumulated in f64.
//! - Failures panic with a message that carries the label, the statistic, the threshold and n.

mod chi_square;
mod hashgrid_reference;
mod ks;
mod probe_cache_reference;
mod quadrature;
mod rng;
mod smis_reference;
mod sphere_bins;
mod vmf_reference;
mod z_test;

pub use chi_square::{
    ChiSquareResult, MIN_EXPECTED_COUNT, assert_chi_square, chi_square_test, merge_bins,
};
pub use hashgrid_reference::{
    floor_view_keys, line_keys, occupancy, plane_keys, sphere_shell_keys,
};
pub use ks::{KsResult, assert_ks, kolmogorov_critical_value, kolmogorov_survival, ks_test};
/// The probe-update policies of the ADGI experiment (re-exported from `mcg-probe-cache`).
pub use mcg_probe_cache::UpdatePolicy;
pub use mcg_test_support::{ROOM_MAX, ROOM_MIN, assert_close, hit_room, proptest_config};
pub use probe_cache_reference::{
    Experiment, ExperimentConfig, FRAMES_TO_ERROR_THRESHOLD, Run, WARM_START_RAYS_PER_TEXEL,
    frames_to_error, frames_to_first_below, mean_error,
};
pub use quadrature::{GaussLegendre, graded_theta_breaks, integrate_sphere, orthonormal_basis};
pub use rng::{Pcg64Mcg, seeded_rng, uniform_sphere_direction, uniform_vec2};
pub use smis_reference::{
    AdaptiveTile, CHAIN_DEFENSIVE, CHAIN_SCALE, ChainState, Convergence, Decorrelation,
    FIG1_BUDGET, FIG1_INTEGRAL, FIG1_NS, FIG1_TECHNIQUES, LineIntegrand, LineTechnique,
    MarginalBoxcar, SphereIntegrand, SphereTechnique, TILE, TSMIS_STEPS, convergence_run,
    draw_line_boxcar, draw_line_lobe, draw_sphere_cap, draw_sphere_lobe, fig1_estimate,
    fig1_estimates, fig1_integrand, lane_integral, lane_integrand, line_integrands,
    sphere_integrands, uniform2, variance_with_error,
};
pub use sphere_bins::{SphereBins, assert_sphere_chi_square};
pub use vmf_reference::{
    one_minus_cos, vmf_cos_theta_cdf, vmf_cos_theta_variance, vmf_mean_cosine,
    vmf_mean_cosine_derivative, vmf_normalization, vmf_one_minus_cos_cdf,
    vmf_one_minus_mean_cosine, vmf_pdf,
};
pub use z_test::{RunningStats, WelchResult, ZTestResult, assert_z_test, welch_t_test, z_test};

/// The workspace README's usage example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeDoctests;
