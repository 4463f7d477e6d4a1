//! The MCPG `Guide` through its public API: unbiasedness, the exact pdf, determinism, threads,
//! bad input, the hemisphere option and the irradiance cache.

use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcg_hashgrid::{AdaptiveGrid, LevelParams};
use mcg_markov_guide::mcpg::{
    BeginUniforms, CacheConfig, FinishUniforms, Guide, GuideConfig, GuidedVertex, Hemisphere,
    IrradianceCache, IsotropicPhase, Lambertian, SampleUniforms, Transition, Vertex,
    VertexObservation,
};
use mcg_markov_guide::toy_scene::{TOY_NORMAL, ToyScene};
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A guide for the toy scene (lengths of a few units): the paper's setting scaled to a 10-unit
/// scene, small tables, no cache (the toy scene's only radiance is emitted).
fn toy_guide(hemisphere: Hemisphere) -> Guide {
    let mut config = GuideConfig::for_scene(Vec3::splat(-5.0), Vec3::splat(5.0));
    config.adaptive_capacity = 1 << 14;
    config.static_capacity = 1 << 10;
    config.cache = None;
    config.hemisphere = hemisphere;
    let mut guide = Guide::new(config).unwrap();
    guide.set_camera(Vec3::new(0.0, -2.5, 3.0));
    guide
}

/// One light of radius 0.6 and radiance 10 at height 3 above the points: small enough that
/// guiding pays, large enough that the estimator's tail is light and a z-test on a few
/// thousand samples decides (the radius-0.25 light needs far more).
fn medium_light() -> ToyScene {
    let mut scene = ToyScene::single_light();
    scene.lights[0].radius = 0.6;
    scene.lights[0].radiance = 10.0;
    scene
}

fn shading_point(i: usize) -> Vec3 {
    Vec3::new(
        (i % 4) as f32 * 0.1 - 0.15,
        (i / 4) as f32 * 0.1 - 0.05,
        0.0,
    )
}

/// One guided sample of the irradiance at `x` on the toy plane: the estimate L·cos/p, and the
/// vertex is finished (trained) with it.
fn guided_sample(guide: &Guide, scene: &ToyScene, x: Vec3, rng: &mut impl Rng) -> (f64, bool) {
    let n = guide.params().candidates as usize;
    let v = guide.begin(
        Vertex::surface(x, TOY_NORMAL),
        Lambertian { normal: TOY_NORMAL },
        &BeginUniforms::from_fn(n, || rng.random()),
    );
    let s = v.sample(&SampleUniforms::from_fn(|| rng.random()));
    let hit = scene.trace(x, s.direction);
    let cos = TOY_NORMAL.dot(s.direction).max(0.0);
    let weight = cos / s.pdf;
    let weight = if weight.is_finite() { weight } else { 0.0 };
    let observation = VertexObservation::hit(
        hit.point,
        -s.direction,
        Vec3::splat(hit.radiance),
        Vec3::splat(weight),
    );
    v.finish(&s, &observation, &FinishUniforms::from_fn(|| rng.random()));
    ((hit.radiance * weight) as f64, s.lobe.is_some())
}

/// Runs `frames` frames of 8 points × `spp` samples; returns per point (sum, sum of squares,
/// count) over frames from `from` on, and the fraction of lobe samples there.
fn run(
    guide: &mut Guide,
    scene: &ToyScene,
    frames: u32,
    from: u32,
    spp: u32,
    rng: &mut Pcg64Mcg,
) -> ([(f64, f64, f64); 8], f64) {
    let mut acc = [(0.0, 0.0, 0.0); 8];
    let (mut lobes, mut total) = (0u32, 0u32);
    for frame in 0..frames {
        for (i, a) in acc.iter_mut().enumerate() {
            for _ in 0..spp {
                let (e, lobe) = guided_sample(guide, scene, shading_point(i), rng);
                if frame >= from {
                    *a = (a.0 + e, a.1 + e * e, a.2 + 1.0);
                    total += 1;
                    lobes += u32::from(lobe);
                }
            }
        }
        guide.end_frame();
    }
    (acc, lobes as f64 / total.max(1) as f64)
}

/// The pooled z of the per-point relative errors: Σ (mean − E)/E over points against its
/// standard error.
fn pooled_z(acc: &[(f64, f64, f64); 8], scene: &ToyScene) -> f64 {
    let (mut diff, mut var) = (0.0, 0.0);
    for (i, &(s, s2, n)) in acc.iter().enumerate() {
        let exact = scene.irradiance(shading_point(i)).unwrap();
        let mean = s / n;
        let sample_var = (s2 / n - mean * mean) * n / (n - 1.0);
        diff += (mean - exact) / exact;
        var += sample_var / n / (exact * exact);
    }
    diff / var.sqrt()
}

/// Hypothesis: the guided estimator L·cos/p with p = `GuidedVertex::pdf` is unbiased for the
/// irradiance E(x) while the guide learns, on a light of radius 0.6 at distance 3.
/// 8 points × 64 spp × 24 frames (frames 4-23 counted: 10 240 samples, > 60 % of them from
/// lobes), pooled relative error against the closed form, |z| < 3.5 (fixed seed). A pdf that
/// forgets the factor 1 − p_bsdf on the lobes gives z ≈ −11.7 here.
#[test]
fn guided_estimate_is_unbiased() {
    let scene = medium_light();
    for hemisphere in [Hemisphere::Sphere, Hemisphere::CosineProduct] {
        let mut guide = toy_guide(hemisphere);
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let (acc, lobe_fraction) = run(&mut guide, &scene, 24, 4, 64, &mut rng);
        let z = pooled_z(&acc, &scene);
        assert!(z.abs() < 3.5, "{hemisphere:?}: z = {z}");
        assert!(lobe_fraction > 0.6, "{hemisphere:?}: {lobe_fraction}");
    }
}

/// Hypothesis: guiding lowers the variance of the irradiance estimate against cosine sampling
/// on a light of radius 0.6 at distance 3: after 8 frames of training, the guided
/// sample variance is below 1/4 of the cosine one (measured: 10.0 against 335, 1/33).
/// 8 points × 64 samples each.
#[test]
fn guiding_beats_cosine_sampling_on_a_small_light() {
    let scene = medium_light();
    let mut guide = toy_guide(Hemisphere::CosineProduct);
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    run(&mut guide, &scene, 8, 8, 64, &mut rng);
    let (guided, _) = run(&mut guide, &scene, 4, 0, 16, &mut rng);
    let var = |acc: &[(f64, f64, f64); 8]| -> f64 {
        acc.iter()
            .map(|&(s, s2, n)| s2 / n - (s / n) * (s / n))
            .sum()
    };
    let mut cosine = [(0.0, 0.0, 0.0); 8];
    for (i, a) in cosine.iter_mut().enumerate() {
        for _ in 0..64 {
            let (w, pdf) = mcg_markov_guide::cosine_hemisphere(
                TOY_NORMAL,
                Vec2::new(rng.random(), rng.random()),
            );
            let e = (scene.trace(shading_point(i), w).radiance * w.z / pdf) as f64;
            *a = (a.0 + e, a.1 + e * e, a.2 + 1.0);
        }
    }
    assert!(
        var(&guided) < 0.25 * var(&cosine),
        "{} vs {}",
        var(&guided),
        var(&cosine)
    );
}

/// `n` points of a Fibonacci sphere, each standing for 4π/n steradians.
fn fibonacci_sphere(n: usize) -> impl Iterator<Item = Vec3> {
    let golden = (1.0 + 5f64.sqrt()) / 2.0;
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = std::f64::consts::TAU * (i as f64 / golden).fract();
        Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
    })
}

/// Σ over a Fibonacci sphere of `pdf(ω)·4π/N`: the integral of the density.
fn integral(v: &GuidedVertex<'_, impl mcg_markov_guide::mcpg::Scatter>) -> f64 {
    let n = 200_000;
    fibonacci_sphere(n).map(|w| v.pdf(w) as f64).sum::<f64>() * 4.0 * std::f64::consts::PI
        / n as f64
}

/// The pdf is a density: it integrates to 1 (±0.5 %, quadrature of 200 000 points) for a
/// trained surface vertex with and without the cosine product, and for a volume vertex with
/// the isotropic phase function.
#[test]
fn pdf_integrates_to_one() {
    let scene = ToyScene::single_light();
    for hemisphere in [Hemisphere::Sphere, Hemisphere::CosineProduct] {
        let mut guide = toy_guide(hemisphere);
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        run(&mut guide, &scene, 6, 6, 64, &mut rng);
        let x = shading_point(5);
        let v = (0..100)
            .map(|_| {
                guide.begin(
                    Vertex::surface(x, TOY_NORMAL),
                    Lambertian { normal: TOY_NORMAL },
                    &BeginUniforms::from_fn(5, || rng.random()),
                )
            })
            .find(|v| v.candidates().iter().filter(|s| s.is_valid()).count() >= 2)
            .expect("a trained vertex");
        let total = integral(&v);
        mcg_test_support::assert_close!(total, 1.0, 5e-3, "{hemisphere:?}: {total}");
        let view = (x - Vec3::new(0.0, -2.5, 3.0)).normalize();
        let volume = guide.begin(
            Vertex::volume(x, view, Vec2::new(0.3, 0.6)),
            IsotropicPhase,
            &BeginUniforms::from_fn(5, || rng.random()),
        );
        let total = integral(&volume);
        mcg_test_support::assert_close!(total, 1.0, 5e-3, "volume: {total}");
    }
}

/// `GuidedVertex::weight_sum` is sum_mc = Σ w̄ over the prepared candidates (MCPG Alg. 1):
/// 0 on an empty guide, and on a trained one the sum of `candidates()`' w̄ in load order,
/// larger than any one of them where two or more are valid.
#[test]
fn weight_sum_is_the_candidates_sum() {
    let scene = ToyScene::single_light();
    let mut guide = toy_guide(Hemisphere::CosineProduct);
    let mut rng = Pcg64Mcg::seed_from_u64(12);
    fn begin<'g>(guide: &'g Guide, rng: &mut Pcg64Mcg) -> GuidedVertex<'g, Lambertian> {
        guide.begin(
            Vertex::surface(shading_point(3), TOY_NORMAL),
            Lambertian { normal: TOY_NORMAL },
            &BeginUniforms::from_fn(5, || rng.random()),
        )
    }
    assert_eq!(begin(&guide, &mut rng).weight_sum(), 0.0, "empty guide");
    run(&mut guide, &scene, 6, 6, 64, &mut rng);
    let mut checked = 0;
    for _ in 0..100 {
        let v = begin(&guide, &mut rng);
        let states = v.candidates();
        let sum = states.iter().fold(0.0_f32, |a, s| a + s.weight_sum);
        assert_eq!(v.weight_sum(), sum, "{states:?}");
        if states.iter().filter(|s| s.weight_sum > 0.0).count() >= 2 {
            let largest = states.iter().map(|s| s.weight_sum).fold(0.0, f32::max);
            assert!(v.weight_sum() > largest);
            checked += 1;
        }
    }
    assert!(checked > 0, "no vertex had two valid candidates");
}

/// The cosine product sends fewer guided directions below the surface. The chains are trained
/// on hits spread over a disc of radius 1.5 whose centre is 10° above the horizon of the
/// points (the same accepted observations in both modes, so the states are the same); then
/// 20 000 directions are drawn at the trained points. The fraction of lobe samples below the
/// surface must drop by half or more (measured: 24.0 % → 10.9 %).
#[test]
fn cosine_product_wastes_fewer_directions() {
    let mut fractions = Vec::new();
    for hemisphere in [Hemisphere::Sphere, Hemisphere::CosineProduct] {
        let guide = toy_guide(hemisphere);
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        for k in 0..4096 {
            let x = shading_point(k % 8);
            let v = guide.begin(
                Vertex::surface(x, TOY_NORMAL),
                Lambertian { normal: TOY_NORMAL },
                &BeginUniforms::from_fn(5, || rng.random()),
            );
            let s = v.sample(&SampleUniforms::from_fn(|| rng.random()));
            let (a, b): (f32, f32) = (rng.random(), rng.random());
            let (r, phi) = (1.5 * a.sqrt(), std::f32::consts::TAU * b);
            let target = Vec3::new(3.0, r * phi.cos(), 0.53 + r * phi.sin());
            let hit = VertexObservation::hit(target, -Vec3::X, Vec3::ONE, Vec3::ONE);
            v.finish(&s, &hit, &FinishUniforms::from_fn(|| rng.random()));
        }
        let (mut below, mut lobes) = (0u32, 0u32);
        for k in 0..20_000 {
            let v = guide.begin(
                Vertex::surface(shading_point(k % 8), TOY_NORMAL),
                Lambertian { normal: TOY_NORMAL },
                &BeginUniforms::from_fn(5, || rng.random()),
            );
            let s = v.sample(&SampleUniforms::from_fn(|| rng.random()));
            if s.lobe.is_some() {
                lobes += 1;
                below += u32::from(s.direction.z <= 0.0);
            }
        }
        fractions.push(below as f64 / lobes as f64);
    }
    assert!(fractions[1] < 0.5 * fractions[0], "{fractions:?}");
}

/// With one thread the guide is deterministic bit for bit: two runs from the same seed leave
/// identical grids and estimates.
#[test]
fn single_thread_runs_are_deterministic() {
    let scene = ToyScene::single_light();
    let mut results = Vec::new();
    for _ in 0..2 {
        let mut guide = toy_guide(Hemisphere::CosineProduct);
        let mut rng = Pcg64Mcg::seed_from_u64(21);
        let (acc, _) = run(&mut guide, &scene, 6, 0, 8, &mut rng);
        let (a, s) = guide.grids_mut();
        results.push((acc, a.snapshot(), s.snapshot()));
    }
    assert_eq!(results[0].0, results[1].0);
    assert!(results[0].1 == results[1].1 && results[0].2 == results[1].2);
    assert!(results[0].1.iter().any(|s| s.is_valid()));
}

/// Hypothesis: a guide shared by 2 threads stays unbiased (pooled z as in
/// `guided_estimate_is_unbiased`, |z| < 3.5) and every state stays finite.
#[test]
fn two_threads_share_a_guide() {
    let scene = medium_light();
    let mut guide = toy_guide(Hemisphere::CosineProduct);
    let mut acc = [(0.0, 0.0, 0.0); 8];
    for frame in 0..16u64 {
        let parts: Vec<[(f64, f64, f64); 8]> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..2u64)
                .map(|t| {
                    let (guide, scene) = (&guide, &scene);
                    s.spawn(move || {
                        let mut rng = Pcg64Mcg::seed_from_u64(1000 * frame + t);
                        let mut acc = [(0.0, 0.0, 0.0); 8];
                        for (i, a) in acc.iter_mut().enumerate() {
                            for _ in 0..64 {
                                let (e, _) =
                                    guided_sample(guide, scene, shading_point(i), &mut rng);
                                *a = (a.0 + e, a.1 + e * e, a.2 + 1.0);
                            }
                        }
                        acc
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        guide.end_frame();
        if frame >= 4 {
            for part in parts {
                for (a, p) in acc.iter_mut().zip(part) {
                    *a = (a.0 + p.0, a.1 + p.1, a.2 + p.2);
                }
            }
        }
    }
    let z = pooled_z(&acc, &scene);
    assert!(z.abs() < 3.5, "z = {z}");
    let (a, _) = guide.grids_mut();
    assert!(a.snapshot().iter().all(state_is_finite));
}

fn state_is_finite(s: &mcg_markov_guide::mcpg::GridState) -> bool {
    s.mean_target.is_finite()
        && s.weight_sum.is_finite()
        && s.one_minus_mean_cosine.is_finite()
        && s.time.is_finite()
        && s.velocity().is_finite()
}

/// NaN and infinite radiance and weights, zero and NaN normals, points far outside any grid,
/// NaN positions and empty frames: nothing panics, every state stays finite, and afterwards
/// the guided estimate is still unbiased (the test of `guided_estimate_is_unbiased`).
#[test]
fn bad_input_leaves_states_finite_and_estimates_unbiased() {
    let scene = medium_light();
    let mut config = GuideConfig::for_scene(Vec3::splat(-5.0), Vec3::splat(5.0));
    config.adaptive_capacity = 1 << 14;
    config.static_capacity = 1 << 10;
    config.cache = Some(CacheConfig {
        capacity: 1 << 12,
        ..CacheConfig::DEFAULT
    });
    let mut guide = Guide::new(config).unwrap();
    guide.set_camera(Vec3::new(0.0, -2.5, 3.0));
    let mut rng = Pcg64Mcg::seed_from_u64(9);
    for _ in 0..3 {
        guide.end_frame(); // empty frames
    }
    let bad_points = [
        (Vec3::splat(1e30), TOY_NORMAL),
        (Vec3::new(-1e38, 5.0, 1e38), Vec3::ZERO),
        (Vec3::splat(f32::NAN), TOY_NORMAL),
        (Vec3::ZERO, Vec3::splat(f32::NAN)),
        (Vec3::new(0.1, 0.0, 0.0), Vec3::ZERO),
    ];
    let bad_values = [f32::NAN, f32::INFINITY, -1.0, 1e38];
    for round in 0..400 {
        let (x, n) = bad_points[round % bad_points.len()];
        let v = guide.begin(
            Vertex::surface(x, n),
            Lambertian { normal: n },
            &BeginUniforms::from_fn(5, || rng.random()),
        );
        let s = v.sample(&SampleUniforms::from_fn(|| rng.random()));
        let bad = bad_values[round % bad_values.len()];
        let next = [Vec3::splat(bad), Vec3::new(0.0, 0.0, 3.0)][round % 2];
        let obs = VertexObservation::hit(next, n, Vec3::splat(bad), Vec3::splat(bad));
        v.finish(&s, &obs, &FinishUniforms::from_fn(|| rng.random()));
        let esc = VertexObservation::escaped(Vec3::splat(bad), Vec3::ONE);
        v.finish(&s, &esc, &FinishUniforms::from_fn(|| rng.random()));
        if round % 100 == 99 {
            guide.end_frame();
        }
    }
    let (a, s) = guide.grids_mut();
    assert!(
        a.snapshot()
            .iter()
            .chain(&s.snapshot())
            .all(state_is_finite)
    );
    assert!(
        guide
            .cache()
            .unwrap()
            .cells()
            .iter()
            .all(|c| c.radiance.iter().all(|r| r.is_finite()) && c.weight.is_finite())
    );
    let (acc, _) = run(&mut guide, &scene, 24, 4, 64, &mut rng);
    let z = pooled_z(&acc, &scene);
    assert!(z.abs() < 3.5, "z = {z}");
}

/// The cache: a frame's samples are averaged into a cell, later frames blend in with
/// α = max(1/frames, α_min), queries read the committed value only, NaN samples are ignored,
/// and idle cells are evicted after `max_age` frames.
#[test]
fn irradiance_cache_accumulates_and_evicts() {
    let grid = AdaptiveGrid::new(LevelParams {
        min_width: 0.1,
        ..LevelParams::MCPG
    })
    .unwrap();
    let config = CacheConfig {
        capacity: 256,
        accumulation: 0.25,
        coarser_levels: 2,
        max_age: 2,
        level_bias: 0,
        add_probability: 1.0,
    };
    let mut cache = IrradianceCache::new(grid, config).unwrap();
    let (x, n, cam) = (
        Vec3::new(0.35, 0.35, 0.0),
        Vec3::Z,
        Vec3::new(0.0, 0.0, 2.0),
    );
    let level = cache.level(x, cam);
    assert_eq!(cache.query(x, n, level, 0.5), Vec3::ZERO);
    assert!(cache.add(x, n, level, 0.5, Vec3::new(1.0, 2.0, 3.0)));
    assert!(cache.add(x, n, level, 0.5, Vec3::new(3.0, 2.0, 1.0)));
    assert!(!cache.add(x, n, level, 0.5, Vec3::new(f32::NAN, 0.0, 0.0)));
    assert_eq!(cache.query(x, n, level, 0.5), Vec3::ZERO); // not committed yet
    cache.end_frame();
    assert_eq!(cache.query(x, n, level, 0.5), Vec3::splat(2.0));
    // Second frame: α = 1/2; then α_min = 1/4 from the fourth frame on.
    cache.add(x, n, level, 0.5, Vec3::splat(4.0));
    cache.end_frame();
    assert_eq!(cache.query(x, n, level, 0.5), Vec3::splat(3.0));
    for _ in 0..2 {
        cache.add(x, n, level, 0.5, Vec3::splat(3.0));
        cache.end_frame();
    }
    cache.add(x, n, level, 0.5, Vec3::splat(7.0));
    cache.end_frame();
    assert_eq!(cache.query(x, n, level, 0.5), Vec3::splat(4.0));
    // The other side of the surface is another cell.
    assert_eq!(cache.query(x, -n, level, 0.5), Vec3::ZERO);
    assert_eq!(cache.cells().iter().filter(|c| c.weight > 0.0).count(), 1);
    // Idle: evicted after more than max_age frames.
    for _ in 0..4 {
        cache.end_frame();
    }
    assert_eq!(cache.cells().iter().filter(|c| c.weight > 0.0).count(), 0);
}

/// A full probe neighbourhood moves an insert to a coarser level, and the lookup follows it.
#[test]
fn cache_goes_coarser_on_collision() {
    let grid = AdaptiveGrid::new(LevelParams {
        min_width: 0.1,
        ..LevelParams::MCPG
    })
    .unwrap();
    let config = CacheConfig {
        capacity: 8,
        accumulation: 0.25,
        coarser_levels: 6,
        max_age: 100,
        level_bias: 0,
        add_probability: 1.0,
    };
    let mut cache = IrradianceCache::new(grid, config).unwrap();
    let cam = Vec3::ZERO;
    let points: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new(i as f32 * 0.5 + 0.2, 0.2, 0.2))
        .collect();
    let stored: Vec<bool> = points
        .iter()
        .map(|&p| cache.add(p, Vec3::Z, cache.level(p, cam), 0.0, Vec3::ONE))
        .collect();
    cache.end_frame();
    assert!(stored.iter().all(|&s| s), "{stored:?}");
    // 8 slots, all taken: a ninth far point can only share a coarse cell or be dropped.
    let far = Vec3::new(100.0, 100.0, 100.0);
    if cache.add(far, Vec3::Z, cache.level(far, cam), 0.0, Vec3::splat(5.0)) {
        cache.end_frame();
        assert!(
            cache
                .query(far, Vec3::Z, cache.level(far, cam), 0.0)
                .max_element()
                > 0.0
        );
    }
    for &p in &points {
        assert!(
            cache
                .query(p, Vec3::Z, cache.level(p, cam), 0.0)
                .max_element()
                > 0.0
        );
    }
}

/// Transitions are reported: the first accepted sample stores, a zero estimate is rejected.
#[test]
fn finish_reports_transitions() {
    let guide = toy_guide(Hemisphere::Sphere);
    let x = shading_point(0);
    let v = guide.begin(
        Vertex::surface(x, TOY_NORMAL),
        Lambertian { normal: TOY_NORMAL },
        &BeginUniforms::from_fn(5, || 0.5),
    );
    let s = v.sample(&SampleUniforms::from_fn(|| 0.5));
    assert_eq!(s.lobe, None);
    let up = VertexObservation::hit(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, Vec3::ONE, Vec3::ONE);
    assert_eq!(
        v.finish(&s, &up, &FinishUniforms::from_fn(|| 0.5)),
        Transition::Stored
    );
    let dark = VertexObservation::hit(Vec3::new(0.0, 0.0, 3.0), -Vec3::Z, Vec3::ZERO, Vec3::ONE);
    assert_eq!(
        v.finish(&s, &dark, &FinishUniforms::from_fn(|| 0.5)),
        Transition::Rejected
    );
}

/// `VertexObservation::emission_weight` w_e (a renderer's MIS weight of emission it also
/// samples as a light): the chain learns from weight·(w_e·L_e + L_r), the irradiance cache
/// from weight·(L_e + L_r). An emitter hit that the light sample carries entirely (w_e = 0)
/// and that reflects nothing trains no chain (rejected: its estimate is 0) but reaches the
/// cache; w_e = 1, NaN (counts as 1) and 3 (clamped to 1) store, and so does w_e = 0 with a
/// reflected part. (With the weight ignored, the first case stores; with it applied to the
/// cache as well, the cache stays empty.)
#[test]
fn emission_weight_splits_the_chain_from_the_cache() {
    let camera = Vec3::new(0.5, 0.5, 0.9);
    let fresh_guide = || {
        let mut config = GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE).for_camera(1.0, 32);
        config.adaptive_capacity = 1 << 12;
        config.static_capacity = 1 << 10;
        config.cache = Some(CacheConfig {
            capacity: 1 << 10,
            add_probability: 1.0,
            ..CacheConfig::DEFAULT
        });
        let mut guide = Guide::new(config).unwrap();
        guide.set_camera(camera);
        guide
    };
    let (x, n) = (Vec3::new(0.5, 0.5, 0.0), Vec3::Z);
    let light = VertexObservation::hit(
        Vec3::new(0.5, 0.5, 1.0),
        -Vec3::Z,
        Vec3::splat(4.0),
        Vec3::splat(0.5),
    );
    let observed = |w_e: f32, reflected: Option<Vec3>| VertexObservation {
        emission_weight: w_e,
        reflected,
        ..light
    };
    let finish = |guide: &Guide, observation: &VertexObservation| {
        let v = guide.begin(
            Vertex::surface(x, n),
            Lambertian { normal: n },
            &BeginUniforms::from_fn(5, || 0.5),
        );
        let s = v.sample(&SampleUniforms::from_fn(|| 0.5));
        assert_eq!(s.lobe, None, "an empty guide samples the material");
        v.finish(&s, observation, &FinishUniforms::from_fn(|| 0.5))
    };
    let mut guide = fresh_guide();
    assert_eq!(
        finish(&guide, &observed(0.0, Some(Vec3::ZERO))),
        Transition::Rejected
    );
    let level = guide.cache().unwrap().level(x, camera);
    guide.end_frame();
    // The cache received weight·L_e = 2 although the chain learnt nothing.
    assert_eq!(
        guide.cache().unwrap().query(x, n, level, 0.5),
        Vec3::splat(2.0)
    );
    for (w_e, reflected, expected) in [
        (1.0, Some(Vec3::ZERO), Transition::Stored),
        (f32::NAN, Some(Vec3::ZERO), Transition::Stored),
        (3.0, Some(Vec3::ZERO), Transition::Stored),
        (0.0, Some(Vec3::splat(0.1)), Transition::Stored),
        (-1.0, Some(Vec3::ZERO), Transition::Rejected),
        // L_r from the cache at the light's position, where nothing was added.
        (0.0, None, Transition::Rejected),
    ] {
        assert_eq!(
            finish(&fresh_guide(), &observed(w_e, reflected)),
            expected,
            "w_e {w_e}, L_r {reflected:?}"
        );
    }
}

/// Where a ray from inside the unit cube leaves it: the point and the inward normal there.
fn cube_exit(o: Vec3, d: Vec3) -> (Vec3, Vec3) {
    let mut best = (f32::INFINITY, 0);
    for axis in 0..3 {
        if d[axis] != 0.0 {
            let wall = if d[axis] > 0.0 { 1.0 } else { 0.0 };
            let t = (wall - o[axis]) / d[axis];
            if t > 0.0 && t < best.0 {
                best = (t, axis);
            }
        }
    }
    let p = (o + best.0 * d).clamp(Vec3::splat(1e-4), Vec3::splat(1.0 - 1e-4));
    let mut n = Vec3::ZERO;
    n[best.1] = -d[best.1].signum();
    (p, n)
}

/// Hypothesis: paths of 3 bounces guided at every vertex, with the chains trained through the
/// irradiance cache, estimate the radiance without bias. A closed unit cube whose walls all
/// emit L_e = 1 and reflect albedo a = 0.5 (a furnace): every path of 3 bounces has expected
/// radiance 1 + a + a² + a³ = 1.875, whatever the sampling. 12 frames × 2 048 camera paths
/// from the cube's centre (frames 2-11 counted, 20 480 paths, > 20 000 lobe samples); |z| < 3.5
/// against 1.875 (fixed seed; seeds 1-6 gave z in [−1.8, 0.7]). The check decides: a pdf that
/// forgets the factor 1 − p_bsdf on the lobes gives z ≈ −19.7.
#[test]
fn three_bounce_furnace_is_unbiased_with_the_cache() {
    let mut config = GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE).for_camera(1.0, 32);
    config.adaptive_capacity = 1 << 14;
    config.static_capacity = 1 << 10;
    config.cache = Some(CacheConfig {
        capacity: 1 << 12,
        ..CacheConfig::DEFAULT
    });
    let mut guide = Guide::new(config).unwrap();
    let camera = Vec3::splat(0.5);
    guide.set_camera(camera);
    let (albedo, emitted) = (0.5f32, 1.0f32);
    let mut rng = Pcg64Mcg::seed_from_u64(1);
    let (mut sum, mut sum2, mut count, mut lobes) = (0.0f64, 0.0f64, 0.0f64, 0u32);
    for frame in 0..12 {
        for _ in 0..2048 {
            let d = mcg_markov_guide::mcg_vmf::Vmf::uniform()
                .sample(Vec2::new(rng.random(), rng.random()));
            let (mut x, mut n) = cube_exit(camera, d);
            let (mut radiance, mut throughput) = (emitted, 1.0f32);
            for _ in 0..3 {
                let v = guide.begin(
                    Vertex::surface(x, n),
                    Lambertian { normal: n },
                    &BeginUniforms::from_fn(5, || rng.random()),
                );
                let s = v.sample(&SampleUniforms::from_fn(|| rng.random()));
                lobes += u32::from(s.lobe.is_some());
                let cos = n.dot(s.direction);
                let weight = if cos > 0.0 {
                    albedo * cos / std::f32::consts::PI / s.pdf
                } else {
                    0.0
                };
                let (next, next_n) = cube_exit(x, s.direction);
                let seen =
                    VertexObservation::hit(next, next_n, Vec3::splat(emitted), Vec3::splat(weight));
                v.finish(&s, &seen, &FinishUniforms::from_fn(|| rng.random()));
                throughput *= weight;
                if throughput == 0.0 {
                    break;
                }
                radiance += throughput * emitted;
                (x, n) = (next, next_n);
            }
            if frame >= 2 {
                let r = f64::from(radiance);
                (sum, sum2, count) = (sum + r, sum2 + r * r, count + 1.0);
            }
        }
        guide.end_frame();
    }
    let mean = sum / count;
    let sd = ((sum2 / count - mean * mean) / (count - 1.0)).sqrt();
    let z = (mean - 1.875) / sd;
    assert!(z.abs() < 3.5, "mean {mean}, z = {z}");
    assert!(lobes > 20_000, "{lobes} lobe samples");
}

/// mcg's extension `McpgParams::confidence_samples` (N_c), checked at one static-grid vertex
/// whose every uniform is fixed, so that each `begin` reads and each `finish` stores the same
/// state. A first scatter sample stores a one-sample chain; then, while that state is chosen:
/// - its lobe gets the part (1 − p_bsdf)·(1 − y) of the choices, y = `young_share(1)` = 15/16
///   (a sweep of 10 000 choice uniforms, ±0.01 %), and the pdf still integrates to 1;
/// - a scatter sample continues its chain (N = 2 after the next accepted `finish`), where the
///   paper (N_c = 0) restarts it (N = 1).
///
/// Breaking any of the three (the lobe choice, the scatter share of the pdf, the continued
/// chain) fails this test.
#[test]
fn young_chains_lend_their_share_and_continue() {
    let x = Vec3::new(0.3, 0.2, 0.0);
    // Static grid only; corner 0 picks the same vertex in `begin` and in `finish`.
    let begin_u = BeginUniforms::from_fn(1, || 0.0);
    let finish_u = FinishUniforms::from_fn(|| 0.0);
    let hit = VertexObservation::hit(
        Vec3::new(0.5, 0.4, 3.0),
        -Vec3::Z,
        Vec3::splat(10.0),
        Vec3::ONE,
    );
    for confidence in [16.0, 0.0] {
        let mut config = GuideConfig::for_scene(Vec3::splat(-5.0), Vec3::splat(5.0));
        config.cache = None;
        config.params.candidates = 1;
        config.params.adaptive_probability = 0.0;
        config.params.confidence_samples = confidence;
        let guide = Guide::new(config).unwrap();
        let begin = || {
            guide.begin(
                Vertex::surface(x, TOY_NORMAL),
                Lambertian { normal: TOY_NORMAL },
                &begin_u,
            )
        };
        let scatter = SampleUniforms {
            choice: 0.0,
            direction: Vec2::new(0.3, 0.7),
        };
        // The empty grid: a scatter sample, accepted, stores a one-sample state.
        let v = begin();
        let s = v.sample(&scatter);
        assert_eq!(v.finish(&s, &hit, &finish_u), Transition::Stored);
        let v = begin();
        assert_eq!(v.candidates()[0].sample_count(), 1, "N_c {confidence}");
        assert_eq!(v.selected(), Some(0));
        let p = guide.params().bsdf_probability;
        let young = guide.params().young_share(1);
        let n = 10_000;
        let lobes = (0..n)
            .filter(|i| {
                let u = SampleUniforms {
                    choice: (*i as f32 + 0.5) / n as f32,
                    direction: Vec2::new(0.3, 0.7),
                };
                v.sample(&u).lobe.is_some()
            })
            .count();
        let expected = (1.0 - p) * (1.0 - young);
        mcg_test_support::assert_close!(
            lobes as f32 / n as f32,
            expected,
            1e-4,
            "N_c {confidence}"
        );
        let total = integral(&v);
        mcg_test_support::assert_close!(total, 1.0, 5e-3, "N_c {confidence}: {total}");
        // A scatter sample (choice below p_bsdf), accepted: continued or restarted.
        let s = v.sample(&scatter);
        assert_eq!(s.lobe, None);
        assert_eq!(v.finish(&s, &hit, &finish_u), Transition::Stored);
        let after = begin().candidates()[0].sample_count();
        let want = if confidence > 0.0 { 2 } else { 1 };
        assert_eq!(after, want, "N_c {confidence}");
    }
}

/// `Guide::begin_in` over a vertex begun elsewhere (another point, a non-finite one, another
/// normal) answers as `begin`'s vertex bit for bit: the candidates, the choice, 16 samples
/// (direction, pdf, lobe) and the density at 16 directions, for 512 vertices of a trained
/// guide (both hemisphere options, young chains lending N_c = 16), the points around the
/// trained ones and a few non-finite.
#[test]
fn begin_in_equals_begin() {
    let scene = medium_light();
    for hemisphere in [Hemisphere::Sphere, Hemisphere::CosineProduct] {
        let mut config = *toy_guide(hemisphere).config();
        config.params.confidence_samples = 16.0;
        let mut guide = Guide::new(config).unwrap();
        guide.set_camera(Vec3::new(0.0, -2.5, 3.0));
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        run(&mut guide, &scene, 6, 6, 32, &mut rng);
        let n = guide.params().candidates as usize;
        let scatter = |normal: Vec3| Lambertian { normal };
        let tilted = Vec3::new(0.3, 0.1, 1.0).normalize();
        let mut kept = guide.begin(
            Vertex::surface(Vec3::new(0.1, 0.0, 0.0), tilted),
            scatter(tilted),
            &BeginUniforms::from_fn(n, || rng.random()),
        );
        let mut lobes = 0;
        for i in 0..512 {
            let x = if i % 97 == 5 {
                Vec3::new(f32::NAN, 0.0, 0.0)
            } else {
                shading_point(i % 8) + Vec3::new(rng.random(), rng.random(), 0.0) * 0.05
            };
            let normal = if i % 5 == 0 { tilted } else { TOY_NORMAL };
            let u = BeginUniforms::from_fn(n, || rng.random());
            let fresh = guide.begin(Vertex::surface(x, normal), scatter(normal), &u);
            guide.begin_in(&mut kept, Vertex::surface(x, normal), scatter(normal), &u);
            assert_eq!(
                format!("{:?}", fresh.candidates()),
                format!("{:?}", kept.candidates()),
                "vertex {i}"
            );
            assert_eq!(fresh.selected(), kept.selected(), "vertex {i}");
            for _ in 0..16 {
                let su = SampleUniforms::from_fn(|| rng.random());
                let (a, b) = (fresh.sample(&su), kept.sample(&su));
                assert_eq!(a.lobe, b.lobe, "vertex {i}");
                assert_eq!(
                    a.direction.to_array().map(f32::to_bits),
                    b.direction.to_array().map(f32::to_bits)
                );
                assert_eq!(a.pdf.to_bits(), b.pdf.to_bits(), "vertex {i}");
                lobes += u32::from(a.lobe.is_some());
                let w = mcg_markov_guide::mcg_vmf::uniform_sphere(Vec2::new(
                    rng.random(),
                    rng.random(),
                ));
                assert_eq!(fresh.pdf(w).to_bits(), kept.pdf(w).to_bits(), "vertex {i}");
            }
        }
        assert!(lobes > 1000, "{lobes}");
    }
}

/// The bin of `w` among 16: 4 bands of z (the toy scene's normal) × 4 sectors of φ.
fn sphere_bin(w: Vec3) -> usize {
    let band = (((w.z + 1.0) * 2.0) as usize).min(3);
    let sector = (((w.y.atan2(w.x) / std::f32::consts::TAU) + 0.5) * 4.0) as usize;
    band * 4 + sector.min(3)
}

/// Pearson's X² of `counts` against the mass of the vertex's `pdf` in each [`sphere_bin`]
/// (quadrature over 400 000 Fibonacci points).
fn chi_square_against_pdf(
    v: &GuidedVertex<'_, impl mcg_markov_guide::mcpg::Scatter>,
    counts: &[u64; 16],
) -> f64 {
    let n = 400_000;
    let mut mass = [0.0f64; 16];
    for w in fibonacci_sphere(n) {
        mass[sphere_bin(w)] += f64::from(v.pdf(w)) * 4.0 * std::f64::consts::PI / n as f64;
    }
    let total: u64 = counts.iter().sum();
    let norm: f64 = mass.iter().sum();
    counts
        .iter()
        .zip(mass)
        .map(|(&o, m)| {
            let e = total as f64 * m / norm;
            (o as f64 - e).powi(2) / e.max(1e-9)
        })
        .sum()
}

/// `sample_mixture` draws from exactly the density `pdf` describes at the vertex (given the
/// vertex, not only on average over Alg. 1's choice). Hypothesis: 200 000 directions at one
/// trained surface vertex (cosine product, at least three candidates with lobes) fall into 16
/// bins (4 bands of z × 4 sectors of φ) with the frequencies of the pdf's mass per bin.
/// Threshold: X² < 44.6 (15 degrees of freedom, α ≈ 10⁻⁴). Negative control at the same
/// vertex: the directions of `sample` (the lobe of the state Alg. 1 chose, whose
/// density given the vertex is that lobe's) must be rejected, X² > 1000.
#[test]
fn sample_mixture_draws_from_the_vertex_density() {
    let scene = medium_light();
    let mut guide = toy_guide(Hemisphere::CosineProduct);
    let mut rng = Pcg64Mcg::seed_from_u64(23);
    run(&mut guide, &scene, 6, 6, 64, &mut rng);
    let v = (0..400)
        .map(|i| {
            guide.begin(
                Vertex::surface(shading_point(i % 8), TOY_NORMAL),
                Lambertian { normal: TOY_NORMAL },
                &BeginUniforms::from_fn(5, || rng.random()),
            )
        })
        .find(|v| v.candidates().iter().filter(|s| s.is_valid()).count() >= 3)
        .expect("a trained vertex");
    let (mut mixture, mut chosen) = ([0u64; 16], [0u64; 16]);
    for _ in 0..200_000 {
        let u = SampleUniforms::from_fn(|| rng.random());
        mixture[sphere_bin(v.sample_mixture(&u))] += 1;
        chosen[sphere_bin(v.sample(&u).direction)] += 1;
    }
    let x2 = chi_square_against_pdf(&v, &mixture);
    assert!(x2 < 44.6, "sample_mixture: X² = {x2} ({mixture:?})");
    let control = chi_square_against_pdf(&v, &chosen);
    assert!(control > 1000.0, "sample: X² = {control}");
}
