//! The vertices of the guide benchmarks, shared by `benches/guide.rs` and
//! `examples/vertex_instructions.rs`: shading points on the floor of a unit room, hits on a
//! patch of its ceiling, a guide trained on them, and the cosine-hemisphere baseline.

#![allow(dead_code)]

use mcg_markov_guide::cosine_hemisphere;
use mcg_markov_guide::glam::{Vec2, Vec3};
use mcg_markov_guide::mcpg::{
    BeginUniforms, FinishUniforms, Guide, GuideConfig, Lambertian, SampleUniforms, Vertex,
    VertexObservation,
};
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

pub const BATCH: usize = 4096;

/// One vertex's inputs: the shading point and all its uniforms, and the hit to report.
pub struct Input {
    x: Vec3,
    begin: BeginUniforms,
    sample: SampleUniforms,
    finish: FinishUniforms,
    hit: VertexObservation,
    extra: Vec3,
}

/// Shading points on the floor of a unit room in raster order (a 64-wide grid, jittered, as
/// a renderer visits its pixels), hits on a 0.2-wide patch of the ceiling.
pub fn inputs(rng: &mut Pcg64Mcg, n: usize) -> Vec<Input> {
    (0..n)
        .map(|i| {
            let (col, row) = ((i % 64) as f32, (i / 64) as f32);
            let rows = (n / 64) as f32;
            let x = Vec3::new(
                (col + rng.random::<f32>()) / 64.0,
                0.0,
                (row + rng.random::<f32>()) / rows,
            );
            let target = Vec3::new(
                0.4 + 0.2 * rng.random::<f32>(),
                1.0,
                0.4 + 0.2 * rng.random::<f32>(),
            );
            Input {
                x,
                begin: BeginUniforms::from_fn(5, || rng.random()),
                sample: SampleUniforms::from_fn(|| rng.random()),
                finish: FinishUniforms::from_fn(|| rng.random()),
                hit: VertexObservation::hit(target, -Vec3::Y, Vec3::splat(5.0), Vec3::splat(0.7)),
                extra: Vec3::new(rng.random::<f32>() - 0.5, 1.0, rng.random::<f32>() - 0.5)
                    .normalize(),
            }
        })
        .collect()
}

pub fn trained_guide(cache: bool, inputs: &[Input]) -> Guide {
    // A 64-pixel-high image with a 60° field of view (cells of about 8 pixels).
    let mut config =
        GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE).for_camera(60f32.to_radians(), 64);
    if !cache {
        config.cache = None;
    }
    let mut guide = Guide::new(config).unwrap();
    guide.set_camera(Vec3::new(0.5, 0.5, 1.5));
    for _ in 0..8 {
        vertices(&guide, inputs);
        guide.end_frame();
    }
    guide
}

/// Runs every input as one full vertex; returns a checksum of the pdfs.
pub fn vertices(guide: &Guide, inputs: &[Input]) -> f32 {
    let mut total = 0.0;
    for input in inputs {
        let v = guide.begin(
            Vertex::surface(input.x, Vec3::Y),
            Lambertian { normal: Vec3::Y },
            &input.begin,
        );
        let s = v.sample(&input.sample);
        total += s.pdf + v.pdf(input.extra);
        v.finish(&s, &input.hit, &input.finish);
    }
    total
}

pub fn cosine_inputs(rng: &mut Pcg64Mcg, n: usize) -> Vec<Vec2> {
    (0..n)
        .map(|_| Vec2::new(rng.random(), rng.random()))
        .collect()
}

pub fn cosine_batch(us: &[Vec2]) -> f32 {
    us.iter()
        .map(|&u| {
            let (w, pdf) = cosine_hemisphere(Vec3::Y, u);
            w.x + pdf
        })
        .sum()
}
