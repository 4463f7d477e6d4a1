//! Section "Probe cache": ADGI's adaptive probe updates against uniform DDGI at an equal ray
//! budget, on the two-room scene whose door slides open (`mcg_probe_cache::scene`).
//!
//! The experiment is `mcg_tests::Experiment`, the same one the suite
//! `tests/probe_cache_adgi.rs` asserts on:
//! 1. slices through the probe grid (the probes of one horizontal layer, each drawn as its
//!    octahedral irradiance map) before and after the event, for the reference, ADGI and
//!    uniform DDGI;
//! 2. the relative RMS error per frame near the event and over the whole grid;
//! 3. frames-to-error and rays spent near the event;
//! 4. memory per probe of ADGI's texel words against RGB32F / RGBA32F.

use mcg_probe_cache::glam::Vec3;
use mcg_probe_cache::{ProbeTexels, TexelConfig};
use mcg_tests::{
    Experiment, ExperimentConfig, Run, UpdatePolicy, frames_to_error, frames_to_first_below,
    mean_error,
};
use plotters::prelude::*;
use plotters::style::FontStyle;

use super::Context;
use crate::Result;
use crate::plot::{self, Axis, FONT_FAMILY, LineChart, PALETTE, Series, SeriesLabelPosition};
use crate::report::{Section, Table};

/// The policies of the experiment, in chart order.
const POLICIES: [UpdatePolicy; 5] = [
    UpdatePolicy::Adgi,
    UpdatePolicy::AdgiRefill,
    UpdatePolicy::AdgiBlend,
    UpdatePolicy::AdgiUnguided,
    UpdatePolicy::Ddgi,
];

/// The error threshold of the frames-to-error table (relative RMS error near the event).
pub const THRESHOLD: f64 = mcg_tests::FRAMES_TO_ERROR_THRESHOLD;

/// The probe layer (y index) the slices show.
const SLICE_LAYER: u32 = 0;

/// Pixels per texel in the slice images.
const SCALE: usize = 3;

/// The experiment's settings for this run: the suite's in a full run; in quick mode fewer
/// frames, reference rays and rays per probe (16).
fn config(ctx: &Context<'_>) -> ExperimentConfig {
    let mut c = ExperimentConfig::TEST;
    c.seed ^= ctx.config.seed;
    if ctx.config.samples < crate::Config::DEFAULT_SAMPLES {
        c.frames = 16;
        c.event_frame = 6;
        c.reference_strata = 4;
        c.rays_per_probe = 16;
    }
    c
}

/// Builds the section.
pub fn build(ctx: &Context<'_>) -> Result<Section> {
    let mut section = Section::new("probe-cache", "Probe cache: ADGI vs uniform DDGI");
    section.paragraph(
        "`mcg-probe-cache` stores a DDGI probe grid in ADGI's 32-bit texel words (R9G9B8 + count \
         for irradiance, 13/13 + count for the distance moments), updated by compare-and-swap, \
         and places its rays with ADGI's guide: pilot rays per probe octant detect changes of \
         visibility and radiance, dynamic Metropolis chains on 3×3×3 proxies spend rays where \
         they changed, static chains spend the rest where probes are close to surfaces. The \
         scene is a lit 8 m room and a dark 0.9 m closet behind a partition wall whose door \
         slides open, letting light fall into the closet (the paper's tunnel gate of Fig. 1 \
         and 8 in miniature). Rays see one bounce of light: the light itself, or a \
         surface's albedo/π times its direct irradiance.",
    );
    let study = Study::run(ctx);
    overview(&mut section, &study);
    slices(ctx, &mut section, &study)?;
    error_over_frames(ctx, &mut section, &study)?;
    memory(&mut section, &study);
    Ok(section)
}

/// The experiment of the section: every policy run on the door scene, with the frames whose
/// probe maps the slice figure shows.
struct Study {
    cfg: ExperimentConfig,
    exp: Experiment,
    runs: Vec<Run>,
    /// The last frame before the door moves.
    before: u32,
    /// A frame shortly after the door has opened.
    after: u32,
}

impl Study {
    /// Runs every policy (with a progress bar).
    fn run(ctx: &Context<'_>) -> Self {
        let cfg = config(ctx);
        let bar = ctx.progress(1 + POLICIES.len() as u64, "Probe cache: experiments");
        let exp = Experiment::new(cfg);
        bar.inc(1);
        let after = (cfg.event_frame + cfg.transition_frames + 2).min(cfg.frames - 1);
        let before = cfg.event_frame - 1;
        let snapshots = [before, after];
        let runs: Vec<Run> = POLICIES
            .iter()
            .map(|&p| {
                let r = exp.run(p, &snapshots);
                bar.inc(1);
                r
            })
            .collect();
        bar.finish_and_clear();
        Self {
            cfg,
            exp,
            runs,
            before,
            after,
        }
    }
}

/// The grid and budget paragraph.
fn overview(section: &mut Section, study: &Study) {
    let Study { cfg, exp, .. } = study;
    let grid = exp.scene.grid;
    let probes = grid.probe_count();
    let near = exp.near.len();
    section.paragraph(&format!(
        "{} probes ({}×{}×{}, spacing {}×{}×{} m), 8×8 octahedral irradiance texels with the \
         1-texel border (6×6 interior) per probe. Every policy traces at most {} probe rays per \
         frame ({} per probe on average) and starts from the same converged cache of the \
         closed-door scene; the door opens over frames {}–{}. {} probes lie near the event (in \
         the closet or within {} m of the doorway). The reference traces {} stratified \
         cosine-weighted rays per texel direction plus as many light samples; errors are \
         relative RMS over the texel directions of a set of probes.",
        probes,
        grid.counts().x,
        grid.counts().y,
        grid.counts().z,
        grid.spacing().x,
        grid.spacing().y,
        grid.spacing().z,
        cfg.rays_per_probe as usize * probes,
        cfg.rays_per_probe,
        cfg.event_frame,
        cfg.event_frame + cfg.transition_frames - 1,
        near,
        cfg.near_radius,
        cfg.reference_strata * cfg.reference_strata,
    ));
}

/// The slice figure: one grid layer's probe maps before and after the door opens.
fn slices(ctx: &Context<'_>, section: &mut Section, study: &Study) -> Result<()> {
    let Study {
        cfg,
        exp,
        runs,
        before,
        after,
    } = study;
    let (before, after) = (*before, *after);
    let grid = exp.scene.grid;
    let snapshots = [before, after];
    let file = "probe-cache-slices.png";
    slice_figure(ctx, file, exp, runs, &snapshots)?;
    section
        .heading("A slice through the probe grid")
        .paragraph(&format!(
            "The {}×{} probes of the lowest layer (y = {:.3} m), seen from above: x to the right, \
             z down; the closet is the two rightmost columns, the light hangs above the middle. \
             Each probe is drawn as its 6×6 octahedral map of irradiance E(p, n) (the same tone \
             map everywhere). Left: frame {} (door closed); right: frame {} ({} frames after \
             the door started to move).",
            grid.counts().x,
            grid.counts().z,
            grid.probe_position(mcg_probe_cache::glam::UVec3::new(0, SLICE_LAYER, 0)).y,
            before,
            after,
            after - cfg.event_frame,
        ))
        .figure(
            file,
            "Probe irradiance maps of one grid layer before and after the door opens: reference, ADGI, ADGI + refill (mcg), ADGI with a constant guide, uniform DDGI.",
        );
    Ok(())
}

/// The error-over-frames chart, the table of frames to the threshold and the text.
fn error_over_frames(ctx: &Context<'_>, section: &mut Section, study: &Study) -> Result<()> {
    let Study { cfg, exp, .. } = study;
    let grid = exp.scene.grid;
    let probes = grid.probe_count();
    let near = exp.near.len();
    let file = error_figure(ctx, study)?;
    let table = error_table(study);
    section
        .heading("Error over frames at equal rays")
        .paragraph(&format!(
            "Lines: the probes near the event ({near} of {probes}); dots: all probes. Uniform \
             DDGI gives every probe the same {} rays per frame and blends them with hysteresis \
             0.94 (Q-DDGI, ADGI Table 3), so after the door opens its error near the event falls \
             by at most 6 % of the gap per frame. ADGI's pilot rays see the visibility and \
             radiance change at the doorway, its dynamic chains send 64 rays per probe octant \
             into the changed octants of the 3×3×3 proxies around it with N_max = 10, and the \
             static chains refine the rest: its error near the event drops within a few frames. \
             It does not stay there: the dynamic rays reach only the octants whose pilot rays saw \
             the change, so texels of the same probes that face the doorway can keep their old, \
             dark value with a full window (N = 63), and the static chains, which know nothing \
             of windows, refresh them at under one ray per texel and frame. ADGI + refill (mcg's \
             extension) restarts every texel of a probe whose change grows and steers the static \
             chains toward texels whose window is not full: it falls below the threshold sooner \
             and stays lower. Over all probes DDGI still ends lower than both: their texels hold \
             radiance per texel, and turning that into irradiance has a floor of its own (≈ 0.10 \
             with the exact mean radiance in every texel) that DDGI's cosine-blended texels do \
             not have. ADGI + blend (mcg's extension that the dynamic-GI section renders with) \
             keeps ADGI's pilot rays and change detection but blends uniform rays into E/π \
             texels as DDGI does; it restarts a probe whose change signal turns on and gives it \
             96 extra rays per frame while the signal is on, and each probe's rays continue a \
             low-discrepancy (R2) sequence from frame to frame, so a texel's window holds rays \
             stratified over its frames: it falls below the threshold within a few frames and \
             ends below DDGI over all probes (mcg-tests' probe_cache_adgi suite asserts both \
             over 8 seeds). \
             The constant-guide run spends ADGI's rays through the same machinery but uniformly \
             over (p, ω): the gap between it and ADGI is what the guide buys.",
            cfg.rays_per_probe
        ))
        .figure(
            file,
            "Relative RMS error per frame, near the event (lines) and over all probes (dots).",
        )
        .table(table);
    Ok(())
}

/// The chart of the relative error per frame, near the event and over all probes, per policy;
/// returns its file name.
fn error_figure(ctx: &Context<'_>, study: &Study) -> Result<&'static str> {
    let Study { cfg, runs, .. } = study;
    let file = "probe-cache-error.png";
    let mut series = Vec::new();
    for (i, run) in runs.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        series.push(Series::line(
            &format!("{}, near the event", run.policy.label()),
            color,
            run.error_near
                .iter()
                .enumerate()
                .map(|(f, &e)| (f as f64, e))
                .collect(),
        ));
        series.push(Series::dots(
            &format!("{}, all probes", run.policy.label()),
            color,
            run.error_all
                .iter()
                .enumerate()
                .map(|(f, &e)| (f as f64, e))
                .collect(),
        ));
    }
    let y_max = runs
        .iter()
        .flat_map(|r| r.error_near.iter().chain(&r.error_all))
        .fold(0.0_f64, |m, &e| m.max(e));
    plot::line_chart(
        &ctx.figure_path(file),
        (1100, 620),
        &LineChart {
            title: format!(
                "Relative RMS error of the probe irradiance, door opening at frame {}",
                cfg.event_frame
            ),
            x: Axis::linear("frame", 0.0..cfg.frames as f64),
            y: Axis::log10("relative RMS error", 0.02..(y_max * 1.5).clamp(1.0, 100.0)),
            series,
            legend: SeriesLabelPosition::LowerRight,
        },
    )?;
    Ok(file)
}

/// Frames until the error near the event drops below [`THRESHOLD`], the errors around the
/// event and the share of rays spent near it, per policy.
fn error_table(study: &Study) -> Table {
    let Study {
        cfg, runs, before, ..
    } = study;
    let before = *before;
    let mut table = Table::new(
        &format!(
            "Frames from the door's first move until the error near the event first drops below {THRESHOLD}, and until it stays below; the errors around it"
        ),
        [
            "policy",
            "frames until first below",
            "frames until it stays below",
            "error before (near)",
            "mean error, 10 frames from the event (near)",
            "mean error, last 5 frames (near / all)",
            "share of rays near the event, 10 frames from it",
        ],
    );
    let tail = cfg.frames;
    let e = cfg.event_frame;
    let window = (e + 10).min(tail);
    for run in runs {
        let fmt = |v: Option<u32>| v.map_or("never".to_owned(), |f| f.to_string());
        let rays: u64 = run.rays[e as usize..window as usize].iter().sum();
        let near_rays: u64 = run.rays_near[e as usize..window as usize].iter().sum();
        table.push_row([
            run.policy.label().to_owned(),
            fmt(frames_to_first_below(&run.error_near, e, THRESHOLD)),
            fmt(frames_to_error(&run.error_near, e, THRESHOLD)),
            format!("{:.3}", run.error_near[before as usize]),
            format!("{:.3}", mean_error(&run.error_near, e, window)),
            format!(
                "{:.3} / {:.3}",
                mean_error(&run.error_near, tail - 5, tail),
                mean_error(&run.error_all, tail - 5, tail)
            ),
            format!("{:.0} %", 100.0 * near_rays as f64 / rays.max(1) as f64),
        ]);
    }
    table
}

/// Bytes per probe of ADGI's words against plain float texels.
fn memory(section: &mut Section, study: &Study) {
    let grid = study.exp.scene.grid;
    let probes = grid.probe_count();
    let texels = ProbeTexels::new(grid, TexelConfig::ADGI);
    let map = TexelConfig::ADGI.irradiance_map;
    let vis = TexelConfig::ADGI.visibility_map;
    let (ni, nv) = (map.texel_count(), vis.texel_count());
    let adgi = texels.bytes_per_probe();
    let mut table = Table::new(
        &format!(
            "Bytes per probe, {}×{} irradiance and {}×{} visibility texels (borders included)",
            map.side(),
            map.side(),
            vis.side(),
            vis.side()
        ),
        [
            "storage",
            "irradiance",
            "visibility",
            "total",
            "irradiance vs ADGI",
            "total vs ADGI",
        ],
    );
    let rows = [
        ("ADGI words (R9G9B8 + N, 13/13 + N)", 4 * ni, 4 * nv),
        ("RGB32F irradiance, RG32F distances", 12 * ni, 8 * nv),
        (
            "RGBA32F irradiance (RTXGI), RG32F distances",
            16 * ni,
            8 * nv,
        ),
        (
            "RGB32F + count, 16 B per texel for both maps (a plain f32 store)",
            16 * ni,
            16 * nv,
        ),
    ];
    for (name, irr, v) in rows {
        table.push_row([
            name.to_owned(),
            format!("{irr} B"),
            format!("{v} B"),
            format!("{} B", irr + v),
            format!("{:.1}×", irr as f64 / (4 * ni) as f64),
            format!("{:.2}×", (irr + v) as f64 / adgi as f64),
        ]);
    }
    section
        .heading("Memory per probe")
        .paragraph(&format!(
            "A probe of this crate's default layout takes {adgi} bytes — {} for the whole grid \
             above. ADGI's \"4× less\" holds against a plain 16-byte f32 texel (RGB32F + \
             count, or RGBA32F irradiance); against packed RGB32F irradiance it is 3×, and the \
             visibility moments halve against RG32F.",
            crate::group_thousands(adgi * probes)
        ))
        .table(table);
}

/// Tone map for the slices: E / (E + k), gamma 2.2, per channel.
fn tone(e: Vec3, k: f32) -> [u8; 3] {
    let m = |v: f32| ((v.max(0.0) / (v.max(0.0) + k)).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
    [m(e.x), m(e.y), m(e.z)]
}

/// The slice figure: rows reference / policies, columns before / after.
fn slice_figure(
    ctx: &Context<'_>,
    file: &str,
    exp: &Experiment,
    runs: &[Run],
    snapshots: &[u32],
) -> Result<()> {
    let grid = exp.scene.grid;
    let counts = grid.counts();
    let map = exp.texel_config.irradiance_map;
    let n = map.interior() as usize;
    let gap_probe = 1;
    let tile = n * SCALE + gap_probe;
    let (iw, ih) = (counts.x as usize * tile, counts.z as usize * tile);
    let (label_w, gap, title_h) = (230, 12, 30);
    let rows = 1 + runs.len();
    let width = label_w + snapshots.len() * (iw + gap);
    let height = title_h + rows * (ih + gap);
    let mut buffer = vec![255_u8; width * height * 3];
    // A common tone-map knee: the median reference irradiance after the event.
    let mut sorted: Vec<f32> = exp
        .reference(snapshots[snapshots.len() - 1])
        .iter()
        .map(|e| e.length())
        .collect();
    sorted.sort_by(f32::total_cmp);
    let k = sorted[sorted.len() / 2].max(1e-3);
    let n_tex = exp.texels.len();
    let draw = |buffer: &mut [u8], x0: usize, y0: usize, values: &[Vec3]| {
        for j in 0..counts.z {
            for i in 0..counts.x {
                let p = grid.probe_index(mcg_probe_cache::glam::UVec3::new(i, SLICE_LAYER, j));
                for (t, &(index, _, _)) in exp.texels.iter().enumerate() {
                    let c = map.coords(index);
                    let (tx, ty) = (c.x as usize - 1, c.y as usize - 1);
                    let rgb = tone(values[p * n_tex + t], k);
                    for dy in 0..SCALE {
                        for dx in 0..SCALE {
                            let x = x0 + i as usize * tile + tx * SCALE + dx;
                            let y = y0 + j as usize * tile + ty * SCALE + dy;
                            let o = (y * width + x) * 3;
                            buffer[o..o + 3].copy_from_slice(&rgb);
                        }
                    }
                }
            }
        }
    };
    for (c, &frame) in snapshots.iter().enumerate() {
        let x0 = label_w + c * (iw + gap);
        draw(&mut buffer, x0, title_h, exp.reference(frame));
        for (r, run) in runs.iter().enumerate() {
            let values = &run
                .snapshots
                .iter()
                .find(|s| s.0 == frame)
                .ok_or("missing snapshot")?
                .1;
            draw(&mut buffer, x0, title_h + (r + 1) * (ih + gap), values);
        }
    }
    let layout = (label_w, gap, title_h, iw, ih);
    draw_slice_labels(&mut buffer, (width, height), exp, runs, snapshots, layout)?;
    crate::plot::write_rgb_png(&ctx.figure_path(file), &buffer, width as u32, height as u32)
}

/// Writes the column titles (frame, door state) and the row labels (reference, policies)
/// over the slice figure's pixels; `layout` is `(label_w, gap, title_h, iw, ih)`.
fn draw_slice_labels(
    buffer: &mut [u8],
    (width, height): (usize, usize),
    exp: &Experiment,
    runs: &[Run],
    snapshots: &[u32],
    (label_w, gap, title_h, iw, ih): (usize, usize, usize, usize, usize),
) -> Result<()> {
    let root =
        BitMapBackend::with_buffer(buffer, (width as u32, height as u32)).into_drawing_area();
    let font = (FONT_FAMILY, 15).into_font();
    let bold = (FONT_FAMILY, 15).into_font().style(FontStyle::Bold);
    for (c, &frame) in snapshots.iter().enumerate() {
        let x0 = (label_w + c * (iw + gap)) as i32;
        let what = if frame < exp.config.event_frame {
            "door closed"
        } else {
            "door open"
        };
        root.draw_text(
            &format!("frame {frame} ({what})"),
            &bold.color(&BLACK),
            (x0, 8),
        )?;
    }
    let mut labels = vec!["reference".to_owned()];
    labels.extend(runs.iter().map(|r| r.policy.label().to_owned()));
    for (r, label) in labels.iter().enumerate() {
        let y = title_h + r * (ih + gap) + ih / 2 - 8;
        root.draw_text(label, &font.color(&BLACK), (6, y as i32))?;
    }
    root.present()?;
    Ok(())
}
