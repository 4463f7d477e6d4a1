//! Smoke test: a small run writes `index.html` and every PNG it references.

mod common;

use mcg_demo::Config;

/// The `src="…"` attributes of a page, in order.
fn image_sources(html: &str) -> Vec<String> {
    html.split("src=\"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn report_writes_index_and_all_figures() {
    let scratch = common::temp_dir("mcg-demo", "smoke");
    let out_dir = scratch.path().join("report");
    let config = Config {
        out_dir: out_dir.clone(),
        samples: 20_000,
        progress: false,
        ..Config::default()
    };
    let index = mcg_demo::run(&config).expect("report runs");

    assert!(index.is_absolute(), "{}", index.display());
    assert_eq!(index, out_dir.canonicalize().unwrap().join("index.html"));
    let html = std::fs::read_to_string(&index).expect("index.html is readable");
    assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
    assert!(html.contains("von Mises-Fisher lobes"));

    let sources = image_sources(&html);
    assert!(
        sources.len() >= 4,
        "expected the vMF figures, found {sources:?}"
    );
    for src in &sources {
        assert!(
            !src.contains("..") && !src.starts_with('/'),
            "{src} is not a plain relative path"
        );
        let bytes = std::fs::read(out_dir.join(src)).unwrap_or_else(|e| panic!("{src}: {e}"));
        assert!(bytes.len() > 1000, "{src} is only {} bytes", bytes.len());
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{src} is not a PNG"
        );
    }
}

/// Hypothesis: every reference committed in `demo/references/` (the default report's, which
/// a fresh checkout copies instead of rendering) is the image the `nee` tracer renders today:
/// per 16 × 16 tile and channel, the mean over 16 independent frames of the study's own size,
/// samples and bounces (seed 77, not the reference's) equals the committed tile mean. The
/// frames' tile means give their variance (the frames are independent); the reference's tile
/// mean has the variance Σ Var Rₚ / n² from its variance file (its pixels are independent
/// too). Test: t = (x̄ − r) / √(s²/16 + Var r) against Student's t with the Welch–Satterthwaite
/// degrees of freedom (the reference's variance from its frames − 1), Bonferroni over a
/// study's tile-channel tests at a family-wise α = 10⁻³ (|t| ≈ 5.6-6.0 at 15 dof for the
/// 192 tests of scene (a)); then the same over the whole image (3 tests), which sees a
/// uniform change of a few per cent that single noisy tiles cannot. It also fails when a
/// study's reference is missing from the folder (a scene or size changed: run the report and
/// copy `out/reference/` there). Checked once: a reference scaled by 0.97, as a changed light
/// or material would leave it, fails the hidden-light room (whole image, 1.96× the critical
/// value) and the sky room (8.9×); the many-lights and sun rooms, noisier per frame, pass it
/// (0.87×, 0.58×). Unchanged references reach at most 0.59× the critical value.
#[test]
fn committed_references_agree_with_the_nee_tracer() {
    use mcg_demo::render::cpu::{BsdfSampler, Method, RenderSettings, render_frame};
    use mcg_demo::render::output::{RgbImage, variance_path};
    use mcg_demo::render::scene::SceneFile;
    use mcg_demo::sections::guided_rendering::{COMMITTED_REFERENCES, Study, reference_name};
    use mcg_tests::{RunningStats, WelchResult};

    const FRAMES: u32 = 16;
    const TILE: u32 = 16;
    let samples = Config::DEFAULT_SAMPLES;
    for study in [
        Study::hidden_light(samples),
        Study::many_lights(samples),
        Study::sky_room(samples),
        Study::sun_room(samples),
    ] {
        let name = reference_name(&study, Config::DEFAULT_SEED).expect("scene builds");
        let path = std::path::Path::new(COMMITTED_REFERENCES).join(&name);
        assert!(
            path.exists() && variance_path(&path).exists(),
            "{name} (and its variance file) is missing from {COMMITTED_REFERENCES}: the study's \
             scene or settings changed; run `cargo run --release -p mcg-demo` and copy \
             out/reference/{name} and its .variance.exr there (remove the stale ones)"
        );
        let reference = RgbImage::read_exr(&path).expect("reference reads");
        let variance = RgbImage::read_exr(&variance_path(&path)).expect("variance reads");
        let s = study.settings;
        let (w, h) = (s.size, s.size);
        assert_eq!((reference.width, reference.height), (w, h), "{name}");
        let scene = SceneFile::open(study.scene).unwrap().build(0.0).unwrap();
        let settings = RenderSettings {
            width: w,
            height: h,
            spp: s.spp,
            bounces: s.bounces,
            seed: 77,
            method: Method::Nee,
        };
        let images: Vec<Vec<glam::Vec3>> = (0..FRAMES)
            .map(|f| render_frame(&scene, &settings, f, || BsdfSampler, || ()))
            .collect();
        // Per 16 × 16 tile, then over the whole image (one tile of w × h: 64× the pixels of a
        // tile in scene (a), so it sees a uniform change of a few per cent that single noisy
        // tiles cannot).
        let mut worst: f64 = 0.0;
        for tile in [TILE, w] {
            let frames = common::tile_stats((w, h, tile, FRAMES), |f| images[f as usize].clone());
            // The reference's tile means, and the tile means of its per-pixel variances
            // (Σ Var Rₚ / n; over n once more, the variance of the tile mean).
            let means = common::tile_stats((w, h, tile, 1), |_| reference.pixels.clone());
            let variances = common::tile_stats((w, h, tile, 1), |_| variance.pixels.clone());
            let n = f64::from(tile * tile);
            let tests = (frames.len() * 3) as f64;
            let reference_dof = f64::from(s.reference_frames - 1);
            for (t, stats) in frames.iter().enumerate() {
                for c in 0..3 {
                    let stats: &RunningStats = &stats[c];
                    let (r, r_var) = (means[t][c].mean(), variances[t][c].mean() / n);
                    let v = stats.variance() / f64::from(FRAMES);
                    let welch = WelchResult {
                        t: (stats.mean() - r) / (v + r_var).sqrt(),
                        degrees_of_freedom: (v + r_var).powi(2)
                            / (v * v / f64::from(FRAMES - 1) + r_var * r_var / reference_dof),
                    };
                    let critical = welch.critical_value(1e-3 / tests);
                    assert!(
                        welch.t.abs() < critical,
                        "{name}: {tile} × {tile} tile {t} channel {c}: frames {} vs reference \
                         {r}: t = {:.2} (critical {critical:.2}); the committed reference no \
                         longer matches the nee tracer: render it again (see above)",
                        stats.mean(),
                        welch.t
                    );
                    worst = worst.max(welch.t.abs() / critical);
                }
            }
        }
        eprintln!("{name}: worst |t| ÷ critical {worst:.2}");
    }
}
