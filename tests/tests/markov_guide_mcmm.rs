//! Statistical suite of MCMM guiding (mcg-markov-guide) on the toy scene: the guided estimators
//! are unbiased with TSMIS and SSMIS decorrelation, biased without it (MCMM sec. 4.2, Fig. 16,
//! appendix A), and adaptation pays against cosine sampling at equal sample counts.
//!
//! Every run is a [`McmmToyRenderer`] (one 8 × 4 tile, 4 samples per pixel and frame, the
//! paper's constants) with its own fixed seed; runs are independent, so per-run means are
//! independent replicates for the z-tests. The reference is the closed-form irradiance of the
//! toy scene at each pixel. The eight-light test runs a 32 × 32-pixel image
//! (`McmmToyConfig::image`) so that neighbour resampling draws from more than one tile.

use mcg_markov_guide::mcmm::ScoreDensity;
use mcg_markov_guide::toy_renderer::{Decorrelation, McmmToyConfig, McmmToyRenderer, Sampling};
use mcg_markov_guide::toy_scene::ToyScene;
#[path = "support/toy_errors.rs"]
mod toy_errors;

use mcg_tests::{RunningStats, assert_z_test, seeded_rng, z_test};
use toy_errors::relative_error_moments;

/// Frames discarded at the start of each run while the chains discover the lights.
const WARM_UP: usize = 20;

/// The mean relative error (estimate/E − 1) over `frames` frames after warm-up and all pixels
/// of one run, and the mean squared relative error.
fn run(scene: &ToyScene, sampling: Sampling, seed: u64, frames: usize) -> (f64, f64) {
    run_config(scene, McmmToyConfig::small(sampling), seed, frames)
}

/// [`run`] with any configuration.
fn run_config(scene: &ToyScene, config: McmmToyConfig, seed: u64, frames: usize) -> (f64, f64) {
    let mut rng = seeded_rng(seed);
    let mut renderer = McmmToyRenderer::new(config);
    let exact = renderer.exact_irradiance(scene).expect("closed form");
    relative_error_moments(&exact, WARM_UP, frames, || {
        renderer.render_frame(scene, &mut rng)
    })
}

/// Per-run mean relative errors of `runs` independent runs.
fn replicates(
    scene: &ToyScene,
    sampling: Sampling,
    seed: u64,
    runs: u64,
    frames: usize,
) -> RunningStats {
    replicates_config(scene, McmmToyConfig::small(sampling), seed, runs, frames)
}

/// [`replicates`] with any configuration.
fn replicates_config(
    scene: &ToyScene,
    config: McmmToyConfig,
    seed: u64,
    runs: u64,
    frames: usize,
) -> RunningStats {
    (0..runs)
        .map(|r| run_config(scene, config, seed + r, frames).0)
        .collect()
}

/// `McmmToyConfig::small(sampling)` with the tile-mixture score.
fn tile_mixture_score(sampling: Sampling) -> McmmToyConfig {
    let mut config = McmmToyConfig::small(sampling);
    config.params.score_density = ScoreDensity::TileMixture;
    config
}

/// H₀: the TSMIS and SSMIS estimators of MCMM are unbiased (MCMM appendix A), on a Cornell-box
/// sized light and a small one. 32 independent runs of 100 frames (102 400 frame estimates per
/// case); the mean relative error must be within 5σ of 0. A broken SSMIS denominator (the
/// tile's techniques reconstructed at their own pixels instead of the estimating pixel, a bug we
/// had) was biased by +57 % on the small light; dropping the TSMIS shift is the `unshuffled`
/// test below.
#[test]
fn tsmis_and_ssmis_are_unbiased() {
    for (name, scene) in [
        ("large light", ToyScene::large_light()),
        ("small light", ToyScene::single_light()),
    ] {
        for decorrelation in [Decorrelation::Tsmis, Decorrelation::Ssmis] {
            let stats = replicates(
                &scene,
                Sampling::Guided(decorrelation),
                0x6D63_6D6D_0000,
                32,
                100,
            );
            assert_z_test(&format!("MCMM {decorrelation:?}, {name}"), &stats, 0.0, 5.0);
        }
    }
}

/// H₀: the tile-mixture score ([`ScoreDensity::TileMixture`], our extension) only steers the
/// chains, so TSMIS and SSMIS stay unbiased with it — on eight small lights, where it changes
/// the chains most, and on one. 32 independent runs of 100 frames per case (102 400 frame
/// estimates); the mean relative error must be within 5σ of 0. With this score the toy loop's
/// SSMIS estimate *is* the score, so a wrong tile mixture biases the image: a mixture that
/// leaves out the pixel's own chain fails this test.
#[test]
fn tile_mixture_score_keeps_tsmis_and_ssmis_unbiased() {
    for (name, scene) in [
        ("eight lights", ToyScene::eight_lights()),
        ("small light", ToyScene::single_light()),
    ] {
        for decorrelation in [Decorrelation::Tsmis, Decorrelation::Ssmis] {
            let stats = replicates_config(
                &scene,
                tile_mixture_score(Sampling::Guided(decorrelation)),
                0x6D63_6D6D_2000,
                32,
                100,
            );
            assert_z_test(
                &format!("MCMM {decorrelation:?} with the tile-mixture score, {name}"),
                &stats,
                0.0,
                5.0,
            );
        }
    }
}

/// H₁ (MCMM Fig. 16): without the shift, a pixel's later lobes have moved towards its own
/// earlier samples, so the n-sample SMIS denominator is too large for them and the estimate is
/// biased low. On the large light (where a lobe follows its samples most, as in the paper's
/// Cornell box), 32 runs of 100 frames must put the mean relative error below 0 by more than 5σ.
#[test]
fn unshuffled_tsmis_is_biased() {
    let stats = replicates(
        &ToyScene::large_light(),
        Sampling::Guided(Decorrelation::Unshuffled),
        0x6D63_6D6D_0000,
        32,
        100,
    );
    let result = z_test(&stats, 0.0);
    assert!(
        result.z < -5.0,
        "unshuffled TSMIS should be biased low by > 5σ: z = {:.2}, mean relative error {:.4} ± {:.4}",
        result.z,
        result.mean,
        result.standard_error
    );
}

/// Adaptation pays (issue requirement): after warm-up, the mean squared relative error of a
/// frame's estimate (4 samples per pixel) with MCMM guiding is at most 1/4 of cosine sampling's
/// on one small light. 4 runs of 300 frames each (38 400 frame estimates per sampler); the
/// measured ratio is about 0.02, so the bound holds with a wide margin.
#[test]
fn guiding_beats_cosine_sampling_on_one_light() {
    let scene = ToyScene::single_light();
    let mse = |sampling| {
        (0..4)
            .map(|r| run(&scene, sampling, 0x6D63_6D6D_1000 + r, 300).1)
            .sum::<f64>()
            / 4.0
    };
    let cosine = mse(Sampling::Cosine);
    for decorrelation in [Decorrelation::Tsmis, Decorrelation::Ssmis] {
        let guided = mse(Sampling::Guided(decorrelation));
        let ratio = guided / cosine;
        println!(
            "one light, {decorrelation:?}: MSE {guided:.4} vs cosine {cosine:.4}, ratio {ratio:.4}"
        );
        assert!(
            ratio <= 0.25,
            "{decorrelation:?}: variance ratio {ratio:.4} > 1/4"
        );
    }
}

/// Adaptation pays with eight lights (issue requirement: variance ≤ 1/2 of cosine sampling's
/// at equal samples). Eight small lights (`ToyScene::eight_lights`, 2.5° to 3.4° across), a
/// 32 × 32-pixel image (`McmmToyConfig::image`: 32 tiles, the paper's 45-pixel neighbour
/// window), SSMIS, 4 samples per pixel and frame; 3 runs of 150 frames after warm-up
/// (460 800 frame estimates per sampler). The mean squared relative error of the frame
/// estimates with the tile-mixture score must be at most 1/2 of cosine sampling's; measured
/// 0.15–0.2. Also printed, not asserted: the paper's own score (about 0.68: fresh hemisphere
/// hits win every acceptance, see [`ScoreDensity`]) and TSMIS, whose n = 4 techniques per pixel
/// cannot cover eight lights (each uncovered light costs 1/p_h = 5 times its cosine variance
/// through the defensive branch), so it stays above cosine sampling (about 2.4).
#[test]
fn guiding_beats_cosine_sampling_on_eight_lights() {
    let scene = ToyScene::eight_lights();
    let mse = |sampling, score_density| {
        let mut config = McmmToyConfig::image(sampling);
        config.params.score_density = score_density;
        (0..3)
            .map(|r| run_config(&scene, config, 0x6D63_6D6D_3000 + r, 150).1)
            .sum::<f64>()
            / 3.0
    };
    let cosine = mse(Sampling::Cosine, ScoreDensity::Technique);
    let ratio = |sampling, score_density| {
        let guided = mse(sampling, score_density);
        println!(
            "eight lights, {sampling:?}, {score_density:?} score: MSE {guided:.3} vs cosine \
             {cosine:.3}, ratio {:.3}",
            guided / cosine
        );
        guided / cosine
    };
    let ssmis = Sampling::Guided(Decorrelation::Ssmis);
    ratio(ssmis, ScoreDensity::Technique);
    ratio(
        Sampling::Guided(Decorrelation::Tsmis),
        ScoreDensity::TileMixture,
    );
    let tile = ratio(ssmis, ScoreDensity::TileMixture);
    assert!(
        tile <= 0.5,
        "SSMIS with the tile-mixture score: variance ratio {tile:.3} > 1/2"
    );
}
