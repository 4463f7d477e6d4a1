//! The end-to-end experiment of mcg-probe-cache: ADGI's adaptive probe updates against DDGI's
//! uniform rays per probe, at an equal ray budget per frame, on the two-room scene whose door
//! slides open ([`DynamicScene::door_opens`]: a lit 8 m room and a dark 0.9 m closet).
//!
//! One definition for the suite `tests/probe_cache_adgi.rs` and the demo's probe-cache
//! section. Everything is deterministic: light samples, ray directions, chains and rounding
//! draw from one [`seeded_rng`] per run (and the pilot rays from a counter hash).
//!
//! # The policies (ADGI sec. 5 compares the same two)
//! - [`Policy::UniformDdgi`] (Q-DDGI of ADGI sec. 5): every probe traces `rays_per_probe`
//!   rays per frame along a randomly rotated spherical Fibonacci set (DDGI), blended into all
//!   its texels with DDGI's cosine weights ([`ProbeTexels::blend_rays`]) and hysteresis
//!   16/17 ≈ 0.94 (Q-DDGI's, ADGI Table 3).
//! - [`Policy::Adgi`], built from this crate's pieces: per frame, 8 pilot rays per probe
//!   ([`pilot_rays`], one per octant, the same rays on both frames of a pair, sec. 4.4; the
//!   first frame of a pair also updates the caches) give f_v and f_r (eq. 11, 12); a
//!   [`ChangeDetector`] turns their change between the two frames into f_Δv, f_Δr (eq. 13-18),
//!   composed with f_c = 1 (the camera sees the whole grid) into the 6-10-10 heuristics words
//!   (eq. 19-20, sec. 4.3). Dynamic Metropolis chains on the 3 × 3 × 3 proxies sample f_d
//!   (sec. 4.9); each sample traces [`DYNAMIC_RAYS_PER_OCTANT`] rays into its octant for every
//!   probe of the proxy, each updating its texel with the dynamic N_max = 10 (Table 3). Static chains
//!   sample h = exp(min(ĝ/f_s, 1)) f_s (sec. 4.8) with the rest of the budget. Every ray
//!   updates the one texel it lands in ([`ProbeTexels::update_sample`], N_max = 63).
//! - [`Policy::AdgiUnguided`]: ADGI with both guides replaced by a constant — the same
//!   machinery, budget and update rules, but the samples spread uniformly over (p, ω). It
//!   isolates what the guide buys.
//!
//! # Our choices where the paper is silent or its scale differs
//! Chosen while building the experiment (and kept fixed for every policy): the trigger decay
//! [`TRIGGER_DECAY`], the smoothing radius [`SMOOTHING_RADIUS`] (scaled to the small grid),
//! [`DYNAMIC_RAYS_PER_OCTANT`] jittered within the texels, [`DYNAMIC_CHAINS`],
//! [`DYNAMIC_SHARE`], the closet's size (the event must be local for adaptive sampling to have
//! something to concentrate on: 74 of the 576 probes are near it), and the warm start
//! ([`WARM_START_RAYS_PER_TEXEL`]).
//!
//! # Equal budget
//! A frame of every policy traces at most `rays_per_probe × probe count` probe rays (each
//! also traces one shadow ray at its hit, for all policies alike). ADGI spends 8 per probe on
//! pilots, up to [`DYNAMIC_SHARE`] of the rest on dynamic samples, and the remainder on static
//! samples, cutting the last sample list at the budget.
//!
//! # Error
//! Each probe's irradiance E(p, n) is read back at the centre direction n of each interior
//! irradiance texel with [`ProbeTexels::probe_irradiance`] — π × the texel for DDGI's texels
//! (they hold E/π), the normalised cosine convolution over the texels for ADGI's (they hold
//! mean radiance per texel, which costs a discretisation floor of ≈ 0.07 relative error on the
//! 6 × 6 map) — and compared with [`reference_irradiance`] for the scene of that frame. The
//! error of a set of probes is the relative RMS error √(Σ |E − E_ref|² / Σ |E_ref|²) over
//! their texels.

use glam::{Quat, UVec2, Vec2, Vec3};
use mcg_probe_cache::guiding_function::{decode_field, octant_feedback};
use mcg_probe_cache::heuristics::{self, OCTANTS, octant};
use mcg_probe_cache::mcg_color_codec::HeuristicsWord;
use mcg_probe_cache::mcg_color_codec::MovingAverage;
use mcg_probe_cache::pilot_rays::{PilotHit, octant_heuristics, pilot_rays};
use mcg_probe_cache::reference::hash_uniform;
use mcg_probe_cache::scene::{ProbeRay, Scene};
use mcg_probe_cache::temporal_gradient::{ChangeDetector, SmoothingKernel, TemporalTrigger};
use mcg_probe_cache::{
    BlendWeights, DynamicScene, GuideParams, GuidingFunction, HeuristicParams, ProbeChains,
    ProbeStepUniforms, ProbeTexels, ProxyGrid, RaySample, TexelConfig, TexelContent,
    reference_irradiance,
};
use mcg_probe_cache::{HeuristicField, PilotFrame, PilotSchedule};
use rand::RngExt;

use crate::{Pcg64Mcg, seeded_rng};

/// Share of the non-pilot budget ADGI may spend on dynamic samples in a frame.
pub const DYNAMIC_SHARE: f32 = 0.75;

/// Rays per probe octant of one dynamic sample (ADGI sec. 4.9: "we trace 64 rays for the
/// octant for all underlying 3x3x3 probes"), spread evenly over the octant's irradiance texels
/// (about 4.5 interior texels of the 6 × 6 map) and uniform within each texel's square. The
/// paper sends them through texel centres; this crate's per-sample texels hold the mean
/// radiance over the texel, which a centre ray does not estimate (we measured a near-event
/// error of 0.7 against 0.4 with centre rays).
pub const DYNAMIC_RAYS_PER_OCTANT: u32 = 64;

/// Dynamic chains (ADGI runs 1024 dynamic chains next to 4096 static ones, sec. 5; here the
/// static chains are sized to the budget, about 2500).
pub const DYNAMIC_CHAINS: usize = 64;

/// Q-DDGI's hysteresis 0.94 (ADGI Table 3) as a counted moving average: N_max = 17 gives
/// 16/17 ≈ 0.941.
pub const QDDGI_MAX_COUNT: u32 = 17;

/// The threshold of the frames-to-error numbers: relative RMS error of the probes near the
/// event. Above both policies' errors before the event (≈ 0.14 for uniform DDGI, ≈ 0.19 for
/// ADGI in [`ExperimentConfig::TEST`]), so it measures the recovery from the event.
pub const FRAMES_TO_ERROR_THRESHOLD: f64 = 0.3;

/// Half-width of the spatial smoothing of the temporal gradients, in probes: 1 gives a
/// 3 × 3 × 3 kernel. ADGI uses 5 × 5 × 5 on grids of 192 × 64 × 192 probes (sec. 4.1.4,
/// Table 2); on this 18 × 4 × 8 grid that kernel would spread a change over half the grid.
pub const SMOOTHING_RADIUS: u32 = 1;

/// The decay θ per detection (every second frame) of the temporal trigger Tr (ADGI eq. 14,
/// Fig. 6a; the paper gives no value). 0.5 ends a dynamic phase within about ten frames.
pub const TRIGGER_DECAY: f32 = 0.5;

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

/// How the rays of a frame are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Policy {
    /// DDGI: the same rays for every probe, cosine-weighted blend, hysteresis 0.94.
    UniformDdgi,
    /// ADGI: pilot rays, guided static and dynamic chains, per-sample updates.
    Adgi,
    /// ADGI with constant guides (the ablation that isolates the guide).
    AdgiUnguided,
}

impl Policy {
    /// A short label for tables and charts.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Policy::UniformDdgi => "uniform DDGI (hysteresis 0.94)",
            Policy::Adgi => "ADGI (guided chains)",
            Policy::AdgiUnguided => "ADGI, constant guide",
        }
    }
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
    pub policy: Policy,
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
    pub fn run(&self, policy: Policy, snapshot_frames: &[u32]) -> Run {
        self.run_with_seed(policy, self.config.seed, snapshot_frames)
    }

    /// [`Self::run`] with the run's random numbers (rays, chains, rounding, pilot directions)
    /// drawn from `seed` instead of the config's; the scene, reference and warm start stay.
    #[must_use]
    pub fn run_with_seed(&self, policy: Policy, seed: u64, snapshot_frames: &[u32]) -> Run {
        let mut rng = seeded_rng(seed ^ (policy as u64 * 0x9e37_79b9));
        let mut state = match policy {
            Policy::UniformDdgi => Renderer::ddgi(self),
            Policy::Adgi | Policy::AdgiUnguided => {
                Renderer::adgi(self, policy == Policy::Adgi, &mut rng)
            }
        };
        let (values, count) = match policy {
            Policy::UniformDdgi => (&self.warm_start.0, QDDGI_MAX_COUNT),
            _ => (&self.warm_start.1, MovingAverage::STATIC.max_count()),
        };
        let n = self.texels.len();
        for p in 0..self.scene.grid.probe_count() {
            for (k, &(index, _, _)) in self.texels.iter().enumerate() {
                state
                    .texels
                    .set_irradiance(p, index, values[p * n + k], count);
            }
        }
        let mut run = Run {
            policy,
            error_near: Vec::new(),
            error_all: Vec::new(),
            rays: Vec::new(),
            rays_near: Vec::new(),
            rays_dynamic: Vec::new(),
            snapshots: Vec::new(),
        };
        let near_mask = {
            let mut m = vec![false; self.scene.grid.probe_count()];
            for &p in &self.near {
                m[p] = true;
            }
            m
        };
        state.seed = seed;
        for frame in 0..self.config.frames {
            let scene = self.scene.at_frame(frame);
            let counter = state.frame(self, &scene, frame, &near_mask, &mut rng);
            run.rays.push(counter.rays);
            run.rays_near.push(counter.rays_near);
            run.rays_dynamic.push(counter.rays_dynamic);
            let estimate = self.estimate(&state.texels, state.content);
            let reference = self.reference(frame);
            run.error_near
                .push(self.relative_rms(&estimate, reference, self.near.iter().copied()));
            run.error_all.push(self.relative_rms(
                &estimate,
                reference,
                0..self.scene.grid.probe_count(),
            ));
            if snapshot_frames.contains(&frame) {
                run.snapshots.push((frame, estimate));
            }
        }
        run
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

#[derive(Clone, Copy, Debug, Default)]
struct RayCounter {
    rays: u64,
    rays_near: u64,
    rays_dynamic: u64,
}

impl RayCounter {
    /// Counts `rays` rays of a probe, near the event or not.
    fn count(&mut self, rays: u64, near: bool) {
        self.rays += rays;
        if near {
            self.rays_near += rays;
        }
    }
}

/// The per-sample update of a probe ray's result.
fn ray_sample(direction: Vec3, hit: &ProbeRay) -> RaySample {
    RaySample {
        direction,
        radiance: hit.radiance,
        distance: hit.distance,
    }
}

/// The state of one policy across frames.
struct Renderer {
    seed: u64,
    texels: ProbeTexels,
    content: TexelContent,
    adgi: Option<AdgiState>,
}

struct AdgiState {
    guided: bool,
    params: HeuristicParams,
    static_chains: ProbeChains,
    dynamic_chains: ProbeChains,
    detector: ChangeDetector,
    /// f_v and f_r per probe octant from this frame's pilot rays.
    f_v: Vec<f32>,
    f_r: Vec<f32>,
    /// The heuristics words (sec. 4.3) and the fields the chains read from them.
    words: Vec<HeuristicsWord>,
    f_s: Vec<f32>,
    f_d: Vec<f32>,
    proxy_f_d: Vec<f32>,
    feedback: Vec<f32>,
    /// For each octant, the interior irradiance texels whose centre lies in it.
    octant_texels: Vec<Vec<(usize, Vec3)>>,
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

fn step_uniforms(rng: &mut Pcg64Mcg) -> ProbeStepUniforms {
    ProbeStepUniforms {
        proposal: core::array::from_fn(|_| rng.random()),
        accept: rng.random(),
    }
}

/// The i-th of n spherical Fibonacci directions (DDGI's ray set before its random rotation).
fn spherical_fibonacci(i: u32, n: u32) -> Vec3 {
    const GOLDEN: f32 = 0.618_034;
    let phi = core::f32::consts::TAU * ((i as f32 * GOLDEN).fract());
    let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

impl Renderer {
    fn ddgi(exp: &Experiment) -> Self {
        let mut config = exp.texel_config;
        config.moving_average = MovingAverage::new(QDDGI_MAX_COUNT).expect("N_max > 0");
        Self {
            seed: exp.config.seed,
            texels: ProbeTexels::new(exp.scene.grid, config),
            content: TexelContent::Irradiance,
            adgi: None,
        }
    }

    fn adgi(exp: &Experiment, guided: bool, rng: &mut Pcg64Mcg) -> Self {
        let grid = exp.scene.grid;
        let n = grid.probe_count() * OCTANTS;
        let budget = (exp.config.rays_per_probe as usize) * grid.probe_count();
        let static_rays = budget.saturating_sub(OCTANTS * grid.probe_count());
        let schedule = mcg_markov_guide::FrameSchedule::DEFAULT;
        let per_chain = (schedule.iterations() - schedule.burn_in()) as usize;
        let mut init = || core::array::from_fn(|_| rng.random::<f32>());
        let static_chains =
            ProbeChains::new_static(grid, static_rays.div_ceil(per_chain).max(1), &mut init)
                .expect("valid chains");
        let dynamic_chains =
            ProbeChains::new_dynamic(grid, DYNAMIC_CHAINS, &mut init).expect("valid chains");
        let proxies = dynamic_chains.cells().table_len();
        let mut octant_texels = vec![Vec::new(); OCTANTS];
        for &(i, d, _) in &exp.texels {
            octant_texels[octant(d)].push((i, d));
        }
        Self {
            seed: exp.config.seed,
            texels: ProbeTexels::new(grid, exp.texel_config),
            content: TexelContent::Radiance,
            adgi: Some(AdgiState {
                guided,
                params: HeuristicParams::new(1.0e3, grid.cell_diagonal())
                    .expect("valid heuristics"),
                static_chains,
                dynamic_chains,
                detector: ChangeDetector::new(
                    grid,
                    TemporalTrigger::new(TRIGGER_DECAY).expect("decay in [0, 1)"),
                    SmoothingKernel {
                        spatial_radius: SMOOTHING_RADIUS,
                        directional: true,
                    },
                ),
                f_v: vec![0.0; n],
                f_r: vec![0.0; n],
                words: vec![HeuristicsWord(0); n],
                f_s: vec![0.0; n],
                f_d: vec![0.0; n],
                proxy_f_d: vec![0.0; proxies],
                feedback: vec![0.0; n],
                octant_texels,
            }),
        }
    }

    fn frame(
        &mut self,
        exp: &Experiment,
        scene: &Scene,
        frame: u32,
        near: &[bool],
        rng: &mut Pcg64Mcg,
    ) -> RayCounter {
        match self.adgi.take() {
            None => self.ddgi_frame(exp, scene, near, rng),
            Some(mut adgi) => {
                let c = self.adgi_frame(&mut adgi, exp, scene, frame, near, rng);
                self.adgi = Some(adgi);
                c
            }
        }
    }

    fn ddgi_frame(
        &mut self,
        exp: &Experiment,
        scene: &Scene,
        near: &[bool],
        rng: &mut Pcg64Mcg,
    ) -> RayCounter {
        let grid = exp.scene.grid;
        let r = exp.config.rays_per_probe;
        // One random rotation per frame for all probes (DDGI).
        let rotation = Quat::from_xyzw(
            rng.random::<f32>() - 0.5,
            rng.random::<f32>() - 0.5,
            rng.random::<f32>() - 0.5,
            rng.random::<f32>() - 0.5,
        )
        .normalize();
        let dirs: Vec<Vec3> = (0..r)
            .map(|i| rotation * spherical_fibonacci(i, r))
            .collect();
        let mut counter = RayCounter::default();
        let mut rays = Vec::with_capacity(r as usize);
        for (p, &is_near) in near.iter().enumerate().take(grid.probe_count()) {
            let pos = grid.probe_position(grid.probe_coords(p));
            rays.clear();
            for &d in &dirs {
                let hit = scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random()));
                rays.push(RaySample {
                    direction: d,
                    radiance: hit.radiance,
                    distance: hit.distance,
                });
            }
            self.texels
                .blend_rays(p, &rays, &BlendWeights::DDGI, rng.random());
            counter.count(u64::from(r), is_near);
        }
        counter
    }

    /// One ADGI frame: pilot rays, heuristics, dynamic chains, static chains (in this order,
    /// so the random stream is consumed as one sequence).
    #[allow(clippy::too_many_arguments)]
    fn adgi_frame(
        &mut self,
        a: &mut AdgiState,
        exp: &Experiment,
        scene: &Scene,
        frame: u32,
        near: &[bool],
        rng: &mut Pcg64Mcg,
    ) -> RayCounter {
        let budget = u64::from(exp.config.rays_per_probe) * exp.scene.grid.probe_count() as u64;
        let mut counter = RayCounter::default();
        let pilot = self.adgi_pilot_rays(a, exp, scene, frame, near, rng, &mut counter);
        compose_adgi_heuristics(a, exp, pilot);
        let f = AdgiFrame {
            exp,
            scene,
            near,
            budget,
        };
        self.adgi_dynamic_chains(a, f, rng, &mut counter);
        self.adgi_static_chains(a, f, rng, &mut counter);
        counter
    }

    /// 1. Pilot rays (sec. 4.4): one per octant, the same set on the two frames of a pair
    ///    (direction and light-sample uniforms hashed from the pattern index), so the
    ///    difference between the two frames is the scene's change, not noise. The first
    ///    frame of a pair also updates the caches. Fills `a.f_v` and `a.f_r`.
    #[allow(clippy::too_many_arguments)]
    fn adgi_pilot_rays(
        &mut self,
        a: &mut AdgiState,
        exp: &Experiment,
        scene: &Scene,
        frame: u32,
        near: &[bool],
        rng: &mut Pcg64Mcg,
        counter: &mut RayCounter,
    ) -> PilotFrame {
        let grid = exp.scene.grid;
        let seed = self.seed;
        let pilot = PilotSchedule::ADGI.frame(u64::from(frame));
        let hash = |pattern: u64, probe: usize, o: usize, k: u64| {
            let c = (seed ^ 0x5bd1_e995)
                .wrapping_add(pattern.wrapping_mul(0x9e37_79b9_7f4a_7c15))
                .wrapping_add(((probe * OCTANTS + o) as u64) << 3)
                .wrapping_add(k);
            Vec2::new(hash_uniform(c), hash_uniform(c + 1))
        };
        let mut rays = Vec::with_capacity(grid.probe_count() * OCTANTS);
        pilot_rays(
            &grid,
            pilot,
            |_| true,
            |pat, p, o| hash(pat, p, o, 0),
            |r| {
                rays.push(r);
            },
        );
        let mut hits = [PilotHit {
            distance: 0.0,
            luminance: 0.0,
        }; OCTANTS];
        for ray in &rays {
            let p = ray.probe as usize;
            let o = usize::from(ray.octant);
            let hit =
                scene.trace_probe_ray(ray.origin, ray.direction, hash(pilot.pattern, p, o, 2));
            hits[o] = PilotHit {
                distance: hit.distance,
                luminance: luminance(hit.radiance),
            };
            if pilot.updates_caches() {
                self.texels
                    .update_sample(p, &ray_sample(ray.direction, &hit), rng.random());
            }
            counter.count(1, near[p]);
            if o == OCTANTS - 1 {
                let (f_v, f_r) = octant_heuristics(&hits, &a.params);
                a.f_v[p * OCTANTS..][..OCTANTS].copy_from_slice(&f_v);
                a.f_r[p * OCTANTS..][..OCTANTS].copy_from_slice(&f_r);
            }
        }
        pilot
    }

    /// 3. Dynamic chains on the proxies (sec. 4.9): each sample = one octant of every probe
    ///    in its proxy, DYNAMIC_RAYS_PER_OCTANT rays spread over the octant's texels, each
    ///    updating its texel with N_max = 10, within `DYNAMIC_SHARE` of the non-pilot budget.
    fn adgi_dynamic_chains(
        &mut self,
        a: &mut AdgiState,
        f: AdgiFrame<'_>,
        rng: &mut Pcg64Mcg,
        counter: &mut RayCounter,
    ) {
        let AdgiFrame {
            exp,
            scene,
            near,
            budget,
        } = f;
        let grid = exp.scene.grid;
        let non_pilot = budget.saturating_sub(counter.rays);
        let dynamic_budget = (non_pilot as f32 * DYNAMIC_SHARE) as u64;
        let proxies = a.dynamic_chains.cells();
        proxies
            .max_pool(&a.f_d, &mut a.proxy_f_d)
            .expect("table sizes");
        let any_change = a.proxy_f_d.iter().any(|&v| v > 0.0);
        let mut dynamic_rays = 0_u64;
        if any_change || !a.guided {
            let samples: Vec<_> = if a.guided {
                let guide = GuidingFunction::new(proxies, &a.proxy_f_d, None, GuideParams::DYNAMIC)
                    .expect("table sizes");
                a.dynamic_chains
                    .step_frame(&guide, || step_uniforms(rng))
                    .to_vec()
            } else {
                let guide = |_: Vec3, _: Vec3| 1.0_f32;
                a.dynamic_chains
                    .step_frame(&guide, || step_uniforms(rng))
                    .to_vec()
            };
            'samples: for s in samples {
                for coords in proxies.probes_of(s.cell as usize) {
                    let p = grid.probe_index(coords);
                    let texels = &a.octant_texels[s.octant as usize];
                    let per_texel = (DYNAMIC_RAYS_PER_OCTANT as usize).div_ceil(texels.len());
                    let cost = (per_texel * texels.len()) as u64;
                    if dynamic_rays + cost > dynamic_budget {
                        break 'samples;
                    }
                    let pos = grid.probe_position(coords);
                    for &(index, _) in texels
                        .iter()
                        .flat_map(|t| core::iter::repeat_n(t, per_texel))
                    {
                        self.dynamic_texel_ray(scene, p, pos, index, rng);
                    }
                    dynamic_rays += cost;
                    if near[p] {
                        counter.rays_near += cost;
                    }
                }
            }
        }
        counter.rays += dynamic_rays;
        counter.rays_dynamic = dynamic_rays;
    }

    /// One dynamic-chain ray of probe `p` at `pos`: a direction uniform in irradiance texel
    /// `index`'s square (see DYNAMIC_RAYS_PER_OCTANT), stored with the dynamic N_max (Table 3).
    fn dynamic_texel_ray(
        &mut self,
        scene: &Scene,
        p: usize,
        pos: Vec3,
        index: usize,
        rng: &mut Pcg64Mcg,
    ) {
        let map = self.texels.config().irradiance_map;
        let t = map.coords(index) - UVec2::ONE;
        let uv = (t.as_vec2() + Vec2::new(rng.random(), rng.random()))
            * (2.0 / map.interior() as f32)
            - Vec2::ONE;
        let d = map.decode(uv);
        let hit = scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random()));
        self.texels.update_sample_with(
            p,
            &RaySample {
                direction: d,
                radiance: hit.radiance,
                distance: hit.distance,
            },
            rng.random(),
            MovingAverage::DYNAMIC,
        );
    }

    /// 4. Static chains (sec. 4.8): h = exp(min(ĝ/f_s, 1)) f_s, ĝ = the octant's mean cached
    ///    luminance, with the rest of the budget; one texel update per sample.
    fn adgi_static_chains(
        &mut self,
        a: &mut AdgiState,
        f: AdgiFrame<'_>,
        rng: &mut Pcg64Mcg,
        counter: &mut RayCounter,
    ) {
        let AdgiFrame {
            exp,
            scene,
            near,
            budget,
        } = f;
        let grid = exp.scene.grid;
        let dirs: Vec<Vec3> = exp.texels.iter().map(|t| t.1).collect();
        for p in 0..grid.probe_count() {
            let mut g = [0.0; OCTANTS];
            octant_feedback(
                &dirs,
                |k| self.texels.irradiance(p, exp.texels[k].0),
                &mut g,
            );
            a.feedback[p * OCTANTS..][..OCTANTS].copy_from_slice(&g);
        }
        let static_budget = budget.saturating_sub(counter.rays);
        let samples: Vec<_> = if a.guided {
            let guide = GuidingFunction::new(
                ProxyGrid::probes(grid),
                &a.f_s,
                Some(&a.feedback),
                GuideParams::STATIC,
            )
            .expect("table sizes");
            a.static_chains
                .step_frame(&guide, || step_uniforms(rng))
                .to_vec()
        } else {
            let guide = |_: Vec3, _: Vec3| 1.0_f32;
            a.static_chains
                .step_frame(&guide, || step_uniforms(rng))
                .to_vec()
        };
        for s in samples.iter().take(static_budget as usize) {
            let p = grid.probe_index(s.probe);
            let pos = grid.probe_position(s.probe);
            let hit =
                scene.trace_probe_ray(pos, s.direction, Vec2::new(rng.random(), rng.random()));
            self.texels
                .update_sample(p, &ray_sample(s.direction, &hit), rng.random());
            counter.count(1, near[p]);
        }
    }
}

/// What the chain steps of an ADGI frame read: the experiment, the scene of this frame, which
/// probes are near the event, and the frame's ray budget.
#[derive(Clone, Copy)]
struct AdgiFrame<'a> {
    exp: &'a Experiment,
    scene: &'a Scene,
    near: &'a [bool],
    budget: u64,
}

/// 2. Change detection (eq. 13-18) on the second frame of a pair, composition (eq. 19, 20;
///    f_c = 1: the camera sees the whole grid) into the 6-10-10 words (sec. 4.3), whose 10-bit
///    f_d ends a decayed trigger at exactly 0; decoded into `a.f_s` and `a.f_d`.
fn compose_adgi_heuristics(a: &mut AdgiState, exp: &Experiment, pilot: PilotFrame) {
    let grid = exp.scene.grid;
    if pilot.measures_gradient() {
        a.detector.detect(&a.f_v, &a.f_r).expect("table sizes");
    } else {
        a.detector
            .set_reference(&a.f_v, &a.f_r)
            .expect("table sizes");
    }
    heuristics::compose_grid(
        &grid,
        &a.params,
        grid.origin(),
        &a.f_v,
        a.detector.delta_visibility(),
        a.detector.delta_radiance(),
        &mut a.words,
    )
    .expect("table sizes");
    decode_field(&a.words, HeuristicField::Static, &mut a.f_s).expect("table sizes");
    decode_field(&a.words, HeuristicField::Dynamic, &mut a.f_d).expect("table sizes");
}
