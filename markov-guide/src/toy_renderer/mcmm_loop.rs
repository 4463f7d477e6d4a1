//! MCMM's full per-frame loop (Dittebrandt et al. 2023, sec. 4.1-4.2) on the toy scene.

use std::vec::Vec;

use glam::{Vec2, Vec3};
use mcg_smis::{CyclicShift, MAX_TILE_SIZE, Technique, XorPermutation, smis, smis_one_sample};
use rand::{Rng, RngExt};

use crate::mcmm::{
    CosineChainTechnique, McmmParams, PixelState, PixelStateBuffers, ScoreDensity, bspline_offset,
    collaborative_discovery, update,
};
use crate::toy_scene::{TOY_NORMAL, ToyScene};

/// How the chains of a tile are decorrelated before their samples enter the estimator
/// (MCMM sec. 4.2, Fig. 5 and 16).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decorrelation {
    /// Temporal SMIS: the chains are shifted cyclically by one lane within the tile before every
    /// step, and each pixel evaluates the n-sample SMIS estimator (eq. 8) over the n
    /// (technique, sample) pairs it drew this frame. Unbiased for n ≤ tile size.
    Tsmis,
    /// Spatial SMIS: after collaborative discovery, a random xor-mask permutation assigns chains
    /// to pixels, and each pixel evaluates the one-sample estimator (eq. 9) over all states of
    /// the tile at that step, reconstructed at its own shading point; the frame estimate is the
    /// mean over the steps.
    Ssmis,
    /// The TSMIS estimator without the shift: every pixel keeps its own chain, so a sample
    /// shapes the pixel's later lobes and the estimator is biased (MCMM Fig. 16).
    Unshuffled,
}

/// How directions are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// MCMM guiding.
    Guided(Decorrelation),
    /// Cosine-weighted hemisphere sampling only, the baseline at equal sample count.
    Cosine,
}

/// The layout and settings of [`McmmToyRenderer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McmmToyConfig {
    /// Tile width in pixels; a tile (at most 32 pixels, a power of two for SSMIS) is the
    /// population one permutation acts on, one GPU subgroup.
    pub tile_width: u32,
    /// Tile height in pixels.
    pub tile_height: u32,
    /// Tiles across.
    pub tiles_x: u32,
    /// Tiles down.
    pub tiles_y: u32,
    /// World position of pixel (0, 0)'s shading point, on the plane z = 0.
    pub origin: Vec3,
    /// World distance between neighbouring pixels' shading points.
    pub pixel_spacing: f32,
    /// n, the MCMM iterations (samples) per pixel and frame; at most the tile size for TSMIS.
    pub steps: u32,
    /// The direction sampler.
    pub sampling: Sampling,
    /// MCMM's constants.
    pub params: McmmParams,
}

impl McmmToyConfig {
    /// One 8 × 4 tile of pixels 0.05 apart around the origin, 4 steps, the paper's constants
    /// with a 4-pixel neighbour window (the paper's 45 px is for 1920 × 1080).
    #[must_use]
    pub fn small(sampling: Sampling) -> Self {
        let mut params = McmmParams::PAPER;
        params.window_half_width = 4.0;
        Self {
            tile_width: 8,
            tile_height: 4,
            tiles_x: 1,
            tiles_y: 1,
            origin: Vec3::new(-0.175, -0.075, 0.0),
            pixel_spacing: 0.05,
            steps: 4,
            sampling,
            params,
        }
    }

    /// A 32 × 32-pixel image (4 × 8 tiles of 8 × 4) of pixels 0.05 apart centred on the
    /// origin, 4 steps, the paper's constants including its 45-pixel neighbour window: enough
    /// tiles that neighbour resampling (Alg. 1) draws from a population larger than one tile,
    /// as on a real frame.
    #[must_use]
    pub fn image(sampling: Sampling) -> Self {
        let spacing = 0.05;
        Self {
            tile_width: 8,
            tile_height: 4,
            tiles_x: 4,
            tiles_y: 8,
            origin: Vec3::new(-15.5 * spacing, -15.5 * spacing, 0.0),
            pixel_spacing: spacing,
            steps: 4,
            sampling,
            params: McmmParams::PAPER,
        }
    }

    fn tile_size(&self) -> u32 {
        self.tile_width * self.tile_height
    }

    fn width(&self) -> u32 {
        self.tile_width * self.tiles_x
    }

    fn height(&self) -> u32 {
        self.tile_height * self.tiles_y
    }
}

/// A pixel's chain: the tentative state S and the current state S_c (MCMM Table 2).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Chain {
    tentative: PixelState,
    current: PixelState,
}

/// MCMM on a grid of shading points of the toy scene: the reference renderer loop that the
/// tests, the demo and the `toy_loop` example run. Read [`McmmToyRenderer::render_frame`] for
/// the order of the steps.
#[derive(Clone, Debug)]
pub struct McmmToyRenderer {
    config: McmmToyConfig,
    buffers: PixelStateBuffers,
    /// Chains in tile-major order: index = tile · tile_size + lane.
    chains: Vec<Chain>,
}

impl McmmToyRenderer {
    /// A renderer with empty chains.
    ///
    /// # Panics
    /// When the tile is empty or larger than 32 pixels, when SSMIS is asked for with a tile size
    /// that is not a power of two, when TSMIS is asked for with more steps than the tile has
    /// pixels, or when the image's state buffers cannot be allocated
    /// ([`PixelStateBuffers::new`]).
    #[must_use]
    pub fn new(config: McmmToyConfig) -> Self {
        let size = config.tile_size();
        assert!(size > 0 && size <= MAX_TILE_SIZE, "tile of 1..=32 pixels");
        match config.sampling {
            Sampling::Guided(Decorrelation::Ssmis) => {
                assert!(size.is_power_of_two(), "SSMIS needs a power-of-two tile")
            }
            Sampling::Guided(Decorrelation::Tsmis) => {
                assert!(config.steps <= size, "TSMIS needs n ≤ tile size")
            }
            _ => {}
        }
        let n = (size * config.tiles_x * config.tiles_y) as usize;
        Self {
            config,
            buffers: PixelStateBuffers::new(config.width(), config.height())
                .expect("toy image too large for its state buffers"),
            chains: std::vec![Chain::default(); n],
        }
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &McmmToyConfig {
        &self.config
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixel_count(&self) -> usize {
        self.chains.len()
    }

    /// Pixel coordinates of tile-major index `index`.
    #[must_use]
    pub fn pixel(&self, index: usize) -> (i32, i32) {
        let size = self.config.tile_size() as usize;
        let (tile, lane) = (index / size, index % size);
        let tx = tile as u32 % self.config.tiles_x;
        let ty = tile as u32 / self.config.tiles_x;
        let lx = lane as u32 % self.config.tile_width;
        let ly = lane as u32 / self.config.tile_width;
        (
            (tx * self.config.tile_width + lx) as i32,
            (ty * self.config.tile_height + ly) as i32,
        )
    }

    /// The shading point of tile-major index `index`.
    #[must_use]
    pub fn shading_point(&self, index: usize) -> Vec3 {
        let (x, y) = self.pixel(index);
        self.config.origin + self.config.pixel_spacing * Vec3::new(x as f32, y as f32, 0.0)
    }

    /// The states written at the end of the last frame, row-major over the image.
    #[must_use]
    pub fn states(&self) -> &[PixelState] {
        self.buffers.previous_states()
    }

    /// The closed-form irradiance of `scene` at every pixel's shading point, in the order of
    /// the estimates [`render_frame`](Self::render_frame) returns; `None` when a pixel has no
    /// closed form ([`ToyScene::irradiance`]).
    #[must_use]
    pub fn exact_irradiance(&self, scene: &ToyScene) -> Option<Vec<f64>> {
        (0..self.pixel_count())
            .map(|i| scene.irradiance(self.shading_point(i)))
            .collect()
    }

    /// Renders one frame of `scene` and returns, per pixel (tile-major index), the frame's
    /// estimate of the irradiance E(x) = ∫ L(x, ω) max(0, n·ω) dω from `steps` samples.
    ///
    /// Per step, for every pixel: TSMIS shifts the chains first (Alg. 1 line 1); collaborative
    /// discovery from the previous frame's states (Alg. 1); SSMIS then permutes the chains of
    /// the tile with a random xor mask — after discovery, so that the technique a pixel samples
    /// is a uniform pick from the set its estimator sums over; the chain's technique
    /// (Alg. 2) samples ω; the scene is traced; the score f = value/p(ω) goes into Alg. 3,
    /// with p(ω | S) or the tile's mixture density as [`McmmParams::score_density`] says.
    /// At the end of the frame every chain's S_c is written to the pixel it ended at.
    pub fn render_frame<R: Rng + ?Sized>(&mut self, scene: &ToyScene, rng: &mut R) -> Vec<f32> {
        let config = self.config;
        let size = config.tile_size() as usize;
        let steps = config.steps as usize;
        let n = self.chains.len();
        self.start_chains();
        let mut frame = FrameSamples::new(n * steps, &config.params);
        let mut estimates = std::vec![0.0f32; n];
        for step in 0..steps {
            if config.sampling == Sampling::Guided(Decorrelation::Tsmis) {
                let shift = CyclicShift::new(size as u32, 1).expect("tile size checked in new");
                for tile in self.chains.chunks_mut(size) {
                    shift.apply(tile);
                }
            }
            if matches!(config.sampling, Sampling::Guided(_)) {
                self.discover(rng);
            }
            if config.sampling == Sampling::Guided(Decorrelation::Ssmis) {
                for tile in self.chains.chunks_mut(size) {
                    XorPermutation::from_uniform(size as u32, rng.random())
                        .expect("tile size checked in new")
                        .apply(tile);
                }
            }
            // The states this step's techniques come from (SSMIS rebuilds them at every pixel).
            let step_states: Vec<PixelState> = self.chains.iter().map(|c| c.tentative).collect();
            self.sample_step(scene, rng, step, &step_states, &mut frame);
            self.accumulate_step(step, &step_states, &mut frame, &mut estimates);
        }
        if matches!(
            config.sampling,
            Sampling::Guided(Decorrelation::Tsmis | Decorrelation::Unshuffled)
        ) {
            // Eq. 8 over the pixel's n (technique, sample) pairs of this frame.
            for (index, estimate) in estimates.iter_mut().enumerate() {
                let range = index * steps..(index + 1) * steps;
                *estimate = smis(
                    &frame.techniques[range.clone()],
                    &frame.samples[range.clone()],
                    &frame.values[range],
                );
            }
        }
        self.end_frame();
        estimates
    }

    /// Every chain starts the frame from the state its pixel wrote last frame.
    fn start_chains(&mut self) {
        for index in 0..self.chains.len() {
            let (px, py) = self.pixel(index);
            let state = self.buffers.previous(px, py).unwrap_or(PixelState::EMPTY);
            self.chains[index] = Chain {
                tentative: state,
                current: state,
            };
        }
    }

    /// Alg. 1: collaborative discovery from the previous frame's states, at every pixel.
    fn discover<R: Rng + ?Sized>(&mut self, rng: &mut R) {
        let params = self.config.params;
        for index in 0..self.chains.len() {
            let pixel = self.pixel(index);
            let mut candidates = Vec::with_capacity(params.neighbour_candidates as usize);
            for _ in 0..params.neighbour_candidates {
                let u: [f32; 12] = core::array::from_fn(|_| rng.random());
                let offset = bspline_offset(&u, params.window_half_width);
                let select: f32 = rng.random();
                if let Some(state) = self.buffers.neighbour(pixel, offset, Vec2::ZERO) {
                    candidates.push((state, select));
                }
            }
            let chain = &mut self.chains[index];
            chain.tentative = collaborative_discovery(chain.tentative, candidates);
        }
    }

    /// Alg. 2, tracing and Alg. 3 at every pixel for step `step`: stores the technique, the
    /// sample, its value and its score in `frame`, and updates guided chains.
    fn sample_step<R: Rng + ?Sized>(
        &mut self,
        scene: &ToyScene,
        rng: &mut R,
        step: usize,
        step_states: &[PixelState],
        frame: &mut FrameSamples,
    ) {
        let params = self.config.params;
        let size = self.config.tile_size() as usize;
        let steps = self.config.steps as usize;
        let guided = matches!(self.config.sampling, Sampling::Guided(_));
        for (index, &step_state) in step_states.iter().enumerate() {
            let x = self.shading_point(index);
            let state = if guided {
                step_state
            } else {
                PixelState::EMPTY
            };
            let technique = CosineChainTechnique::new(&state, x, TOY_NORMAL, &params);
            let u_select: f32 = rng.random();
            let u = Vec2::new(rng.random(), rng.random());
            let (w, from_hemisphere) = technique.sample_with_branch(u_select, u);
            let hit = scene.trace(x, w);
            let value = hit.radiance * TOY_NORMAL.dot(w).max(0.0);
            // f = value/p as a one-sample SMIS estimate over the scoring set (0 where
            // p = 0 or the ratio overflows): the chain's own technique, or the tile.
            let score = match params.score_density {
                ScoreDensity::Technique => {
                    smis_one_sample(core::slice::from_ref(&technique), &w, value)
                }
                ScoreDensity::TileMixture => {
                    tile_techniques(&mut frame.set, step_states, index, size, x, &params);
                    smis_one_sample(&frame.set, &w, value)
                }
            };
            let slot = index * steps + step;
            frame.scores[slot] = score;
            frame.techniques[slot] = technique;
            frame.samples[slot] = w;
            frame.values[slot] = value;
            if guided {
                let chain = &mut self.chains[index];
                let u_accept: f32 = rng.random();
                update(
                    &mut chain.tentative,
                    &mut chain.current,
                    x,
                    hit.point,
                    score,
                    from_hemisphere,
                    u_accept,
                    &params,
                );
            }
        }
    }

    /// Adds step `step`'s share to the estimates of the estimators that sum per step: SSMIS
    /// (eq. 9) and plain cosine sampling.
    fn accumulate_step(
        &self,
        step: usize,
        step_states: &[PixelState],
        frame: &mut FrameSamples,
        estimates: &mut [f32],
    ) {
        let params = self.config.params;
        let size = self.config.tile_size() as usize;
        let steps = self.config.steps as usize;
        match self.config.sampling {
            Sampling::Guided(Decorrelation::Ssmis) => {
                // Eq. 9 at each pixel over all of its tile's states at this step, each
                // reconstructed at the pixel's own shading point.
                // With the tile-mixture score the score already is this estimate.
                for (index, estimate) in estimates.iter_mut().enumerate() {
                    let slot = index * steps + step;
                    let one_sample = if params.score_density == ScoreDensity::TileMixture {
                        frame.scores[slot]
                    } else {
                        let x = self.shading_point(index);
                        tile_techniques(&mut frame.set, step_states, index, size, x, &params);
                        smis_one_sample(&frame.set, &frame.samples[slot], frame.values[slot])
                    };
                    *estimate += one_sample / steps as f32;
                }
            }
            Sampling::Cosine => {
                for (index, estimate) in estimates.iter_mut().enumerate() {
                    let slot = index * steps + step;
                    let pdf = frame.techniques[slot].pdf(&frame.samples[slot]);
                    if pdf > 0.0 {
                        *estimate += frame.values[slot] / pdf / steps as f32;
                    }
                }
            }
            _ => {}
        }
    }

    /// Writes S_c where each chain ended; it becomes the previous frame.
    fn end_frame(&mut self) {
        let guided = matches!(self.config.sampling, Sampling::Guided(_));
        for index in 0..self.chains.len() {
            let (px, py) = self.pixel(index);
            let state = if guided {
                self.chains[index].current
            } else {
                PixelState::EMPTY
            };
            self.buffers.set_current(px, py, state);
        }
        self.buffers.swap();
    }
}

/// A frame's (technique, sample, value, score) per pixel and step (slot `index · steps + step`),
/// and the scratch set of a tile's techniques.
struct FrameSamples {
    techniques: Vec<CosineChainTechnique>,
    samples: Vec<Vec3>,
    values: Vec<f32>,
    scores: Vec<f32>,
    set: Vec<CosineChainTechnique>,
}

impl FrameSamples {
    /// `slots` empty slots.
    fn new(slots: usize, params: &McmmParams) -> Self {
        let empty = CosineChainTechnique::new(&PixelState::EMPTY, Vec3::ZERO, TOY_NORMAL, params);
        Self {
            techniques: std::vec![empty; slots],
            samples: std::vec![Vec3::ZERO; slots],
            values: std::vec![0.0f32; slots],
            scores: std::vec![0.0f32; slots],
            set: Vec::new(),
        }
    }
}

/// The techniques of all states of `index`'s tile at this step, each reconstructed at the
/// shading point `x` of pixel `index`: the set of the SSMIS estimator (eq. 9) and of
/// [`ScoreDensity::TileMixture`].
fn tile_techniques(
    set: &mut Vec<CosineChainTechnique>,
    step_states: &[PixelState],
    index: usize,
    size: usize,
    x: Vec3,
    params: &McmmParams,
) {
    let tile = index / size * size;
    set.clear();
    set.extend(
        step_states[tile..tile + size]
            .iter()
            .map(|s| CosineChainTechnique::new(s, x, TOY_NORMAL, params)),
    );
}
