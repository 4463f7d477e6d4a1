//! Section "Guided rendering": the built-in hidden-light room (scene (a)) path traced with
//! `bsdf`, `nee` and `mcpg`, and the many-lights room (scene (b), direct light) with `bsdf`,
//! `nee`, `mcpg` (irradiance cache off) and `mcmm`, at equal samples and at equal time,
//! against a reference.
//!
//! Every render goes through [`render_on`], which takes the device: the CPU tracer always, and
//! the GPU tracer where wgpu finds an adapter ([`devices`]). What the section shows:
//!
//! 1. the images of the three methods after the same number of frames (equal samples), and of
//!    `bsdf` and `nee` after as many frames as fit in the time `mcpg` took (equal time);
//! 2. the relative MSE of the running mean after each frame against the frame count (the
//!    learning curve, MCPG Fig. 5) and against the elapsed time;
//! 3. a table of relMSE and frame time per method and device, with the ratios the issue's
//!    targets name;
//! 4. the guide after the last frame at each pixel's first hit: the mean direction of the
//!    chosen chain state, its concentration κ and the adaptive grid's level (MCPG Fig. 3
//!    right), for scene (a);
//! 5. for scene (b), MCMM's targets and a map of the tiles where `mcmm` or `mcpg` has the
//!    lower error.
//!
//! Each scene is a [`Study`]; [`build`] runs them in turn through the compute
//! (`compute_runs`), figure (`image_figures`, `error_charts`), table (`results_table`) and
//! target (`mcpg_targets`, `mcmm_targets`) steps.
//!
//! The reference is `nee` with many samples per pixel, cached under
//! `<out>/reference/` with its settings and the scene's fingerprint in the file name.
//!
//! FLIP (LDR-FLIP of the tone-mapped images, [`crate::render::output::flip`]) stands beside
//! relMSE in the tables: relMSE weighs the few bright, noisy pixels near a light; FLIP what a
//! viewer sees across the image.

use std::path::{Path, PathBuf};

use glam::Vec3;
use mcg_hashgrid::AdaptiveGrid;
use mcg_markov_guide::mcpg::{BeginUniforms, Guide, Vertex as GuideVertex};

use super::Context;
use crate::Result;
use crate::plot::{self, Axis, LineChart, PALETTE, Series, SeriesLabelPosition};
use crate::render::cpu::Method;
use crate::render::gpu::GpuTiming;
use crate::render::guided::{EMISSION_SAMPLES, MaterialScatter};
use crate::render::output::{self, Errors, RgbImage, srgb_encode};
use crate::render::scene::{SceneFile, frame_time};
use crate::render::{Device, GPU_WARM_UP_S, RenderArgs, Rendered, render};
use crate::report::{Section, Table};

/// The scene of the section: a room lit through a slit around a panel (GI, MCPG's case).
pub const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/hidden_light_room.gltf");

/// The environment variable that overrides [`device_choice`]: `0` renders on the CPU only,
/// `1` on the GPU too wherever wgpu finds an adapter (a slow software one included); unset
/// or any other value: the choice of [`device_choice`].
pub const REPORT_GPU_VAR: &str = "MCG_REPORT_GPU";

/// What a software adapter's share of the full report costs, in frames of scene (a)'s
/// `bsdf` at [`Settings::FULL`] (128², 8 spp, 3 bounces) on that adapter: on the 2-vCPU AMD
/// EPYC VM (Zen 4) lavapipe's frames took 0.077 s and its renders 257 s of the report
/// (6 min 55 s with, 2 min 38 s without it, references cached), ≈ 3 300 frames; on a 2-vCPU
/// Intel Xeon VM (Ice Lake) 0.16-0.20 s a frame and about 12 minutes (≈ 3 600-4 500 frames;
/// the report took 22 min 23 s there with lavapipe and its references to render, 5 min 22 s
/// without lavapipe and with the committed references).
const SOFTWARE_GPU_REPORT_FRAMES: f64 = 3_300.0;

/// The most the full report spends on a software adapter's renders by its prediction
/// (about 3 300 × its measured frame of scene (a)'s `bsdf`), so that the default run stays
/// under 10 minutes on 2 cores: the CPU's own renders take another 2½-4 minutes there.
pub const SOFTWARE_GPU_BUDGET_S: f64 = 300.0;

/// The devices the report renders on, and why the GPU is not among them when an adapter was
/// found ([`device_choice`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceChoice {
    /// The CPU, then the GPU where it takes part.
    pub devices: Vec<Device>,
    /// One sentence for the report and the terminal when an adapter was left out.
    pub note: Option<String>,
}

/// The devices the report's renders run on, decided once per process: the CPU, and the GPU
/// when wgpu finds an adapter. A hardware adapter always takes part. A software one
/// ([`DeviceType::Cpu`](mcg_gpu_backend::wgpu::DeviceType::Cpu), such as lavapipe's
/// llvmpipe, whose WGSL tracer then runs on the CPU's cores at 1.5-2.7× the rayon tracer's
/// wall clock) takes part in the full report only where its share is predicted to fit in
/// [`SOFTWARE_GPU_BUDGET_S`]: four frames of scene (a)'s `bsdf` are timed on it first
/// (about 2 s), since the same 2-core machine type ran lavapipe 2.6× slower on one CPU than
/// another while the rayon tracer differed by 1.25×. In the smaller reports (`--quick`, the
/// tests) it always does. [`REPORT_GPU_VAR`]: `0` leaves the GPU out, `1` takes any adapter.
pub fn device_choice(samples: usize, seed: u64) -> &'static DeviceChoice {
    static CHOICE: std::sync::OnceLock<DeviceChoice> = std::sync::OnceLock::new();
    CHOICE.get_or_init(|| {
        let cpu_only = |note: Option<String>| DeviceChoice {
            devices: vec![Device::Cpu],
            note,
        };
        let forced = std::env::var(REPORT_GPU_VAR).ok();
        if forced.as_deref() == Some("0") {
            return cpu_only(None);
        }
        let Some(info) = crate::render::gpu_adapter_info() else {
            return cpu_only(None);
        };
        let both = DeviceChoice {
            devices: vec![Device::Cpu, Device::Gpu],
            note: None,
        };
        let software = info.device_type == mcg_gpu_backend::wgpu::DeviceType::Cpu;
        if forced.as_deref() == Some("1") || !software || samples < crate::Config::DEFAULT_SAMPLES {
            return both;
        }
        let study = Study::hidden_light(samples);
        let timed = render_on(Device::Gpu, &args(&study, Method::Bsdf, 4, seed, None));
        let frame = match timed {
            Ok(r) => super::median(r.report.frame_times_s[1..].iter().copied()),
            Err(e) => {
                return cpu_only(Some(format!(
                    "The GPU tracer on {} was left out: its timing frames failed ({e}).",
                    info.name
                )));
            }
        };
        let predicted = SOFTWARE_GPU_REPORT_FRAMES * frame;
        if predicted <= SOFTWARE_GPU_BUDGET_S {
            return both;
        }
        cpu_only(Some(format!(
            "The GPU tracer on {name} (a software adapter: its shaders run on this machine's \
             cores) was left out of this report: a frame of scene (a)'s bsdf took it {ms:.0} ms, \
             so its renders would have added about {minutes:.0} minutes, beyond the \
             {budget:.0} the report allows them. `{REPORT_GPU_VAR}=1 cargo run --release -p \
             mcg-demo` includes them; `render --device gpu` renders any scene on it.",
            name = info.name,
            ms = 1e3 * frame,
            minutes = predicted / 60.0,
            budget = SOFTWARE_GPU_BUDGET_S / 60.0,
        )))
    })
}

/// The devices of [`device_choice`] for `ctx`'s report.
pub fn devices(ctx: &Context<'_>) -> Vec<Device> {
    device_choice(ctx.config.samples, ctx.config.seed)
        .devices
        .clone()
}

/// The methods compared on scene (a), in display order: the two a renderer has without a
/// guide, the guide alone (the paper's setting, no light information) and the guide beside
/// light sampling (`mcpg-nee`, mcg's extension).
pub const METHODS: [Method; 4] = [Method::Bsdf, Method::Nee, Method::Mcpg, Method::McpgNee];

/// Scene (b): many small lights of different colours (direct light, MCMM's case).
pub const MANY_LIGHTS_SCENE: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/many_lights_room.gltf");

/// The methods compared on scene (b), in display order.
pub const MANY_LIGHTS_METHODS: [Method; 4] =
    [Method::Bsdf, Method::Nee, Method::Mcpg, Method::Mcmm];

/// The sky room: no lamp, a window onto a uniform sky (its extras name the sky's radiance).
pub const SKY_ROOM_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sky_room.gltf");

/// The sun room: the sky room under a sky with a sun (an environment map its extras name).
pub const SUN_ROOM_SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/sun_room.gltf");

/// The sizes of one run of the section.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// Image width and height in pixels.
    pub size: u32,
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Frames of the equal-samples renders.
    pub frames: u32,
    /// Scattering events per path.
    pub bounces: u32,
    /// Samples per pixel of the reference, per reference frame.
    pub reference_spp: u32,
    /// Frames of the reference.
    pub reference_frames: u32,
}

impl Settings {
    /// The full report: 128 × 128, 8 spp × 64 frames, 3 bounces; the reference 64 spp × 256
    /// frames (16 384 spp, 32× the samples of a measured render).
    ///
    /// A reference's own error adds to every method's relMSE against it (for independent
    /// renders, E[(X − R)²] = E[(X − I)²] + E[(R − I)²]): at 4 096 spp of `nee` it was ≈ 0.003,
    /// a ninth of `mcpg`'s relMSE after 64 frames and a quarter of `nee`'s at equal time, so it
    /// skewed the ratios between methods. At 16 384 spp it is ≈ 0.0008.
    pub const FULL: Self = Self {
        size: 128,
        spp: 8,
        frames: 64,
        bounces: 3,
        reference_spp: 64,
        reference_frames: 256,
    };
    /// `--quick`: 64 × 64, 16 frames.
    pub const QUICK: Self = Self {
        size: 64,
        spp: 8,
        frames: 16,
        bounces: 3,
        reference_spp: 64,
        reference_frames: 32,
    };
    /// Scene (b) in the full report: 64 × 64, 4 spp × 64 frames, direct light (1 bounce);
    /// the reference 128 spp × 16 frames (2 048 spp, 8× the samples of a measured render).
    pub const MANY_LIGHTS: Self = Self {
        size: 64,
        spp: 4,
        frames: 64,
        bounces: 1,
        reference_spp: 128,
        reference_frames: 16,
    };
    /// The sky room in the full report: 64 × 64, 8 spp × 32 frames, 3 bounces; the reference
    /// 64 spp × 32 frames (2 048 spp, 8× the samples of a measured render; its own error is
    /// taken out of the table's net column).
    pub const SKY_ROOM: Self = Self {
        size: 64,
        spp: 8,
        frames: 32,
        bounces: 3,
        reference_spp: 64,
        reference_frames: 32,
    };
    /// Fewer samples than `--quick` (the smoke test): 32 × 32, 4 frames of 2 spp.
    pub const SMOKE: Self = Self {
        size: 32,
        spp: 2,
        frames: 4,
        bounces: 3,
        reference_spp: 16,
        reference_frames: 4,
    };

    /// The settings for a report of `samples` samples per experiment.
    #[must_use]
    pub fn for_samples(samples: usize) -> Self {
        crate::Config::tier(samples, Self::FULL, Self::QUICK, Self::SMOKE)
    }
}

/// Renders `args` on `device` (the seam where the GPU tracer slots in).
///
/// # Errors
/// As [`render`].
pub fn render_on(device: Device, args: &RenderArgs) -> Result<Rendered> {
    render(&RenderArgs {
        device,
        ..args.clone()
    })
}

/// The arguments of one render of the section.
fn args(
    study: &Study,
    method: Method,
    frames: u32,
    seed: u64,
    reference: Option<&Path>,
) -> RenderArgs {
    let s = &study.settings;
    RenderArgs {
        method,
        device: Device::Cpu,
        width: s.size,
        height: s.size,
        spp: s.spp,
        frames,
        bounces: s.bounces,
        seed,
        out: PathBuf::new(),
        reference: reference.map(Path::to_path_buf),
        no_progress: true,
        no_irradiance_cache: !study.mcpg_cache,
        mcpg_emission_samples: study.mcpg_emission,
        ..RenderArgs::new(study.scene)
    }
}

/// The seed of a study's reference render for a report of seed `seed` (independent of the
/// measured renders' streams).
#[must_use]
pub fn reference_seed(seed: u64) -> u64 {
    seed ^ 0x0005_eed0_f7ef
}

/// The file name of `study`'s reference for a report of seed `seed`: scene, size, bounces,
/// samples, the reference's seed and the scene's fingerprint (which keeps a reference of an
/// older version of the scene, a file or map rewritten by `mcg-demo scenes`, from being taken
/// for this one's).
///
/// # Errors
/// When the scene cannot be read or built.
pub fn reference_name(study: &Study, seed: u64) -> Result<String> {
    let s = &study.settings;
    let stem = Path::new(study.scene)
        .file_stem()
        .and_then(|n| n.to_str())
        .unwrap_or("scene");
    let fingerprint = SceneFile::open(study.scene)?.build(0.0)?.fingerprint();
    Ok(format!(
        "{stem}_{0}x{0}_b{1}_nee_{2}spp_seed{3:x}_{fingerprint:016x}.exr",
        s.size,
        s.bounces,
        s.reference_spp * s.reference_frames,
        reference_seed(seed),
    ))
}

/// The cached reference of `study`, copied from the committed ones or rendered when missing
/// (`nee`, [`Settings::reference_spp`] × [`Settings::reference_frames`]); returns its path.
fn reference(ctx: &Context<'_>, study: &Study) -> Result<PathBuf> {
    let s = &study.settings;
    let dir = ctx.out_dir().join("reference");
    let path = dir.join(reference_name(study, ctx.config.seed)?);
    let variance_path = output::variance_path(&path);
    if path.exists() && variance_path.exists() {
        return Ok(path);
    }
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    if copy_committed_reference(&path)? {
        return Ok(path);
    }
    let bar = ctx.progress(1, "guided rendering: reference");
    let mut a = args(
        study,
        Method::Nee,
        s.reference_frames,
        reference_seed(ctx.config.seed),
        None,
    );
    a.spp = s.reference_spp;
    let r = render_on(Device::Cpu, &a)?;
    r.image.write_exr(&path)?;
    r.variance
        .ok_or("the reference has no variance (fewer than two frames)")?
        .write_exr(&variance_path)?;
    bar.finish_and_clear();
    Ok(path)
}

/// The folder of the references committed with the demo: the default report's, named as
/// [`reference_name`] names them.
pub const COMMITTED_REFERENCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/references");

/// Copies the committed reference of `path`'s name and its variance file from
/// [`COMMITTED_REFERENCES`] to `path`, when both are there: a fresh checkout's report then
/// skips rendering them (the hidden-light room's 16 384 spp take 2½-4½ minutes on 2 cores).
/// The name holds the settings and the scene's fingerprint, so a changed scene or size
/// renders its own; `tests/report.rs` checks that the committed files still agree with the
/// `nee` tracer. Returns whether it copied.
///
/// # Errors
/// When a committed file exists but cannot be copied.
fn copy_committed_reference(path: &Path) -> Result<bool> {
    let Some(name) = path.file_name() else {
        return Ok(false);
    };
    let committed = Path::new(COMMITTED_REFERENCES).join(name);
    let committed_variance = output::variance_path(&committed);
    if !(committed.exists() && committed_variance.exists()) {
        return Ok(false);
    }
    for (from, to) in [
        (committed, path.to_path_buf()),
        (committed_variance, output::variance_path(path)),
    ] {
        std::fs::copy(&from, &to)
            .map_err(|e| format!("cannot copy {} to {}: {e}", from.display(), to.display()))?;
    }
    Ok(true)
}

/// One method's renders on one device.
struct Runs {
    method: Method,
    /// `frames` frames.
    equal_samples: Rendered,
    /// As many frames as fit in the time of the slowest method (`None` for that method).
    equal_time: Option<Rendered>,
}

/// The least total CPU time (seconds) that [`frame_costs`] trusts: shorter runs (the tests'
/// small renders) are mostly the threads' start-up and scheduling, and where the system's
/// process clock counts in coarse ticks they read as 0 (which made the equal-time frame count
/// unbounded).
const MIN_CPU_SECONDS: f64 = 0.1;

/// The most frames an equal-time render gets, as a multiple of the equal-samples frames.
const MAX_EQUAL_TIME_FACTOR: u32 = 8;

/// The cost of each frame: its CPU seconds where the frame ran on this machine's cores (the
/// CPU tracer, or a software GPU such as lavapipe), the system reports them (steadier than the
/// wall clock on a shared machine) and they add up to at least [`MIN_CPU_SECONDS`]; else its
/// frame time (on a hardware GPU the timestamp queries' GPU time: its CPU seconds there would
/// be the host's wait for the GPU).
fn frame_costs(r: &Rendered) -> &[f64] {
    if costs_are_cpu(r) {
        &r.report.frame_cpu_times_s
    } else {
        &r.report.frame_times_s
    }
}

/// Whether [`frame_costs`] are CPU seconds.
fn costs_are_cpu(r: &Rendered) -> bool {
    let on_cores = r.report.device == "cpu" || r.report.adapter_type.as_deref() == Some("Cpu");
    on_cores && r.report.frame_cpu_times_s.iter().sum::<f64>() >= MIN_CPU_SECONDS
}

fn cumulative_seconds(r: &Rendered) -> Vec<f64> {
    frame_costs(r)
        .iter()
        .scan(0.0, |t, s| {
            *t += s;
            Some(*t)
        })
        .collect()
}

fn seconds_per_frame(r: &Rendered) -> f64 {
    let t = frame_costs(r);
    t.iter().sum::<f64>() / t.len() as f64
}

fn wall_seconds_per_frame(r: &Rendered) -> f64 {
    let t = &r.report.frame_times_s;
    t.iter().sum::<f64>() / t.len() as f64
}

/// The equal-time render of a method (the equal-samples one for the slowest).
fn equal_time_image(r: &Runs) -> &Rendered {
    r.equal_time.as_ref().unwrap_or(&r.equal_samples)
}

/// The mean relMSE of a single frame's image over the second half of the frames: the error
/// of one frame once the guide has learned (no warm-up, no accumulation).
fn late_frame_error(r: &Rendered) -> f64 {
    let e = &r.report.frame_errors;
    let late = &e[e.len() / 2..];
    late.iter().map(|e| e.rel_mse).sum::<f64>() / late.len() as f64
}

/// A FLIP value for a table (`–` without a reference).
fn format_flip(flip: Option<f64>) -> String {
    flip.map_or_else(|| "–".to_owned(), |f| format!("{f:.4}"))
}

/// Mean seconds of the guide's end of frame (0 without a guide).
fn end_frame_seconds(r: &Rendered) -> f64 {
    let t = &r.report.end_frame_times_s;
    if t.is_empty() {
        0.0
    } else {
        t.iter().sum::<f64>() / t.len() as f64
    }
}

fn last_error(r: &Rendered) -> Errors {
    *r.report
        .errors
        .last()
        .expect("renders with a reference have errors")
}

/// Images side by side, each scaled up `zoom`× (nearest), sRGB-encoded and clipped.
pub(crate) fn image_strip(path: &Path, images: &[&RgbImage], zoom: u32) -> Result<()> {
    let (w, h) = (images[0].width * zoom, images[0].height * zoom);
    let gap = 4;
    let total_w = images.len() as u32 * (w + gap) - gap;
    let mut buffer = vec![255u8; (total_w * h * 3) as usize];
    for (k, image) in images.iter().enumerate() {
        let x0 = k as u32 * (w + gap);
        for y in 0..h {
            for x in 0..w {
                let p = image.pixels[((y / zoom) * image.width + x / zoom) as usize];
                let o = ((y * total_w + x0 + x) * 3) as usize;
                for c in 0..3 {
                    buffer[o + c] = (srgb_encode(p[c]) * 255.0 + 0.5) as u8;
                }
            }
        }
    }
    plot::write_rgb_png(path, &buffer, total_w, h)
}

/// The guide at each pixel's first hit (pixel centres): the chosen state's mean direction,
/// its κ and the adaptive grid's target level; `None` where the pixel sees nothing or no
/// state is stored.
fn guide_picture(guide: &Guide, s: &Settings) -> Result<Vec<Option<(Vec3, f32, u32)>>> {
    let scene = SceneFile::open(SCENE)?.build(frame_time(0))?;
    let grid = AdaptiveGrid::new(guide.config().adaptive).map_err(|e| format!("{e:?}"))?;
    let candidates = guide.params().candidates as usize;
    let mut out = Vec::with_capacity((s.size * s.size) as usize);
    for y in 0..s.size {
        for x in 0..s.size {
            let d = scene
                .camera
                .direction(x as f32 + 0.5, y as f32 + 0.5, s.size, s.size);
            let o = scene.camera.position;
            let Some(hit) = scene.intersect(o, d, 0.0, f32::INFINITY) else {
                out.push(None);
                continue;
            };
            let tri = scene.bvh.triangles[hit.triangle as usize];
            let n = tri.cross().normalize();
            let n = if n.dot(d) < 0.0 { n } else { -n };
            let p = o + hit.t * d;
            let scatter = MaterialScatter {
                material: scene.material_at(&hit),
                normal: n,
                wo: -d,
            };
            // Fixed uniforms: the candidates of the pixel centre's cell, the adaptive grid at
            // the target level (grid < p_adaptive), the reservoir's ξ in the middle.
            let mut k = 0u32;
            let u = BeginUniforms::from_fn(candidates, || {
                k += 1;
                match k % 4 {
                    1 => 0.0,
                    2 => 0.0,
                    3 => (k / 4) as f32 / candidates as f32,
                    _ => 0.5,
                }
            });
            let v = guide.begin(GuideVertex::surface(p, n), scatter, &u);
            let state = v.selected().map(|i| v.candidates()[i]);
            out.push(state.and_then(|st| {
                let dir = (st.mean_target - p).try_normalize()?;
                let r = (1.0 - st.one_minus_mean_cosine).clamp(0.0, 0.9999);
                // Banerjee et al. 2005, eq. 4.4: κ ≈ r̄(3 − r̄²)/(1 − r̄²) for vMF on S².
                let kappa = r * (3.0 - r * r) / (1.0 - r * r);
                Some((dir, kappa, grid.target_level(o.distance(p))))
            }));
        }
    }
    Ok(out)
}

/// A false-colour ramp (dark blue → yellow) of t ∈ [0, 1].
fn ramp(t: f32) -> Vec3 {
    let t = t.clamp(0.0, 1.0);
    Vec3::new(0.05, 0.05, 0.35).lerp(Vec3::new(0.1, 0.7, 0.6), (2.0 * t).min(1.0))
        + Vec3::new(0.9, 0.25, -0.5) * (2.0 * t - 1.0).max(0.0)
}

/// Draws the three guide panels into one strip (linear RGB images, then [`image_strip`]).
fn write_guide_picture(
    path: &Path,
    picture: &[Option<(Vec3, f32, u32)>],
    size: u32,
) -> Result<(f32, f32, u32, u32)> {
    let none = Vec3::splat(0.02);
    let (mut k_lo, mut k_hi, mut l_lo, mut l_hi) = (f32::MAX, 0.0f32, u32::MAX, 0u32);
    for (_, k, l) in picture.iter().flatten() {
        k_lo = k_lo.min(k.max(1e-3));
        k_hi = k_hi.max(*k);
        l_lo = l_lo.min(*l);
        l_hi = l_hi.max(*l);
    }
    // Colours are given linear and sRGB-encoded by image_strip: decode the ramp first.
    let decode = |c: Vec3| c.powf(2.2);
    let panel = |f: &dyn Fn(&(Vec3, f32, u32)) -> Vec3| RgbImage {
        width: size,
        height: size,
        pixels: picture
            .iter()
            .map(|p| p.as_ref().map_or(none, |p| decode(f(p))))
            .collect(),
    };
    let direction = panel(&|(d, _, _)| *d * 0.5 + Vec3::splat(0.5));
    let (lk_lo, lk_hi) = (k_lo.ln(), k_hi.max(k_lo * 1.01).ln());
    let kappa = panel(&|(_, k, _)| ramp((k.max(1e-3).ln() - lk_lo) / (lk_hi - lk_lo)));
    let span = (l_hi.saturating_sub(l_lo)).max(1) as f32;
    let level = panel(&|(_, _, l)| ramp((l - l_lo) as f32 / span));
    image_strip(path, &[&direction, &kappa, &level], 2)?;
    Ok((k_lo, k_hi, l_lo, l_hi))
}

fn format_ratio(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.2}")
    }
}

/// One scene of the section: what is rendered, with which methods and sizes.
#[derive(Clone, Copy, Debug)]
pub struct Study {
    /// Short name, part of the figure and reference file names.
    pub key: &'static str,
    /// The heading's scene name.
    pub title: &'static str,
    /// The glTF file.
    pub scene: &'static str,
    /// The methods compared, in display order.
    pub methods: &'static [Method],
    /// Sizes.
    pub settings: Settings,
    /// Whether `mcpg` uses its irradiance cache.
    pub mcpg_cache: bool,
    /// `mcpg`'s emission-only directions per vertex.
    pub mcpg_emission: u32,
    /// Which targets the study checks.
    pub targets: Targets,
}

/// The targets a study checks ([`Study::targets`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Targets {
    /// Issue 18's `mcpg` targets on scene (a).
    Mcpg,
    /// MCMM's on scene (b).
    Mcmm,
    /// None: the study only shows where each method stands.
    None,
}

impl Study {
    /// Scene (a), the hidden-light room (global illumination, MCPG's case), for `samples`.
    #[must_use]
    pub fn hidden_light(samples: usize) -> Self {
        Self {
            key: "hidden-light",
            title: "Hidden light room",
            scene: SCENE,
            methods: &METHODS,
            settings: Settings::for_samples(samples),
            mcpg_cache: true,
            mcpg_emission: EMISSION_SAMPLES,
            targets: Targets::Mcpg,
        }
    }

    /// Scene (b), the many-lights room, direct light only (MCMM's case), for `samples`: `mcpg`
    /// without its irradiance cache (as MCPG Fig. 8 compares direct light), small images.
    #[must_use]
    pub fn many_lights(samples: usize) -> Self {
        let full = Settings::for_samples(samples) == Settings::FULL;
        let quick = Settings::for_samples(samples) == Settings::QUICK;
        let settings = if full {
            Settings::MANY_LIGHTS
        } else if quick {
            Settings {
                size: 48,
                frames: 32,
                ..Settings::MANY_LIGHTS
            }
        } else {
            Settings {
                size: 32,
                frames: 4,
                reference_spp: 16,
                reference_frames: 4,
                ..Settings::MANY_LIGHTS
            }
        };
        Self {
            key: "many-lights",
            title: "Many-lights room",
            scene: MANY_LIGHTS_SCENE,
            methods: &MANY_LIGHTS_METHODS,
            settings,
            mcpg_cache: false,
            mcpg_emission: 0,
            targets: Targets::Mcmm,
        }
    }

    /// The sky room (light from a uniform sky through a window, no lamp), for `samples`, with
    /// scene (a)'s methods: [`Settings::SKY_ROOM`] in the full report, else the sizes of the
    /// smaller reports.
    #[must_use]
    pub fn sky_room(samples: usize) -> Self {
        Self::through_the_window(samples, "sky-room", "Sky room", SKY_ROOM_SCENE)
    }

    /// The sun room (the sky room under a sky with a sun), as [`Study::sky_room`].
    #[must_use]
    pub fn sun_room(samples: usize) -> Self {
        Self::through_the_window(samples, "sun-room", "Sun room", SUN_ROOM_SCENE)
    }

    /// A room lit through its window, `scene`, for `samples`, with scene (a)'s methods and no
    /// targets: [`Settings::SKY_ROOM`] in the full report, else the sizes of the smaller
    /// reports.
    fn through_the_window(
        samples: usize,
        key: &'static str,
        title: &'static str,
        scene: &'static str,
    ) -> Self {
        let settings = match Settings::for_samples(samples) {
            Settings::FULL => Settings::SKY_ROOM,
            smaller => Settings {
                size: smaller.size.min(48),
                ..smaller
            },
        };
        Self {
            key,
            title,
            scene,
            methods: &METHODS,
            settings,
            mcpg_cache: true,
            mcpg_emission: EMISSION_SAMPLES,
            targets: Targets::None,
        }
    }
}

/// Builds the section: scene (a) with [`METHODS`], then scene (b) with
/// [`MANY_LIGHTS_METHODS`], then the sky room and the sun room with [`METHODS`].
///
/// # Errors
/// When a scene cannot be loaded, a render fails or a file cannot be written.
pub fn build(ctx: &Context<'_>) -> Result<Section> {
    let mut section = Section::new("guided-rendering", "Guided rendering");
    let mut summary = serde_json::Map::new();
    if let Some(note) = &device_choice(ctx.config.samples, ctx.config.seed).note {
        if ctx.config.progress {
            eprintln!("{note}");
        }
        section.paragraph(note);
    }
    let hidden = Study::hidden_light(ctx.config.samples);
    let reference_path = study_section(ctx, &hidden, &mut section, &mut summary)?;
    section.paragraph(&format!(
        "The scene (demo/scenes/hidden_light_room.gltf): a closed room whose only light, 1.2 m \
         square, lies in a 2.2 m tray hung under the ceiling and shines up at it; the tray's rim \
         stops 0.25 m below the ceiling, so the room receives the light only through that slit, \
         after it bounced off the ceiling above the tray. A light sample (nee) from the floor or \
         the walls is occluded; what reaches the camera has scattered at least twice. \
         Paths of {} scattering events, no Russian roulette, no light information for mcpg. \
         mcpg's young chains (fewer than {} samples) lend part of their share to the material \
         and continue after its samples (mcg's extension of MCPG Alg. 2, \
         McpgParams::confidence_samples; `render --mcpg-confidence 0` gives the paper's rule, \
         whose one-sample lobes cost this scene 10-20 % more error and occasional frames of \
         3-5× the usual error), and each chain averages its last ~{:.0} samples (α_min {}, \
         the blend factor of Dittebrandt et al. that MCPG Alg. 3 cites; the MCPG authors' \
         engine value 0.01, `render --mcpg-alpha-min 0.01`, lets the error climb back by \
         15-20 % after 32 frames here). \
         mcpg's chains learn the radiance reflected at the next hit from the path's own \
         estimate wherever the path went on, and from the irradiance cache only at a path's \
         last vertex (mcg's extension; `render --mcpg-reflected cache` is the paper's rule, \
         which finishes a vertex as soon as its ray is traced; the GPU tracer holds a path's \
         vertices for it, up to 3 bounces, and the first two of deeper paths), and one vertex in {} adds its sample to the cache \
         (`--mcpg-cache-add 1` adds all): on the CPU together a guided frame about 15 % \
         cheaper at the same error, on lavapipe 12 % less error at the same frame time. On \
         both devices, mcpg \
         also draws {} more directions per vertex on average from the guide's mixture that \
         only gather the emission they meet, the emission along each of a vertex's K + 1 \
         directions counting 1/(K + 1) \
         (mcg's extension, still without light information; `render \
         --mcpg-emission-samples 0` gives the paper's one direction): more chances at the \
         light per vertex than nee's one light sample, each costing a sample of the vertex \
         already begun and a walk of the emitters' own small tree, with a shadow ray only \
         where it meets an emitter; drawn from the whole mixture (not only the lobe of the \
         state Alg. 1 chose) with uniforms from a randomly shifted R3 lattice, and spread over \
         the path's depths by each depth's variance measured in the frames before, at the same \
         mean; on the CPU also within a depth, by the variance measured for vertices of like \
         expected contribution (the path's throughput times the guide's own radiance \
         estimate, sum_mc) \
         (`--mcpg-emission-allocation adaptive` spreads by depth only, `uniform` spends as \
         many at every vertex). \
         FLIP is NVIDIA's LDR-FLIP of the sRGB images (the PNGs) at 67 pixels per degree. \
         The reference is cached in {}.",
        hidden.settings.bounces,
        crate::render::guided::CONFIDENCE_SAMPLES,
        1.0 / crate::render::guided::ALPHA_MIN,
        crate::render::guided::ALPHA_MIN,
        (1.0 / crate::render::guided::CACHE_ADD_PROBABILITY).round(),
        EMISSION_SAMPLES,
        reference_path
            .strip_prefix(ctx.out_dir())
            .unwrap_or(&reference_path)
            .display()
    ));
    let by_triangles = cost_by_triangles(ctx, &hidden, &mut section)?;
    summary.insert("cost_by_triangles".to_owned(), by_triangles);
    let many = Study::many_lights(ctx.config.samples);
    let mut many_summary = serde_json::Map::new();
    study_section(ctx, &many, &mut section, &mut many_summary)?;
    section.paragraph(&format!(
        "The scene (demo/scenes/many_lights_room.gltf): a room lit by 24 small lights of \
         different colours on the ceiling and the walls, with a glossy metal block; direct \
         light only ({} scattering event): the case MCMM was made for. mcmm (MCMM, Dittebrandt \
         et al. 2023) keeps one chain per pixel on the screen, discovers lights from its \
         neighbours (Alg. 1), shuffles the 64 chains of each 8 × 8 tile by a random xor mask (the paper's tile is a \
         subgroup of 32; 64 chains hold lobes for more of the lights) \
         and weights each sample by the tile's mixture density (spatial SMIS, eq. 9); its \
         chains are scored by that mixture density (an extension of the paper, see \
         mcg_markov_guide::mcmm::ScoreDensity), its defensive technique is the material's \
         sampling with p_h = 0.5 (the paper's 0.2 leaves the lights no lobe of a tile covers \
         at a fifth of the BSDF's density), its lobes' prior has mean cosine 0.9 (young lobes \
         as narrow as a small light, so the chains warm up twice as fast as with the paper's \
         uninformed prior) and Alg. 1 draws neighbours from a window of 0.75 × the image \
         height (see mcg_demo::render::mcmm). mcpg runs without its irradiance cache, as MCPG Fig. 8 \
         compares on direct light (with the young-chain confidence of scene (a): the paper's rule \
         degrades over the frames here, to about 4× this error). Neither guide knows where \
         the lights are; nee does. \
         Where each wins: here, direct light from many small lights, mcmm pools the lobes of \
         a tile's 64 chains for every pixel of the tile, while mcpg's cells learn only from \
         the emission their own rays happen to hit, so mcmm wins most tiles of the map; \
         mcpg's case is scene (a), light that \
         arrives after scattering, which mcmm (direct light only) does not render at all.",
        many.settings.bounces
    ));
    summary.insert("many_lights_room".to_owned(), many_summary.into());
    let sky = Study::sky_room(ctx.config.samples);
    let mut sky_summary = serde_json::Map::new();
    study_section(ctx, &sky, &mut section, &mut sky_summary)?;
    section.paragraph(&format!(
        "The scene (demo/scenes/sky_room.gltf): the rooms' shell without a lamp; a 0.6 m × \
         0.8 m window high in the right wall, out of view, opens onto a uniform sky, which \
         the file's extras name (`render --environment R,G,B` gives any file one), together \
         with the window as a portal. All light enters through the window. nee aims its light \
         samples of the sky at uniform points of the window, as a renderer that knows its \
         openings does (`render --no-portals` turns that off: its samples are then \
         cosine-distributed and find the window as rarely as the material's); mcpg's lobes \
         must learn where the window is. {} scattering events. Where each wins: nee, by far — \
         at 128 × 128 and 64 frames (markov-guide/benches/README.md) it has 1/100 of mcpg's \
         error at equal samples, and mcpg-nee 0.9× nee's at twice its frame time. Without the \
         portal the order turns: mcpg-nee 0.47× and mcpg 0.68× nee's error at equal samples, \
         mcpg-nee 0.96× at equal time on the CPU. Guiding pays where the renderer does not know \
         where the light comes in.",
        sky.settings.bounces
    ));
    summary.insert("sky_room".to_owned(), sky_summary.into());
    let sun = Study::sun_room(ctx.config.samples);
    let mut sun_summary = serde_json::Map::new();
    study_section(ctx, &sun, &mut section, &mut sun_summary)?;
    section.paragraph(&format!(
        "The scene (demo/scenes/sun_room.gltf): the sky room under a sky with a sun, an \
         equirectangular environment map (demo/scenes/sun_room_sky.hdr, which the file's \
         extras name; `render --environment sky.exr` or `.hdr` gives any file one) whose sun, \
         30° high, shines through the window onto the floor at the foot of the left box. nee \
         samples the map in proportion to its luminance, as renderers do for environment \
         maps: most of its samples go to the sun, and from most of the room the walls block \
         them. {} scattering events. Where each wins (at 128 × 128 and 64 frames, \
         markov-guide/benches/README.md): nee at equal time; at equal samples mcpg-nee is \
         within ±20 % of nee (0.83× on the CPU, 1.00× on the GPU there; a single run of this \
         sun swings that much) at twice nee's frame time; mcpg, without light samples, has \
         12-21× nee's error, most of it from its first frame, which an empty guide renders \
         with bsdf's fireflies (bsdf: about 600×; `render --ramp-frames 6` brings mcpg to \
         2.3×). A guide of the light samples' own directions, which learns which sun samples \
         the walls block, is what this case asks for; MCPG guides the material's.",
        sun.settings.bounces
    ));
    summary.insert("sun_room".to_owned(), sun_summary.into());
    std::fs::write(
        ctx.figure_path("guided-rendering.json"),
        serde_json::to_string_pretty(&serde_json::Value::Object(summary))? + "\n",
    )
    .map_err(|e| format!("cannot write guided-rendering.json: {e}"))?;
    Ok(section)
}

/// The subdivisions (`render --subdivide`) of [`cost_by_triangles`] for `samples`: the file
/// as it is, and split into 4^L triangles per non-emitting triangle.
fn subdivisions(samples: usize) -> &'static [u32] {
    crate::Config::tier(samples, &[0, 3, 5], &[0, 3], &[0, 1])
}

/// The frames [`cost_by_triangles`] renders per method; the first is not counted.
const COST_FRAMES: u32 = 5;

/// What a frame of each method costs as `study`'s scene grows: its triangles that emit
/// nothing split into 4^L ([`subdivisions`]), so the image stays the same in expectation
/// while every ray walks a larger tree. A table per device in `section`; returns the numbers
/// for the summary.
fn cost_by_triangles(
    ctx: &Context<'_>,
    study: &Study,
    section: &mut Section,
) -> Result<serde_json::Value> {
    let levels = subdivisions(ctx.config.samples);
    let devices = devices(ctx);
    let bar = ctx.progress(
        (levels.len() * study.methods.len() * devices.len()) as u64,
        "guided rendering: cost by triangles",
    );
    let s = &study.settings;
    let mut header = vec!["device".to_owned(), "triangles".to_owned()];
    header.extend(study.methods.iter().map(|m| m.name().to_owned()));
    let mut table = Table::new(
        &format!(
            "Frame cost of each method as the {title}'s surfaces are split into more triangles \
             (`render --subdivide L`: 4^L per triangle, the emitters as they are; the same \
             image in expectation): median of frames 2-{COST_FRAMES} at {size} × {size}, {spp} \
             spp, {bounces} scattering events; in brackets ÷ bsdf's. CPU: CPU seconds; GPU: \
             its frame times.",
            title = study.title.to_lowercase(),
            size = s.size,
            spp = s.spp,
            bounces = s.bounces
        ),
        header,
    );
    let mut rows = Vec::new();
    for device in devices {
        for &level in levels {
            let mut costs = Vec::new();
            let (mut device_name, mut triangles) = ("", 0);
            for &method in study.methods {
                let mut a = args(study, method, COST_FRAMES, ctx.config.seed, None);
                a.subdivide = level;
                let r = render_on(device, &a)?;
                bar.inc(1);
                device_name = r.report.device;
                triangles = r.report.triangles;
                costs.push((method, super::median(frame_costs(&r)[1..].iter().copied())));
            }
            let bsdf = costs
                .iter()
                .find(|(m, _)| *m == Method::Bsdf)
                .map_or(f64::NAN, |c| c.1);
            let mut row = vec![device_name.to_owned(), triangles.to_string()];
            row.extend(
                costs
                    .iter()
                    .map(|(_, c)| format!("{:.1} ms ({}×)", 1e3 * c, format_ratio(c / bsdf))),
            );
            table.push_row(row);
            rows.push(serde_json::json!({
                "device": device_name,
                "subdivide": level,
                "triangles": triangles,
                "seconds_per_frame": costs
                    .iter()
                    .map(|(m, c)| (m.name().to_owned(), serde_json::json!(c)))
                    .collect::<serde_json::Map<_, _>>(),
            }));
        }
    }
    bar.finish_and_clear();
    section.table(table);
    section.paragraph(
        "The frame target (issue: an mcpg frame at most 1.5× a bsdf frame) is measured on the \
         room as committed, whose rays are nearly free: there the guide's work per vertex \
         (five hashed state reads, the lobes, the emission-only directions, the store) is \
         most of an mcpg frame. As a scene grows its rays cost more and the guide's own work \
         per vertex does not (mcpg's frames grow too: they trace the same paths, and shadow \
         rays behind the emission-only directions that meet a light). The rows above split \
         the same surfaces into more triangles to show where an mcpg frame stands against \
         bsdf's once rays cost what they cost in a scene of that size.",
    );
    Ok(serde_json::Value::Array(rows))
}

/// Renders `study` on every device of [`devices`] and adds its headings, figures, table and
/// targets to `section` and its numbers to `summary` (per device); returns the reference's
/// path.
fn study_section(
    ctx: &Context<'_>,
    study: &Study,
    section: &mut Section,
    summary: &mut serde_json::Map<String, serde_json::Value>,
) -> Result<PathBuf> {
    let reference_path = reference(ctx, study)?;
    let reference = RgbImage::read_exr(&reference_path)?;
    for device in devices(ctx) {
        let (runs, budget, slowest) = compute_runs(ctx, study, device, &reference_path)?;
        let device_name = runs[0].equal_samples.report.device;
        let clock = if runs.iter().all(|r| costs_are_cpu(&r.equal_samples)) {
            "CPU seconds (all threads)".to_owned()
        } else if runs
            .iter()
            .all(|r| r.equal_samples.report.gpu_timing == Some(GpuTiming::Timestamps))
        {
            if runs
                .iter()
                .any(|r| r.equal_samples.report.gpu_warm_up_frames > Some(0))
            {
                format!(
                    "GPU seconds (timestamp queries, after {GPU_WARM_UP_S} s of untimed frames)"
                )
            } else {
                "GPU seconds (timestamp queries)".to_owned()
            }
        } else {
            "seconds (wall clock)".to_owned()
        };
        let id = |name: &str| format!("guided-rendering-{}-{device_name}-{name}.png", study.key);
        section.heading(&format!("{} on the {device_name}", study.title));
        image_figures(ctx, section, study, &runs, &reference, budget, &clock, &id)?;
        error_charts(ctx, section, study, &runs, budget, &clock, &id)?;
        let (table, mut device_summary) = results_table(study, &runs, budget, slowest, &clock);
        section.table(table);
        let targets = match study.targets {
            Targets::Mcmm => Some(mcmm_targets(ctx, section, study, &runs, &reference, &id)?),
            Targets::Mcpg => Some(mcpg_targets(section, &runs)),
            Targets::None => None,
        };
        if let Some(targets) = targets {
            device_summary.insert("targets".to_owned(), targets);
        }
        summary.insert(device_name.to_owned(), device_summary.into());
        let mcpg = find(&runs, Method::Mcpg);
        if let Some(guide) = mcpg
            .equal_samples
            .guide
            .as_ref()
            .filter(|_| study.mcpg_cache)
        {
            guide_figure(ctx, section, guide, &study.settings, &id)?;
        }
    }
    Ok(reference_path)
}

/// The run of `method`.
fn find(runs: &[Runs], method: Method) -> &Runs {
    runs.iter().find(|r| r.method == method).expect("method")
}

/// The equal-samples renders of every method, then the equal-time renders (as many frames as
/// fit in the slowest method's total cost); the runs, that budget and the slowest method.
fn compute_runs(
    ctx: &Context<'_>,
    study: &Study,
    device: Device,
    reference_path: &Path,
) -> Result<(Vec<Runs>, f64, Method)> {
    let s = &study.settings;
    let seed = ctx.config.seed;
    let bar = ctx.progress(
        2 * study.methods.len() as u64 - 1,
        &format!("guided rendering: {}", study.key),
    );
    let mut runs: Vec<Runs> = Vec::new();
    for &method in study.methods {
        let r = render_on(
            device,
            &args(study, method, s.frames, seed, Some(reference_path)),
        )?;
        bar.inc(1);
        runs.push(Runs {
            method,
            equal_samples: r,
            equal_time: None,
        });
    }
    let budget = runs
        .iter()
        .map(|r| frame_costs(&r.equal_samples).iter().sum::<f64>())
        .fold(0.0, f64::max);
    let slowest = runs
        .iter()
        .max_by(|a, b| {
            seconds_per_frame(&a.equal_samples).total_cmp(&seconds_per_frame(&b.equal_samples))
        })
        .map(|r| r.method)
        .expect("methods");
    for run in &mut runs {
        if run.method == slowest {
            continue;
        }
        let per_frame = seconds_per_frame(&run.equal_samples).max(1e-9);
        let frames = ((budget / per_frame).round() as u32)
            .clamp(1, MAX_EQUAL_TIME_FACTOR * study.settings.frames);
        run.equal_time = Some(render_on(
            device,
            &args(
                study,
                run.method,
                frames,
                seed ^ 0xe07e,
                Some(reference_path),
            ),
        )?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok((runs, budget, slowest))
}

/// The methods' names joined for captions ("bsdf, nee, mcpg").
fn method_list(study: &Study) -> String {
    study
        .methods
        .iter()
        .map(|m| m.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The equal-samples and equal-time image strips.
#[allow(clippy::too_many_arguments)]
fn image_figures(
    ctx: &Context<'_>,
    section: &mut Section,
    study: &Study,
    runs: &[Runs],
    reference: &RgbImage,
    budget: f64,
    clock: &str,
    id: &dyn Fn(&str) -> String,
) -> Result<()> {
    let s = &study.settings;
    let zoom = (256 / s.size).max(1);
    let mut images: Vec<&RgbImage> = runs.iter().map(|r| &r.equal_samples.image).collect();
    images.push(reference);
    image_strip(&ctx.figure_path(&id("equal-samples")), &images, zoom)?;
    let mut images: Vec<&RgbImage> = runs.iter().map(|r| &equal_time_image(r).image).collect();
    images.push(reference);
    image_strip(&ctx.figure_path(&id("equal-time")), &images, zoom)?;
    let methods = method_list(study);
    section.figure(
        &id("equal-samples"),
        &format!(
            "Equal samples ({} frames × {} spp): {methods}, and the reference ({} spp of nee), \
             left to right. sRGB, clipped at 1.",
            s.frames,
            s.spp,
            s.reference_spp * s.reference_frames
        ),
    );
    section.figure(
        &id("equal-time"),
        &format!(
            "Equal time ({budget:.1} {clock} each): {methods}, and the reference, left to right."
        ),
    );
    Ok(())
}

/// The colour of a method in the charts.
fn colour(m: Method) -> plot::RGBColor {
    match m {
        Method::Bsdf => PALETTE[0],
        Method::Nee => PALETTE[2],
        Method::Mcpg => PALETTE[1],
        Method::Mcmm => PALETTE[3],
        Method::McpgNee => PALETTE[4],
        Method::Ddgi => PALETTE[5],
        Method::Adgi => PALETTE[3],
        Method::AdgiRefill => PALETTE[1],
        Method::AdgiBlend => PALETTE[0],
    }
}

/// The log axis of relMSE spanning every error of `runs` (whole decades).
fn error_axis(runs: &[Runs]) -> Axis {
    let all_errors = runs
        .iter()
        .flat_map(|r| {
            std::iter::once(&r.equal_samples)
                .chain(&r.equal_time)
                .flat_map(|x| x.report.errors.iter().map(|e| e.rel_mse))
        })
        .filter(|e| *e > 0.0 && e.is_finite());
    let (lo, hi) = all_errors.fold((f64::MAX, 0.0f64), |(lo, hi), e| (lo.min(e), hi.max(e)));
    Axis::log10(
        "relative MSE of the running mean",
        10f64.powf(lo.log10().floor())..10f64.powf(hi.log10().ceil()),
    )
}

/// The learning curve (error against frame) and the error against time.
fn error_charts(
    ctx: &Context<'_>,
    section: &mut Section,
    study: &Study,
    runs: &[Runs],
    budget: f64,
    clock: &str,
    id: &dyn Fn(&str) -> String,
) -> Result<()> {
    let s = &study.settings;
    let device_name = runs[0].equal_samples.report.device;
    let y = error_axis(runs);
    let curve = |r: &Rendered, x: Vec<f64>| -> Vec<(f64, f64)> {
        x.into_iter()
            .zip(r.report.errors.iter().map(|e| e.rel_mse))
            .collect()
    };
    let per_frame = LineChart {
        title: format!("Learning curve ({device_name}, {} spp per frame)", s.spp),
        x: Axis::linear("frame", 1.0..f64::from(s.frames)),
        y: y.clone(),
        series: runs
            .iter()
            .map(|r| {
                let frames = (1..=r.equal_samples.report.errors.len())
                    .map(|i| i as f64)
                    .collect();
                Series::line(
                    r.method.name(),
                    colour(r.method),
                    curve(&r.equal_samples, frames),
                )
            })
            .collect(),
        legend: SeriesLabelPosition::UpperRight,
    };
    plot::line_chart(&ctx.figure_path(&id("per-frame")), (720, 420), &per_frame)?;
    let first = runs
        .iter()
        .map(|r| frame_costs(&r.equal_samples)[0].max(1e-3))
        .fold(f64::MAX, f64::min);
    let per_time = LineChart {
        title: format!("Error against time ({device_name})"),
        x: Axis::log10(
            clock,
            10f64.powf(first.log10().floor())..10f64.powf(budget.log10().ceil()),
        ),
        y,
        series: runs
            .iter()
            .map(|r| {
                let longest = equal_time_image(r);
                Series::line(
                    r.method.name(),
                    colour(r.method),
                    curve(longest, cumulative_seconds(longest)),
                )
            })
            .collect(),
        legend: SeriesLabelPosition::UpperRight,
    };
    plot::line_chart(&ctx.figure_path(&id("per-time")), (720, 420), &per_time)?;
    section.figure(
        &id("per-frame"),
        "Relative MSE of the running mean after each frame (the learning curve of MCPG \
         Fig. 5). The guides start as plain BSDF sampling — they are empty — and pull away as \
         their chains find the light.",
    );
    section.figure(
        &id("per-time"),
        &format!("The same errors against the tracing cost ({clock}), equal-time runs."),
    );
    Ok(())
}

/// The table of relMSE and cost per method (ratios against the study's guide: `mcmm` where
/// it runs, else `mcpg`), and the same numbers for the JSON summary.
fn results_table(
    study: &Study,
    runs: &[Runs],
    budget: f64,
    slowest: Method,
    clock: &str,
) -> (Table, serde_json::Map<String, serde_json::Value>) {
    let device_name = runs[0].equal_samples.report.device;
    let guide = if study.methods.contains(&Method::Mcmm) {
        Method::Mcmm
    } else {
        Method::Mcpg
    };
    let g = find(runs, guide);
    let (g_error, g_late) = (
        last_error(&g.equal_samples).rel_mse,
        late_frame_error(&g.equal_samples),
    );
    let own = reference_own_rel_mse(runs);
    let mut table = results_header(study, device_name, guide, (budget, slowest, clock), own);
    let mut summary = serde_json::Map::new();
    for r in runs {
        let es = last_error(&r.equal_samples).rel_mse;
        let et_run = equal_time_image(r);
        let et = last_error(et_run).rel_mse;
        let late = late_frame_error(&r.equal_samples);
        table.push_row([
            r.method.name().to_owned(),
            device_name.to_owned(),
            format!("{:.1}", 1e3 * wall_seconds_per_frame(&r.equal_samples)),
            format!("{:.1}", 1e3 * seconds_per_frame(&r.equal_samples)),
            format!("{es:.4}"),
            format_ratio(es / g_error),
            format_flip(r.equal_samples.report.flip),
            et_run.report.frames.to_string(),
            format!("{et:.4}"),
            format_ratio(et / g_error),
            format_flip(et_run.report.flip),
            format!("{late:.4}"),
            format_ratio(late / g_late),
            format!("{:.1}", 1e3 * end_frame_seconds(&r.equal_samples)),
        ]);
        summary.insert(
            r.method.name().to_owned(),
            serde_json::json!({
                "cost_seconds_per_frame": seconds_per_frame(&r.equal_samples),
                "wall_seconds_per_frame": wall_seconds_per_frame(&r.equal_samples),
                "cost_clock": clock,
                "rel_mse_equal_samples": es,
                "rmse_equal_samples": last_error(&r.equal_samples).rmse,
                "flip_equal_samples": r.equal_samples.report.flip,
                "flip_equal_time": et_run.report.flip,
                "frames_equal_time": et_run.report.frames,
                "rel_mse_equal_time": et,
                "late_frame_rel_mse": late,
                "end_frame_seconds": end_frame_seconds(&r.equal_samples),
            }),
        );
    }
    (table, summary)
}

/// The empty results table: its caption (device, settings, cost clock, equal-time budget) and
/// its columns, with ratios to the `guide` method.
fn results_header(
    study: &Study,
    device_name: &str,
    guide: Method,
    (budget, slowest, clock): (f64, Method, &str),
    own: f64,
) -> Table {
    let s = &study.settings;
    let per = format!("÷ {}", guide.name());
    Table::new(
        &format!(
            "{device_name}, {0}×{0}, {1} bounces, {2} spp per frame; relMSE of the mean \
             against the reference (which carries the reference's own, {7:.5}); cost = {6}; \
             equal time = the {3:.1} s that {4} took for {5} frames",
            s.size,
            s.bounces,
            s.spp,
            budget,
            slowest.name(),
            s.frames,
            clock,
            own
        ),
        [
            "method",
            "device",
            "ms per frame (wall)",
            "cost per frame, ms",
            "relMSE, equal samples",
            &per,
            "FLIP, equal samples",
            "frames in equal time",
            "relMSE, equal time",
            &per,
            "FLIP, equal time",
            "relMSE of one late frame",
            &per,
            "of which end_frame, ms",
        ],
    )
}

/// The relMSE of `m`'s mean, at equal samples or at equal time.
fn error_of(runs: &[Runs], m: Method, equal_time: bool) -> f64 {
    let r = find(runs, m);
    last_error(if equal_time {
        equal_time_image(r)
    } else {
        &r.equal_samples
    })
    .rel_mse
}

/// The reference's own relMSE ([`output::own_error`]) that every error measured against it
/// carries, 0 where its variance file is missing.
fn reference_own_rel_mse(runs: &[Runs]) -> f64 {
    runs[0]
        .equal_samples
        .report
        .reference_own_error
        .map_or(0.0, |e| e.rel_mse)
}

/// The paragraph of MCPG's targets (scene (a)); their numbers.
fn mcpg_targets(section: &mut Section, runs: &[Runs]) -> serde_json::Value {
    let ratio_samples = error_of(runs, Method::Mcpg, false) / error_of(runs, Method::Bsdf, false);
    let mcpg_et = error_of(runs, Method::Mcpg, true);
    let (vs_bsdf, vs_nee) = (
        mcpg_et / error_of(runs, Method::Bsdf, true),
        mcpg_et / error_of(runs, Method::Nee, true),
    );
    let time_of = |m: Method| seconds_per_frame(&find(runs, m).equal_samples);
    let late_of = |m: Method| late_frame_error(&find(runs, m).equal_samples);
    // The same ratios with the reference's own error taken out of every relMSE.
    let own = reference_own_rel_mse(runs);
    let net = |m: Method, equal_time: bool| error_of(runs, m, equal_time) - own;
    let net_samples = net(Method::Mcpg, false) / net(Method::Bsdf, false);
    let (net_bsdf, net_nee) = (
        net(Method::Mcpg, true) / net(Method::Bsdf, true),
        net(Method::Mcpg, true) / net(Method::Nee, true),
    );
    section.paragraph(&format!(
        "Targets (issue: mcpg relMSE ≤ ¼ of bsdf at equal samples, below both at equal \
         time): mcpg ÷ bsdf at equal samples = {ratio_samples:.3}; at equal time mcpg ÷ \
         bsdf = {vs_bsdf:.3}, mcpg ÷ nee = {vs_nee:.3}. Where the time goes: an mcpg frame \
         costs {:.1}× a bsdf frame and {:.1}× a nee frame ({:.1} ms of it the guide's \
         end_frame). Once learned, one late mcpg frame has {:.3}× the relMSE of a bsdf frame \
         and {:.3}× that of a nee frame. The late-frame ratios against the accumulated ones \
         separate the learned guide from its warm-up (the first frames, sampled while the \
         guide is still empty or thin, weigh on the mean); the cost ratio is what equal time \
         charges for the guide.",
        time_of(Method::Mcpg) / time_of(Method::Bsdf),
        time_of(Method::Mcpg) / time_of(Method::Nee),
        1e3 * end_frame_seconds(&find(runs, Method::Mcpg).equal_samples),
        late_of(Method::Mcpg) / late_of(Method::Bsdf),
        late_of(Method::Mcpg) / late_of(Method::Nee),
    ));
    section.paragraph(&format!(
        "Every relMSE above is measured against a reference that has its own noise, and \
         carries it: for independent renders E[(X − R)²] = E[(X − I)²] + Var R, so each \
         method's relMSE against the reference exceeds its relMSE against the true image I by \
         the reference's own, {own:.5} here (estimated from the reference's frames, \
         Σ Var Rₚ/(Rₚ² + ε) over pixels and channels). The same for every method, it weighs \
         most on the lowest errors. Net of it: mcpg ÷ bsdf = {net_samples:.3} at equal samples \
         and {net_bsdf:.3} at equal time, mcpg ÷ nee = {net_nee:.3} at equal time."
    ));
    let mut targets = serde_json::json!({
        "mcpg_over_bsdf_equal_samples": ratio_samples,
        "mcpg_over_bsdf_equal_time": vs_bsdf,
        "mcpg_over_nee_equal_time": vs_nee,
        "reference_own_rel_mse": own,
        "net_of_reference": {
            "mcpg_over_bsdf_equal_samples": net_samples,
            "mcpg_over_bsdf_equal_time": net_bsdf,
            "mcpg_over_nee_equal_time": net_nee,
        },
    });
    if runs.iter().any(|r| r.method == Method::McpgNee) {
        let samples = error_of(runs, Method::McpgNee, false) / error_of(runs, Method::Nee, false);
        let time = error_of(runs, Method::McpgNee, true) / error_of(runs, Method::Nee, true);
        section.paragraph(&format!(
            "With the light sampling a renderer already has (mcpg-nee, mcg's extension: the \
             guide samples the scattered direction, one light sample per vertex as in nee, the \
             two combined by MIS with the guide's exact mixture density, and the chains learn \
             only the MIS-weighted share of the emission their directions hit): mcpg-nee ÷ nee = \
             {samples:.3} at equal samples and {time:.3} at equal time; its frame costs {:.1}× a \
             nee frame, and one late frame has {:.3}× the relMSE of a nee frame. Why the \
             paper's mcpg (one direction per vertex) does not beat nee here: nee gathers a \
             light sample at every vertex besides the direction it continues in, where the \
             paper's guide must spend its one direction on either; the light, 1.2 m wide and \
             0.4 m under the ceiling it lights, is near and wide from there, where a light \
             sample is hard to beat. Guiding only the last vertex of mcpg's paths (with one \
             direction per vertex) lowers a late frame's relMSE 1.4× against bsdf, nee's light \
             samples 6.7× (markov-guide/benches/README.md); mcpg's emission-only directions \
             give the guide those chances back. The guide's gain is in the directions light \
             sampling cannot find: the slit, the lit ceiling, the walls it lights.",
            time_of(Method::McpgNee) / time_of(Method::Nee),
            late_of(Method::McpgNee) / late_of(Method::Nee),
        ));
        targets["mcpg_nee_over_nee_equal_samples"] = samples.into();
        targets["mcpg_nee_over_nee_equal_time"] = time.into();
        targets["net_of_reference"]["mcpg_nee_over_nee_equal_samples"] =
            (net(Method::McpgNee, false) / net(Method::Nee, false)).into();
        targets["net_of_reference"]["mcpg_nee_over_nee_equal_time"] =
            (net(Method::McpgNee, true) / net(Method::Nee, true)).into();
    }
    targets
}

/// Side of the tiles of the MCMM-against-MCPG map, in pixels.
const WIN_TILE: u32 = 8;

/// The paragraph of MCMM's targets (scene (b)), with a map of the tiles where `mcmm` or
/// `mcpg` has the lower relMSE at equal samples; their numbers.
fn mcmm_targets(
    ctx: &Context<'_>,
    section: &mut Section,
    study: &Study,
    runs: &[Runs],
    reference: &RgbImage,
    id: &dyn Fn(&str) -> String,
) -> Result<serde_json::Value> {
    let mcmm = error_of(runs, Method::Mcmm, false);
    let over_bsdf = mcmm / error_of(runs, Method::Bsdf, false);
    let over_mcpg = mcmm / error_of(runs, Method::Mcpg, false);
    let over_mcpg_time = error_of(runs, Method::Mcmm, true) / error_of(runs, Method::Mcpg, true);
    let time_of = |m: Method| seconds_per_frame(&find(runs, m).equal_samples);
    let late_of = |m: Method| late_frame_error(&find(runs, m).equal_samples);
    let a = &find(runs, Method::Mcmm).equal_samples.image;
    let b = &find(runs, Method::Mcpg).equal_samples.image;
    let (map, mcmm_wins, tiles) = win_map(a, b, reference, study.settings.size);
    image_strip(
        &ctx.figure_path(&id("wins")),
        &[&map],
        256 / study.settings.size,
    )?;
    section.paragraph(&format!(
        "Targets (issue: mcmm relMSE ≤ ¼ of bsdf at equal samples after {} frames): mcmm ÷ \
         bsdf = {over_bsdf:.3}; mcmm ÷ mcpg = {over_mcpg:.3} at equal samples and \
         {over_mcpg_time:.3} at equal time. Cost: an mcmm frame costs {:.2}× a bsdf frame and \
         {:.2}× an mcpg frame here (CPU tracers; the GPU ratio is measured with mcg-demo \
         render). One late frame: mcmm ÷ bsdf = {:.3}, mcmm ÷ mcpg = {:.3}.",
        study.settings.frames,
        time_of(Method::Mcmm) / time_of(Method::Bsdf),
        time_of(Method::Mcmm) / time_of(Method::Mcpg),
        late_of(Method::Mcmm) / late_of(Method::Bsdf),
        late_of(Method::Mcmm) / late_of(Method::Mcpg),
    ));
    section.figure(
        &id("wins"),
        &format!(
            "Where each guide wins, at equal samples: {WIN_TILE}×{WIN_TILE}-pixel tiles \
             coloured by the method with the lower relMSE against the reference (mcmm blue, \
             mcpg orange, brighter = larger margin, log₂ of the ratio up to 8×). mcmm wins \
             {mcmm_wins} of {tiles} tiles."
        ),
    );
    Ok(serde_json::json!({
        "mcmm_over_bsdf_equal_samples": over_bsdf,
        "mcmm_over_mcpg_equal_samples": over_mcpg,
        "mcmm_over_mcpg_equal_time": over_mcpg_time,
        "mcmm_over_bsdf_cost": time_of(Method::Mcmm) / time_of(Method::Bsdf),
        "mcmm_tiles_won_against_mcpg": mcmm_wins,
        "tiles": tiles,
    }))
}

/// Per tile of [`WIN_TILE`] pixels, which of `a` (blue) and `b` (orange) has the lower
/// relMSE against `reference`; the map, the tiles `a` wins and the tile count.
fn win_map(a: &RgbImage, b: &RgbImage, reference: &RgbImage, size: u32) -> (RgbImage, u32, u32) {
    let per_side = size.div_ceil(WIN_TILE);
    let mut err = vec![(0.0f64, 0.0f64); (per_side * per_side) as usize];
    for (i, r) in reference.pixels.iter().enumerate() {
        let (x, y) = (i as u32 % size, i as u32 / size);
        let t = ((y / WIN_TILE) * per_side + x / WIN_TILE) as usize;
        let d = |p: Vec3| {
            let q = (p - *r) * (p - *r) / (*r * *r + Vec3::splat(1e-2));
            f64::from(q.x + q.y + q.z)
        };
        err[t].0 += d(a.pixels[i]);
        err[t].1 += d(b.pixels[i]);
    }
    let wins = err.iter().filter(|(ea, eb)| ea < eb).count() as u32;
    let pixels = (0..size * size)
        .map(|i| {
            let (x, y) = (i % size, i / size);
            let (ea, eb) = err[((y / WIN_TILE) * per_side + x / WIN_TILE) as usize];
            let margin = ((eb.max(1e-12) / ea.max(1e-12)).log2().abs() / 3.0).min(1.0) as f32;
            let level = 0.25 + 0.75 * margin;
            let c = if ea < eb {
                Vec3::new(0.1, 0.35, 1.0)
            } else {
                Vec3::new(1.0, 0.5, 0.05)
            };
            (c * level).powf(2.2)
        })
        .collect();
    let map = RgbImage {
        width: size,
        height: size,
        pixels,
    };
    (map, wins, per_side * per_side)
}

/// The picture of the MCPG guide after the last frame (scene (a)).
fn guide_figure(
    ctx: &Context<'_>,
    section: &mut Section,
    guide: &Guide,
    s: &Settings,
    id: &dyn Fn(&str) -> String,
) -> Result<()> {
    let picture = guide_picture(guide, s)?;
    let (k_lo, k_hi, l_lo, l_hi) =
        write_guide_picture(&ctx.figure_path(&id("guide")), &picture, s.size)?;
    section.figure(
        &id("guide"),
        &format!(
            "The guide after the last frame, at each pixel's first hit (MCPG Fig. 3 \
             right): the chosen chain state's mean direction (RGB = ½ + ½·xyz), its \
             concentration κ (log scale, {k_lo:.2} dark to {k_hi:.0} yellow) and the \
             adaptive grid's level ({l_lo} dark to {l_hi} yellow). Dark grey: no state \
             stored there."
        ),
    );
    Ok(())
}
