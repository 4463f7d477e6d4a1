//! CPU/GPU parity of the two ADGI steps that feed the guide: the feedback ĝ of eq. 2
//! (`GpuProbeChains::record_feedback` against `guiding_function::octant_feedback` of every
//! probe) and the heuristics words of sec. 4.1-4.3 (`GpuTriggerSmoothing::record_compose`
//! against `heuristics::compose_grid`), for the same texel words, pilot state and smoothed
//! triggers.
//!
//! Tolerances from WGSL's accuracy (WGSL spec, "Floating Point Accuracy"): +, −, × and
//! comparisons are correctly rounded (the kernels keep the CPU's roundings), division is within
//! 2.5 ULP, `sqrt` within 2.5 ULP, `exp(x)` within 3 + 2|x| ULP. So ĝ, a sum in the CPU's order
//! divided by the texel count, is within 3 ULP of the CPU's; a heuristics word equals the CPU's
//! bit for bit except that its f_s or f_d code may differ by one where the CPU's scaled value
//! lies within the bound below of a rounding tie (f_v and the flags are always exact).

mod common;

use glam::{UVec2, UVec3, Vec3};
use mcg_color_codec::{HeuristicsWord, IrradianceLayout, IrradianceWord};
use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::guides::adgi::{
    GpuProbeCache, GpuProbeChains, GpuTriggerSmoothing, ProbeCacheConfig,
};
use mcg_markov_guide::FrameSchedule;
use mcg_probe_cache::guiding_function::octant_feedback;
use mcg_probe_cache::heuristics::{
    camera_distance, compose_grid, dynamic_heuristic, static_heuristic,
};
use mcg_probe_cache::temporal_gradient::spatial_smoothing;
use mcg_probe_cache::{
    ChainKind, GuideParams, HeuristicParams, MapKind, ProbeChains, ProbeGrid, ProxyGrid,
    SmoothingKernel, TexelMap,
};
use rand::RngExt;
use rand_pcg::Pcg64;

/// Four chains of `kind` on `grid` (static: the probes, whose feedback table is one value per
/// probe and octant; dynamic: ADGI's proxies).
fn chains(ctx: &GpuContext, grid: ProbeGrid, kind: ChainKind) -> GpuProbeChains {
    let (cells, guide) = match kind {
        ChainKind::Static => (ProxyGrid::probes(grid), GuideParams::STATIC),
        ChainKind::Dynamic => (ProxyGrid::adgi(grid), GuideParams::DYNAMIC),
    };
    let chains = ProbeChains::new(cells, kind, 4, FrameSchedule::DEFAULT, || [0.5; 5]).unwrap();
    GpuProbeChains::new(ctx, &chains, guide).unwrap()
}

/// ĝ of every probe as the CPU's `ProbeUpdater` computes it: `octant_feedback` over the
/// interior irradiance texels (stored order) of each probe's words.
fn cpu_feedback(map: TexelMap, words: &[u32], probes: usize) -> Vec<f32> {
    let interior: Vec<(usize, Vec3)> = (0..map.texel_count())
        .filter_map(|i| {
            let t: UVec2 = map.coords(i);
            (!map.is_border(t)).then(|| (i, map.direction(t)))
        })
        .collect();
    let dirs: Vec<Vec3> = interior.iter().map(|t| t.1).collect();
    let per_probe = map.texel_count();
    let mut out = vec![0.0; probes * 8];
    for p in 0..probes {
        let mut g = [0.0; 8];
        octant_feedback(
            &dirs,
            |k| IrradianceLayout::ADGI.decode(IrradianceWord(words[p * per_probe + interior[k].0])),
            &mut g,
        );
        out[p * 8..][..8].copy_from_slice(&g);
    }
    out
}

/// The feedback ĝ on a 5 × 4 × 3 grid with ADGI's 8 × 8 irradiance map and on a 3 × 2 × 2 grid
/// with a 4 × 4 map (2 × 2 interior texels on the equator: octants 4-7 hold none and get 0):
/// random words, every word 0 (black), every word all ones (each channel's largest code), and
/// probes mixing black and bright texels. Equals `octant_feedback` within 3 ULP (WGSL's
/// division; lavapipe: 0); a break of the kernel fails it. The dynamic chains' proxies are
/// refused.
#[test]
fn feedback_matches_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("feedback_matches_the_cpu", 40) else {
        return;
    };
    let mut compared = 0;
    let mut worst = 0;
    for (counts, side) in [(UVec3::new(5, 4, 3), 8), (UVec3::new(3, 2, 2), 4)] {
        let grid = ProbeGrid::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::splat(0.75), counts).unwrap();
        let mut config = ProbeCacheConfig::adgi(grid, 1);
        config.texels.irradiance_map = TexelMap::new(MapKind::Octahedral, side, true).unwrap();
        let cache = GpuProbeCache::new(ctx, &config).unwrap();
        let map = config.texels.irradiance_map;
        let probes = grid.probe_count();
        let per_probe = map.texel_count();
        let words: Vec<u32> = (0..probes * per_probe)
            .map(|i| match (i / per_probe) % 5 {
                0 => 0,
                1 => u32::MAX,
                2 if rng.random_range(0..2) == 0 => 0,
                _ => rng.random(),
            })
            .collect();
        let visibility = vec![0; probes * config.texels.visibility_map.texel_count()];
        cache.upload_words(ctx, &words, &visibility).unwrap();
        let chains = chains(ctx, grid, ChainKind::Static);
        let got = chains.feedback_from_cache(ctx, &cache).unwrap();
        let want = cpu_feedback(map, &words, probes);
        assert_eq!(got.len(), want.len());
        for (i, (&g, &c)) in got.iter().zip(&want).enumerate() {
            let e = common::ulps(g, c);
            worst = worst.max(e);
            assert!(
                c.is_finite() && e <= 3,
                "{counts} side {side}: probe {} octant {}: GPU {g} CPU {c} ({e} ULP)",
                i / 8,
                i % 8
            );
        }
        compared += got.len();
        // Black probes give 0, bright ones a positive mean in every octant with texels.
        assert!(want[..8].iter().all(|&g| g == 0.0));
        let bright = &want[8..16];
        if side == 8 {
            assert!(bright.iter().all(|&g| g > 1.0), "{bright:?}");
        } else {
            assert!(bright[..4].iter().all(|&g| g > 1.0) && bright[4..] == [0.0; 4]);
        }
    }
    println!("feedback: {compared} (probe, octant) values, worst {worst} ULP");
    // Dynamic chains' cells are proxies, not the cache's probes.
    let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(6, 6, 6)).unwrap();
    let cache = common::adgi_cache(ctx, grid);
    let dynamic = chains(ctx, grid, ChainKind::Dynamic);
    assert!(dynamic.feedback_from_cache(ctx, &cache).is_err());
}

/// A value drawn with NaN, ±∞, negatives, values above 1 and exact 0 and 1 mixed in.
fn edgy(rng: &mut Pcg64) -> f32 {
    match rng.random_range(0..40) {
        0 => f32::NAN,
        1 => f32::INFINITY,
        2 => f32::NEG_INFINITY,
        3 => -0.3,
        4 => 1.7,
        5 => 0.0,
        6 => 1.0,
        _ => rng.random(),
    }
}

/// Field `shift`/`bits` of a word.
fn field(word: u32, shift: u32, bits: u32) -> u32 {
    word >> shift & ((1 << bits) - 1)
}

/// Whether `value · max` lies within `relative` (of itself) of a round-to-nearest tie, where
/// WGSL's few-ULP `sqrt`, `exp` and division may round the code the other way.
fn near_tie(value: f32, max: u32, relative: f64) -> bool {
    let x = f64::from(value) * f64::from(max);
    (x - x.floor() - 0.5).abs() <= relative * x + 1e-9
}

/// One composition's inputs: the pilot state's f_v, the smoothed f_Δv and f_Δr, the old words.
struct Inputs<'a> {
    f_v: &'a [f32],
    delta_v: &'a [f32],
    delta_r: &'a [f32],
    old: &'a [u32],
}

/// Checks the GPU's words `got` against `compose_grid` of `inputs`: f_v and the flags exactly;
/// f_s (10 bits at 6) and f_d (10 bits at 16) exactly, or one code off where the CPU's value
/// lies within WGSL's error of a tie: f_c's relative error from `sqrt` (2.5 ULP of d, and
/// |∂f_c/∂d| = f_c) and `exp` (3 + 2|x| ULP), the products, and for f_d the division. Returns
/// (fields within the error of a tie, codes one off).
fn check_words(
    grid: &ProbeGrid,
    params: &HeuristicParams,
    camera: Vec3,
    inputs: &Inputs<'_>,
    got: &[u32],
) -> (usize, usize) {
    let mut want: Vec<_> = inputs.old.iter().map(|&w| HeuristicsWord(w)).collect();
    let (f_v, dv, dr) = (inputs.f_v, inputs.delta_v, inputs.delta_r);
    compose_grid(grid, params, camera, f_v, dv, dr, &mut want).unwrap();
    let eps = f64::from(f32::EPSILON);
    let (k, mu) = (params.camera_threshold(), params.lighting_weight());
    let (mut exempt, mut flips) = (0, 0);
    assert_eq!(got.len(), want.len());
    for (i, (&g, c)) in got.iter().zip(&want).enumerate() {
        let c = c.0;
        let probe = grid.probe_position(grid.probe_coords(i / 8));
        let f_c = camera_distance(probe, camera, k);
        let what = format!(
            "camera {camera} k {k} μ {mu}: probe {} octant {}",
            i / 8,
            i % 8
        );
        assert_eq!(
            field(g, 0, 6),
            field(c, 0, 6),
            "{what}: f_v of {g:#x} / {c:#x}"
        );
        assert_eq!(field(g, 26, 6), field(c, 26, 6), "{what}: flags");
        assert_eq!(
            field(c, 26, 6),
            field(inputs.old[i], 26, 6),
            "{what}: CPU flags"
        );
        let d = f64::from((probe - camera).length());
        let rel_c = if f_c == 1.0 || f_c == 0.0 {
            0.0
        } else {
            (6.0 + 2.5 * d + 2.0 * (d - f64::from(k)).abs()) * eps
        };
        let f_s = static_heuristic(f_c, f_v[i]);
        let f_d = dynamic_heuristic(f_c, f_v[i], dv[i], dr[i], mu);
        for (shift, value, relative) in [(6, f_s, rel_c), (16, f_d, rel_c + 5.0 * eps)] {
            let (gc, cc) = (field(g, shift, 10), field(c, shift, 10));
            let tie = relative > 0.0 && near_tie(value, 1023, relative);
            exempt += usize::from(tie);
            flips += usize::from(gc != cc);
            assert!(
                gc == cc || (tie && gc.abs_diff(cc) == 1),
                "{what}: field at {shift}: GPU {gc} CPU {cc} (value {value}, f_c {f_c})"
            );
        }
    }
    (exempt, flips)
}

/// The heuristics words on a 7 × 5 × 4 grid: f_v in the pilot state and f_Δv, f_Δr with NaN,
/// ±∞, negative and > 1 values, random old words (their flags kept), for cameras inside the
/// grid, far away (f_c tiny) and NaN (f_c = 0), thresholds 0, 1.5 and 100 (every probe within
/// it: f_c = 1) and μ = 0, 2, 3.5: every word equals `compose_grid`'s (see `check_words`; a
/// break of the kernel fails it). Then end to end from the trigger states through the GPU
/// smoothing (ADGI's kernel) and composition, against `spatial_smoothing` + `compose_grid`.
#[test]
fn composed_words_match_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("composed_words_match_the_cpu", 41) else {
        return;
    };
    let grid = common::adgi_grid();
    let cache = common::adgi_cache(ctx, grid);
    let smoothing = GpuTriggerSmoothing::new(ctx, &cache);
    let n = grid.probe_count() * 8;
    let state: Vec<[f32; 4]> = (0..n)
        .map(|_| [edgy(&mut rng), rng.random(), edgy(&mut rng), edgy(&mut rng)])
        .collect();
    let delta: Vec<[f32; 2]> = (0..n).map(|_| [edgy(&mut rng), edgy(&mut rng)]).collect();
    ctx.write(cache.pilot_state(), &state).unwrap();
    ctx.write(smoothing.delta(), &delta).unwrap();
    let f_v: Vec<f32> = state.iter().map(|s| s[0]).collect();
    let (dv, dr): (Vec<f32>, Vec<f32>) = delta.iter().map(|d| (d[0], d[1])).unzip();
    let old: Vec<u32> = (0..n).map(|_| rng.random()).collect();
    let inputs = Inputs {
        f_v: &f_v,
        delta_v: &dv,
        delta_r: &dr,
        old: &old,
    };
    let (mut words, mut exempt, mut flips) = (0, 0, 0);
    for camera in [
        Vec3::new(0.7, 2.1, 1.4),
        Vec3::new(40.0, -3.0, 9.0),
        Vec3::NAN,
    ] {
        for (k, mu) in [(0.0, 2.0), (1.5, 0.0), (1.5, 3.5), (100.0, 2.0)] {
            let params = HeuristicParams::with_ranges(k, grid.cell_diagonal(), 5.0, mu).unwrap();
            let got = smoothing
                .compose(ctx, &cache, &params, camera, &old)
                .unwrap();
            let (e, f) = check_words(&grid, &params, camera, &inputs, &got);
            (words, exempt, flips) = (words + got.len(), exempt + e, flips + f);
            let positive = got.iter().filter(|&&w| field(w, 16, 10) > 0).count();
            if camera.x < 1.0 && k > 1.0 && mu > 0.0 {
                assert!(positive > n / 4, "{positive} positive f_d");
            }
        }
    }
    println!(
        "compose: {words} words, {flips} codes one off, {exempt} fields within WGSL's error of a tie"
    );

    let params = HeuristicParams::new(1.5, grid.cell_diagonal()).unwrap();
    let camera = Vec3::new(0.2, 1.0, 2.0);
    let kernel = SmoothingKernel::ADGI;
    let (gv, gr) = smoothing.smooth(ctx, &cache, kernel).unwrap();
    let got = smoothing
        .compose(ctx, &cache, &params, camera, &old)
        .unwrap();
    let (tv, tr): (Vec<f32>, Vec<f32>) = state.iter().map(|s| (s[2], s[3])).unzip();
    let (mut sv, mut sr, mut scratch) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    spatial_smoothing(&grid, kernel, &tv, &mut sv, &mut scratch).unwrap();
    spatial_smoothing(&grid, kernel, &tr, &mut sr, &mut scratch).unwrap();
    assert_eq!((&gv, &gr), (&sv, &sr), "smoothed triggers");
    let inputs = Inputs {
        delta_v: &sv,
        delta_r: &sr,
        ..inputs
    };
    let (e, f) = check_words(&grid, &params, camera, &inputs, &got);
    println!("end to end: {n} words, {f} codes one off, {e} fields within the error of a tie");
    assert!(got.iter().filter(|&&w| field(w, 16, 10) > 0).count() > n / 4);
}
