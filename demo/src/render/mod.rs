//! The renderer: glTF 2.0 scenes path traced with and without mcg's guides.
//!
//! `mcg-demo render --scene FILE --method bsdf|nee|mcpg|mcmm|adgi|adgi-refill|ddgi …` renders a scene and
//! writes `<out>/<method>.exr` (the mean over all frames, linear RGB; `--ramp-frames` weighs
//! the first frames less, [`frame_weight`]), `<out>/<method>.png`
//! (sRGB-encoded, clipped) and `<out>/<method>.json` (settings, device, per-frame times and,
//! with `--reference`, per-frame errors of the running mean; with `--reference-spp`, each
//! frame's errors against the reference of its scene state, [`states`]). `mcg-demo scenes` rewrites the
//! built-in scenes of `demo/scenes/`.
//!
//! | module | what it does |
//! |---|---|
//! | [`scene`] | glTF loading ([`scene::SceneFile`]), animation, camera, the traceable [`scene::Scene`] |
//! | [`bvh`] | the flattened `#[repr(C)]` BVH and triangle layout, built by `obvhs`, walked by the CPU tracer and its WGSL twin |
//! | [`material`] | Lambertian + GGX conductor materials with emission |
//! | [`cpu`] | the CPU path tracer (rayon), methods `bsdf` and `nee`, the per-vertex sampler seam of the guides |
//! | [`gpu`] | the WGSL twin of the CPU tracer on wgpu, over the same BVH, triangle and material buffers; `mcpg` and `mcmm` with the GPU guides of `mcg-gpu-backend`; `ddgi`, `adgi`, `adgi-refill` with its probe cache (`ddgi`'s and `adgi`'s updates wholly on the GPU, `adgi-refill`'s and `adgi-blend`'s decisions on the host) |
//! | [`guided`] | `mcpg` on the CPU: the MCPG guide behind the sampler seam |
//! | [`mcmm`] | `mcmm` on the CPU: MCMM's screen-space chains for direct light, SSMIS over tiles of 64 pixels |
//! | [`probe_gi`] | `adgi` and `ddgi` on the CPU: a probe grid fitted to the scene, probe rays in the BVH, first hits shaded with a light sample plus probe irradiance |
//! | [`states`] | per-state references of animated scenes and per-frame errors against them, over the image and the event region |
//! | [`output`] | EXR/PNG files, RMSE and relative MSE |
//! | [`scene_generator`] | the built-in scenes |

// NaN-safe guards (`!(x > 0.0)` is true for NaN) are the house style.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bvh;
pub mod cpu;
pub mod environment;
pub mod gpu;
pub mod guided;
pub mod material;
pub mod mcmm;
pub mod output;
pub mod probe_gi;
pub mod scene;
pub mod scene_generator;
pub mod states;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use mcg_markov_guide::mcpg::{EmissionAllocation, Guide, GuideConfig, MAX_CANDIDATES, McpgParams};
use mcg_probe_cache::ProbeGrid;

use crate::Result;
use cpu::{BsdfSampler, Method, RenderSettings, render_frame};
use gpu::{GpuTiming, GpuTracer};
use guided::{McpgSampler, guide_config};
use mcmm::{McmmRenderer, McmmScore, mcmm_params};
use output::{Errors, FrameVariance, RgbImage, errors};
use probe_gi::{DEFAULT_PROBE_RAYS, DEFAULT_PROBE_SPACING, ProbeGi, fit_grid};
use scene::{Scene, SceneFile, frame_time};
use states::{DynamicErrors, ReferenceSettings, SceneStates};

/// Where the tracer runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Device {
    /// The GPU when a wgpu adapter exists, the method has a WGSL twin and the device can
    /// hold the scene and the image; the CPU otherwise (with a one-line message saying why).
    #[value(
        help = "The GPU when one can render the method and the scene, else the CPU (saying why)"
    )]
    Auto,
    /// The CPU tracer (rayon threads).
    #[value(help = "The CPU tracer (rayon threads)")]
    Cpu,
    /// The WGSL tracer ([`gpu`]); an error when there is no adapter.
    #[value(help = "The WGSL tracer on wgpu; an error when there is no adapter")]
    Gpu,
}

/// Seconds of untimed load a hardware GPU gets before a render's timed frames
/// ([`GpuTracer::warm_up`]), so that they run at its working clocks, not at an idle GPU's.
pub const GPU_WARM_UP_S: f64 = 0.5;

/// The arguments of `mcg-demo render`.
#[derive(Clone, Debug, clap::Parser)]
#[command(
    name = "mcg-demo render",
    about = "Path traces a glTF 2.0 scene and writes EXR, PNG and JSON."
)]
pub struct RenderArgs {
    /// The glTF 2.0 scene (.gltf with .bin or embedded buffers, or .glb).
    #[arg(long)]
    pub scene: PathBuf,
    /// How directions are sampled and lights found.
    #[arg(long, value_enum, default_value_t = Method::Nee)]
    pub method: Method,
    /// Where the tracer runs.
    #[arg(long, value_enum, default_value_t = Device::Auto)]
    pub device: Device,
    /// Image width in pixels.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// Samples per pixel per frame.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: u32,
    /// Frames; the output is their mean (an animated scene moves from frame to frame), weighted
    /// by `--ramp-frames`.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    #[arg(help = "Frames; the output is their mean (an animated scene moves from frame to frame)")]
    pub frames: u32,
    /// Scattering events per path (1 = direct light only).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub bounces: u32,
    /// Seed of the random stream (decimal or 0x-hex; the low and high 32 bits are folded).
    #[arg(long, default_value = "0x6d6367", value_parser = parse_seed)]
    pub seed: u64,
    /// Output folder (created if missing).
    #[arg(long, default_value = "out/render")]
    #[arg(help_heading = "Output and measurement")]
    pub out: PathBuf,
    /// A reference EXR of the same size: per-frame errors go into the JSON, and the
    /// reference's own error too when its variance file (`REF.variance.exr`, which `render`
    /// writes beside every plain mean of a still scene) lies beside it.
    #[arg(long)]
    #[arg(
        help = "A reference EXR of the same size: each frame's errors go into the JSON (and the reference's own error, from REF.variance.exr beside it)",
        help_heading = "Output and measurement"
    )]
    pub reference: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    #[arg(help_heading = "Output and measurement")]
    pub no_progress: bool,
    /// `mcpg` without its irradiance cache: the guide learns from the emission its rays hit
    /// only (as MCPG Fig. 8 compares on direct light).
    #[arg(long)]
    #[arg(
        help = "mcpg without its irradiance cache: the chains learn only from the emission their rays hit",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub no_irradiance_cache: bool,
    /// Where `mcpg`'s training takes the radiance reflected at the next hit, on either device:
    /// the path's own estimate where the path went on (mcg's extension; the GPU tracer holds
    /// a path's vertices for it, the first two of paths deeper than 3 bounces), or the irradiance cache at every vertex (the
    /// paper's rule) ([`guided::Reflected`]); with `--no-irradiance-cache`, neither.
    #[arg(long, value_enum, default_value_t = guided::Reflected::Path)]
    #[arg(
        help = "Where mcpg's training takes the radiance reflected at the next hit",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_reflected: guided::Reflected,
    /// How many directions `mcpg` draws per vertex, besides the path's, from the guide's
    /// mixture for the emission they meet, the emission along each of the K + 1 directions
    /// counting 1/(K + 1) (mcg's extension), on either device ([`guided::EMISSION_SAMPLES`]);
    /// 0 is the paper's one direction. `mcpg-nee` samples its lights instead.
    #[arg(long, default_value_t = guided::EMISSION_SAMPLES)]
    #[arg(
        help = "Directions per vertex that mcpg draws from its guide, besides the path's, for the emission they meet (mcg's extension; 0 is the paper's one direction)",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_emission_samples: u32,
    /// How `mcpg` spreads its emission-only directions over the vertices of a path: as many
    /// at every vertex, or, with the same mean, by each depth's variance measured in the
    /// frames before, on the CPU also by each vertex's expected contribution
    /// ([`guided::Allocation`], mcg's extension; the GPU tracer measures the depths in about
    /// [`gpu::MOMENT_PIXELS`] evenly spaced pixels).
    #[arg(long, value_enum, default_value_t = guided::Allocation::Contribution)]
    #[arg(
        help = "How mcpg spreads those directions over the vertices of a path",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_emission_allocation: guided::Allocation,
    /// The share of `mcpg`'s vertices whose sample goes into its irradiance cache, in (0, 1]
    /// ([`guided::CACHE_ADD_PROBABILITY`]; 1 is the paper's rule).
    #[arg(long, default_value_t = guided::CACHE_ADD_PROBABILITY)]
    #[arg(
        help = "The share of mcpg's vertices that add their sample to its irradiance cache, in (0, 1]; 1 is the paper's rule",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_cache_add: f32,
    /// `mcpg`'s young-chain confidence N_c (mcg's extension of MCPG Alg. 2: a chain of fewer
    /// samples lends part of its share to the material and continues after the material's
    /// samples); 0 is the paper's rule.
    #[arg(long, default_value_t = guided::CONFIDENCE_SAMPLES)]
    #[arg(
        help = "mcpg's young-chain confidence N_c: a chain of fewer samples lends part of its share to the material (mcg's extension; 0 is the paper's rule)",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_confidence: f32,
    /// `mcpg`'s N_mc, the candidates each vertex reads from the grids (MCPG Alg. 1), 1 to 8 on
    /// either device; the paper's 5 by default. Fewer make a vertex cheaper and its mixture
    /// poorer: on scene (a) 3 and 4 lost to 5 at equal time (`markov-guide/benches/README.md`).
    #[arg(long, default_value_t = McpgParams::PAPER.candidates,
          value_parser = clap::value_parser!(u32).range(1..=MAX_CANDIDATES as i64))]
    #[arg(
        help = "mcpg's N_mc, the chain states each vertex reads from the grids (MCPG Alg. 1), 1 to 8",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_candidates: u32,
    /// `mcpg`'s α_min, the smallest blend factor of the chains' update (MCPG Alg. 3 line 5;
    /// [`guided::ALPHA_MIN`]); 0.01 is the MCPG authors' engine value, which the crate's
    /// `McpgParams::PAPER` keeps.
    #[arg(long, default_value_t = guided::ALPHA_MIN, value_parser = parse_alpha_min)]
    #[arg(
        help = "mcpg's α_min, the smallest blend factor of the chains' update (MCPG Alg. 3; the authors' engine uses 0.01)",
        help_heading = "mcpg and mcpg-nee"
    )]
    pub mcpg_alpha_min: f32,
    /// The warm-up ramp R of the accumulated mean: frame i enters it with the weight
    /// min(1, (i + 1)/R) ([`frame_weight`]), so the frames of a guide that is still learning
    /// count less. 1 (the default) is the plain mean over all frames, which the report's
    /// targets are measured on; [`guided::RAMP_FRAMES`] is what suits `mcpg` on scene (a).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    #[arg(
        help = "Weight frame i of the mean by min(1, (i + 1)/R), so that a learning guide's first frames count less; 1 is the plain mean",
        help_heading = "Output and measurement"
    )]
    pub ramp_frames: u32,
    /// The score of `mcmm`'s chains (MCMM Alg. 3): the tile's mixture density (the pixel's
    /// one-sample SSMIS estimate, with the defensive probability p_h = 0.4) or the paper's,
    /// the chain's own technique density (with the paper's p_h = 0.2).
    #[arg(long, value_enum, default_value_t = McmmScore::TileMixture)]
    #[arg(
        help = "The score of mcmm's chains (MCMM Alg. 3)",
        help_heading = "mcmm"
    )]
    pub mcmm_score: McmmScore,
    /// An environment around the scene, what a ray that leaves it sees (glTF has none):
    /// `R,G,B`, a uniform radiance (linear, W·sr⁻¹·m⁻² per channel;
    /// [`scene::Scene::environment`]), or `FILE.exr` / `FILE.hdr`, an equirectangular map of
    /// linear radiance, its centre straight down −Z and its top row the zenith (+Y;
    /// [`environment::EnvironmentMap`]). A scene lit by it needs no emissive material; `nee`
    /// samples a uniform one with cosine-distributed directions and a map in proportion to its
    /// luminance ([`scene::ENVIRONMENT_PICK`] of its light samples where the scene also has
    /// emitters). It replaces an environment the file's extras name.
    #[arg(long, value_parser = parse_environment)]
    #[arg(
        help = "What rays that leave the scene see: R,G,B (a uniform linear radiance) or FILE.exr / FILE.hdr (an equirectangular map, its centre along −Z, its top row +Y); replaces the file's",
        help_heading = "Scene"
    )]
    pub environment: Option<EnvironmentArg>,
    /// A camera at EX,EY,EZ looking at TX,TY,TZ with +Y up, replacing the file's (or giving a
    /// file without one a camera; [`scene::SceneFile::with_camera`]): six comma-separated
    /// numbers, in the scene's metres.
    #[arg(long, value_parser = parse_look_at, value_name = "EX,EY,EZ,TX,TY,TZ", allow_hyphen_values = true)]
    #[arg(
        help = "A camera at EX,EY,EZ looking at TX,TY,TZ (+Y up, in metres), replacing the file's",
        help_heading = "Scene"
    )]
    pub camera: Option<[Vec3; 2]>,
    /// The vertical field of view of `--camera`, degrees (default: the file camera's, else 45).
    #[arg(long, requires = "camera")]
    #[arg(
        help = "The vertical field of view of --camera in degrees (default: the file camera's, else 45)",
        help_heading = "Scene"
    )]
    pub yfov: Option<f32>,
    /// Turn the environment map by this many degrees about +Y (right-handed: at 90 the map's
    /// centre lies along −X; [`environment::EnvironmentMap::with_rotation`]), replacing the
    /// rotation the file's extras name; no effect on a uniform environment.
    #[arg(long, allow_hyphen_values = true)]
    #[arg(
        help = "Turn the environment map by this many degrees about +Y (at 90 its centre lies along −X), replacing the file's rotation",
        help_heading = "Scene"
    )]
    pub environment_rotation: Option<f32>,
    /// Ignore the portals the file's extras name (`mcg.portals`, as the built-in sky and sun
    /// rooms name their windows; [`scene::Scene::portals`]): light samples of the environment
    /// then do not aim at the openings.
    #[arg(long)]
    #[arg(
        help = "Ignore the portals the file names: light samples of the environment then do not aim at the openings",
        help_heading = "Scene"
    )]
    pub no_portals: bool,
    /// Split every triangle that emits nothing into 4^N at its edges' midpoints
    /// ([`scene::SceneFile::with_subdivision`]): the same image in expectation, from a BVH over
    /// more triangles, to see what a method's frame costs against the rays' as scenes grow.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=12))]
    #[arg(
        help = "Split every triangle that emits nothing into 4^N (the same image in expectation, from a BVH over more triangles)",
        help_heading = "Scene"
    )]
    pub subdivide: u32,
    /// For a file without a camera: one looking down −Z at the whole scene (45° vertical
    /// field of view; [`scene::SceneFile::with_auto_camera`]); without it such a file is an
    /// error.
    #[arg(long)]
    #[arg(
        help = "For a file without a camera: one looking down −Z at the whole scene (45° vertical field of view)",
        help_heading = "Scene"
    )]
    pub auto_camera: bool,
    /// Probe GI and per-state reference options.
    #[command(flatten)]
    pub probes: ProbeOptions,
}

impl RenderArgs {
    /// The arguments `mcg-demo render --scene SCENE` parses to: every option at the command
    /// line's default. Callers set what they change with struct update syntax:
    ///
    /// ```
    /// use mcg_demo::render::cpu::Method;
    /// use mcg_demo::render::{Device, RenderArgs};
    ///
    /// let args = RenderArgs {
    ///     method: Method::Mcpg,
    ///     device: Device::Cpu,
    ///     frames: 64,
    ///     ..RenderArgs::new("room.gltf")
    /// };
    /// assert_eq!((args.width, args.spp, args.bounces), (256, 16, 3));
    /// ```
    #[must_use]
    pub fn new(scene: impl Into<PathBuf>) -> Self {
        use clap::Parser as _;
        // The scene is set after parsing so that no path (one starting with `-`, one that is
        // not UTF-8) can be read as anything else.
        let mut args = Self::try_parse_from(["mcg-demo render", "--scene", "scene.gltf"])
            .expect("the command line's defaults parse");
        args.scene = scene.into();
        args
    }
}

/// The options of `adgi`/`ddgi`, of the per-state references (`--reference-spp`) and of the
/// frames kept besides the mean (`--keep-frames`).
#[derive(Clone, Debug, clap::Args)]
pub struct ProbeOptions {
    /// `adgi`/`ddgi`: the spacing of the probe grid in metres (fitted to the scene's bounds,
    /// [`probe_gi::fit_grid`]).
    #[arg(long, default_value_t = DEFAULT_PROBE_SPACING)]
    #[arg(
        help = "The spacing of the probe grid in metres (fitted to the scene's bounds)",
        help_heading = "adgi and ddgi"
    )]
    pub probe_spacing: f32,
    /// `adgi`/`ddgi`: probe rays per probe per frame of `ddgi`; `adgi` spends the same total.
    #[arg(long, default_value_t = DEFAULT_PROBE_RAYS, value_parser = clap::value_parser!(u32).range(1..=65536))]
    #[arg(
        help = "Probe rays per probe per frame of ddgi; adgi spends the same total",
        help_heading = "adgi and ddgi"
    )]
    pub probe_rays: u32,
    /// Renders a `nee` reference of each scene state with this many samples per pixel
    /// (cached in `<out>/reference/`) and records each frame's errors against its state's
    /// reference, over the image and the event region (not with `--reference`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    #[arg(
        help = "Render a nee reference of each scene state with this many spp (cached in <out>/reference/) and record each frame's errors against it, over the image and the event region",
        help_heading = "Output and measurement"
    )]
    pub reference_spp: Option<u32>,
    /// Scattering events per path of the `--reference-spp` references.
    #[arg(long, default_value_t = DEFAULT_REFERENCE_BOUNCES, value_parser = clap::value_parser!(u32).range(1..=64))]
    #[arg(
        help = "Scattering events per path of the --reference-spp references",
        help_heading = "Output and measurement"
    )]
    pub reference_bounces: u32,
    /// The event region's relMSE that `frames_to_threshold` waits for (`--reference-spp`).
    #[arg(long, default_value_t = states::DEFAULT_EVENT_ERROR_THRESHOLD)]
    #[arg(
        help = "The event region's relMSE that frames_to_threshold waits for (with --reference-spp)",
        help_heading = "Output and measurement"
    )]
    pub event_error_threshold: f64,
    /// Frames whose own images are kept besides the mean (comma-separated); written as
    /// `<method>_frame<N>.png` and `.exr`.
    #[arg(long, value_delimiter = ',')]
    #[arg(
        help = "Frames whose own images are kept besides the mean (comma-separated), as <method>_frame<N>.png and .exr",
        help_heading = "Output and measurement"
    )]
    pub keep_frames: Vec<u32>,
}

impl Default for ProbeOptions {
    /// The command line's defaults.
    fn default() -> Self {
        Self {
            probe_spacing: DEFAULT_PROBE_SPACING,
            probe_rays: DEFAULT_PROBE_RAYS,
            reference_spp: None,
            reference_bounces: DEFAULT_REFERENCE_BOUNCES,
            event_error_threshold: states::DEFAULT_EVENT_ERROR_THRESHOLD,
            keep_frames: Vec::new(),
        }
    }
}

/// The default of `--reference-bounces`.
pub const DEFAULT_REFERENCE_BOUNCES: u32 = 8;

fn parse_seed(v: &str) -> Result<u64, String> {
    match v.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16),
        None => v.parse(),
    }
    .map_err(|_| format!("not a number: {v}"))
}

/// What `--environment` names.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentArg {
    /// A uniform radiance.
    Uniform(Vec3),
    /// The file of an environment map.
    Map(PathBuf),
}

/// `--environment`: a file ending in `.exr` or `.hdr` (any case), else [`parse_rgb`]'s
/// `R,G,B`.
fn parse_environment(v: &str) -> Result<EnvironmentArg, String> {
    let lower = v.to_ascii_lowercase();
    if lower.ends_with(".exr") || lower.ends_with(".hdr") {
        Ok(EnvironmentArg::Map(PathBuf::from(v)))
    } else {
        parse_rgb(v)
            .map(EnvironmentArg::Uniform)
            .map_err(|e| format!("{e}; expected R,G,B or an environment map, FILE.exr or FILE.hdr"))
    }
}

/// Comma-separated numbers (spaces allowed around them).
fn parse_numbers(v: &str) -> Result<Vec<f32>, String> {
    v.split(',')
        .map(|c| {
            c.trim()
                .parse::<f32>()
                .map_err(|_| format!("not a number: {c}"))
        })
        .collect()
}

/// `--camera`: six comma-separated finite numbers, an eye and a target.
fn parse_look_at(v: &str) -> Result<[Vec3; 2], String> {
    let n = parse_numbers(v)?;
    match n[..] {
        [ex, ey, ez, tx, ty, tz] if n.iter().all(|c| c.is_finite()) => {
            Ok([Vec3::new(ex, ey, ez), Vec3::new(tx, ty, tz)])
        }
        _ => Err(format!(
            "{v}: expected EX,EY,EZ,TX,TY,TZ (six finite numbers)"
        )),
    }
}

/// A uniform radiance: three comma-separated non-negative numbers, `R,G,B`.
fn parse_rgb(v: &str) -> Result<Vec3, String> {
    match parse_numbers(v)?[..] {
        [r, g, b] if [r, g, b].iter().all(|c| c.is_finite() && *c >= 0.0) => Ok(Vec3::new(r, g, b)),
        [_, _, _] => Err(format!("{v}: channels must be finite and non-negative")),
        _ => Err(format!("{v}: expected R,G,B")),
    }
}

/// `--mcpg-alpha-min`: a blend factor in [0, 1] (0 gives a plain running mean up to N_max).
fn parse_alpha_min(v: &str) -> Result<f32, String> {
    match v.parse::<f32>() {
        Ok(a) if (0.0..=1.0).contains(&a) => Ok(a),
        Ok(a) => Err(format!("{a} is outside [0, 1]")),
        Err(_) => Err(format!("not a number: {v}")),
    }
}

/// The weight of frame `frame` (counted from 0) in a mean accumulated with the warm-up ramp
/// `ramp` R: w_i = min(1, (i + 1)/R), 1 for every frame when R ≤ 1 (the plain mean).
///
/// Why a fixed ramp is unbiased and what it buys: every frame X_i of a guided method is an
/// unbiased estimate of the image I given the guide it was drawn from (the estimator divides
/// by the exact density it sampled, [`mcg_markov_guide::mcpg::GuidedVertex::pdf`]), and the
/// guide depends only on earlier frames, so E[X_i | frames before i] = I. Then for weights
/// fixed in advance, E[Σ w_i X_i / Σ w_i] = I, and the errors X_i − I are uncorrelated (a
/// martingale difference sequence), so the mean's variance is Σ w_i² v_i / (Σ w_i)², v_i the
/// variance of frame i: minimal for w_i ∝ 1/v_i (inverse-variance weighting). A guide's first
/// frames have a larger v_i (in `hidden_light_room`, 128², 8 spp, per-frame relMSE 5.4-6.0,
/// 2.6-3.4, 1.9-4.2, 1.3-2.3 in frames 0-3 against 1.2-1.3 after frame 16), and a ramp
/// over R frames follows 1/v_i roughly without estimating v_i from the frames — weights
/// estimated from the same samples (as Müller's "Practical Path Guiding in Production",
/// 2019, does for its training iterations) would correlate with X_i and bias the mean.
#[must_use]
pub fn frame_weight(frame: u32, ramp: u32) -> f32 {
    if ramp <= 1 {
        return 1.0;
    }
    ((frame as f32 + 1.0) / ramp as f32).min(1.0)
}

/// The arguments of `mcg-demo scenes`.
#[derive(Clone, Debug, clap::Parser)]
#[command(name = "mcg-demo scenes", about = "Writes the built-in glTF scenes.")]
pub struct ScenesArgs {
    /// Output folder.
    #[arg(long, default_value = "demo/scenes")]
    pub out: PathBuf,
}

/// What a render wrote and measured (the content of `<method>.json`).
#[derive(Clone, Debug, serde::Serialize)]
pub struct RenderReport {
    /// The scene file.
    pub scene: PathBuf,
    /// The method.
    pub method: Method,
    /// The device that rendered.
    pub device: &'static str,
    /// Threads of the CPU tracer.
    pub threads: usize,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Frames.
    pub frames: u32,
    /// The warm-up ramp of the mean (`--ramp-frames`, [`frame_weight`]); 1 is the
    /// plain mean.
    pub ramp_frames: u32,
    /// `mcpg`'s emission-only directions per vertex (`--mcpg-emission-samples`); absent for
    /// other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mcpg_emission_samples: Option<u32>,
    /// How `mcpg` spread them over the depths (`--mcpg-emission-allocation`); absent for
    /// other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mcpg_emission_allocation: Option<guided::Allocation>,
    /// `mcpg`'s K(d) after the last frame, per depth of a scattering vertex (the next frame's
    /// allocation); absent for other methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mcpg_emission_per_depth: Option<Vec<f32>>,
    /// Scattering events per path.
    pub bounces: u32,
    /// The seed as given.
    pub seed: u64,
    /// The GPU adapter (name and backend) when the GPU rendered.
    pub adapter: Option<String>,
    /// How GPU frame times were measured (timestamp queries or wall clock), when the GPU
    /// rendered.
    pub gpu_timing: Option<GpuTiming>,
    /// The GPU adapter's kind (wgpu's `DeviceType`: `Cpu` for a software implementation such
    /// as lavapipe, whose passes run on this machine's cores; `DiscreteGpu`, …), when the GPU
    /// rendered.
    pub adapter_type: Option<String>,
    /// The untimed `bsdf` frames a hardware GPU rendered before the timed ones
    /// ([`GpuTracer::warm_up`] for [`GPU_WARM_UP_S`]; 0 on a software adapter), when the GPU
    /// rendered.
    pub gpu_warm_up_frames: Option<u32>,
    /// The scene's triangles (after `--subdivide`; of the last frame's scene).
    pub triangles: usize,
    /// Seconds of each frame's tracing (scene building and upload of animated frames
    /// excluded): wall clock on the CPU; on the GPU the summed timestamp-query time of the
    /// frame's passes when the adapter has timestamps, else the wall clock from the first
    /// submission to the end of the wait (read-back excluded). The guide's end of frame is
    /// included.
    pub frame_times_s: Vec<f64>,
    /// CPU seconds (user + system, all threads) of this process during each frame, where the
    /// system reports them (its process CPU clock; empty where it has none). On a machine
    /// shared with other work they measure a frame's cost better than the wall clock.
    pub frame_cpu_times_s: Vec<f64>,
    /// Of the frame times, those of each frame's [`Guide::end_frame`] (`mcpg` only; empty for
    /// the other methods); on the GPU the guide's per-frame pass, timestamped like the frame
    /// or on the wall clock ([`GpuTracer::last_end_frame_s`]).
    pub end_frame_times_s: Vec<f64>,
    /// The reference, if any.
    pub reference: Option<PathBuf>,
    /// The error the reference carries itself ([`output::own_error`]), when its variance
    /// file ([`output::variance_path`]) lies beside it: subtract its `rel_mse` from a relMSE
    /// in `errors` for an unbiased estimate of the error against the true image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference_own_error: Option<Errors>,
    /// Errors of the running mean after each frame against the reference.
    pub errors: Vec<Errors>,
    /// Errors of each frame's own image against the reference (what a real-time renderer
    /// that shows every frame without accumulation would show).
    pub frame_errors: Vec<Errors>,
    /// Mean LDR-FLIP of the output image (the mean over all frames) against the reference
    /// ([`output::flip`]); `None` without a reference.
    pub flip: Option<f64>,
    /// Probe rays traced in each frame (`adgi`, `ddgi`; empty for the other methods).
    pub probe_rays_per_frame: Vec<u64>,
    /// Probes of the grid (`adgi`, `ddgi`).
    pub probe_count: Option<usize>,
    /// With `--reference-spp`: the state references, the event and the event region's errors
    /// per frame ([`DynamicErrors`]); `frame_errors` then holds each frame's errors against
    /// its state's reference.
    pub dynamic: Option<DynamicErrors>,
    /// What the scene loader ignored.
    pub warnings: Vec<String>,
}

/// A finished render: the mean image and its report.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The mean over all frames ([`Accumulation`]).
    pub image: RgbImage,
    /// The variance of `image` per pixel and channel, estimated from the frames
    /// ([`FrameVariance`]); `None` for a weighted mean (`--ramp-frames` above 1), an animated
    /// scene or a single frame.
    pub variance: Option<RgbImage>,
    /// Settings and measurements.
    pub report: RenderReport,
    /// The CPU guide as the last frame left it (`mcpg` on the CPU only).
    pub guide: Option<Arc<Guide>>,
    /// The images of the frames of `--keep-frames`, in frame order.
    pub frames: Vec<(u32, RgbImage)>,
}

/// Renders as `args` say, without writing files.
///
/// # Errors
/// Scene errors ([`scene::SceneError`]), an unreadable reference or one of another size.
pub fn render(args: &RenderArgs) -> Result<Rendered> {
    let mut file = SceneFile::open(&args.scene)?;
    match &args.environment {
        Some(EnvironmentArg::Uniform(radiance)) => file = file.with_environment(*radiance)?,
        Some(EnvironmentArg::Map(map)) => file = file.with_environment_map(map)?,
        None => {}
    }
    if args.auto_camera {
        file = file.with_auto_camera();
    }
    if let Some([eye, target]) = args.camera {
        file = file.with_camera(eye, target, args.yfov)?;
    }
    if let Some(degrees) = args.environment_rotation {
        file = file.with_environment_rotation(degrees)?;
    }
    if args.no_portals {
        file = file.without_portals();
    }
    if args.subdivide > 0 {
        file = file.with_subdivision(args.subdivide);
    }
    let reference = read_reference(args)?;
    let reference_own_error = read_reference_own_error(args, reference.as_ref())?;
    let settings = render_settings(args)?;
    let mut states = scene_states(&file, args)?;
    let mut scene = file.build(frame_time(0))?;
    let warnings = scene.warnings.clone();
    let gpu = gpu_tracer(args.device, args.method)?;
    let mut gpu = gpu.map(|g| g.lock().unwrap_or_else(std::sync::PoisonError::into_inner));
    if let Some(g) = gpu.as_deref_mut()
        && let Err(e) = g
            .upload(&scene)
            .and_then(|()| g.image_entries(&settings).map(drop))
    {
        if args.device == Device::Gpu {
            return Err(e);
        }
        eprintln!("mcg-demo: the GPU cannot hold this render ({e}) — rendering on the CPU");
        gpu = None;
    }
    let mut guide = start_guide(args, &scene, &mut gpu)?;
    // Again: `mcpg`'s guide, started now, may add its emission statistics to the image.
    if let Some(g) = gpu.as_deref() {
        g.image_entries(&settings)?;
    }
    let gpu_warm_up_frames = match gpu.as_deref_mut() {
        Some(g) if g.adapter_info().device_type != mcg_gpu_backend::wgpu::DeviceType::Cpu => {
            Some(g.warm_up(&settings, GPU_WARM_UP_S)?)
        }
        Some(_) => Some(0),
        None => None,
    };
    let progress = progress_bar(args)?;
    let pixels = (args.width * args.height) as usize;
    let mut sum = Accumulation::new(pixels, args.ramp_frames);
    // The variance of the plain mean of a still scene's frames.
    let mut spread =
        (args.ramp_frames == 1 && !file.is_animated()).then(|| FrameVariance::new(pixels));
    let mut times = FrameTimes::default();
    let probe_count = guide.probe_count().or_else(|| {
        let g = gpu.as_deref()?;
        Some(g.probe_cache()?.config().grid.probe_count())
    });
    let mut collected = Collected::default();
    for frame in 0..args.frames {
        if frame > 0 && file.is_animated() {
            scene = file.build(frame_time(frame))?;
            if let Some(g) = gpu.as_deref_mut() {
                g.upload(&scene)?;
            }
        }
        let image = if let Some(g) = gpu.as_deref_mut() {
            let (image, seconds) = g.render_frame(&settings, frame)?;
            times.frame.push(seconds);
            times.end_frame.extend(g.last_end_frame_s());
            if args.method.uses_probes() {
                times.probe_rays.extend(g.probe_rays_last_frame());
            }
            image
        } else {
            cpu_frame(&scene, &settings, frame, &mut guide, &mut times)?
        };
        progress.inc(1);
        let checks = (reference.as_ref(), states.as_mut());
        accumulate(&mut sum, &image, frame, checks, &mut collected);
        if let Some(spread) = &mut spread {
            spread.add(&image);
        }
        if args.probes.keep_frames.contains(&frame) {
            collected.keep(frame, args, image);
        }
    }
    let Collected {
        errs,
        frame_errs,
        kept,
    } = collected;
    progress.finish_and_clear();
    let image = RgbImage {
        width: args.width,
        height: args.height,
        pixels: sum.mean(),
    };
    let report = RenderReport {
        flip: reference.as_ref().and_then(|r| output::flip(&image, r)),
        scene: args.scene.clone(),
        method: args.method,
        device: if gpu.is_some() { "gpu" } else { "cpu" },
        threads: rayon::current_num_threads(),
        adapter: gpu.as_deref().map(GpuTracer::adapter_name),
        gpu_timing: gpu.as_deref().map(|g| g.timing_of(args.method)),
        adapter_type: gpu
            .as_deref()
            .map(|g| format!("{:?}", g.adapter_info().device_type)),
        gpu_warm_up_frames,
        triangles: scene.bvh.triangles.len(),
        width: args.width,
        height: args.height,
        spp: args.spp,
        frames: args.frames,
        ramp_frames: args.ramp_frames,
        mcpg_emission_samples: (args.method == Method::Mcpg).then_some(args.mcpg_emission_samples),
        mcpg_emission_allocation: (args.method == Method::Mcpg)
            .then_some(args.mcpg_emission_allocation),
        mcpg_emission_per_depth: match (&guide, gpu.as_deref()) {
            _ if args.method != Method::Mcpg => None,
            (CpuGuide::Mcpg(_, _, e), _) => Some(e.per_depth()),
            (_, Some(g)) => Some(g.mcpg_emission_per_depth()),
            _ => None,
        }
        .map(|k| k[..(args.bounces as usize).min(k.len())].to_vec()),
        bounces: args.bounces,
        seed: args.seed,
        frame_cpu_times_s: if times.cpu.len() == times.frame.len() {
            times.cpu
        } else {
            Vec::new()
        },
        frame_times_s: times.frame,
        end_frame_times_s: times.end_frame,
        reference: args.reference.clone(),
        reference_own_error,
        errors: errs,
        frame_errors: frame_errs,
        probe_rays_per_frame: times.probe_rays,
        probe_count,
        dynamic: states.map(SceneStates::finish),
        warnings,
    };
    let variance = spread
        .and_then(|s| s.variance_of_mean())
        .map(|pixels| RgbImage {
            width: args.width,
            height: args.height,
            pixels,
        });
    Ok(Rendered {
        image,
        variance,
        report,
        guide: match guide {
            CpuGuide::Mcpg(g, ..) => Some(Arc::new(*g)),
            CpuGuide::None | CpuGuide::Mcmm(_) | CpuGuide::Probes(_) => None,
        },
        frames: kept,
    })
}

/// The per-state references of `--reference-spp`, or `None` without it.
fn scene_states(file: &SceneFile, args: &RenderArgs) -> Result<Option<SceneStates>> {
    let Some(spp) = args.probes.reference_spp else {
        return Ok(None);
    };
    if args.reference.is_some() {
        return Err("give --reference or --reference-spp, not both".into());
    }
    let settings = ReferenceSettings {
        width: args.width,
        height: args.height,
        spp,
        bounces: args.probes.reference_bounces,
    };
    let threshold = args.probes.event_error_threshold;
    Ok(Some(SceneStates::new(
        file,
        args.frames,
        settings,
        &args.out,
        threshold,
    )?))
}

/// The tracer's settings from the command's arguments, once they are checked to go together.
fn render_settings(args: &RenderArgs) -> Result<RenderSettings> {
    if args.method == Method::Mcmm && args.bounces != 1 {
        return Err(format!(
            "--method mcmm guides direct light only: use --bounces 1 (got {})",
            args.bounces
        )
        .into());
    }
    Ok(RenderSettings {
        width: args.width,
        height: args.height,
        spp: args.spp,
        bounces: args.bounces,
        seed: (args.seed ^ (args.seed >> 32)) as u32,
        method: args.method,
    })
}

/// What the frame loop of [`render`] collects besides the times: the errors of the running
/// mean and of each frame, and the kept frames.
#[derive(Default)]
struct Collected {
    errs: Vec<Errors>,
    frame_errs: Vec<Errors>,
    kept: Vec<(u32, RgbImage)>,
}

impl Collected {
    /// Keeps frame `frame`'s `image` (of the size `args` give).
    fn keep(&mut self, frame: u32, args: &RenderArgs, image: Vec<Vec3>) {
        let (width, height) = (args.width, args.height);
        let pixels = image;
        self.kept.push((
            frame,
            RgbImage {
                width,
                height,
                pixels,
            },
        ));
    }
}

/// The running mean of a render's frames, frame i weighted by [`frame_weight`]`(i, ramp)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    sum: Vec<Vec3>,
    weight: f32,
    ramp: u32,
}

impl Accumulation {
    /// No frames yet, over `pixels` pixels, with the warm-up ramp `ramp`.
    #[must_use]
    pub fn new(pixels: usize, ramp: u32) -> Self {
        Self {
            sum: vec![Vec3::ZERO; pixels],
            weight: 0.0,
            ramp,
        }
    }

    /// Adds frame `frame`'s image (of the accumulation's size) with its weight.
    pub fn add(&mut self, frame: u32, image: &[Vec3]) {
        let w = frame_weight(frame, self.ramp);
        for (s, p) in self.sum.iter_mut().zip(image) {
            *s += *p * w;
        }
        self.weight += w;
    }

    /// The weighted mean Σ w_i X_i / Σ w_i of the frames added (zeros before the first).
    #[must_use]
    pub fn mean(&self) -> Vec<Vec3> {
        let scale = if self.weight > 0.0 {
            1.0 / self.weight
        } else {
            0.0
        };
        self.sum.iter().map(|s| *s * scale).collect()
    }
}

/// Adds frame `frame`'s `image` to `sum` and, with a reference, the errors of the running
/// mean and of the frame alone to `collected`; with per-state references, the frame's errors
/// against its state's reference.
fn accumulate(
    sum: &mut Accumulation,
    image: &[Vec3],
    frame: u32,
    (reference, states): (Option<&RgbImage>, Option<&mut SceneStates>),
    collected: &mut Collected,
) {
    let Collected {
        errs, frame_errs, ..
    } = collected;
    if let Some(s) = states {
        frame_errs.extend(s.frame_errors(frame, image));
    }
    sum.add(frame, image);
    if let Some(r) = reference {
        errs.extend(errors(&sum.mean(), &r.pixels));
        frame_errs.extend(errors(image, &r.pixels));
    }
}

/// The reference of `--reference`, checked to have the render's size.
fn read_reference(args: &RenderArgs) -> Result<Option<RgbImage>> {
    let Some(path) = &args.reference else {
        return Ok(None);
    };
    let r = RgbImage::read_exr(path)?;
    if (r.width, r.height) != (args.width, args.height) {
        return Err(format!(
            "{}: the reference is {}×{}, the render {}×{}",
            path.display(),
            r.width,
            r.height,
            args.width,
            args.height
        )
        .into());
    }
    Ok(Some(r))
}

/// The reference's own error ([`output::own_error`]) from the variance file beside it
/// ([`output::variance_path`]), `None` without a reference or without that file.
fn read_reference_own_error(
    args: &RenderArgs,
    reference: Option<&RgbImage>,
) -> Result<Option<Errors>> {
    let (Some(path), Some(reference)) = (&args.reference, reference) else {
        return Ok(None);
    };
    let path = output::variance_path(path);
    if !path.exists() {
        return Ok(None);
    }
    let variance = RgbImage::read_exr(&path)?;
    let own = output::own_error(&reference.pixels, &variance.pixels);
    if own.is_none() {
        return Err(format!("{}: not the size of the reference", path.display()).into());
    }
    Ok(own)
}

/// The progress bar of a render (hidden with `--no-progress`).
fn progress_bar(args: &RenderArgs) -> Result<ProgressBar> {
    if args.no_progress {
        return Ok(ProgressBar::hidden());
    }
    let bar = ProgressBar::new(u64::from(args.frames));
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] frame {pos}/{len} ({elapsed}, eta {eta})")
            .map_err(|e| e.to_string())?,
    );
    bar.set_message(format!("{} {}", args.method.name(), args.scene.display()));
    Ok(bar)
}

/// The per-frame times a render measures (see [`RenderReport`]).
#[derive(Default)]
struct FrameTimes {
    frame: Vec<f64>,
    cpu: Vec<f64>,
    end_frame: Vec<f64>,
    probe_rays: Vec<u64>,
}

/// The CPU side of a guided method: its guide, or nothing (`bsdf`, `nee`, or a guide that
/// runs on the GPU).
enum CpuGuide {
    None,
    Mcpg(Box<Guide>, guided::Reflected, Box<EmissionAllocation>),
    Mcmm(McmmRenderer),
    Probes(Box<ProbeGi>),
}

impl CpuGuide {
    /// Probes of the grid of a probe method.
    fn probe_count(&self) -> Option<usize> {
        match self {
            Self::Probes(p) => Some(p.shading().texels.grid().probe_count()),
            Self::None | Self::Mcpg(..) | Self::Mcmm(_) => None,
        }
    }
}

/// MCPG's configuration for `args` on `scene`: [`guide_config`], without the irradiance
/// cache under `--no-irradiance-cache`, N_c from `--mcpg-confidence`, α_min from
/// `--mcpg-alpha-min`, N_mc from `--mcpg-candidates`, the cache's add probability from
/// `--mcpg-cache-add`.
#[must_use]
pub fn mcpg_config(scene: &Scene, args: &RenderArgs) -> GuideConfig {
    let mut config = guide_config(scene, args.width, args.height);
    config.params.confidence_samples = args.mcpg_confidence;
    config.params.fit.alpha_min = args.mcpg_alpha_min;
    config.params.candidates = args.mcpg_candidates;
    if args.no_irradiance_cache {
        config.cache = None;
    }
    if let Some(cache) = &mut config.cache {
        cache.add_probability = args.mcpg_cache_add;
    }
    config
}

/// `mcpg`'s emission-only directions per vertex: `--mcpg-emission-samples`, or none in a scene
/// lit by its environment alone, where they have no emitting triangle to find.
fn emission_samples(args: &RenderArgs, scene: &Scene) -> u32 {
    if scene.emitters.is_empty() {
        0
    } else {
        args.mcpg_emission_samples
    }
}

/// Starts the method's guide on the GPU when `gpu` holds a tracer (under `--device auto`, a
/// guide the GPU cannot run drops `gpu` with a one-line message), else on the CPU.
fn start_guide(
    args: &RenderArgs,
    scene: &Scene,
    gpu: &mut Option<std::sync::MutexGuard<'_, GpuTracer>>,
) -> Result<CpuGuide> {
    let mcmm = || mcmm_params(args.mcmm_score, args.height);
    // `--no-irradiance-cache` keeps its meaning (the guide learns from the emission its rays
    // hit only): no reflected radiance from the path either.
    let reflected = if args.no_irradiance_cache {
        guided::Reflected::Cache
    } else {
        args.mcpg_reflected
    };
    if let Some(g) = gpu.as_deref_mut() {
        let started = match args.method {
            Method::Mcpg | Method::McpgNee => {
                g.set_mcpg_reflected(reflected);
                g.set_mcpg_emission_samples(emission_samples(args, scene));
                g.set_mcpg_emission_allocation(args.mcpg_emission_allocation);
                g.start_mcpg(&mcpg_config(scene, args))
            }
            Method::Mcmm => g.start_mcmm(&mcmm(), args.width, args.height),
            Method::Bsdf | Method::Nee => Ok(()),
            Method::Adgi | Method::AdgiRefill | Method::AdgiBlend | Method::Ddgi => {
                probe_setup(args, scene).and_then(|(grid, seed)| {
                    g.start_probes(args.method, grid, args.probes.probe_rays, seed)
                })
            }
        };
        match started {
            Ok(()) => return Ok(CpuGuide::None),
            Err(e) if args.device == Device::Gpu => {
                return Err(format!("--device gpu: {e}").into());
            }
            Err(e) => {
                let name = args.method.name();
                eprintln!("mcg-demo: {name} cannot run on this GPU ({e}) — rendering on the CPU");
                *gpu = None;
            }
        }
    }
    Ok(match args.method {
        Method::Mcpg | Method::McpgNee => {
            let mut guide = Guide::new(mcpg_config(scene, args))
                .map_err(|e| format!("the MCPG guide: {e:?}"))?;
            guide.set_camera(scene.camera.position);
            CpuGuide::Mcpg(
                Box::new(guide),
                reflected,
                Box::new(EmissionAllocation::new(
                    emission_samples(args, scene),
                    args.mcpg_emission_allocation.into(),
                )),
            )
        }
        Method::Mcmm => CpuGuide::Mcmm(McmmRenderer::new(args.width, args.height, mcmm())?),
        Method::Bsdf | Method::Nee => CpuGuide::None,
        Method::Adgi | Method::AdgiRefill | Method::AdgiBlend | Method::Ddgi => {
            let (grid, seed) = probe_setup(args, scene)?;
            CpuGuide::Probes(Box::new(ProbeGi::new(
                args.method,
                grid,
                args.probes.probe_rays,
                seed,
            )?))
        }
    })
}

/// The probe grid of `--probe-spacing` fitted to `scene` and the probe GI's 32-bit seed of
/// `--seed` (the same on both devices).
fn probe_setup(args: &RenderArgs, scene: &Scene) -> Result<(ProbeGrid, u32)> {
    let grid = fit_grid(scene, args.probes.probe_spacing)
        .map_err(|e| format!("--probe-spacing {}: {e:?}", args.probes.probe_spacing))?;
    Ok((grid, (args.seed ^ (args.seed >> 32)) as u32))
}

/// One frame on the CPU with `guide`; its times go into `times`.
fn cpu_frame(
    scene: &Scene,
    settings: &RenderSettings,
    frame: u32,
    guide: &mut CpuGuide,
    times: &mut FrameTimes,
) -> Result<Vec<Vec3>> {
    let started = Instant::now();
    let cpu_started = process_cpu_seconds();
    let image = match guide {
        CpuGuide::Mcpg(g, reflected, emission) => {
            g.set_camera(scene.camera.position);
            let reflected = *reflected;
            let allocation = &**emission;
            let sampler = || {
                McpgSampler::new(g)
                    .with_reflected(reflected)
                    .with_emission_allocation(allocation)
            };
            let image = render_frame(scene, settings, frame, sampler, || ());
            emission.end_frame();
            let ending = Instant::now();
            g.end_frame();
            times.end_frame.push(ending.elapsed().as_secs_f64());
            image
        }
        CpuGuide::Mcmm(r) => r.render_frame(scene, settings, frame)?,
        CpuGuide::Probes(p) => {
            let image = p.frame(scene, settings, frame)?;
            times.probe_rays.push(p.rays_last_frame());
            image
        }
        CpuGuide::None => render_frame(scene, settings, frame, || BsdfSampler, || ()),
    };
    times.frame.push(started.elapsed().as_secs_f64());
    if let (Some(a), Some(b)) = (cpu_started, process_cpu_seconds()) {
        times.cpu.push(b - a);
    }
    Ok(image)
}

/// CPU seconds (user + system, all threads) this process has used, from the system's
/// process CPU clock (`clock_gettime(CLOCK_PROCESS_CPUTIME_ID)`, nanoseconds, on Linux and
/// macOS; `GetProcessTimes`, 100 ns, on Windows); `None` where the system gives none.
fn process_cpu_seconds() -> Option<f64> {
    cpu_time::ProcessTime::try_now()
        .ok()
        .map(|t| t.as_duration().as_secs_f64())
}

/// The process-wide GPU tracer, created on first use; the error says why there is none.
fn shared_tracer() -> std::result::Result<&'static Mutex<GpuTracer>, &'static String> {
    static TRACER: OnceLock<Result<Mutex<GpuTracer>, String>> = OnceLock::new();
    TRACER
        .get_or_init(|| GpuTracer::new().map(Mutex::new).map_err(|e| e.to_string()))
        .as_ref()
}

/// The adapter of the process-wide GPU tracer (created on first use, as `--device auto`
/// would), or `None` where wgpu finds no adapter.
#[must_use]
pub fn gpu_adapter_info() -> Option<mcg_gpu_backend::wgpu::AdapterInfo> {
    let tracer = shared_tracer().ok()?;
    let tracer = tracer
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    Some(tracer.adapter_info())
}

/// The process-wide GPU tracer for `device` and `method`, created on first use (device
/// creation and shader compilation cost about a second on a software adapter), or `None` for
/// the CPU. `Auto` falls back to the CPU with a one-line message when there is no adapter or
/// the method has no WGSL twin.
///
/// # Errors
/// `--device gpu` without adapter, or with a method the GPU tracer does not have.
fn gpu_tracer(device: Device, method: Method) -> Result<Option<&'static Mutex<GpuTracer>>> {
    if device == Device::Cpu {
        return Ok(None);
    }
    if gpu::method_code(method).is_none() {
        if device == Device::Gpu {
            return Err(format!(
                "--device gpu: the GPU tracer has no method {} yet (use --device cpu)",
                method.name()
            )
            .into());
        }
        eprintln!(
            "mcg-demo: the GPU tracer has no method {} yet — rendering on the CPU",
            method.name()
        );
        return Ok(None);
    }
    match shared_tracer() {
        Ok(tracer) => Ok(Some(tracer)),
        Err(e) if device == Device::Gpu => Err(format!("--device gpu: {e}").into()),
        Err(e) => {
            eprintln!("mcg-demo: no GPU ({e}) — rendering on the CPU");
            Ok(None)
        }
    }
}

/// `mcg-demo render`: renders and writes `<out>/<method>.{exr,png,json}`; returns the paths.
///
/// # Errors
/// As [`render`], and when a file cannot be written.
pub fn run_render(args: &RenderArgs) -> Result<Vec<PathBuf>> {
    let rendered = render(args)?;
    for w in &rendered.report.warnings {
        eprintln!("mcg-demo: {}: {w}", args.scene.display());
    }
    write_outputs(&args.out, &rendered)
}

/// Writes `<dir>/<method>.{exr,png,json}`, the variance of the mean where it was estimated
/// (`<dir>/<method>.variance.exr`, [`Rendered::variance`]: a `nee` render written so serves as
/// a `--reference` whose own error the errors can be corrected for) and the kept frames'
/// `<dir>/<method>_frame<N>.{exr,png}`; returns the paths (the three first).
///
/// # Errors
/// When the folder or a file cannot be written.
pub fn write_outputs(dir: &Path, rendered: &Rendered) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let name = rendered.report.method.name();
    let exr = dir.join(format!("{name}.exr"));
    let png = dir.join(format!("{name}.png"));
    let json = dir.join(format!("{name}.json"));
    rendered.image.write_exr(&exr)?;
    rendered.image.write_png(&png)?;
    let text = serde_json::to_string_pretty(&rendered.report)?;
    std::fs::write(&json, text + "\n")
        .map_err(|e| format!("cannot write {}: {e}", json.display()))?;
    let mut paths = vec![exr, png, json];
    if let Some(variance) = &rendered.variance {
        let path = output::variance_path(&paths[0]);
        variance.write_exr(&path)?;
        paths.push(path);
    }
    for (frame, image) in &rendered.frames {
        let stem = dir.join(format!("{name}_frame{frame}"));
        let (exr, png) = (stem.with_extension("exr"), stem.with_extension("png"));
        image.write_exr(&exr)?;
        image.write_png(&png)?;
        paths.extend([exr, png]);
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--camera` takes six finite numbers, an eye and a target.
    #[test]
    fn camera_argument_is_an_eye_and_a_target() {
        assert_eq!(
            parse_look_at("-1.8, 2.6,2.4,0.5,0.3,-1.2"),
            Ok([Vec3::new(-1.8, 2.6, 2.4), Vec3::new(0.5, 0.3, -1.2)])
        );
        for bad in ["1,2,3,4,5", "1,2,3,4,5,6,7", "1,2,3,4,5,inf", "1,2,3,a,5,6"] {
            assert!(parse_look_at(bad).is_err(), "{bad}");
        }
    }

    /// `--environment` takes three non-negative numbers or a file ending in `.exr` or `.hdr`
    /// (any case), and names both forms when it gets neither.
    #[test]
    fn environment_argument_is_a_radiance_or_a_map() {
        assert_eq!(
            parse_environment("4, 4.5,5.5"),
            Ok(EnvironmentArg::Uniform(Vec3::new(4.0, 4.5, 5.5)))
        );
        for file in ["sky.exr", "dir/Sky.HDR"] {
            assert_eq!(
                parse_environment(file),
                Ok(EnvironmentArg::Map(PathBuf::from(file)))
            );
        }
        for bad in ["1,2", "1,-2,3", "sky.png", "1,NaN,3"] {
            let e = parse_environment(bad).unwrap_err();
            assert!(
                e.contains("R,G,B") || e.contains("non-negative"),
                "{bad}: {e}"
            );
            assert!(e.contains("FILE.exr"), "{bad}: {e}");
        }
    }

    /// The ramp's weights rise as (i + 1)/R to 1 and stay there; R ≤ 1 is the plain mean.
    #[test]
    fn frame_weights_ramp_to_one() {
        let w: Vec<f32> = (0..6).map(|i| frame_weight(i, 4)).collect();
        assert_eq!(w, [0.25, 0.5, 0.75, 1.0, 1.0, 1.0]);
        for i in [0, 1, 7, u32::MAX] {
            assert_eq!(frame_weight(i, 1), 1.0);
            assert_eq!(frame_weight(i, 0), 1.0);
        }
        assert_eq!(frame_weight(u32::MAX, 6), 1.0);
    }

    /// The weighted mean normalises its weights (frames that all equal one image average to
    /// that image: the mean of unbiased frames stays unbiased), equals the plain mean with
    /// R = 1, and weighs the ramp's frames as [`frame_weight`] says.
    #[test]
    fn accumulation_is_the_normalised_weighted_mean() {
        let image = [Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.5, 0.0, 4.0)];
        let mut a = Accumulation::new(2, 6);
        assert_eq!(a.mean(), [Vec3::ZERO; 2]);
        for frame in 0..9 {
            a.add(frame, &image);
            for (m, p) in a.mean().iter().zip(&image) {
                assert!((*m - *p).abs().max_element() < 1e-6, "{frame}: {m} vs {p}");
            }
        }
        let frames = [Vec3::splat(4.0), Vec3::splat(1.0), Vec3::splat(1.0)];
        let mut plain = Accumulation::new(1, 1);
        let mut ramp = Accumulation::new(1, 2);
        for (i, f) in frames.iter().enumerate() {
            plain.add(i as u32, core::slice::from_ref(f));
            ramp.add(i as u32, core::slice::from_ref(f));
        }
        assert_eq!(plain.mean(), [Vec3::splat(2.0)]);
        // (0.5·4 + 1 + 1) / 2.5
        assert_eq!(ramp.mean(), [Vec3::splat(1.6)]);
    }

    /// Every method takes the plain mean unless `--ramp-frames` says otherwise.
    #[test]
    fn ramp_defaults_to_the_plain_mean() {
        use clap::Parser;
        let args = |extra: &[&str]| {
            let mut v = vec!["render", "--scene", "x.gltf"];
            v.extend_from_slice(extra);
            RenderArgs::parse_from(v)
        };
        for m in ["mcpg", "mcpg-nee", "bsdf", "nee"] {
            assert_eq!(args(&["--method", m]).ramp_frames, 1, "{m}");
        }
        let ramped = args(&["--method", "mcpg", "--ramp-frames", "6"]);
        assert_eq!(ramped.ramp_frames, 6);
        assert!(
            RenderArgs::try_parse_from(["render", "--scene", "x", "--ramp-frames", "0"]).is_err()
        );
    }

    /// `RenderArgs::new` is the command line with only `--scene` given, for any path (one that
    /// starts with `-` too, which the parser would take for an option).
    #[test]
    fn new_is_the_command_lines_defaults_for_any_scene() {
        use clap::Parser;
        let parsed = RenderArgs::parse_from(["render", "--scene", "x.gltf"]);
        assert_eq!(
            format!("{:?}", RenderArgs::new("x.gltf")),
            format!("{parsed:?}")
        );
        let odd = RenderArgs::new("-o.gltf");
        assert_eq!(odd.scene, PathBuf::from("-o.gltf"));
        assert_eq!(
            format!("{:?}", RenderArgs::new("x.gltf").out),
            format!("{:?}", odd.out)
        );
    }

    /// `render --help` is written for users: no rustdoc paths or code spans (the struct's and
    /// the enums' doc comments, which cite items like `guided::Reflected`, stay for rustdoc),
    /// every method described, and the options grouped under their headings.
    #[test]
    fn help_speaks_to_users() {
        use clap::CommandFactory;
        let help = RenderArgs::command().render_long_help().to_string();
        for leak in ["`", "::", "[`"] {
            assert!(!help.contains(leak), "{leak:?} in render --help:\n{help}");
        }
        for method in [
            "- bsdf:",
            "- nee:",
            "- mcpg:",
            "- mcpg-nee:",
            "- mcmm:",
            "- adgi:",
        ] {
            assert!(help.contains(method), "{method} missing");
        }
        for heading in [
            "Output and measurement:",
            "Scene:",
            "mcpg and mcpg-nee:",
            "mcmm:",
            "adgi and ddgi:",
        ] {
            assert!(help.contains(heading), "{heading} missing");
        }
        let short = RenderArgs::command().render_help().to_string();
        assert!(short.lines().count() < help.lines().count() / 2);
    }

    /// `--mcpg-candidates` defaults to the paper's N_mc = 5 and takes 1 to the guide's
    /// [`MAX_CANDIDATES`].
    #[test]
    fn candidates_default_to_the_papers_and_stay_in_range() {
        use clap::Parser;
        let parse = |n: Option<&str>| {
            let mut v = vec!["render", "--scene", "x.gltf"];
            if let Some(n) = n {
                v.extend_from_slice(&["--mcpg-candidates", n]);
            }
            RenderArgs::try_parse_from(v).map(|a| a.mcpg_candidates)
        };
        assert_eq!(parse(None).ok(), Some(5));
        assert_eq!(parse(Some("1")).ok(), Some(1));
        assert_eq!(parse(Some("8")).ok(), Some(MAX_CANDIDATES as u32));
        for bad in ["0", "9", "-1", "five"] {
            assert!(parse(Some(bad)).is_err(), "{bad}");
        }
    }
}
