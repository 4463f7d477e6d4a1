//! MCPG's full per-sample loop (Alber et al. 2025, Alg. 1-3 and sec. 5) on the toy scene.

use std::vec::Vec;

use glam::{Vec2, Vec3};
use rand::{Rng, RngExt};

use mcg_smis::path_estimate;

use crate::cosine_hemisphere;
use crate::mcpg::{
    CandidateSet, CosineVertexTechnique, GridEnsemble, GridSlot, GridUniforms, McpgParams,
    Observation, SampleChoice, choose_technique, prepare_candidate, should_discard, update,
};
use crate::toy_scene::{TOY_NORMAL, ToyScene};

/// The most candidates a vertex loads ([`McpgParams::candidates`] is clamped to this).
pub const MAX_CANDIDATES: usize = 8;

/// The layout and settings of [`McpgToyRenderer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct McpgToyConfig {
    /// Pixels across.
    pub width: u32,
    /// Pixels down.
    pub height: u32,
    /// World position of pixel (0, 0)'s shading point, on the plane z = 0.
    pub origin: Vec3,
    /// World distance between neighbouring pixels' shading points.
    pub pixel_spacing: f32,
    /// The camera position (the adaptive grid's level follows the distance to it).
    pub camera: Vec3,
    /// Samples per pixel and frame.
    pub samples_per_pixel: u32,
    /// `false` samples the cosine hemisphere only: the baseline at equal sample count.
    pub guided: bool,
    /// Velocity prediction on load (MCPG eq. 10).
    pub velocity_prediction: bool,
    /// The discard heuristic (MCPG sec. 5).
    pub discard: bool,
    /// MCPG's constants.
    pub params: McpgParams,
    /// Slots of the adaptive grid's table.
    pub adaptive_capacity: u32,
    /// Slots of the static grid's table.
    pub static_capacity: u32,
}

impl McpgToyConfig {
    /// 8 × 4 pixels 0.05 apart around the origin seen from a camera 4 units away, 4 samples
    /// per pixel and frame, velocity prediction and the discard heuristic on, the paper's
    /// constants, tables of 65 521 and 4 099 slots.
    #[must_use]
    pub fn small(guided: bool) -> Self {
        Self {
            width: 8,
            height: 4,
            origin: Vec3::new(-0.175, -0.075, 0.0),
            pixel_spacing: 0.05,
            camera: Vec3::new(0.0, -2.5, 3.0),
            samples_per_pixel: 4,
            guided,
            velocity_prediction: true,
            discard: true,
            params: McpgParams::PAPER,
            adaptive_capacity: 65_521,
            static_capacity: 4_099,
        }
    }
}

/// What one frame of [`McpgToyRenderer`] measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct McpgFrame {
    /// Per pixel (row-major), the frame's irradiance estimate (mean over its samples).
    pub estimates: Vec<f32>,
    /// Samples drawn from a lobe (the rest came from the BSDF technique).
    pub lobe_samples: u32,
    /// All samples of the frame.
    pub samples: u32,
    /// Sum over lobe samples of the angle (radians) between the lobe's mean direction and the
    /// direction to the nearest light's centre (0 contributions when the scene has no light).
    pub lobe_angle_sum: f64,
}

impl McpgFrame {
    /// The fraction of samples drawn from lobes.
    #[must_use]
    pub fn lobe_fraction(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            self.lobe_samples as f64 / self.samples as f64
        }
    }

    /// The mean angle between the sampled lobes and the nearest light, in radians (`NaN` when no
    /// lobe was sampled).
    #[must_use]
    pub fn mean_lobe_angle(&self) -> f64 {
        self.lobe_angle_sum / self.lobe_samples as f64
    }
}

/// MCPG direct-illumination guiding on a grid of shading points of the toy scene: the reference
/// renderer loop of the tests, the demo and the examples. Read
/// [`McpgToyRenderer::render_frame`] for the order of the steps.
#[derive(Clone, Debug)]
pub struct McpgToyRenderer {
    config: McpgToyConfig,
    grids: GridEnsemble,
    frame: u32,
}

impl McpgToyRenderer {
    /// A renderer with empty grids.
    ///
    /// # Panics
    /// When a table capacity is below 8 slots.
    #[must_use]
    pub fn new(config: McpgToyConfig) -> Self {
        let grids = GridEnsemble::new(
            config.adaptive_capacity,
            config.static_capacity,
            config.params.adaptive_probability,
        )
        .expect("table capacities of at least 8 slots");
        Self {
            config,
            grids,
            frame: 0,
        }
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &McpgToyConfig {
        &self.config
    }

    /// The grids (states and tables).
    #[must_use]
    pub const fn grids(&self) -> &GridEnsemble {
        &self.grids
    }

    /// Number of pixels.
    #[must_use]
    pub fn pixel_count(&self) -> usize {
        (self.config.width * self.config.height) as usize
    }

    /// The shading point of row-major pixel `index`.
    #[must_use]
    pub fn shading_point(&self, index: usize) -> Vec3 {
        let x = (index as u32 % self.config.width) as f32;
        let y = (index as u32 / self.config.width) as f32;
        self.config.origin + self.config.pixel_spacing * Vec3::new(x, y, 0.0)
    }

    fn grid_uniforms<R: Rng + ?Sized>(rng: &mut R) -> GridUniforms {
        GridUniforms {
            grid: rng.random(),
            level: rng.random(),
            corner: rng.random(),
        }
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

    /// Renders frame T (its index, starting at 0; one time unit per frame) of `scene`.
    ///
    /// Per sample at shading point x: load N_mc candidates from the grids (Alg. 1, with
    /// velocity prediction, eq. 10) into a [`CandidateSet`]; choose BSDF or lobe (Alg. 2) and
    /// sample ω; trace; estimate f(ω)/p(ω | S) with the candidate set's pdf (eq. 6-7); run the
    /// transition (eq. 8, Alg. 3) with f_mc = that estimate and store the new state at a fresh
    /// vertex; or, after a rejected lobe sample, apply the discard heuristic (sec. 5).
    pub fn render_frame<R: Rng + ?Sized>(&mut self, scene: &ToyScene, rng: &mut R) -> McpgFrame {
        let config = self.config;
        let now = self.frame as f32;
        let n = self.pixel_count();
        let spp = config.samples_per_pixel.max(1);
        let mut frame = McpgFrame {
            estimates: std::vec![0.0; n],
            ..McpgFrame::default()
        };
        for index in 0..n {
            let x = self.shading_point(index);
            for _ in 0..spp {
                frame.samples += 1;
                let u_dir = Vec2::new(rng.random(), rng.random());
                if !config.guided {
                    let (w, pdf) = cosine_hemisphere(TOY_NORMAL, u_dir);
                    let value = scene.trace(x, w).radiance * TOY_NORMAL.dot(w).max(0.0);
                    if pdf > 0.0 {
                        frame.estimates[index] += value / pdf / spp as f32;
                    }
                    continue;
                }
                self.guided_sample(scene, x, index, u_dir, now, rng, &mut frame);
            }
        }
        self.frame += 1;
        frame
    }

    /// Alg. 1: grid resampling of `candidates` states at x into a candidate set, with the
    /// grid slot each came from.
    fn load_candidates<R: Rng + ?Sized>(
        &self,
        x: Vec3,
        now: f32,
        candidates: usize,
        rng: &mut R,
    ) -> (
        CandidateSet<MAX_CANDIDATES>,
        [Option<GridSlot>; MAX_CANDIDATES],
    ) {
        let config = self.config;
        let params = config.params;
        let mut set = CandidateSet::<MAX_CANDIDATES>::new();
        let mut slots: [Option<GridSlot>; MAX_CANDIDATES] = [None; MAX_CANDIDATES];
        for slot in slots.iter_mut().take(candidates) {
            let u = Self::grid_uniforms(rng);
            let (state, collided, grid, found) = self.grids.load(x, TOY_NORMAL, config.camera, &u);
            let predict_to = if config.velocity_prediction {
                now
            } else {
                state.time
            };
            let candidate = prepare_candidate(
                state,
                collided,
                grid,
                x,
                Some(TOY_NORMAL),
                predict_to,
                &params,
            );
            set.offer(candidate, rng.random());
            *slot = found;
        }
        (set, slots)
    }

    /// One guided sample at x (pixel `index`): Alg. 1 (candidates), Alg. 2 (sampling and
    /// tracing), eq. 6-7 (the estimate, added to the pixel's), Alg. 3 (transition or discard).
    #[allow(clippy::too_many_arguments)]
    fn guided_sample<R: Rng + ?Sized>(
        &mut self,
        scene: &ToyScene,
        x: Vec3,
        index: usize,
        u_dir: Vec2,
        now: f32,
        rng: &mut R,
        frame: &mut McpgFrame,
    ) {
        let config = self.config;
        let params = config.params;
        let spp = config.samples_per_pixel.max(1);
        let candidates = (params.candidates as usize).clamp(1, MAX_CANDIDATES);
        let (set, slots) = self.load_candidates(x, now, candidates, rng);
        // Alg. 2: sampling and tracing.
        let (choice, state) = choose_technique(set.selected(), x, rng.random(), &params);
        let w = match choice {
            SampleChoice::Bsdf => cosine_hemisphere(TOY_NORMAL, u_dir).0,
            SampleChoice::Lobe(lobe) => {
                frame.lobe_samples += 1;
                if let Some(light) = scene
                    .lights
                    .iter()
                    .min_by(|a, b| a.center.distance(x).total_cmp(&b.center.distance(x)))
                {
                    let to_light = (light.center - x).normalize();
                    frame.lobe_angle_sum += lobe.mu().dot(to_light).clamp(-1.0, 1.0).acos() as f64;
                }
                lobe.sample(u_dir)
            }
        };
        let hit = scene.trace(x, w);
        let value = hit.radiance * TOY_NORMAL.dot(w).max(0.0);
        // Eq. 6-7: the estimator over the accessed states (a one-vertex path).
        let technique = CosineVertexTechnique::new(&set, x, TOY_NORMAL, &params);
        let estimate = path_estimate(value, &[&[technique]], &[w]);
        frame.estimates[index] += estimate / spp as f32;
        // Alg. 3: transition, or discard.
        let observation = Observation {
            x,
            next: hit.point,
            next_previous: hit.point - hit.velocity,
            estimate,
            now,
            frame_time: 1.0,
        };
        match update(
            &state,
            set.mean_weight(),
            &observation,
            rng.random(),
            &params,
        ) {
            Some(new) => {
                let u = Self::grid_uniforms(rng);
                self.grids.store(x, TOY_NORMAL, config.camera, &u, new);
            }
            None => {
                if config.discard
                    && matches!(choice, SampleChoice::Lobe(_))
                    && should_discard(&state, x, w, estimate, now, &params)
                    && let Some(slot) = set.selected_index().and_then(|i| slots[i])
                {
                    self.grids.discard(slot);
                }
            }
        }
    }
}
