//! CPU/GPU parity of ADGI's probe cache: `mcg::adgi` through `GpuProbeCache` against
//! `mcg_probe_cache::ProbeTexels` for the same samples, rays and uniforms.
//!
//! Equal bit for bit, but for a few fields a code step or two apart (`assert_words_close`):
//! every texel word after ADGI's per-sample updates (static and dynamic moving average,
//! stochastic and round-down rounding), after DDGI's blend, and after the clip-volume reset.
//! Within a tolerance: the irradiance query, whose `sqrt`, `pow`, division
//! and fusable products WGSL computes within a few ULP (WGSL spec, "Floating Point Accuracy")
//! where the CPU rounds exactly; every weight of the query is continuous in its inputs, so
//! those ULPs stay ULPs — relative 10⁻⁴ bounds them with margin (observed below 10⁻⁶).

mod common;

use std::collections::HashSet;

use glam::camera::rh::{proj::directx::perspective, view::look_at_mat4};
use glam::{UVec3, Vec3};
use mcg_color_codec::MovingAverage;
use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::guides::adgi::{
    GpuIrradianceQuery, GpuProbeCache, GpuRaySample, ProbeCacheConfig,
};
use mcg_probe_cache::clip_volume::{
    ClipRegion, ClipVolumes, SHELL_COUNT, clamp_irradiance_counts, clamp_visibility_counts,
};
use mcg_probe_cache::{
    BlendWeights, ProbeGrid, ProbeTexels, QueryConfig, RaySample, RoundingMode, TexelConfig,
};
use rand::{Rng, RngExt};

fn grid() -> ProbeGrid {
    ProbeGrid::new(
        Vec3::new(-1.0, 0.0, 0.5),
        Vec3::new(1.0, 1.5, 0.75),
        UVec3::new(3, 2, 2),
    )
    .unwrap()
}

fn config(texels: TexelConfig, rays_per_probe: u32) -> ProbeCacheConfig {
    ProbeCacheConfig {
        grid: grid(),
        texels,
        query: QueryConfig::DDGI,
        blend: BlendWeights::DDGI,
        rays_per_probe,
    }
}

fn unit_direction(rng: &mut impl Rng) -> Vec3 {
    let z: f32 = rng.random::<f32>() * 2.0 - 1.0;
    let phi: f32 = rng.random::<f32>() * core::f32::consts::TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A ray with the awkward cases mixed in: unnormalised directions, zero and NaN directions,
/// NaN and infinite radiance, misses (+∞), NaN and negative distances.
fn random_ray(rng: &mut impl Rng) -> RaySample {
    let mut direction = unit_direction(rng) * rng.random_range(0.2f32..3.0);
    let mut radiance = Vec3::new(
        rng.random_range(0.0f32..4.0),
        rng.random_range(0.0f32..2.0),
        rng.random_range(0.0f32..1.0),
    );
    let mut distance = rng.random_range(0.0f32..6.0);
    match rng.random_range(0u32..40) {
        0 => direction = Vec3::ZERO,
        1 => direction = Vec3::NAN,
        2 => radiance.y = f32::NAN,
        3 => radiance = Vec3::INFINITY,
        4 => distance = f32::INFINITY,
        5 => distance = f32::NAN,
        6 => distance = -1.0,
        _ => {}
    }
    RaySample {
        direction,
        radiance,
        distance,
    }
}

fn cpu_words(t: &ProbeTexels) -> (Vec<u32>, Vec<u32>) {
    (t.irradiance_words(), t.visibility_words())
}

/// The first word index where two word arrays differ, for the failure message.
fn first_difference(a: &[u32], b: &[u32]) -> Option<(usize, u32, u32)> {
    a.iter()
        .zip(b)
        .enumerate()
        .find(|(_, (x, y))| x != y)
        .map(|(i, (x, y))| (i, *x, *y))
}

fn assert_words_equal(ctx: &GpuContext, gpu: &GpuProbeCache, cpu: &ProbeTexels, what: &str) {
    let (gi, gv) = gpu.read_words(ctx).unwrap();
    let (ci, cv) = cpu_words(cpu);
    let config = cpu.config();
    let (irradiance, visibility) = (config.irradiance_layout, config.visibility_layout);
    let irradiance_fields = |w: u32| {
        let w = mcg_color_codec::IrradianceWord(w);
        (irradiance.codes(w).to_vec(), irradiance.count(w))
    };
    let visibility_fields = |w: u32| {
        let w = mcg_color_codec::VisibilityWord(w);
        (visibility.codes(w).to_vec(), visibility.count(w))
    };
    assert_words_close(
        &gi,
        &ci,
        irradiance_fields,
        &format!("{what}: irradiance words"),
    );
    assert_words_close(
        &gv,
        &cv,
        visibility_fields,
        &format!("{what}: visibility words"),
    );
}

/// The GPU's words equal the CPU's, or, for at most 2 % of them, carry the same count and
/// each field's code within two steps of the CPU's. WGSL's division and fused multiply-adds
/// put the float before quantisation a few ULP from the CPU's, and a value that close to a
/// rounding threshold takes the neighbouring code; the moving averages then carry such a
/// step into later frames. Lavapipe matches bit for bit; an NVIDIA H200 put one field of one
/// word one step over in two of the tests below (first differences seen: 0x09637090 against
/// 0x09637091, 0x125a7505 against 0x125a5505).
fn assert_words_close(
    gpu: &[u32],
    cpu: &[u32],
    fields: impl Fn(u32) -> (Vec<u32>, u32),
    what: &str,
) {
    assert_eq!(gpu.len(), cpu.len(), "{what}: lengths");
    let mut differing = 0;
    for (i, (&g, &c)) in gpu.iter().zip(cpu).enumerate() {
        if g == c {
            continue;
        }
        differing += 1;
        let ((gc, gn), (cc, cn)) = (fields(g), fields(c));
        let near = gn == cn && gc.iter().zip(&cc).all(|(a, b)| a.abs_diff(*b) <= 2);
        assert!(near, "{what}: word {i}, GPU {g:#010x} CPU {c:#010x}");
    }
    assert!(
        differing <= cpu.len() / 50,
        "{what}: {differing} of {} words differ (first {:?})",
        cpu.len(),
        first_difference(gpu, cpu)
    );
}

/// ADGI's per-sample update, 12 rounds of 400 samples at random probes (the first 6 rounds
/// with the static average N_max = 63, then the dynamic N_max = 10 over the grown counts), for
/// stochastic and round-down rounding: the GPU's words equal the CPU's serial updates bit for
/// bit. Within one dispatch samples race, so each round keeps only samples whose irradiance
/// and visibility texels no earlier sample of the round touched (then any order gives the
/// serial result).
#[test]
fn per_sample_updates_write_the_cpu_words() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("per_sample_updates_write_the_cpu_words", 20)
    else {
        return;
    };
    for rounding in [RoundingMode::Stochastic, RoundingMode::Down] {
        let texels = TexelConfig {
            rounding,
            ..TexelConfig::ADGI
        };
        let cfg = config(texels, 1);
        let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
        let cpu = ProbeTexels::new(cfg.grid, texels);
        let (im, vm) = (texels.irradiance_map, texels.visibility_map);
        let mut updates = 0;
        for round in 0..12 {
            let average = if round < 6 {
                MovingAverage::STATIC
            } else {
                MovingAverage::DYNAMIC
            };
            let mut used = HashSet::new();
            let mut samples = Vec::new();
            let mut uniforms = Vec::new();
            for _ in 0..400 {
                let probe = rng.random_range(0..cfg.grid.probe_count());
                let ray = random_ray(&mut rng);
                let ti = im.index(im.texel(ray.direction));
                let tv = vm.index(vm.texel(ray.direction));
                if used.contains(&(probe, 0, ti)) || used.contains(&(probe, 1, tv)) {
                    continue;
                }
                used.insert((probe, 0, ti));
                used.insert((probe, 1, tv));
                let u: f32 = rng.random();
                cpu.update_sample_with(probe, &ray, u, average);
                samples.push(GpuRaySample::new(probe as u32, &ray));
                uniforms.push(u);
            }
            updates += samples.len();
            gpu.update_samples(ctx, &samples, &uniforms, average)
                .unwrap();
        }
        assert!(updates > 2000, "{updates} updates");
        assert_words_equal(ctx, &gpu, &cpu, &format!("{rounding:?}"));
        // The updates reached the dynamic cap: some count is exactly 10.
        let (words, _) = gpu.read_words(ctx).unwrap();
        let layout = texels.irradiance_layout;
        assert!(
            words
                .iter()
                .any(|&w| layout.count(mcg_color_codec::IrradianceWord(w)) == 10)
        );
    }
}

/// DDGI's blend, 4 frames of 48 rays per probe on every probe (with the awkward rays of
/// [`random_ray`]) and a fresh uniform per probe and frame: the GPU's words equal
/// `ProbeTexels::blend_rays`' (`assert_words_close`).
#[test]
fn ddgi_blend_writes_the_cpu_words() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("ddgi_blend_writes_the_cpu_words", 21) else {
        return;
    };
    let rays_per_probe = 48;
    let cfg = config(TexelConfig::ADGI, rays_per_probe);
    let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
    let cpu = ProbeTexels::new(cfg.grid, TexelConfig::ADGI);
    let probes = cfg.grid.probe_count();
    for _ in 0..4 {
        let mut gpu_rays = Vec::new();
        let mut uniforms = Vec::new();
        for probe in 0..probes {
            let rays: Vec<RaySample> = (0..rays_per_probe).map(|_| random_ray(&mut rng)).collect();
            let u: f32 = rng.random();
            cpu.blend_rays(probe, &rays, &cfg.blend, u);
            gpu_rays.extend(rays.iter().map(|r| GpuRaySample::new(probe as u32, r)));
            uniforms.push(u);
        }
        gpu.blend(ctx, &gpu_rays, &uniforms).unwrap();
    }
    assert_words_equal(ctx, &gpu, &cpu, "blend");
    let (words, _) = gpu.read_words(ctx).unwrap();
    assert!(words.iter().filter(|&&w| w != 0).count() > probes * 30);
}

/// Relative closeness with an absolute floor (irradiance values are O(1)).
fn close(a: Vec3, b: Vec3, rel: f32) -> bool {
    (a - b).abs().max_element() <= rel * a.abs().max(b.abs()).max_element() + 1e-6
}

/// The irradiance query at 600 points (inside, on and outside the grid) with random normals and
/// view directions, on texels filled by DDGI's blend (read as irradiance) and by ADGI's
/// per-sample update (read as radiance, the cosine convolution), with and without visibility
/// and the square-root blend: GPU within relative 10⁻⁴ of the CPU.
#[test]
fn irradiance_query_matches_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("irradiance_query_matches_the_cpu", 22) else {
        return;
    };
    let rays_per_probe = 96;
    let base = config(TexelConfig::ADGI, rays_per_probe);
    let probes = base.grid.probe_count();
    let cpu = ProbeTexels::new(base.grid, TexelConfig::ADGI);
    for _ in 0..3 {
        for probe in 0..probes {
            let rays: Vec<RaySample> = (0..rays_per_probe)
                .map(|_| {
                    let mut r = random_ray(&mut rng);
                    r.radiance = r.radiance.min(Vec3::splat(8.0));
                    // Hits nearer than most probe-to-point distances, so that Chebyshev's
                    // test r > t̄ fires for about half the lookups.
                    if r.distance.is_finite() {
                        r.distance *= 0.25;
                    }
                    r
                })
                .collect();
            cpu.blend_rays(probe, &rays, &base.blend, rng.random());
        }
    }
    let (irr, vis) = cpu_words(&cpu);
    let queries: Vec<(Vec3, Vec3, Vec3)> = (0..600)
        .map(|i| {
            let lo = Vec3::new(-1.6, -0.5, 0.0);
            let hi = Vec3::new(1.6, 2.0, 1.8);
            let x = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
            let n = if i % 50 == 0 {
                Vec3::ZERO
            } else {
                unit_direction(&mut rng)
            };
            let v = if i % 3 == 0 {
                Vec3::ZERO
            } else {
                unit_direction(&mut rng)
            };
            (x, n, v)
        })
        .collect();
    let gpu_queries: Vec<GpuIrradianceQuery> = queries
        .iter()
        .map(|&(x, n, v)| GpuIrradianceQuery::new(x, n, v))
        .collect();
    for query in [
        QueryConfig::DDGI,
        QueryConfig::ADGI_RADIANCE,
        QueryConfig {
            visibility: false,
            sqrt_blend: false,
            ..QueryConfig::DDGI
        },
    ] {
        let cfg = ProbeCacheConfig { query, ..base };
        let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
        gpu.upload_words(ctx, &irr, &vis).unwrap();
        let got = gpu.query(ctx, &gpu_queries).unwrap();
        let mut worst = 0.0f32;
        let mut occluded = 0;
        for (&(x, n, v), g) in queries.iter().zip(&got) {
            let c = cpu.irradiance_at(x, n, v, &query);
            let without = cpu.irradiance_at(
                x,
                n,
                v,
                &QueryConfig {
                    visibility: false,
                    ..query
                },
            );
            occluded += usize::from(!close(c, without, 1e-3));
            assert!(
                close(*g, c, 1e-4),
                "{query:?} at {x} n {n} v {v}: GPU {g} CPU {c}"
            );
            worst = worst.max((*g - c).abs().max_element() / c.max_element().max(1e-3));
        }
        assert!(got.iter().any(|e| e.max_element() > 0.1));
        if query.visibility {
            assert!(
                occluded > 100,
                "visibility changed {occluded} of 600 queries"
            );
        }
        println!(
            "{:?}: worst relative difference {worst:e}, {occluded} queries changed by visibility",
            query.content
        );
    }
}

/// The clip-volume reset: words with counts 5 and 40 on every probe; after the reset with
/// N = 16, every word of a shell probe (V_out − V_in) has count min(N, 16) and its value, all
/// others are untouched — the GPU's words equal the CPU's `clamp_*_counts` on the shell probes
/// of `ClipVolumes::classify_grid`, and the camera puts probes in all three regions.
#[test]
fn clip_reset_matches_the_cpu() {
    let Some((ctx, mut rng)) = common::gpu_and_rng("clip_reset_matches_the_cpu", 23) else {
        return;
    };
    let grid = ProbeGrid::new(Vec3::splat(-4.0), Vec3::splat(1.0), UVec3::splat(9)).unwrap();
    let cfg = ProbeCacheConfig {
        grid,
        ..config(TexelConfig::ADGI, 1)
    };
    let cpu = ProbeTexels::new(grid, TexelConfig::ADGI);
    let (ni, nv) = (64, 256);
    for p in 0..grid.probe_count() {
        for i in 0..ni {
            let count = if rng.random::<bool>() { 40 } else { 5 };
            cpu.set_irradiance(p, i, Vec3::splat(rng.random::<f32>()), count);
        }
        for i in 0..nv {
            let count = if rng.random::<bool>() { 40 } else { 5 };
            let t: f32 = rng.random::<f32>() * 3.0;
            cpu.set_visibility(p, i, glam::Vec2::new(t, t * t), count);
        }
    }
    let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
    let (irr, vis) = cpu_words(&cpu);
    gpu.upload_words(ctx, &irr, &vis).unwrap();
    let clip = camera_volumes();
    let mut regions = vec![ClipRegion::Outside; grid.probe_count()];
    clip.classify_grid(&grid, &mut regions).unwrap();
    for region in [ClipRegion::Inner, ClipRegion::Shell, ClipRegion::Outside] {
        assert!(regions.contains(&region), "no probe in {region:?}");
    }
    let layout = TexelConfig::ADGI;
    for (p, r) in regions.iter().enumerate() {
        if *r == ClipRegion::Shell {
            let words = &cpu.irradiance_atomics()[p * ni..(p + 1) * ni];
            clamp_irradiance_counts(words, &layout.irradiance_layout, SHELL_COUNT);
            let words = &cpu.visibility_atomics()[p * nv..(p + 1) * nv];
            clamp_visibility_counts(words, &layout.visibility_layout, SHELL_COUNT);
        }
    }
    gpu.clip_reset(ctx, &clip, SHELL_COUNT).unwrap();
    assert_words_equal(ctx, &gpu, &cpu, "clip reset");
    assert_ne!(cpu.irradiance_words(), irr, "the reset changed nothing");
}

/// Memory: ADGI's words take 4 bytes per texel of both maps, 1 280 bytes per probe — a quarter
/// of 16-byte float texels (RGB32F + count) in both maps (5 120), and 2.4× less than RGBA32F
/// irradiance + RG32F moments (3 072). The CPU grid reports the same figure.
#[test]
fn bytes_per_probe_are_a_quarter_of_float_texels() {
    let Some(ctx) = mcg_gpu_backend::testing::gpu_or_skip("bytes_per_probe") else {
        return;
    };
    let cfg = config(TexelConfig::ADGI, 1);
    let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
    let cpu = ProbeTexels::new(cfg.grid, TexelConfig::ADGI);
    assert_eq!(gpu.bytes_per_probe(), 1280);
    assert_eq!(gpu.bytes_per_probe(), cpu.bytes_per_probe() as u64);
    let (ni, nv) = (64u64, 256u64);
    assert_eq!(16 * (ni + nv), 4 * gpu.bytes_per_probe());
    assert_eq!(gpu.words().len() as u64, 12 * (ni + nv));
}

/// The clip volumes of a camera at (0, 0.5, 6) looking at the origin over the 9 × 9 × 9 grid
/// of the clip tests: probes in all three regions.
fn camera_volumes() -> ClipVolumes {
    let view = look_at_mat4(Vec3::new(0.0, 0.5, 6.0), Vec3::ZERO, Vec3::Y);
    let proj = perspective(0.9, 1.5, 0.1, 30.0);
    let lo = Vec3::splat(-3.0);
    let hi = Vec3::splat(3.0);
    ClipVolumes::from_camera(proj * view, (lo, hi), 1.5, (lo - 1.0, hi + 1.0)).unwrap()
}

/// Pilot rays and their state over 4 frames (reference, detect, reference, detect) on the
/// 9 × 9 × 9 grid: the GPU's directions are the CPU's `pilot_direction` within 2·10⁻⁶ (WGSL's
/// `sin`/`cos`) in the same octant, traced exactly for the probes in V_out; after each frame's
/// hits (random distances with misses, random radiance, NaN for a failed ray: f_r = 0, the
/// luminance's `mcg_rounded` products turn NaN into −f32::MAX, WGSL's `max` returning the
/// operand that is not NaN) the reference f_v, f_r
/// (`octant_heuristics`, eq. 11-12) and the trigger states (`temporal_gradient` +
/// `TemporalTrigger::apply`, eq. 13-17) equal the CPU's within relative 10⁻⁵ (`exp` in f_v).
#[test]
fn pilot_rays_and_trigger_match_the_cpu() {
    use mcg_probe_cache::heuristics::octant;
    use mcg_probe_cache::pilot_rays::{PilotHit, octant_heuristics, pilot_direction};
    use mcg_probe_cache::temporal_gradient::temporal_gradient;
    use mcg_probe_cache::{HeuristicParams, PilotPhase, TemporalTrigger};
    let Some((ctx, mut rng)) = common::gpu_and_rng("pilot_rays_and_trigger_match_the_cpu", 24)
    else {
        return;
    };
    let grid = ProbeGrid::new(Vec3::splat(-4.0), Vec3::splat(1.0), UVec3::splat(9)).unwrap();
    let cfg = ProbeCacheConfig {
        grid,
        ..config(TexelConfig::ADGI, 1)
    };
    let gpu = GpuProbeCache::new(ctx, &cfg).unwrap();
    let clip = camera_volumes();
    let probes = grid.probe_count();
    let n = 8 * probes;
    let uniforms: Vec<f32> = (0..2 * n).map(|_| rng.random()).collect();
    let rays = gpu.pilot_rays(ctx, &uniforms, &clip).unwrap();
    let mut traced = 0;
    for (i, r) in rays.iter().enumerate() {
        let (probe, o) = (i / 8, i % 8);
        let d = pilot_direction(o, glam::Vec2::new(uniforms[2 * i], uniforms[2 * i + 1]));
        let g = Vec3::new(r[0], r[1], r[2]);
        assert!((g - d).abs().max_element() < 2e-6, "{i}: GPU {g} CPU {d}");
        assert_eq!(octant(g), o);
        let p = grid.probe_position(grid.probe_coords(probe));
        assert_eq!(r[3] == 1.0, clip.traces_pilots(p), "probe {probe}");
        traced += usize::from(r[3] == 1.0);
    }
    assert!(
        traced > 0 && traced < n,
        "{traced} of {n} pilot rays traced"
    );

    let heuristics = HeuristicParams::new(5.0, grid.cell_diagonal()).unwrap();
    let trigger = TemporalTrigger::DEFAULT;
    let luminance = mcg_probe_cache::guiding_function::LUMINANCE;
    // CPU state per probe · 8 + octant: reference f_v, f_r, trigger states.
    let mut state = vec![[0.0f32; 4]; n];
    for frame in 0..4 {
        let phase = mcg_probe_cache::PilotFrame::of(frame).phase;
        let hits: Vec<GpuRaySample> = (0..n)
            .map(|i| GpuRaySample {
                direction: Vec3::new(rays[i][0], rays[i][1], rays[i][2]),
                distance: if rng.random_range(0..10) == 0 {
                    f32::INFINITY
                } else {
                    rng.random_range(0.0f32..3.0)
                },
                // Every 13th a failed ray (NaN): f_r = 0.
                radiance: Vec3::new(rng.random(), rng.random(), rng.random()) * 4.0
                    + Vec3::splat(if i % 13 == 5 { f32::NAN } else { 0.0 }),
                probe: (i / 8) as u32,
            })
            .collect();
        gpu.pilot_hits(ctx, &hits, &clip, &heuristics, trigger, phase)
            .unwrap();
        for probe in 0..probes {
            if rays[probe * 8][3] != 1.0 {
                continue;
            }
            let h: [PilotHit; 8] = core::array::from_fn(|o| PilotHit {
                distance: hits[probe * 8 + o].distance,
                luminance: hits[probe * 8 + o].radiance.dot(luminance),
            });
            let (f_v, f_r) = octant_heuristics(&h, &heuristics);
            for o in 0..8 {
                let s = &mut state[probe * 8 + o];
                if phase == PilotPhase::Detect {
                    let mut d = [0.0; 2];
                    temporal_gradient(&[f_v[o], f_r[o]], &[s[0], s[1]], &mut d).unwrap();
                    s[2] = trigger.apply(d[0], s[2]);
                    s[3] = trigger.apply(d[1], s[3]);
                }
                if f_v[o].is_finite() {
                    s[0] = f_v[o];
                }
                if f_r[o].is_finite() {
                    s[1] = f_r[o];
                }
            }
        }
        let got = gpu.read_pilot_state(ctx).unwrap();
        for (i, (g, c)) in got.iter().zip(&state).enumerate() {
            for k in 0..4 {
                assert!(
                    (g[k] - c[k]).abs() <= 1e-5 * c[k].abs() + 1e-6,
                    "frame {frame} probe {} octant {} field {k}: GPU {g:?} CPU {c:?}",
                    i / 8,
                    i % 8
                );
            }
        }
    }
    assert!(
        state.iter().filter(|s| s[2] > 0.05).count() > traced / 2,
        "the trigger fired"
    );
}
