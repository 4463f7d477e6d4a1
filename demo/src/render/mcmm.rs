//! MCMM in the CPU tracer (Dittebrandt et al. 2023, "Markov Chain Mixture Models for Real-Time
//! Direct Illumination"): [`McmmRenderer`], one chain per pixel over the screen, for direct
//! light (`--bounces 1`).
//!
//! The image is cut into tiles of [`TILE_WIDTH`] × [`TILE_HEIGHT`] = 64 pixels (one GPU
//! workgroup in the WGSL twin; the paper's tile is one subgroup of 32, see
//! [`TILE_SIZE`]: 64 chains is mcg's choice). Each frame, every chain starts from the state its
//! pixel wrote last frame; then, per sample (step) of the frame and per pixel:
//! 1. collaborative discovery (MCMM Alg. 1): the chain's tentative state is resampled from
//!    neighbour states of the previous frame at B-spline offsets (no motion: the built-in
//!    cameras are static, the motion vector is zero);
//! 2. the chains of the tile are permuted by a random xor mask, one per tile and step
//!    (spatial SMIS, MCMM sec. 4.2), so that the technique a pixel samples is a uniform pick
//!    from the tile's;
//! 3. the camera ray (box filter) finds the shading point x; the chain's technique (Alg. 2:
//!    the material's BSDF sampling — MCMM's defensive "hemisphere" technique, here the
//!    material so that glossy surfaces stay well sampled — with probability p_h or when the
//!    state has no lobe, else the state's vMF lobe) samples ω; the ray along ω finds the
//!    emitter;
//! 4. the pixel's estimate is the one-sample SSMIS estimator (MCMM eq. 9)
//!    f(ω) / ((1/n) Σⱼ p(ω | tⱼ)), the tile's n = 64 techniques reconstructed at x;
//! 5. the chain learns (Alg. 3) from the score f = lum(f_r cos L_e)/p, p the tile's mixture
//!    density ([`ScoreDensity::TileMixture`], default) or the chain's own technique density
//!    (the paper's [`ScoreDensity::Technique`]).
//!
//! At the end of the frame each chain's current state is written where it ended. The estimator
//! is unbiased for any chain states: the states a step samples from are fixed before that
//! step's samples are drawn, and the mixture density is exact (MCMM appendix A).
//!
//! # Where the error comes from (many-lights room)
//!
//! Issue target: relMSE ≤ ¼ of `bsdf` at equal samples after 64 frames. Measured with
//! `cargo run --release -p mcg-demo --example mcmm_diagnostics -- REF.exr` (64 × 64, 64 frames
//! of 4 spp, REF a 16 384-spp `nee` render), p_h = 0.2, 32-lane tiles:
//! - `mcmm` ÷ `bsdf` = 0.557 (0.2257 / 0.4053), and 0.539 over the last 16 frames alone: the
//!   error is not the chains' warm-up, the chains plateau.
//! - Diffuse pixels carry 94 % of `mcmm`'s error (ratio 0.535 there); the 62 metal pixels 6 %
//!   (ratio 1.50: worse than `bsdf`, whose sampling is near-optimal there); lights seen
//!   directly nothing. By the pixel's effective number of lights (Σc)²/Σc²: 1–2 lights →
//!   ratio 0.21, 4–8 → 0.42 (34 % of the error), ≥ 8 → 0.72 (47 %).
//! - The chains after 64 frames: 4092 of 4096 valid, mean sample count N = 11, 23 % with
//!   N ≤ 4, 75 % with a mean target within 0.25 m of a light. Per tile, the 32 states point
//!   at 6.8 distinct lights, while 9.4 lights carry 90 % of the tile's pixels' light, and 5.9
//!   of those 9.4 are covered. A light no lobe covers is sampled with density p_h · p_bsdf,
//!   so its share of the variance is 1/p_h = 5 times what `bsdf` gives it.
//! - Sweeps (64-frame ratio, one seed): window half width 8 → 0.64, 16 → 0.56, 32 → 0.60;
//!   α_min 0.02 → 0.55, 0.3 → 0.56; neighbour candidates 2 → 0.61, 10 → 0.58; the paper's
//!   score → 0.64; p_h 0.1 → 0.71, 0.4 → 0.50 ([`DEFENSIVE_PROBABILITY`], 4 seeds).
//! - Tile size (a CPU experiment, not in the code): 64 lanes (8 × 8) → 0.44 (p_h 0.2) and
//!   0.40 (p_h 0.4); 128 lanes (16 × 8) → 0.37 and 0.35, 10.0 of 10.6 needed lights covered,
//!   and 0.19–0.21 over the last 16 frames alone — there the warm-up (valid chains after
//!   frame 1, 4, 8, 16: 56, 415, 1712, 3438 of 4096 at 32 lanes) is what keeps the 64-frame
//!   mean above ¼. But the mixture costs n pdf evaluations per sample: the diagnostics'
//!   CPU seconds (both methods) grow from 3.0 (32 lanes) to 4.1 (64) and 6.0 (128), which
//!   the GPU frame-time target (≤ 1.5 × `bsdf`) does not leave room for.
//!
//! So with 24 lights and one lobe per pixel, a 32-chain tile cannot hold a lobe for every
//! light that matters, and the uncovered lights cost more than `bsdf` pays for them. mcg
//! therefore uses tiles of 64 chains ([`TILE_SIZE`]) and p_h = 0.4: `mcmm` ÷ `bsdf` = 0.404,
//! 0.413, 0.442, 0.433 over four seeds (8.1–8.5 of 9.7 needed lights covered per tile), at
//! the same GPU cost as 32 lanes within the noise of this machine (lavapipe, process CPU
//! seconds of 32 frames: `bsdf` 0.93, 32 lanes 1.34, 64 lanes 1.39, 128 lanes 2.06, medians
//! of three). What is left above ¼: the uncovered lights (about 1.4 of 9.7 per tile), the
//! warm-up (0.30–0.36 over the last 16 frames alone) and the metal box; 128-lane tiles
//! would reach 0.35 at 2.2 × the `bsdf` frame, over the cost target.
//!
//! # Warm-up and coverage: the prior and the window
//!
//! The same diagnostics with the 64-lane tiles and p_h = 0.4 (seed 0x6d6367, REF 4096-spp
//! `nee`): the running ratio is 0.70 after 16 frames, 0.52 after 32, 0.41 after 64, and 0.30
//! over the last 16 frames alone; valid chains after frame 1, 2, 4, 8, 16, 32: 56, 123, 356,
//! 1392, 2653, 3729 of 4096. The warm-up is slow because a state with one sample has a wide
//! lobe under the uninformed prior (κ ≈ 6), so a neighbour that adopts it seldom hits the
//! light again and never confirms it ([`CHAIN_PRIOR`]). Three changes, none of them a cost
//! per sample (the GPU runs them through the same [`McmmParams`]):
//! - [`CHAIN_PRIOR`] (r_p = 0.9, N_p = 0.05): young lobes as narrow as a small light;
//!   ratio 0.406 → 0.288 (p_h 0.4, one seed);
//! - p_h = 0.5 ([`DEFENSIVE_PROBABILITY`]): 0.286 (mean of four seeds);
//! - a neighbour window of 0.75 × the image height ([`WINDOW_HALF_WIDTH_FRACTION`]) instead
//!   of 16 pixels: 0.208 (seeds 0x6d6367, 1, 2, 3: 0.202, 0.215, 0.219, 0.195).
//!
//! With all three (seed 0x6d6367): valid chains after frame 2, 4, 8, 16: 207, 1739, 3516,
//! 4029; a tile's chains point at 12.9 lights and cover 9.2 of the 9.7 that carry 90 % of its
//! light (8.1 before); running ratio 0.34 after 16 frames, 0.24 after 32, 0.20 after 64 and
//! 0.15 over the last 16 frames alone. Diffuse pixels carry 97 % of the error (ratio 0.20),
//! the metal box 3 % (ratio 0.27: better than `bsdf` now); by effective light count 1–2 →
//! 0.14, 2–4 → 0.17, 4–8 → 0.17, ≥ 8 → 0.26 (46 % of the error). What is left is the warm-up
//! (the first 16 frames average 0.34) and the pixels lit by many lights. Tried and not kept:
//! a chain without a lobe adopting a random state of its tile within the frame (0.284 against
//! 0.286 without, four seeds), and the same as a reservoir candidate for every chain (0.50: the
//! tile's chains collapse onto its brightest lights).
//!
//! With [`NEIGHBOUR_CANDIDATES`] = 3 (the defaults of [`mcmm_params`]), `mcg-demo render
//! --scene demo/scenes/many_lights_room.gltf --method bsdf|mcmm --device cpu|gpu --bounces 1
//! --width 64 --height 64 --spp 4 --frames 64 --seed S --reference REF.exr` (REF a 4096-spp
//! `nee` render), `mcmm` ÷ `bsdf` for S = 0x6d6367, 1, 2, 3: CPU 0.215, 0.231, 0.212, 0.189;
//! GPU (lavapipe) 0.214, 0.231, 0.214, 0.201. Cost on lavapipe, process CPU seconds of 60
//! frames (a 64-frame run less a 4-frame run), five interleaved repetitions: `bsdf` 26.7 ms
//! per frame, `mcmm` 38.0 ms (medians; 1.42 ×, repetitions 1.37–1.55 ×), the same as before
//! these changes (38.2 ms): the faster warm-up evaluates more lobes per mixture (1.57 × with
//! the prior, p_h and window alone), paid for by the two fewer candidates (1.51 ×) and by
//! `render_mcmm`'s three workgroup barriers per step instead of six (1.46 ×; those three
//! steps are medians of three repetitions on a busier machine).

use glam::{Vec2, Vec3};
use mcg_gpu_backend::sampling::next_uniform;
use mcg_markov_guide::mcmm::{
    McmmParams, McmmPrior, PixelState, PixelStateBuffers, SampleChoice, ScoreDensity,
    bspline_offset, choose_technique, collaborative_discovery, technique_pdf, update,
};
use mcg_markov_guide::mcpg::{Scatter, luminance};
use mcg_smis::{select_uniform, xor_source_lane};
use mcg_vmf::{MapPrior, PriorDecay};
use rayon::prelude::*;

use super::cpu::{RenderSettings, offset, path_seed};
use super::guided::MaterialScatter;
use super::scene::Scene;
use crate::Result;

/// Tile width in pixels (the population one xor permutation acts on).
pub const TILE_WIDTH: u32 = 8;
/// Tile height in pixels.
pub const TILE_HEIGHT: u32 = 8;
/// Pixels per tile: 64 chains share one SSMIS mixture. The paper's tile is one subgroup of
/// 32 lanes; on the many-lights room 32 chains hold lobes for about 6 of the 9–10 lights that
/// matter to a tile, 64 chains for about 8 (module docs), so mcg's tile is one workgroup of 64
/// invocations (an extension of the paper; the xor permutation of sec. 4.2 runs through
/// workgroup memory).
pub const TILE_SIZE: usize = (TILE_WIDTH * TILE_HEIGHT) as usize;

/// The salt of the per-tile stream of the xor masks (the WGSL twin uses the same).
pub const TILE_SALT: u32 = 0x7f4a_7c15;

/// The score density on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum McmmScore {
    /// [`ScoreDensity::TileMixture`]: the score is the pixel's one-sample SSMIS estimate, with
    /// p_h = [`DEFENSIVE_PROBABILITY`], the prior [`CHAIN_PRIOR`] and the screen-wide window
    /// of [`WINDOW_HALF_WIDTH_FRACTION`] (mcg's extension).
    #[value(
        help = "The pixel's one-sample estimate of its tile's mixture, p_h = 0.4 (mcg's extension)"
    )]
    #[default]
    TileMixture,
    /// [`ScoreDensity::Technique`]: the paper's score, divided by the chain's own density, with
    /// the paper's p_h = 0.2 and uninformed prior.
    #[value(help = "The chain's own technique density, p_h = 0.2 (the paper's)")]
    Paper,
}

/// The smallest half width of the neighbour window of [`McmmScore::Paper`], in pixels. Measured
/// on the many-lights room at 64 × 64, 64 frames of 4 spp, relMSE of `mcmm` (tile-mixture
/// score, uninformed prior): half width 2 → 0.35, 4 → 0.34, 8 → 0.26, 16 → 0.23, 32 → 0.24
/// (`bsdf`: 0.41). The paper's 45 pixels at 1080 rows scale to 3 pixels there: too few
/// neighbours to spread what a chain finds.
pub const MIN_WINDOW_HALF_WIDTH: f32 = 16.0;

/// The half width of the neighbour window of [`McmmScore::TileMixture`] as a fraction of the
/// image height (at least the paper's 45 pixels at 1080 rows): 0.75, so that Alg. 1's
/// candidates come from anywhere on the screen, not from the tile's neighbourhood alone (mcg's
/// choice). A light that no chain of a tile covers is found by a BSDF sample (density
/// p_h · p_bsdf, rare for a small light) or by a neighbour that covers it; neighbours from
/// afar carry lights the nearby tiles lack. With [`CHAIN_PRIOR`] and p_h = 0.5, `mcmm` ÷
/// `bsdf` on the many-lights room (64 × 64, 64 frames of 4 spp, mean of seeds 0x6d6367, 1, 2,
/// 3): half width 8 px → 0.352, 24 → 0.245, 32 → 0.236, 40 → 0.220, 48 (0.75 h) → 0.208,
/// 64 → 0.225, 96 → 0.244.
pub const WINDOW_HALF_WIDTH_FRACTION: f32 = 0.75;

/// The probability p_h of the defensive technique (the material's sampling) although the state
/// holds a lobe: 0.5 instead of the paper's 0.2 (MCMM Alg. 2 line 2), mcg's choice for scenes
/// with more lights than a tile's chains cover.
///
/// A light that no lobe of the tile covers is sampled with density p_h · p_bsdf only, so its
/// share of a pixel's variance is 1/p_h times what BSDF sampling alone gives it. Measured on
/// the many-lights room at 64 × 64, 64 frames of 4 spp, `mcmm` ÷ `bsdf` (mean of seeds
/// 0x6d6367, 1, 2, 3), with [`CHAIN_PRIOR`] and the window of
/// [`WINDOW_HALF_WIDTH_FRACTION`]: p_h = 0.4 → 0.246 (window 64 px), 0.5 → 0.208,
/// 0.6 → 0.218. Before the prior and the window (uninformed prior, 16-pixel window):
/// p_h = 0.2 → 0.557, 0.548, 0.519, 0.562 (seeds 0x6d6367, 1, 2, 3, 32-lane tiles);
/// 0.4 → 0.498, 0.518, 0.505, 0.516.
pub const DEFENSIVE_PROBABILITY: f32 = 0.5;

/// The MAP prior of the chains' lobes for [`McmmScore::TileMixture`]: mean cosine r_p = 0.9 with
/// N_p = 0.05 virtual samples, decaying with N² (MCMM sec. 5 "Uninformed vs. informed priors";
/// the paper's Falcor scenes use r_p = 0, [`McmmParams::PAPER`]). mcg's choice for small
/// lights, without knowing their size (the paper's informed prior, `McmmPrior::LightSize`,
/// needs it).
///
/// A state with one sample has r̄ = 1; the uninformed prior (r_p = 0, N_p = 0.2) widens its lobe
/// to κ ≈ 6 (mean cosine 0.83), in which a neighbour that adopts the state (Alg. 1) seldom
/// hits the light again, so the state is not confirmed (S_c stays empty) and discovery spreads
/// slowly: 1392 of 4096 chains valid after 8 frames, 2653 after 16. With r_p = 0.9 (κ ≈ 200 at
/// N = 1) the young lobe is a few degrees wide, about as wide as the small light it found: the adopters hit it, and the chains warm
/// up twice as fast (3917 valid after 8 frames, 4084 after 16, p_h = 0.5, 16-pixel window).
/// Measured `mcmm` ÷ `bsdf` on the many-lights room (64 × 64, 64 frames of 4 spp, one seed,
/// p_h = 0.4, 16-pixel window): r_p 0 / N_p 0.2 → 0.406; r_p 0.8 → 0.319, 0.9 → 0.288,
/// 0.95 → 0.297 (N_p 0.2); 0.9 with N_p 1 → 0.355, 4 → 0.470; at p_h = 0.5 (four seeds)
/// N_p 0.05 → 0.286, 0.2 → 0.295.
pub const CHAIN_PRIOR: MapPrior = MapPrior {
    mean_cosine: 0.9,
    weight: 0.05,
    decay: PriorDecay::SquaredCount,
};

/// Neighbour candidates per step of Alg. 1 for [`McmmScore::TileMixture`]: 3 instead of vkdt's 5
/// (mcg's choice for cost). Each candidate costs 13 uniforms and a load, 4 times per frame;
/// with [`CHAIN_PRIOR`], p_h = [`DEFENSIVE_PROBABILITY`] and the window of
/// [`WINDOW_HALF_WIDTH_FRACTION`], `mcmm` ÷ `bsdf` on the many-lights room (64 × 64, 64 frames
/// of 4 spp, mean of seeds 0x6d6367, 1, 2, 3) is 0.212 with 3 candidates and 0.208 with 5.
pub const NEIGHBOUR_CANDIDATES: u32 = 3;

/// MCMM's constants for an image `height` pixels high: the paper's (MCMM sec. 5) for
/// [`McmmScore::Paper`] with the neighbour window scaled from 45 pixels at 1080 rows to the
/// image (at least [`MIN_WINDOW_HALF_WIDTH`]); for [`McmmScore::TileMixture`] mcg's choices:
/// the tile-mixture score, p_h = [`DEFENSIVE_PROBABILITY`], the prior [`CHAIN_PRIOR`] and a
/// window of [`WINDOW_HALF_WIDTH_FRACTION`] of the height.
#[must_use]
pub fn mcmm_params(score: McmmScore, height: u32) -> McmmParams {
    let mut params = McmmParams::PAPER;
    let paper_window = 45.0 * height as f32 / 1080.0;
    match score {
        McmmScore::TileMixture => {
            params.hemisphere_probability = DEFENSIVE_PROBABILITY;
            params.prior = McmmPrior::Fixed(CHAIN_PRIOR);
            params.window_half_width = paper_window.max(WINDOW_HALF_WIDTH_FRACTION * height as f32);
            params.score_density = ScoreDensity::TileMixture;
            params.neighbour_candidates = NEIGHBOUR_CANDIDATES;
        }
        McmmScore::Paper => {
            params.window_half_width = paper_window.max(MIN_WINDOW_HALF_WIDTH);
            params.score_density = ScoreDensity::Technique;
        }
    }
    params
}

/// The tiles across and down of a `width × height` image.
#[must_use]
pub fn tile_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE_WIDTH), height.div_ceil(TILE_HEIGHT))
}

/// The xor mask of tile `tile` at step `step` of `frame`: ⌊n u⌋ (n = [`TILE_SIZE`]) of the
/// first uniform of the tile's own stream. Lane l samples the chain of lane l ⊕ mask
/// ([`xor_source_lane`]), a permutation of the tile ([`mcg_smis::XorPermutation`], which
/// stops at 32 lanes, for a larger tile).
#[must_use]
pub fn tile_mask(seed: u32, frame: u32, tile: u32, step: u32) -> u32 {
    let mut rng = path_seed(seed ^ TILE_SALT, frame, tile, step);
    select_uniform(TILE_SIZE, next_uniform(&mut rng)) as u32
}

/// A pixel's chain: tentative state S and current state S_c (MCMM Table 2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Chain {
    tentative: PixelState,
    current: PixelState,
}

/// MCMM on the CPU: the per-pixel state buffers of the previous and the current frame.
#[derive(Clone, Debug)]
pub struct McmmRenderer {
    params: McmmParams,
    buffers: PixelStateBuffers,
}

impl McmmRenderer {
    /// Empty chains for a `width × height` image.
    ///
    /// # Errors
    /// Invalid `params`, or an image too large for its state buffers.
    pub fn new(width: u32, height: u32, params: McmmParams) -> Result<Self> {
        params
            .validate()
            .map_err(|e| format!("MCMM parameters: {e:?}"))?;
        let buffers = PixelStateBuffers::new(width, height)
            .map_err(|e| format!("MCMM state buffers: {e:?}"))?;
        Ok(Self { params, buffers })
    }

    /// The constants.
    #[must_use]
    pub const fn params(&self) -> &McmmParams {
        &self.params
    }

    /// The states written by the last frame, row-major.
    #[must_use]
    pub fn states(&self) -> &[PixelState] {
        self.buffers.previous_states()
    }

    /// Renders one frame of direct light (`settings.bounces` must be 1): `spp` MCMM steps per
    /// pixel; returns the per-pixel mean radiance, row-major.
    ///
    /// # Errors
    /// When `settings` do not match the image of [`McmmRenderer::new`] or ask for more than
    /// one bounce.
    pub fn render_frame(
        &mut self,
        scene: &Scene,
        settings: &RenderSettings,
        frame: u32,
    ) -> Result<Vec<Vec3>> {
        check_settings(settings, self.buffers.width(), self.buffers.height())?;
        let (tiles_x, tiles_y) = tile_grid(settings.width, settings.height);
        let done: Vec<([Vec3; TILE_SIZE], [Chain; TILE_SIZE])> = (0..tiles_x * tiles_y)
            .into_par_iter()
            .map(|tile| self.tile_frame(scene, settings, frame, tile))
            .collect();
        let mut image = vec![Vec3::ZERO; (settings.width * settings.height) as usize];
        for (tile, (radiance, chains)) in done.iter().enumerate() {
            for lane in 0..TILE_SIZE {
                if let Some((x, y)) = lane_pixel(settings, tile as u32, lane) {
                    image[(y * settings.width + x) as usize] = radiance[lane];
                    self.buffers
                        .set_current(x as i32, y as i32, chains[lane].current);
                }
            }
        }
        self.buffers.swap();
        Ok(image)
    }

    /// One frame of the [`TILE_SIZE`] chains of `tile`: their radiance (mean over the steps) and the
    /// chains where they ended.
    fn tile_frame(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        frame: u32,
        tile: u32,
    ) -> ([Vec3; TILE_SIZE], [Chain; TILE_SIZE]) {
        let pixels: [Option<(u32, u32)>; TILE_SIZE] =
            core::array::from_fn(|lane| lane_pixel(settings, tile, lane));
        let mut chains: [Chain; TILE_SIZE] = core::array::from_fn(|lane| {
            let state = pixels[lane]
                .and_then(|(x, y)| self.buffers.previous(x as i32, y as i32))
                .unwrap_or(PixelState::EMPTY);
            Chain {
                tentative: state,
                current: state,
            }
        });
        let mut sums = [Vec3::ZERO; TILE_SIZE];
        for step in 0..settings.spp {
            let mut rngs = [0u32; TILE_SIZE];
            for lane in 0..TILE_SIZE {
                if let Some((x, y)) = pixels[lane] {
                    let index = y * settings.width + x;
                    rngs[lane] = path_seed(settings.seed, frame, index, step);
                    chains[lane].tentative =
                        self.discover(chains[lane].tentative, (x, y), &mut rngs[lane]);
                }
            }
            let mask = tile_mask(settings.seed, frame, tile, step);
            let before = chains;
            for (lane, chain) in chains.iter_mut().enumerate() {
                *chain = before[xor_source_lane(lane as u32, mask) as usize];
            }
            // The streams stay with the pixels; only the chains move.
            let step_states: [PixelState; TILE_SIZE] =
                core::array::from_fn(|lane| chains[lane].tentative);
            for lane in 0..TILE_SIZE {
                if let Some(pixel) = pixels[lane] {
                    sums[lane] += self.shade(
                        scene,
                        settings,
                        pixel,
                        &step_states,
                        &mut chains[lane],
                        &mut rngs[lane],
                    );
                }
            }
        }
        let scale = 1.0 / settings.spp as f32;
        (sums.map(|s| s * scale), chains)
    }

    /// Alg. 1 for the pixel `(x, y)`: 12 uniforms for the offset and one for the selection per
    /// candidate, in this order (the WGSL twin's).
    fn discover(&self, state: PixelState, (x, y): (u32, u32), rng: &mut u32) -> PixelState {
        let params = &self.params;
        let mut candidates = Vec::with_capacity(params.neighbour_candidates as usize);
        for _ in 0..params.neighbour_candidates {
            let u: [f32; 12] = core::array::from_fn(|_| next_uniform(rng));
            let offset = bspline_offset(&u, params.window_half_width);
            let select = next_uniform(rng);
            let pixel = (x as i32, y as i32);
            if let Some(s) = self.buffers.neighbour(pixel, offset, Vec2::ZERO) {
                candidates.push((s, select));
            }
        }
        collaborative_discovery(state, candidates)
    }

    /// One step at pixel `(x, y)`: the camera ray, the chain's sample, the SSMIS estimate over
    /// the tile's `step_states` and the chain's update (Alg. 2-3); the step's estimate
    /// (camera-visible emission plus the SSMIS estimate).
    fn shade(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        (x, y): (u32, u32),
        step_states: &[PixelState; TILE_SIZE],
        chain: &mut Chain,
        rng: &mut u32,
    ) -> Vec3 {
        let params = &self.params;
        let (jx, jy) = (next_uniform(rng), next_uniform(rng));
        let d = scene.camera.direction(
            x as f32 + jx,
            y as f32 + jy,
            settings.width,
            settings.height,
        );
        let origin = scene.camera.position;
        let Some(hit) = scene.intersect(origin, d, 0.0, f32::INFINITY) else {
            return scene.environment_radiance(d);
        };
        let tri = scene.bvh.triangles[hit.triangle as usize];
        let material = scene.material_at(&hit);
        let n_front = tri.cross().normalize();
        let front = n_front.dot(d) < 0.0;
        let normal = if front { n_front } else { -n_front };
        let position = origin + hit.t * d;
        let mut radiance = if front {
            material.emission()
        } else {
            Vec3::ZERO
        };
        let u_select = next_uniform(rng);
        let u = Vec2::new(next_uniform(rng), next_uniform(rng));
        let scatter = MaterialScatter {
            material,
            normal,
            wo: -d,
        };
        let (w, from_hemisphere) =
            match choose_technique(&chain.tentative, position, u_select, params) {
                SampleChoice::Lobe(lobe) => (lobe.sample(u), false),
                SampleChoice::Hemisphere => (scatter.sample(u), true),
            };
        let (x2, emitted) = emitter_along(scene, offset(position, normal), w);
        let value = material.eval(normal, -d, w) * emitted;
        let bsdf_pdf = scatter.pdf(w);
        let pdf_of = |s: &PixelState| technique_pdf(s, position, w, bsdf_pdf, params);
        let mixture = step_states.iter().map(pdf_of).sum::<f32>().min(f32::MAX) / TILE_SIZE as f32;
        radiance += ratio(value, mixture);
        let density = match params.score_density {
            ScoreDensity::TileMixture => mixture,
            ScoreDensity::Technique => pdf_of(&chain.tentative),
        };
        let score = ratio(Vec3::splat(luminance(value)), density).x;
        let u_accept = next_uniform(rng);
        update(
            &mut chain.tentative,
            &mut chain.current,
            position,
            x2,
            score,
            from_hemisphere,
            u_accept,
            params,
        );
        radiance
    }
}

/// The pixel of `lane` in `tile`, `None` past the image's edge.
fn lane_pixel(settings: &RenderSettings, tile: u32, lane: usize) -> Option<(u32, u32)> {
    let (tiles_x, _) = tile_grid(settings.width, settings.height);
    let x = (tile % tiles_x) * TILE_WIDTH + lane as u32 % TILE_WIDTH;
    let y = (tile / tiles_x) * TILE_HEIGHT + lane as u32 / TILE_WIDTH;
    (x < settings.width && y < settings.height).then_some((x, y))
}

/// The point the ray `(origin, w)` hits and the radiance it carries back (front faces emit);
/// `origin + w` and the environment's radiance when it leaves the scene.
fn emitter_along(scene: &Scene, origin: Vec3, w: Vec3) -> (Vec3, Vec3) {
    match scene.intersect(origin, w, 0.0, f32::INFINITY) {
        Some(hit) => {
            let tri = scene.bvh.triangles[hit.triangle as usize];
            let emitted = if tri.cross().dot(w) < 0.0 {
                scene.material_at(&hit).emission()
            } else {
                Vec3::ZERO
            };
            (origin + hit.t * w, emitted)
        }
        None => (origin + w, scene.environment_radiance(w)),
    }
}

/// `value / density`, zero where the density is not positive or the quotient not finite.
fn ratio(value: Vec3, density: f32) -> Vec3 {
    let r = value / density;
    if density > 0.0 && r.is_finite() {
        r
    } else {
        Vec3::ZERO
    }
}

/// MCMM renders direct light of one image size.
///
/// # Errors
/// When `settings.bounces` is not 1 or the image is not `width × height`.
pub fn check_settings(settings: &RenderSettings, width: u32, height: u32) -> Result<()> {
    if settings.bounces != 1 {
        return Err(format!(
            "mcmm guides direct light only: use --bounces 1 (got {})",
            settings.bounces
        )
        .into());
    }
    if (settings.width, settings.height) != (width, height) {
        return Err(format!(
            "mcmm: the chains are for {width}×{height}, the frame is {}×{}",
            settings.width, settings.height
        )
        .into());
    }
    Ok(())
}
