//! Shared by the renderer's test files: the built-in scenes' folder, the furnace scene and the
//! per-tile statistics of the expectation tests and their z-test.
#![allow(dead_code)] // each test file uses a part

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use mcg_demo::render::bvh::Triangle;
use mcg_demo::render::cpu::{Method, RenderSettings};
use mcg_demo::render::environment::EnvironmentMap;
use mcg_demo::render::material::Material;
use mcg_demo::render::scene::{Camera, Scene, TextureInfo, TriangleAttributes, WRAP_REPEAT};
use mcg_demo::render::{Device, ProbeOptions, RenderArgs};
use mcg_tests::{RunningStats, welch_t_test};

/// `demo/scenes/`.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// A direction uniform on the sphere from two of `u`'s uniforms.
pub fn uniform_direction(u: &mut impl FnMut() -> f32) -> Vec3 {
    let z = 2.0 * u() - 1.0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A closed cube of side 2 m around the camera; every face Lambertian of albedo `rho` and
/// emitting `le` from its inner (front) face.
pub fn furnace(rho: Vec3, le: Vec3) -> Scene {
    let mut tris = Vec::new();
    let c = [
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(1.0, -1.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(-1.0, 1.0, 1.0),
    ];
    // Faces listed counter-clockwise as seen from inside the cube.
    for [a, b, cc, d] in [
        [0, 1, 2, 3],
        [4, 7, 6, 5],
        [0, 4, 5, 1],
        [3, 2, 6, 7],
        [0, 3, 7, 4],
        [1, 5, 6, 2],
    ] {
        tris.push(Triangle::new(c[a], c[b], c[cc], 0));
        tris.push(Triangle::new(c[a], c[cc], c[d], 0));
    }
    for t in &tris {
        assert!(
            t.cross().dot(-Vec3::from(t.v0)) > 0.0,
            "front faces point inwards"
        );
    }
    let camera = Camera {
        position: Vec3::new(0.1, -0.2, 0.3),
        right: Vec3::X,
        up: Vec3::Y,
        forward: Vec3::NEG_Z,
        yfov: 1.2,
    };
    Scene::new(
        camera,
        &tris,
        vec![Material::lambertian(rho, le)],
        Vec::new(),
    )
    .unwrap()
}

/// A 2×2 texture (red, green / grey, blue; RGBA8) as texture 0 of `scene`, with texture
/// coordinates (0,0), (1,0), (0,1) at every triangle's corners, rotated by one corner from
/// triangle to triangle (so that a texel read through the wrong triangle shows): each
/// triangle shows three of the texels.
pub fn with_texture(mut scene: Scene) -> Scene {
    scene.textures = vec![TextureInfo {
        offset: 0,
        width: 2,
        height: 2,
        wrap: WRAP_REPEAT,
        map: TextureInfo::IDENTITY,
    }];
    scene.texels = vec![0xff00_00ff, 0xff00_ff00, 0xff80_8080, 0xffff_0000];
    let corners = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    scene.attributes = (0..scene.bvh.triangles.len())
        .map(|i| TriangleAttributes {
            uv: [0, 1, 2].map(|k| corners[(k + i) % 3]),
            ..TriangleAttributes::default()
        })
        .collect();
    scene
}

/// The furnace (ρ = 0.5 grey, L_e = (2, 3, 1)) with [`with_texture`]'s texture as the
/// emissive texture of every face: an emission that varies across each triangle, which a
/// light sample must read at the point it samples.
pub fn emissive_texture_furnace() -> Scene {
    let mut scene = with_texture(furnace(Vec3::splat(0.5), Vec3::new(2.0, 3.0, 1.0)));
    scene.materials[0].emissive_texture = 0;
    scene
}

/// The furnace (ρ = 1, L_e = (2, 3, 1)) with [`with_texture`]'s texture as the base-colour
/// texture of every face, its grey texel made transparent (alpha 0) and the faces alpha masks
/// at cutoff ½: every triangle has a hole where the grey texel maps, through which rays leave
/// the cube, and which neither emits nor reflects. With ρ = 1 elsewhere, what escapes through
/// the holes is all that is lost.
pub fn masked_furnace() -> Scene {
    let mut scene = with_texture(furnace(Vec3::ONE, Vec3::new(2.0, 3.0, 1.0)));
    scene.materials[0].base_color_texture = 0;
    scene.materials[0].alpha_cutoff = 0.5;
    scene.texels[2] = 0x0080_8080;
    scene
}

/// A Lambertian floor of albedo `rho` (a 200 m square at y = 0, facing up) under a uniform
/// environment of radiance `sky`, seen by a camera 1 m above it looking straight down (every
/// pixel sees the floor) or, with `up`, straight up (every pixel sees the sky). Below the
/// floor an emitting triangle faces down, away from everything the camera sees: light
/// sampling picks it half of the time ([`ENVIRONMENT_PICK`](mcg_demo::render::scene::ENVIRONMENT_PICK))
/// and finds its back face. The floor's upper hemisphere is all sky, so every pixel's radiance
/// is ρ·L_env (looking down, any B ≥ 1) or L_env (looking up).
pub fn sky_floor(rho: Vec3, sky: Vec3, up: bool) -> Scene {
    let c = [
        (-100.0, -100.0),
        (100.0, -100.0),
        (100.0, 100.0),
        (-100.0, 100.0),
    ]
    .map(|(x, z)| Vec3::new(x, 0.0, z));
    // Counter-clockwise seen from above: the front face points up.
    let below = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)].map(|(x, z)| Vec3::new(x, -1.0, z));
    let tris = [
        Triangle::new(c[0], c[3], c[2], 0),
        Triangle::new(c[0], c[2], c[1], 0),
        Triangle::new(below[0], below[1], below[2], 1),
    ];
    assert!(
        tris[..2].iter().all(|t| t.cross().y > 0.0),
        "the floor faces up"
    );
    assert!(tris[2].cross().y < 0.0, "the hidden emitter faces down");
    let forward = if up { Vec3::Y } else { Vec3::NEG_Y };
    let camera = Camera {
        position: Vec3::new(0.3, 1.0, -0.2),
        right: Vec3::X,
        up: if up { Vec3::NEG_Z } else { Vec3::Z },
        forward,
        yfov: 1.0,
    };
    let materials = vec![
        Material::lambertian(rho, Vec3::ZERO),
        Material::lambertian(Vec3::ZERO, Vec3::splat(5.0)),
    ];
    Scene::new_lit(camera, &tris, materials, Vec::new(), sky).unwrap()
}

/// A 32 × 16 environment map for the tests: a blue sky brightening toward the horizon in
/// the upper half (rows 0-7), its row 1 black (a row light sampling never picks) and texel
/// (4, 2) black too, a sun in texel (20, 3) about 600 times as bright as the sky (θ ≈ 39°),
/// and brown ground in the lower half (rows 8-15).
pub fn sky_map() -> EnvironmentMap {
    let (w, h) = (32u32, 16u32);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            match (x, y) {
                (_, 1) | (4, 2) => Vec3::ZERO,
                (20, 3) => Vec3::new(400.0, 360.0, 300.0),
                (_, y) if y < h / 2 => Vec3::new(0.3, 0.5, 1.0) * (1.0 + y as f32 / h as f32),
                _ => Vec3::new(0.2, 0.15, 0.1),
            }
        })
        .collect();
    EnvironmentMap::new(w, h, texels).unwrap()
}

/// The radiance that a white Lambertian surface facing up (+Y) reflects under `map`, with
/// nothing above it: (1/π) ∫ L(ω) cos θ dω over the upper hemisphere, summed in `f64` texel by
/// texel (the map's texels hold constant radiance; a texel of rows θ₀ to θ₁ spans 2π/W of
/// azimuth and ∫ cos θ sin θ dθ = (sin² θ₁ − sin² θ₀)/2). The map's height must be even, so
/// that the horizon is a row boundary.
pub fn upward_reflection(map: &EnvironmentMap) -> Vec3 {
    let (w, h) = (map.width() as usize, map.height() as usize);
    assert_eq!(h % 2, 0, "the horizon must be a row boundary");
    let mut sum = [0.0f64; 3];
    for row in 0..h / 2 {
        let sin2 = |r: usize| (r as f64 / h as f64 * std::f64::consts::PI).sin().powi(2);
        let band = (sin2(row + 1) - sin2(row)) / 2.0 * std::f64::consts::TAU / w as f64;
        for texel in &map.texels()[row * w..(row + 1) * w] {
            for c in 0..3 {
                sum[c] += f64::from(texel[c]) * band;
            }
        }
    }
    Vec3::from(sum.map(|c| (c / std::f64::consts::PI) as f32))
}

/// [`sky_floor`] under [`sky_map`] instead of a uniform sky, looking down: every pixel shows
/// ρ × [`upward_reflection`].
pub fn sky_map_floor(rho: Vec3) -> Scene {
    let mut scene = sky_floor(rho, Vec3::ONE, false);
    scene.set_environment_map(Arc::new(sky_map()));
    scene
}

/// The floors of the probe methods' environment tests, ρ = (0.5, 0.3, 0.8), looking down:
/// [`sky_floor`] under L_env = (1, 2, 0.5) and [`sky_map_floor`], each with the pixel mean it
/// must show (ρ·L_env, ρ × [`upward_reflection`]) and its name.
pub fn environment_floors() -> [(Scene, Vec3, &'static str); 2] {
    let rho = Vec3::new(0.5, 0.3, 0.8);
    let sky = Vec3::new(1.0, 2.0, 0.5);
    [
        (sky_floor(rho, sky, false), rho * sky, "uniform sky"),
        (
            sky_map_floor(rho),
            rho * upward_reflection(&sky_map()),
            "environment map",
        ),
    ]
}

/// The settings of the environment furnace tests: 16×16 pixels × 16 spp, seed 5.
pub fn sky_settings(method: Method, bounces: u32) -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 16,
        spp: 16,
        bounces,
        seed: 5,
        method,
    }
}

/// The mean image of one run's `frames` frames, `frame(f)` rendering frame `f` (a guided
/// run's frames share its guide or chains, so only whole runs are independent samples).
pub fn run_mean(frames: u32, mut frame: impl FnMut(u32) -> Vec<Vec3>) -> Vec<Vec3> {
    let mut sum: Vec<Vec3> = Vec::new();
    for f in 0..frames {
        let image = frame(f);
        sum.resize(image.len(), Vec3::ZERO);
        for (a, p) in sum.iter_mut().zip(image) {
            *a += p / frames as f32;
        }
    }
    sum
}

/// Per `tile × tile` tile (row-major) and channel of a `w × h` image, over `samples`
/// independent images: the running statistics of the tile's mean pixel value, one value per
/// image. `image(i)` renders independent image `i` (one frame, or one run's mean image).
///
/// The tile mean of each image is the sample, not each pixel: the pixels of one image may be
/// correlated (a guide, chains or a tile mixture that they share), so a variance summed over
/// pixels would understate the variance of the tile mean; only the images are independent.
pub fn tile_stats(
    (w, h, tile, samples): (u32, u32, u32, u32),
    mut image: impl FnMut(u32) -> Vec<Vec3>,
) -> TileStats {
    let tiles = ((w / tile) * (h / tile)) as usize;
    let n = f64::from(tile * tile);
    let mut out = vec![[RunningStats::new(); 3]; tiles];
    for i in 0..samples {
        let mut sums = vec![[0.0f64; 3]; tiles];
        for (p, value) in image(i).into_iter().enumerate() {
            let (x, y) = (p as u32 % w, p as u32 / w);
            let t = ((y / tile) * (w / tile) + x / tile) as usize;
            for c in 0..3 {
                sums[t][c] += f64::from(value[c]) / n;
            }
        }
        for (stats, sum) in out.iter_mut().zip(&sums) {
            for c in 0..3 {
                stats[c].push(sum[c]);
            }
        }
    }
    out
}

/// [`tile_stats`]' result: per tile, per channel, the statistics of the tile mean over
/// independent images.
pub type TileStats = Vec<[RunningStats; 3]>;

/// Asserts that two sets of [`tile_stats`] agree: per tile and channel, Welch's t-test
/// ([`welch_t_test`]) below the Bonferroni critical value at family-wise `alpha` over all
/// tile-channel tests — the (1 − α/(2·tests)) quantile of Student's t with the test's
/// Welch–Satterthwaite degrees of freedom. Returns the worst |t| ÷ critical value.
pub fn assert_tiles_agree(a: &TileStats, b: &TileStats, alpha: f64, what: &str) -> f64 {
    let per_test = alpha / (a.len() * 3) as f64;
    let mut worst: f64 = 0.0;
    let mut worst_test = (0.0, 0.0, 0.0);
    for (t, (ta, tb)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            let r = welch_t_test(&ta[c], &tb[c]);
            let critical = r.critical_value(per_test);
            assert!(
                r.t.abs() < critical,
                "{what}: tile {t} channel {c}: {} vs {} t = {:.2} (critical {critical:.2}, {:.0} dof)",
                ta[c].mean(),
                tb[c].mean(),
                r.t,
                r.degrees_of_freedom
            );
            if r.t.abs() / critical > worst {
                worst = r.t.abs() / critical;
                worst_test = (r.t, critical, r.degrees_of_freedom);
            }
        }
    }
    assert!(
        a.iter().flatten().all(|m| m.mean() > 0.0),
        "every tile is lit"
    );
    let (t, critical, dof) = worst_test;
    eprintln!("{what}: worst t = {t:.2} (critical {critical:.2} at {dof:.0} dof)");
    worst
}

/// Asserts that a furnace image learned lobes: the standard deviation of its pixels' red
/// channel exceeds 10⁻³ of the expected value (BSDF sampling alone is exact in the furnace, so
/// spread means guided lobes were sampled).
pub fn assert_spread(image: &[Vec3], expected: Vec3, what: &str) {
    let spread: RunningStats = image.iter().map(|p| f64::from(p.x)).collect();
    let sd = spread.variance().sqrt();
    assert!(
        sd > 1e-3 * f64::from(expected.x),
        "{what} sampled no lobe: {sd}"
    );
}

/// Asserts per channel that the mean over `image`'s pixels equals `expected` within 5 standard
/// errors, or within `floor · expected` (for estimators without variance; 0 for none).
pub fn assert_pixel_mean(image: &[Vec3], expected: Vec3, floor: f64, what: &str) {
    for c in 0..3 {
        let stats: RunningStats = image.iter().map(|p| f64::from(p[c])).collect();
        let diff = stats.mean() - f64::from(expected[c]);
        let z = diff / stats.standard_error();
        eprintln!("{what} channel {c}: z = {z:.2}");
        assert!(
            z.abs() < 5.0 || diff.abs() < floor * f64::from(expected[c]),
            "{what} channel {c}: mean {} expected {} (z = {z:.2}, n = {})",
            stats.mean(),
            expected[c],
            stats.count()
        );
    }
}

/// Asserts that at least 90 % of the lit pixels of `cpu` (more than 500 of them) equal those
/// of `gpu` to 10⁻³ relative (10⁻⁷ absolute) in every channel.
pub fn assert_lit_pixels_agree(cpu: &[Vec3], gpu: &[Vec3], what: &str) {
    let lit: Vec<(Vec3, Vec3)> = cpu
        .iter()
        .zip(gpu)
        .filter(|(c, _)| c.max_element() > 0.0)
        .map(|(c, g)| (*c, *g))
        .collect();
    let same = lit
        .iter()
        .filter(|(c, g)| ((*c - *g).abs().cmple(c.abs() * 1e-3 + Vec3::splat(1e-7))).all())
        .count();
    eprintln!("{what}: {same} of {} lit pixels equal", lit.len());
    assert!(lit.len() > 500, "the test needs lit pixels: {}", lit.len());
    assert!(
        same * 10 >= lit.len() * 9,
        "{what}: only {same} of {} lit pixels agree",
        lit.len()
    );
}

/// Equal ray budgets: `ddgi` traces the same positive number of probe rays in every frame,
/// and `adgi` never more than that in any frame and at least 99 % of it over the run (its
/// updater cuts its last sample list at the budget, so a frame may fall a few rays short).
pub fn assert_equal_budgets(ddgi: &[u64], adgi: &[u64]) {
    assert_eq!(ddgi.len(), adgi.len());
    assert!(
        ddgi[0] > 0 && ddgi.iter().all(|&r| r == ddgi[0]),
        "{ddgi:?}"
    );
    assert!(
        adgi.iter().all(|&r| r <= ddgi[0]),
        "{adgi:?} above {}",
        ddgi[0]
    );
    let (a, d): (u64, u64) = (adgi.iter().sum(), ddgi.iter().sum());
    assert!(a * 100 >= d * 99, "adgi traced {a} rays, ddgi {d}");
}

/// A fresh folder `<prefix>-<name>-…` under the system's temporary directory, removed with
/// everything in it when the returned guard drops (also when the test fails).
pub fn temp_dir(prefix: &str, name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("{prefix}-{name}-"))
        .tempdir()
        .unwrap()
}

/// Settings of a small render of the door room with per-state references.
pub fn door_args(method: Method, out: PathBuf, frames: u32) -> RenderArgs {
    RenderArgs {
        method,
        device: Device::Cpu,
        width: 24,
        height: 24,
        spp: 1,
        frames,
        bounces: 3,
        seed: 7,
        out,
        no_progress: true,
        probes: ProbeOptions {
            probe_spacing: 1.0,
            probe_rays: 16,
            reference_spp: Some(16),
            reference_bounces: 4,
            ..ProbeOptions::default()
        },
        ..RenderArgs::new(scenes_dir().join("door_room.gltf"))
    }
}
