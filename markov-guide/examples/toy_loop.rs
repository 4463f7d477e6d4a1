//! The full renderer loop of Markov chain guiding on the toy scene, end to end: frames of
//! guided direct illumination on a patch of a plane under one small light — MCMM (screen-space
//! chains, TSMIS) and MCPG (hash-grid chains) — against cosine sampling at the same number of
//! rays, all compared with the closed-form irradiance.
//!
//! Run with `cargo run --release -p mcg-markov-guide --example toy_loop --features toy`.
//! The loops themselves are `McmmToyRenderer::render_frame` (src/toy_renderer/mcmm_loop.rs)
//! and `McpgToyRenderer::render_frame` (src/toy_renderer/mcpg_loop.rs).

use mcg_markov_guide::toy_renderer::{
    Decorrelation, McmmToyConfig, McmmToyRenderer, McpgToyConfig, McpgToyRenderer, Sampling,
};
use mcg_markov_guide::toy_scene::ToyScene;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

fn main() {
    let scene = ToyScene::single_light();
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let mut mcmm =
        McmmToyRenderer::new(McmmToyConfig::small(Sampling::Guided(Decorrelation::Tsmis)));
    let mut mcpg = McpgToyRenderer::new(McpgToyConfig::small(true));
    let mut cosine = McmmToyRenderer::new(McmmToyConfig::small(Sampling::Cosine));
    let exact = mcmm.exact_irradiance(&scene).expect("closed form exists");
    // Both renderers lay out the same 8 × 4 shading points (MCMM tile-major, MCPG row-major).
    let exact_rows = mcpg.exact_irradiance(&scene).expect("closed form exists");
    println!("relative RMS error of each frame (4 samples per pixel)");
    println!("frames     MCMM (TSMIS)    MCPG    cosine sampling");
    let (mut sums, mut count) = ([0.0f64; 3], 0);
    for frame in 1..=60 {
        let a = mcmm.render_frame(&scene, &mut rng);
        let b = mcpg.render_frame(&scene, &mut rng).estimates;
        let c = cosine.render_frame(&scene, &mut rng);
        sums[0] += mean_squared_relative_error(&a, &exact);
        sums[1] += mean_squared_relative_error(&b, &exact_rows);
        sums[2] += mean_squared_relative_error(&c, &exact);
        count += 1;
        if frame % 10 == 0 {
            let rms = sums.map(|s| (s / count as f64).sqrt());
            println!(
                "{:>2}-{:<2}   {:>12.3}   {:>6.3}   {:>15.3}",
                frame - 9,
                frame,
                rms[0],
                rms[1],
                rms[2]
            );
            (sums, count) = ([0.0; 3], 0);
        }
    }
}

fn mean_squared_relative_error(estimates: &[f32], exact: &[f64]) -> f64 {
    let sum: f64 = estimates
        .iter()
        .zip(exact)
        .map(|(&e, &x)| ((e as f64 - x) / x).powi(2))
        .sum();
    sum / exact.len() as f64
}
