//! The full renderer loop of MCMM guiding on the toy scene, end to end: frames of guided
//! direct illumination on a patch of a plane under one small light, compared with cosine
//! sampling at the same number of rays, against the closed-form irradiance.
//!
//! Run with `cargo run --release -p mcg-markov-guide --example toy_loop --features toy`.
//! The loop itself is `McmmToyRenderer::render_frame` (src/toy_renderer/mcmm_loop.rs).

use mcg_markov_guide::toy_renderer::{Decorrelation, McmmToyConfig, McmmToyRenderer, Sampling};
use mcg_markov_guide::toy_scene::ToyScene;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn main() {
    let scene = ToyScene::single_light();
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let mut guided =
        McmmToyRenderer::new(McmmToyConfig::small(Sampling::Guided(Decorrelation::Tsmis)));
    let mut cosine = McmmToyRenderer::new(McmmToyConfig::small(Sampling::Cosine));
    let exact: Vec<f64> = (0..guided.pixel_count())
        .map(|i| {
            scene
                .irradiance(guided.shading_point(i))
                .expect("closed form exists")
        })
        .collect();
    println!("frame   relative RMS error (guided, TSMIS)   (cosine sampling)");
    for frame in 0..=30 {
        let g = guided.render_frame(&scene, &mut rng);
        let c = cosine.render_frame(&scene, &mut rng);
        if frame % 5 == 0 {
            println!(
                "{frame:>5}   {:>34.4}   {:>17.4}",
                relative_rms(&g, &exact),
                relative_rms(&c, &exact)
            );
        }
    }
}

fn relative_rms(estimates: &[f32], exact: &[f64]) -> f64 {
    let sum: f64 = estimates
        .iter()
        .zip(exact)
        .map(|(&e, &x)| ((e as f64 - x) / x).powi(2))
        .sum();
    (sum / exact.len() as f64).sqrt()
}
