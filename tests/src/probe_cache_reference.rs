//! The end-to-end experiment of mcg-probe-cache: ADGI's adaptive probe updates against DDGI's
//! uniform rays per probe, at an equal ray budget per frame, on the two-room scene whose door
//! slides open ([`DynamicScene::door_opens`]: a lit 8 m room and a dark 0.9 m closet).
//!
//! One definition for the suite `tests/probe_cache_adgi.rs` and the demo's probe-cache
//! section. Everything is deterministic: light samples, ray directions, chains and rounding
//! draw from one [`seeded_rng`] per run (and the pilot rays from a counter hash).
//!
//! # The policies
//! The per-frame update is `mcg_probe_cache`'s [`ProbeUpdater`] with [`UpdateConfig::DEFAULT`]
//! (its docs give every rule and constant): [`UpdatePolicy::Ddgi`] (Q-DDGI of ADGI sec. 5:
//! uniform rotated rays, cosine-weighted blend, hysteresis 16/17), [`UpdatePolicy::Adgi`]
//! (pilot rays, heuristics with f_c = 1 — the camera sees the whole grid —, dynamic chains on
//! the proxies, static chains) and [`UpdatePolicy::AdgiUnguided`] (ADGI with constant
//! guides). This file owns the fixture scene, traces the updater's ray batches in it, and
//! measures the error.
//!
//! # Our choices where the paper is silent or its scale differs
//! Besides the updater's defaults: the closet's size (the event must be local for adaptive
//! sampling to have something to concentrate on: 74 of the 576 probes are near it), and the
//! warm start ([`WARM_START_RAYS_PER_TEXEL`]).
//!
//! # Equal budget
//! A frame of every policy traces at most `rays_per_probe × probe count` probe rays (each
//! also traces one shadow ray at its hit, for all policies alike). ADGI spends 8 per probe on
//! pilots, up to [`UpdateConfig::dynamic_share`] of the rest on dynamic samples, and the
//! remainder on static samples, cutting the last sample list at the budget.
//!
//! # Error
//! Each probe's irradiance E(p, n) is read back at the centre direction n of each interior
//! irradiance texel with [`ProbeTexels::probe_irradiance`] — π × the texel for DDGI's texels
//! (they hold E/π), the normalised cosine convolution over the texels for ADGI's (they hold
//! mean radiance per texel, which costs a discretisation floor of ≈ 0.10 relative error on the
//! 6 × 6 map of this scene, [`Experiment::radiance_texel_floor`]) — and compared with [`reference_irradiance`] for the scene of that frame. The
//! error of a set of probes is the relative RMS error √(Σ |E − E_ref|² / Σ |E_ref|²) over
//! their texels.

use glam::{UVec2, Vec2, Vec3};
use mcg_probe_cache::heuristics::OCTANTS;
use mcg_probe_cache::{
    DynamicScene, ProbeTexels, ProbeUpdater, TexelConfig, TexelContent, UpdateConfig, UpdatePolicy,
    reference_irradiance,
};
use rand::RngExt;

use crate::seeded_rng;

/// The threshold of the frames-to-error numbers: relative RMS error of the probes near the
/// event. Above both policies' errors before the event (≈ 0.14 for uniform DDGI, ≈ 0.19 for
/// ADGI in [`ExperimentConfig::TEST`]), so it measures the recovery from the event.
pub const FRAMES_TO_ERROR_THRESHOLD: f64 = 0.3;

/// Settings of one experiment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExperimentConfig {
    /// Frames per run.
    pub frames: u32,
    /// The first frame of the door's movement.
    pub event_frame: u32,
    /// Frames the door takes to open.
    pub transition_frames: u32,
    /// DDGI's rays per probe per frame; every policy traces this × the probe count per frame.
    pub rays_per_probe: u32,
    /// The reference traces `strata²` rays per texel direction.
    pub reference_strata: u32,
    /// Probes within this distance of the doorway (or in the closet) are "near the event".
    pub near_radius: f32,
    /// Seed of the runs and of the reference.
    pub seed: u64,
}

impl ExperimentConfig {
    /// The suite's setting: 40 frames, the door opening over frames 16-17, 32 rays per probe
    /// (ADGI sec. 5 gives Q-DDGI 32), 10² rays per reference texel.
    pub const TEST: Self = Self {
        frames: 40,
        event_frame: 16,
        transition_frames: 2,
        rays_per_probe: 32,
        reference_strata: 10,
        near_radius: 1.0,
        seed: 0x8_ad61,
    };
}

/// The scene, its reference, and the probe sets the error is measured on.
#[derive(Clone, Debug)]
pub struct Experiment {
    /// The settings.
    pub config: ExperimentConfig,
    /// The scene.
    pub scene: DynamicScene,
    /// The texels of every run (ADGI's: octahedral 8 × 8 with border, R9G9B8).
    pub texel_config: TexelConfig,
    /// Interior irradiance texels: (stored index, centre direction, solid angle).
    pub texels: Vec<(usize, Vec3, f32)>,
    /// Probes near the event.
    pub near: Vec<usize>,
    /// Reference irradiance per distinct scene state: `(progress, E)` with E indexed
    /// `probe · texels.len() + k`.
    pub references: Vec<(f32, Vec<Vec3>)>,
    /// The converged cache every run starts from (see [`WARM_START_RAYS_PER_TEXEL`]): per probe
    /// and interior texel, DDGI's cosine-weighted mean radiance E/π and ADGI's mean radiance
    /// over the texel.
    pub warm_start: (Vec<Vec3>, Vec<Vec3>),
}

/// The per-frame record of one run.
#[derive(Clone, Debug)]
pub struct Run {
    /// The policy.
    pub policy: UpdatePolicy,
    /// Relative RMS error of the probes near the event, per frame.
    pub error_near: Vec<f64>,
    /// Relative RMS error of all probes, per frame.
    pub error_all: Vec<f64>,
    /// Probe rays traced per frame.
    pub rays: Vec<u64>,
    /// Of them, the rays that started at a probe near the event.
    pub rays_near: Vec<u64>,
    /// Of them, the rays of ADGI's dynamic chains.
    pub rays_dynamic: Vec<u64>,
    /// Probes whose change signal f_d (ADGI eq. 20) is above 0 in some octant, per frame
    /// (0 for DDGI).
    pub changed_probes: Vec<u32>,
    /// Irradiance estimates (indexed like the references) at the frames asked for.
    pub snapshots: Vec<(u32, Vec<Vec3>)>,
}

impl Experiment {
    /// Builds the scene and its references (one per distinct scene state of the run).
    #[must_use]
    pub fn new(config: ExperimentConfig) -> Self {
        let scene = DynamicScene::door_opens(config.event_frame, config.transition_frames);
        let texel_config = TexelConfig::ADGI;
        let map = texel_config.irradiance_map;
        let texels: Vec<(usize, Vec3, f32)> = (0..map.texel_count())
            .filter_map(|i| {
                let t = map.coords(i);
                (!map.is_border(t)).then(|| (i, map.direction(t), map.solid_angle(t)))
            })
            .collect();
        let dirs: Vec<Vec3> = texels.iter().map(|t| t.1).collect();
        let near = scene.probes_near_event(config.near_radius);
        let mut references: Vec<(f32, Vec<Vec3>)> = Vec::new();
        for frame in 0..config.frames {
            let s = scene.progress(frame);
            if references.iter().any(|r| r.0 == s) {
                continue;
            }
            let state = scene.at_frame(frame);
            let e = (0..scene.grid.probe_count())
                .flat_map(|p| {
                    let pos = scene.grid.probe_position(scene.grid.probe_coords(p));
                    reference_irradiance(&state, pos, &dirs, config.reference_strata, config.seed)
                })
                .collect();
            references.push((s, e));
        }
        let warm_start = warm_start(&scene, &texel_config, &texels, config.seed);
        Self {
            config,
            scene,
            texel_config,
            texels,
            near,
            references,
            warm_start,
        }
    }

    /// The reference irradiance at frame `frame` (indexed `probe · texels.len() + k`).
    #[must_use]
    pub fn reference(&self, frame: u32) -> &[Vec3] {
        let s = self.scene.progress(frame);
        &self
            .references
            .iter()
            .find(|r| r.0 == s)
            .expect("a reference per scene state")
            .1
    }

    /// Runs `policy` for all frames and records errors, ray counts and the snapshots at
    /// `snapshot_frames`.
    #[must_use]
    pub fn run(&self, policy: UpdatePolicy, snapshot_frames: &[u32]) -> Run {
        self.run_with_seed(policy, self.config.seed, snapshot_frames)
    }

    /// [`Self::run`] with the run's random numbers (rays, chains, rounding, pilot directions)
    /// drawn from `seed` instead of the config's; the scene, reference and warm start stay.
    #[must_use]
    pub fn run_with_seed(&self, policy: UpdatePolicy, seed: u64, snapshot_frames: &[u32]) -> Run {
        self.run_with_config(policy, seed, self.update_config(seed), snapshot_frames)
    }

    /// [`Self::run_with_seed`] with the updater's settings given instead of
    /// [`Self::update_config`] (for ablations of one setting).
    #[must_use]
    pub fn run_with_config(
        &self,
        policy: UpdatePolicy,
        seed: u64,
        config: UpdateConfig,
        snapshot_frames: &[u32],
    ) -> Run {
        let mut rng = seeded_rng(seed ^ (policy_code(policy) * 0x9e37_79b9));
        let grid = self.scene.grid;
        let mut updater = ProbeUpdater::new(grid, policy, config, || rng.random::<f32>())
            .expect("valid update settings");
        let values = match policy.content() {
            TexelContent::Irradiance => &self.warm_start.0,
            TexelContent::Radiance => &self.warm_start.1,
        };
        updater.warm_start(values).expect("one value per texel");
        let mut run = Run {
            policy,
            error_near: Vec::new(),
            error_all: Vec::new(),
            rays: Vec::new(),
            rays_near: Vec::new(),
            rays_dynamic: Vec::new(),
            changed_probes: Vec::new(),
            snapshots: Vec::new(),
        };
        let mut near_mask = vec![false; grid.probe_count()];
        for &p in &self.near {
            near_mask[p] = true;
        }
        for frame in 0..self.config.frames {
            let scene = self.scene.at_frame(frame);
            let mut rays_near = 0_u64;
            let rays = updater.frame(
                u64::from(frame),
                grid.origin(),
                || rng.random::<f32>(),
                |requests, samples| {
                    for (r, s) in requests.iter().zip(samples) {
                        let hit = scene.trace_probe_ray(r.origin, r.direction, r.u);
                        s.radiance = hit.radiance;
                        s.distance = hit.distance;
                        rays_near += u64::from(near_mask[r.probe as usize]);
                    }
                },
            );
            run.rays.push(rays.rays);
            run.rays_near.push(rays_near);
            run.rays_dynamic.push(rays.rays_dynamic);
            run.changed_probes
                .push(updater.heuristics().map_or(0, |(_, f_d)| {
                    f_d.chunks(OCTANTS)
                        .filter(|o| o.iter().any(|&d| d > 0.0))
                        .count() as u32
                }));
            let estimate = self.estimate(updater.texels(), updater.content());
            let reference = self.reference(frame);
            run.error_near
                .push(self.relative_rms(&estimate, reference, self.near.iter().copied()));
            run.error_all
                .push(self.relative_rms(&estimate, reference, 0..grid.probe_count()));
            if snapshot_frames.contains(&frame) {
                run.snapshots.push((frame, estimate));
            }
        }
        run
    }

    /// The updater's settings of a run: [`UpdateConfig::DEFAULT`] with this experiment's
    /// budget, the run seed for the pilot directions, and no camera falloff (f_c = 1: the
    /// camera sees the whole grid).
    #[must_use]
    pub fn update_config(&self, seed: u64) -> UpdateConfig {
        let mut config = UpdateConfig::DEFAULT;
        config.rays_per_probe = self.config.rays_per_probe;
        config.texels = self.texel_config;
        config.pilot_seed = seed;
        config
    }

    /// Every probe's irradiance at its interior texel directions, from the texels
    /// ([`ProbeTexels::probe_irradiance`]).
    #[must_use]
    pub fn estimate(&self, texels: &ProbeTexels, content: TexelContent) -> Vec<Vec3> {
        (0..self.scene.grid.probe_count())
            .flat_map(|p| {
                self.texels
                    .iter()
                    .map(move |&(_, dir, _)| texels.probe_irradiance(p, dir, content))
            })
            .collect()
    }

    /// The discretisation floor of radiance texels ([`TexelContent::Radiance`], ADGI's
    /// content) at frame `frame`: the relative RMS error (all probes, near probes) of the
    /// irradiance from texels that hold the exact mean radiance over each texel, estimated
    /// with `strata²` jittered rays per texel. No sampling policy can get below it (up to the
    /// noise of those means); DDGI's texels (E/π at the centre direction) have no such floor.
    #[must_use]
    pub fn radiance_texel_floor(&self, frame: u32, strata: u32) -> (f64, f64) {
        let mut rng = seeded_rng(self.config.seed ^ 0x0f1e_2d3c);
        let scene = self.scene.at_frame(frame);
        let grid = self.scene.grid;
        let map = self.texel_config.irradiance_map;
        let texels = ProbeTexels::new(grid, self.texel_config);
        let full = self.texel_config.moving_average.max_count();
        for p in 0..grid.probe_count() {
            let pos = grid.probe_position(grid.probe_coords(p));
            for &(index, _, _) in &self.texels {
                let t = map.coords(index) - UVec2::ONE;
                let mut sum = Vec3::ZERO;
                for i in 0..strata * strata {
                    let cell = Vec2::new((i % strata) as f32, (i / strata) as f32);
                    let jitter = Vec2::new(rng.random(), rng.random());
                    let uv = (t.as_vec2() + (cell + jitter) / strata as f32)
                        * (2.0 / map.interior() as f32)
                        - Vec2::ONE;
                    let u = Vec2::new(rng.random(), rng.random());
                    sum += scene.trace_probe_ray(pos, map.decode(uv), u).radiance;
                }
                texels.set_irradiance(p, index, sum / (strata * strata) as f32, full);
            }
        }
        let estimate = self.estimate(&texels, TexelContent::Radiance);
        let reference = self.reference(frame);
        (
            self.relative_rms(&estimate, reference, 0..grid.probe_count()),
            self.relative_rms(&estimate, reference, self.near.iter().copied()),
        )
    }

    /// √(Σ |E − E_ref|² / Σ |E_ref|²) over the texels of `probes`.
    #[must_use]
    pub fn relative_rms(
        &self,
        estimate: &[Vec3],
        reference: &[Vec3],
        probes: impl Iterator<Item = usize>,
    ) -> f64 {
        let n = self.texels.len();
        let (mut num, mut den) = (0.0_f64, 0.0_f64);
        for p in probes {
            for k in p * n..(p + 1) * n {
                num += f64::from((estimate[k] - reference[k]).length_squared());
                den += f64::from(reference[k].length_squared());
            }
        }
        if den > 0.0 { (num / den).sqrt() } else { 0.0 }
    }
}

/// Rays per interior texel of the warm start: every run starts from a converged cache of the
/// scene before the event, built from this many rays per texel of every probe (uniform in the
/// texel's square), so that the comparison measures the response to the event and each
/// policy's own steady state, not how fast an empty cache fills (ADGI's per-sample texels, at
/// under one sample per texel and frame, take about a hundred frames to fill their N_max = 63
/// window; DDGI's blend fills its 17 in 17 frames). DDGI's texels get the cosine-weighted mean
/// of all the probe's rays with count 17, ADGI's the mean of the texel's own rays with count
/// 63. The visibility texels start empty (no error here reads them).
pub const WARM_START_RAYS_PER_TEXEL: u32 = 32;

fn warm_start(
    scene: &DynamicScene,
    config: &TexelConfig,
    texels: &[(usize, Vec3, f32)],
    seed: u64,
) -> (Vec<Vec3>, Vec<Vec3>) {
    let mut rng = seeded_rng(seed ^ 0x3a27_1d5f);
    let state = scene.at_frame(0);
    let map = config.irradiance_map;
    let grid = scene.grid;
    let mut ddgi = Vec::with_capacity(grid.probe_count() * texels.len());
    let mut adgi = Vec::with_capacity(grid.probe_count() * texels.len());
    // (direction, radiance, weight): rays uniform per texel square are not uniform in solid
    // angle, so each is weighted by its texel's solid angle over the texels' mean.
    let mut rays: Vec<(Vec3, Vec3, f32)> = Vec::new();
    for p in 0..grid.probe_count() {
        let pos = grid.probe_position(grid.probe_coords(p));
        rays.clear();
        for &(index, _, omega) in texels {
            let t = map.coords(index) - UVec2::ONE;
            let weight = omega / map.mean_solid_angle();
            let mut sum = Vec3::ZERO;
            for _ in 0..WARM_START_RAYS_PER_TEXEL {
                let uv = (t.as_vec2() + Vec2::new(rng.random(), rng.random()))
                    * (2.0 / map.interior() as f32)
                    - Vec2::ONE;
                let d = map.decode(uv);
                let l = state
                    .trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random()))
                    .radiance;
                sum += l;
                rays.push((d, l, weight));
            }
            adgi.push(sum / WARM_START_RAYS_PER_TEXEL as f32);
        }
        for &(_, n, _) in texels {
            let (mut num, mut den) = (Vec3::ZERO, 0.0_f32);
            for &(d, l, weight) in &rays {
                let w = n.dot(d).max(0.0) * weight;
                num += w * l;
                den += w;
            }
            ddgi.push(if den > 0.0 { num / den } else { Vec3::ZERO });
        }
    }
    (ddgi, adgi)
}

/// Frames from `from` until the error settles below `threshold`: the smallest k such that
/// `errors[from + j] < threshold` for every j ≥ k; `None` if the last frame is not below.
#[must_use]
pub fn frames_to_error(errors: &[f64], from: u32, threshold: f64) -> Option<u32> {
    let from = from as usize;
    // `e >= threshold` or NaN: not below.
    let above = |e: f64| e.partial_cmp(&threshold) != Some(core::cmp::Ordering::Less);
    if from >= errors.len() || above(errors[errors.len() - 1]) {
        return None;
    }
    let last_above = errors[from..].iter().rposition(|&e| above(e));
    Some(last_above.map_or(0, |i| i as u32 + 1))
}

/// Frames from `from` until the error first drops below `threshold` (0 if `errors[from]` is
/// already below); `None` if it never does.
#[must_use]
pub fn frames_to_first_below(errors: &[f64], from: u32, threshold: f64) -> Option<u32> {
    errors
        .get(from as usize..)?
        .iter()
        .position(|&e| e < threshold)
        .map(|i| i as u32)
}

/// Mean of `errors[from..to]`.
#[must_use]
pub fn mean_error(errors: &[f64], from: u32, to: u32) -> f64 {
    let s = &errors[from as usize..to as usize];
    s.iter().sum::<f64>() / s.len() as f64
}

/// A stable number per policy for the run's seed (the order the experiment has always used).
fn policy_code(policy: UpdatePolicy) -> u64 {
    match policy {
        UpdatePolicy::Ddgi => 0,
        UpdatePolicy::Adgi => 1,
        UpdatePolicy::AdgiUnguided => 2,
        UpdatePolicy::AdgiBlend => 4,
        _ => 3,
    }
}
