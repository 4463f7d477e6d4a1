//! The CPU path tracer: unidirectional path tracing over a [`Scene`], one rayon task per image
//! row, with every random decision drawn from the counter-based stream of
//! [`mcg_gpu_backend::sampling`] so that a GPU tracer seeded the same way draws the same
//! numbers.
//!
//! Conventions: `bounces` counts scattering events (1 = direct light only: emission seen by the
//! camera plus light scattered once); no Russian roulette; a box pixel filter (uniform jitter
//! in the pixel); rays that leave the scene see its environment
//! ([`Scene::environment_radiance`]: uniform or a map; none by default); emission from front
//! faces only; both faces scatter.
//!
//! Methods ([`Method`]): `bsdf` samples directions from the BSDF and finds lights only by
//! chance; `nee` adds one light sample per scattering event (an emitter triangle picked in
//! proportion to its power, a uniform point on it) and weights both strategies with the power
//! heuristic (Veach and Guibas 1995, "Optimally Combining Sampling Techniques for Monte Carlo
//! Rendering", eq. 9 with β = 2). `mcpg` draws every direction from MCPG's guide
//! ([`super::guided`]) and samples no lights; `mcpg-nee` adds `nee`'s light sample to it, the
//! light sample weighted against the guide's exact mixture density (mcg's extension: the paper
//! uses no light sampling).
//!
//! The direction of each bounce comes from a [`VertexSampler`] — the seam where a path guide
//! (MCPG's begin / sample / pdf / finish) replaces BSDF sampling without touching the rest of
//! the loop.

use glam::Vec3;
use mcg_gpu_backend::sampling::{next_uniform, pcg_hash};
use rayon::prelude::*;

use super::bvh::{Hit, Triangle};
use super::environment::ONE_BELOW;
use super::material::{BsdfSample, Material};
use super::scene::{Light, Scene};

/// How directions are chosen and lights are found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// BSDF sampling only; lights are found by chance.
    #[value(help = "BSDF sampling only; lights are found by chance")]
    Bsdf,
    /// BSDF sampling plus light sampling, combined by multiple importance sampling.
    #[value(
        help = "BSDF sampling plus one light sample per vertex, combined by MIS (what renderers use today)"
    )]
    Nee,
    /// MCPG's guide (Alber et al. 2025) at every scattering vertex, no light sampling: the
    /// guide learns where light comes from without being told where the lights are.
    #[value(help = "MCPG's path guide at every vertex, no light sampling (Alber et al. 2025)")]
    Mcpg,
    /// MCPG's guide for the scattered direction plus one light sample per vertex, the two
    /// combined by MIS with the guide's exact mixture density — mcg's extension of MCPG (the
    /// paper uses no light sampling) for renderers that already sample their lights: the
    /// chains learn only the MIS-weighted share of the emission their directions hit
    /// ([`NextHit::emission_weight`]), so the guide learns the light that light sampling cannot
    /// reach.
    #[value(help = "MCPG's guide plus nee's light sample, combined by MIS (mcg's extension)")]
    McpgNee,
    /// MCMM's screen-space chains (Dittebrandt et al. 2023) at the first hit, for direct light
    /// only (`--bounces 1`), no light sampling: rendered by [`super::mcmm::McmmRenderer`] on
    /// the CPU, not by [`render_frame`] (which would treat it as `bsdf`).
    #[value(help = "MCMM's screen-space chains at the first hit, direct light only (--bounces 1)")]
    Mcmm,
    /// ADGI's adaptive probe GI (DDGI's irradiance probes, their rays placed by ADGI's
    /// guide within DDGI's ray budget): the first hit lit by one light sample plus the probes'
    /// diffuse irradiance; rendered by [`super::probe_gi::ProbeGi`] on the CPU (`--bounces`
    /// is not used: the probes gather all bounces). On the GPU its whole per-frame update
    /// runs there (pilot rays, heuristics, feedback ĝ, static and dynamic chains, their rays
    /// and texel updates), recorded into the frame's encoder.
    #[value(
        help = "ADGI: DDGI's irradiance probes with rays placed by ADGI's guide (--bounces unused)"
    )]
    Adgi,
    /// DDGI (Majercik et al. 2019): the same shading as `adgi`, probes updated by uniform rays
    /// and DDGI's blend; rendered by [`super::probe_gi::ProbeGi`] on the CPU (`--bounces` is
    /// not used).
    #[value(help = "DDGI: irradiance probes updated by uniform rays (--bounces unused)")]
    Ddgi,
    /// `adgi` with mcg's refill extension ([`mcg_probe_cache::UpdatePolicy::AdgiRefill`]):
    /// texels of a probe whose change signal rises restart at a short window that later
    /// samples extend, and the static chains favour probe octants whose windows are not
    /// full — ADGI's paper recovers slowly where its dynamic rays miss the octants that
    /// changed. On the GPU its decisions run on the host (the CPU's updater) and only its
    /// rays and the shading on the GPU.
    #[value(help = "adgi whose changed probes restart short windows (mcg's extension)")]
    AdgiRefill,
    /// `adgi` with mcg's blend extension ([`mcg_probe_cache::UpdatePolicy::AdgiBlend`]):
    /// ADGI's pilot rays, staggered so that a change is seen on the frame after it, restart
    /// the windows of the probes it touches and send them extra rays, which DDGI's blend
    /// spreads over all their texels — ADGI's per-texel samples are too few per frame in
    /// the renderer to beat DDGI's blend after a change.
    #[value(help = "adgi whose changed probes get extra rays and DDGI's blend (mcg's extension)")]
    AdgiBlend,
}

impl Method {
    /// The method's name on the command line and in file names.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Bsdf => "bsdf",
            Self::Nee => "nee",
            Self::Mcpg => "mcpg",
            Self::McpgNee => "mcpg-nee",
            Self::Mcmm => "mcmm",
            Self::Adgi => "adgi",
            Self::Ddgi => "ddgi",
            Self::AdgiRefill => "adgi-refill",
            Self::AdgiBlend => "adgi-blend",
        }
    }

    /// Whether the method takes one light sample per scattering vertex.
    #[must_use]
    pub fn samples_lights(self) -> bool {
        matches!(self, Self::Nee | Self::McpgNee)
    }

    /// Whether the method shades from a probe grid (`adgi`, `adgi-refill`, `adgi-blend`,
    /// `ddgi`) instead of tracing paths.
    #[must_use]
    pub fn uses_probes(self) -> bool {
        matches!(
            self,
            Self::Adgi | Self::AdgiRefill | Self::AdgiBlend | Self::Ddgi
        )
    }

    /// Whether the method draws its directions from an MCPG guide.
    #[must_use]
    pub fn is_guided(self) -> bool {
        matches!(self, Self::Mcpg | Self::McpgNee)
    }
}

/// What one render pass computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel per frame.
    pub spp: u32,
    /// Scattering events per path (1 = direct light).
    pub bounces: u32,
    /// Seed of the random stream.
    pub seed: u32,
    /// The method.
    pub method: Method,
}

/// The state of a path at a scattering vertex, as a [`VertexSampler`] sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// The hit point.
    pub position: Vec3,
    /// The unit geometric normal, turned towards `wo`.
    pub normal: Vec3,
    /// The unit direction back along the incoming ray.
    pub wo: Vec3,
    /// The material.
    pub material: Material,
    /// Scattering events before this one (0 at the first hit).
    pub depth: u32,
}

/// What a sampler learns once its path is complete: the radiance that arrived at `vertex`
/// along the direction it sampled, estimated by the rest of the path — the emission of the
/// next hit in full, plus the next vertex's light samples and everything after them with
/// their MIS weights (an unbiased estimate of the incident radiance for every method).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// The vertex, as given to [`VertexSampler::sample`].
    pub vertex: Vertex,
    /// The sampled direction and its density.
    pub sample: BsdfSample,
    /// Incident radiance along `sample.direction`, linear RGB.
    pub radiance: Vec3,
    /// What the sampled ray hit; `None` when it left the scene.
    pub next: Option<NextHit>,
    /// Where the ray left the scene ([`Observation::next`] is `None`): the environment's
    /// radiance along it ([`Scene::environment`], zero without one) and the MIS weight the
    /// path gave it against a light sample of the environment (1 without light sampling), as
    /// [`NextHit::emission_weight`] for emitters.
    pub escaped: (Vec3, f32),
    /// The part of `radiance` reflected at the next hit, `radiance` − its emission: the path's
    /// own estimate of L_r(hit_next, −ω), present when the path scattered at the next hit
    /// (so that `radiance` carries what it gathered from there on); `None` when the path
    /// ended there (the next hit's depth was the last) or the ray left the scene.
    pub reflected: Option<Vec3>,
}

/// The surface a sampled ray hit, as [`Observation::next`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NextHit {
    /// The hit point.
    pub position: Vec3,
    /// The unit geometric normal, turned towards the ray's origin.
    pub normal: Vec3,
    /// The radiance the hit surface emits back along the ray (0 from a back face).
    pub emitted: Vec3,
    /// The MIS weight the path gave `emitted` against a light sample of the same point (the
    /// power heuristic, [`Method::samples_lights`]); 1 without light sampling, also where a
    /// guide's emission-only direction shares the emission
    /// ([`VertexSampler::sample_emission`]: both directions are the guide's). A guide learns
    /// from `emission_weight · emitted` the part its direction carries
    /// ([`mcg_markov_guide::mcpg::VertexObservation::emission_weight`]).
    pub emission_weight: f32,
}

/// The per-vertex direction sampler of the path loop: MCPG's seam (begin with the vertex,
/// sample a direction, evaluate the density of another, and learn from the finished path).
/// Implementations hold their own state; one is created per rayon task.
pub trait VertexSampler {
    /// Samples the next direction at `vertex` from three uniforms; `None` ends the path.
    fn sample(&mut self, vertex: &Vertex, u: Vec3) -> Option<BsdfSample>;
    /// The density with which [`VertexSampler::sample`] picks `wi` at `vertex` (for MIS).
    fn pdf(&self, vertex: &Vertex, wi: Vec3) -> f32;
    /// Called once per sampled vertex when the path is complete, in path order.
    fn finish(&mut self, observation: &Observation);
    /// Called when a path starts, with a seed derived from the path's random stream (for
    /// samplers that draw uniforms of their own, as a guide's lookups and updates do). The
    /// default ignores it.
    fn begin_path(&mut self, seed: u32) {
        let _ = seed;
    }
    /// How many times the tracer asks [`VertexSampler::sample_emission`] at this vertex of
    /// depth `depth`, reached with the path throughput `throughput` (asked once per vertex of
    /// a method without light sampling, after [`VertexSampler::sample`] and before the
    /// directions), K; the emission found along each of the vertex's K + 1 directions then
    /// counts 1/(K + 1). The default: 0.
    fn emission_samples(&mut self, depth: u32, throughput: Vec3) -> u32 {
        let _ = (depth, throughput);
        0
    }
    /// What one of the directions of [`VertexSampler::sample_emission`] at the vertex of the
    /// last [`VertexSampler::emission_samples`] added to the pixel before its weight 1/(K + 1)
    /// (0 when it met no emission), for samplers that measure them. The default ignores it.
    fn emission_gathered(&mut self, value: Vec3) {
        let _ = value;
    }
    /// A direction at `vertex`, after [`VertexSampler::sample`] there, whose ray only gathers
    /// the emission it meets (`None` gathers nothing); the tracer divides by
    /// [`VertexSampler::pdf`] of it, asked only when it met emission. Any density keeps the
    /// estimate unbiased (the weights are constant); the default samples nothing.
    fn sample_emission(&mut self, vertex: &Vertex, u: Vec3) -> Option<Vec3> {
        let _ = (vertex, u);
        None
    }
}

/// Plain BSDF sampling ([`Material::sample`]); learns nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct BsdfSampler;

impl VertexSampler for BsdfSampler {
    fn sample(&mut self, v: &Vertex, u: Vec3) -> Option<BsdfSample> {
        v.material.sample(v.normal, v.wo, u)
    }
    fn pdf(&self, v: &Vertex, wi: Vec3) -> f32 {
        v.material.pdf(v.normal, v.wo, wi)
    }
    fn finish(&mut self, _: &Observation) {}
}

/// The seed of the random stream of one path: a hash of (seed, frame, pixel, sample), each
/// word mixed through [`pcg_hash`] (the WGSL tracer computes the same).
#[must_use]
pub fn path_seed(seed: u32, frame: u32, pixel: u32, sample: u32) -> u32 {
    pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(frame.wrapping_mul(0x9e37_79b9) ^ pcg_hash(sample))))
}

/// Offset of ray origins off a surface, relative to the size of the coordinates (metres).
const RAY_OFFSET: f32 = 1e-4;

/// `p` moved off its surface along `n` by a distance that grows with `|p|`.
pub(crate) fn offset(p: Vec3, n: Vec3) -> Vec3 {
    p + n * (RAY_OFFSET * p.abs().max_element().max(1.0))
}

/// Power heuristic weight `a² / (a² + b²)` (Veach and Guibas 1995, eq. 9, β = 2).
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// Most scattering events a path records for [`VertexSampler::finish`]; deeper vertices are
/// still traced but not reported.
pub(crate) const MAX_RECORDED: usize = 16;

/// A vertex of the path as [`VertexSampler::finish`] will need it.
#[derive(Clone, Copy)]
struct Recorded {
    vertex: Vertex,
    sample: BsdfSample,
    /// The path's radiance before the vertex's sample.
    before: Vec3,
    /// The throughput after the sample.
    throughput: Vec3,
    /// The share of the next hit's emission that its MIS weight left out.
    discarded: Vec3,
    /// What the sampled ray hit.
    next: Option<NextHit>,
    /// Where the sampled ray left the scene: the environment's radiance along it and the MIS
    /// weight the path gave it ([`Observation::escaped`]).
    escaped: (Vec3, f32),
}

/// The salt of [`VertexSampler::begin_path`]'s seed: the sampler's stream starts away from
/// the path's.
const SAMPLER_SALT: u32 = 0x5bd1_e995;

/// Traces one path from the camera ray `(origin, direction)` and returns its radiance.
pub fn trace_path<S: VertexSampler>(
    scene: &Scene,
    sampler: &mut S,
    method: Method,
    bounces: u32,
    origin: Vec3,
    direction: Vec3,
    rng: &mut u32,
) -> Vec3 {
    sampler.begin_path(pcg_hash(*rng ^ SAMPLER_SALT));
    let mut u = || next_uniform(rng);
    let mut radiance = Vec3::ZERO;
    let mut throughput = Vec3::ONE;
    let (mut o, mut d) = (origin, direction);
    // The density of the direction that produced the current ray (0 for the camera ray, whose
    // emitter hits need no MIS weight).
    let mut last_pdf = 0.0;
    let mut recorded: [Option<Recorded>; MAX_RECORDED] = [None; MAX_RECORDED];
    let mut depth = 0u32;
    // The weight of the emission the last sampled direction meets: 1/(K + 1) beside the K
    // emission-only directions of its vertex (a guide's, without light sampling).
    let mut share = 1.0;
    // The normal of the vertex that sampled the current ray (for the density with which a
    // light sample of the environment would have found it).
    let mut last_normal = Vec3::ZERO;
    loop {
        let Some(hit) = scene.intersect(o, d, 0.0, f32::INFINITY) else {
            if scene.environment != Vec3::ZERO {
                let seen = scene.environment_radiance(d);
                let weight = environment_weight(scene, method, last_pdf, (o, last_normal), d);
                radiance += throughput * seen * weight;
                if let Some(r) = previous_record(&mut recorded, depth) {
                    r.discarded += throughput * seen * (1.0 - weight);
                    r.escaped = (seen, weight);
                }
            }
            break;
        };
        let tri = scene.bvh.triangles[hit.triangle as usize];
        let material = scene.material_at(&hit);
        let (area, n_front, cos_front) = front_face(&tri, d);
        let position = o + hit.t * d;
        if let Some(r) = previous_record(&mut recorded, depth) {
            r.next = Some(next_hit(position, n_front, cos_front, &material));
        }
        if cos_front > 0.0 && material.is_emitter() {
            let weight = emitter_weight(
                method,
                share,
                last_pdf,
                tri.emitter_pmf,
                area,
                hit.t,
                cos_front,
            );
            radiance += throughput * material.emission() * weight;
            // The vertex whose sample found this emitter observes all of its emission: the
            // MIS weight splits the estimate of *its* direct light with its light sample,
            // not the radiance arriving along the sampled direction.
            if let Some(r) = previous_record(&mut recorded, depth) {
                r.discarded += throughput * material.emission() * (1.0 - weight);
                // Against a light sample; a guide's own emission-only directions share the
                // emission with this one, and the guide learns all of it.
                if let Some(next) = r.next.as_mut().filter(|_| method.samples_lights()) {
                    next.emission_weight = weight;
                }
            }
        }
        if depth == bounces {
            break;
        }
        let normal = if cos_front > 0.0 { n_front } else { -n_front };
        let vertex = Vertex {
            position,
            normal,
            wo: -d,
            material,
            depth,
        };
        let origin_next = offset(position, normal);
        // Three uniforms for light sampling are drawn for every method, so that the stream
        // of the BSDF sample does not depend on the method.
        let (ul, u1, u2) = (u(), u(), u());
        // The direction is sampled before the light: a guide's density (for the light
        // sample's MIS weight) exists once its vertex has begun.
        let sampled = sampler.sample(&vertex, Vec3::new(u(), u(), u()));
        if method.samples_lights() {
            radiance +=
                throughput * light_sample(scene, sampler, &vertex, origin_next, [ul, u1, u2]);
        } else {
            // The directions' uniforms: the light sample's, which `mcpg` does not use, moved
            // along a lattice ([`emission_uniforms`]).
            let gathers = sampler.emission_samples(depth, throughput);
            share = 1.0 / (1 + gathers) as f32;
            for i in 0..gathers {
                let ue = emission_uniforms(Vec3::new(ul, u1, u2), i);
                let value = sampler
                    .sample_emission(&vertex, ue)
                    .map_or(Vec3::ZERO, |wi| {
                        throughput * emission_weighted(scene, sampler, &vertex, origin_next, wi)
                    });
                sampler.emission_gathered(value);
                radiance += share * value;
            }
        }
        let Some(sample) = sampled else {
            break;
        };
        let before = radiance;
        throughput *= sample.weight;
        record_vertex(&mut recorded, depth, vertex, sample, before, throughput);
        last_pdf = sample.pdf;
        last_normal = normal;
        o = origin_next;
        d = sample.direction;
        depth += 1;
        if throughput == Vec3::ZERO {
            break;
        }
    }
    report_recorded(sampler, &recorded, radiance, bounces);
    radiance
}

/// The generator of the R₃ lattice (Roberts 2018, "The unreasonable effectiveness of
/// quasirandom sequences"): 1/φ₃, 1/φ₃², 1/φ₃³ with φ₃ ≈ 1.2207440846, the real root of
/// x⁴ = x + 1. Its points i·α mod 1 fill the unit cube more evenly than independent ones.
pub const EMISSION_LATTICE: Vec3 = Vec3::new(0.819_172_5, 0.671_043_6, 0.549_700_5);

/// The three uniforms of a vertex's `i`-th emission-only direction
/// ([`VertexSampler::sample_emission`]): `first` + i·[`EMISSION_LATTICE`] mod 1, a
/// Cranley–Patterson rotation of the R₃ lattice by the vertex's own uniforms `first`. Each
/// direction's uniforms alone are uniform in [0, 1)³ (so each direction is drawn from the
/// sampler's density and the estimate stays unbiased); together a vertex's K directions cover
/// the mixture's choice and the lobes' angles more evenly than K independent draws (mcg's
/// extension: 3 % less error after 64 frames on scene (a), lower on each of six seeds,
/// `markov-guide/benches/README.md`). The WGSL tracer's `emission_uniforms` is the twin.
#[must_use]
pub fn emission_uniforms(first: Vec3, i: u32) -> Vec3 {
    let v = first + i as f32 * EMISSION_LATTICE;
    // ⌊v⌋ as the truncation, less 1 where it lies above v (v < 0): SSE2 conversions and a
    // compare, where `floor` is three calls into libm at baseline x86-64 (3.7 % of an `mcpg`
    // frame's instructions). The same as `v.floor()` for |v| < 2³¹; NaN and +∞ end in [0, 1)
    // through the `min`, as with `floor`.
    let t = v.as_ivec3().as_vec3();
    let whole = t - Vec3::select(t.cmpgt(v), Vec3::ONE, Vec3::ZERO);
    (v - whole).min(Vec3::splat(1.0 - f32::EPSILON / 2.0))
}

/// f·cos/p times the emission that the direction `wi` sampled at `vertex` meets from `origin`,
/// p the sampler's density of `wi`; 0 without emission, before any density or material is
/// evaluated (most such directions meet none).
fn emission_weighted<S: VertexSampler>(
    scene: &Scene,
    sampler: &S,
    vertex: &Vertex,
    origin: Vec3,
    wi: Vec3,
) -> Vec3 {
    let emitted = emission_along(scene, origin, wi);
    if emitted == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let pdf = sampler.pdf(vertex, wi);
    if !(pdf > 0.0) {
        return Vec3::ZERO;
    }
    vertex.material.eval(vertex.normal, vertex.wo, wi) / pdf * emitted
}

/// The emission a ray from `origin` along `d` finds first (0 from a back face or a surface
/// that emits nothing, and when it leaves the scene).
///
/// Found without the first hit: the nearest emitter whose front face the ray meets
/// ([`Scene::emitter_bvh`]), then whether any triangle blocks the ray before it. That is the
/// first hit's [`front_emission`] (the emitter itself is hit at the same `t` in both trees,
/// which the strict `t < t_max` of [`Bvh::occluded`](super::bvh::Bvh::occluded) excludes),
/// and a ray that meets no emitter — most of them — walks only the emitters' small tree.
fn emission_along(scene: &Scene, origin: Vec3, d: Vec3) -> Vec3 {
    let Some(e) = scene.intersect_emitter(origin, d) else {
        return Vec3::ZERO;
    };
    if scene.occluded(origin, d, 0.0, e.t) {
        return Vec3::ZERO;
    }
    scene.emitter_emission(e.triangle, e.b1, e.b2)
}

/// What a surface of `material` hit at cosine `cos_front` with its front normal emits back
/// along the ray: its emission from the front face, 0 from the back.
fn front_emission(material: &Material, cos_front: f32) -> Vec3 {
    if cos_front > 0.0 {
        material.emission()
    } else {
        Vec3::ZERO
    }
}

/// The record of the vertex whose sampled ray made the hit at `depth` (none for the camera
/// ray, nor past [`MAX_RECORDED`]).
fn previous_record(recorded: &mut [Option<Recorded>], depth: u32) -> Option<&mut Recorded> {
    depth
        .checked_sub(1)
        .and_then(|d| recorded.get_mut(d as usize))
        .and_then(Option::as_mut)
}

/// The area of `tri`, its front normal and the cosine between that normal and the reversed
/// ray direction `d`.
pub(crate) fn front_face(tri: &Triangle, d: Vec3) -> (f32, Vec3, f32) {
    let cross = tri.cross();
    let area = 0.5 * cross.length();
    let n_front = cross / (2.0 * area);
    let cos_front = -n_front.dot(d);
    (area, n_front, cos_front)
}

/// Records the vertex at `depth` with its sample, the radiance before it and the throughput
/// after it (vertices past [`MAX_RECORDED`] are not recorded).
fn record_vertex(
    recorded: &mut [Option<Recorded>],
    depth: u32,
    vertex: Vertex,
    sample: BsdfSample,
    before: Vec3,
    throughput: Vec3,
) {
    if let Some(slot) = recorded.get_mut(depth as usize) {
        *slot = Some(Recorded {
            vertex,
            sample,
            before,
            throughput,
            discarded: Vec3::ZERO,
            next: None,
            escaped: (Vec3::ZERO, 1.0),
        });
    }
}

/// The hit at `position` as the vertex that sampled it sees it: facing the ray, with the
/// emission only of a front-facing surface.
fn next_hit(position: Vec3, n_front: Vec3, cos_front: f32, material: &Material) -> NextHit {
    NextHit {
        position,
        normal: if cos_front > 0.0 { n_front } else { -n_front },
        emitted: front_emission(material, cos_front),
        emission_weight: 1.0,
    }
}

/// The weight of an emitter hit at distance `t` by a sampled direction of density `last_pdf`
/// in the estimate: the MIS weight against a light sample (`emitter_pmf`, `area` and
/// `cos_front` give its density of the hit), else `share`, 1/(K + 1) when the vertex also
/// gathers emission along K more directions ([`VertexSampler::sample_emission`]) (and 1 for
/// the camera ray).
fn emitter_weight(
    method: Method,
    share: f32,
    last_pdf: f32,
    emitter_pmf: f32,
    area: f32,
    t: f32,
    cos_front: f32,
) -> f32 {
    if !(last_pdf > 0.0) {
        1.0
    } else if method.samples_lights() {
        let light_pdf = emitter_pmf / area * t * t / cos_front;
        power_heuristic(last_pdf, light_pdf)
    } else {
        share
    }
}

/// The weight of the environment seen along `d` by a ray sampled with density `last_pdf` at a
/// vertex of normal `normal`: the MIS weight against a light sample of the environment
/// ([`Scene::environment_pmf`] × [`Scene::environment_pdf`], [`environment_light`]) for
/// methods that sample lights,
/// else 1 (a guide's emission-only directions gather only emitting triangles, and the camera
/// ray has no alternative).
fn environment_weight(
    scene: &Scene,
    method: Method,
    last_pdf: f32,
    (origin, normal): (Vec3, Vec3),
    d: Vec3,
) -> f32 {
    if last_pdf > 0.0 && method.samples_lights() {
        let light_pdf = scene.environment_pmf * scene.environment_pdf(origin, normal, d);
        power_heuristic(last_pdf, light_pdf)
    } else {
        1.0
    }
}

/// Reports every recorded vertex to the sampler with the radiance its sample gained, in
/// path order, once the path's total `radiance` of a path of at most `bounces` scattering
/// events is known.
fn report_recorded<S: VertexSampler>(
    sampler: &mut S,
    recorded: &[Option<Recorded>],
    radiance: Vec3,
    bounces: u32,
) {
    for r in recorded.iter().flatten() {
        let Recorded {
            vertex,
            sample,
            before,
            throughput,
            discarded,
            next,
            escaped,
        } = r;
        let gained = radiance - *before + *discarded;
        let incident = Vec3::select(
            throughput.cmpgt(Vec3::ZERO),
            gained / *throughput,
            Vec3::ZERO,
        );
        // The loop scattered at the next hit unless its depth was the last.
        let reflected = next
            .filter(|_| vertex.depth + 1 < bounces)
            .map(|hit| (incident - hit.emitted).max(Vec3::ZERO));
        sampler.finish(&Observation {
            vertex: *vertex,
            sample: *sample,
            radiance: incident,
            next: *next,
            escaped: if next.is_none() {
                *escaped
            } else {
                (Vec3::ZERO, 1.0)
            },
            reflected,
        });
    }
}

/// One light sample at `vertex` with MIS weight: `f·cos·L_e·w / p_light`, 0 when the point is
/// occluded, on the emitter's back face, or below the surface.
fn light_sample<S: VertexSampler>(
    scene: &Scene,
    sampler: &S,
    vertex: &Vertex,
    origin: Vec3,
    u: [f32; 3],
) -> Vec3 {
    let Some((estimate, light_pdf, wi)) = direct_light(scene, vertex, origin, u) else {
        return Vec3::ZERO;
    };
    estimate * power_heuristic(light_pdf, sampler.pdf(vertex, wi))
}

/// A light sample of the environment at `vertex` ([`direct_light`]'s, picked with
/// probability [`Scene::environment_pmf`]): a direction from [`Scene::sample_environment`]
/// (`u`; cosine-distributed about the vertex's normal for a uniform environment, in proportion
/// to an environment map's luminance), density `environment_pmf` × its density; `None` where
/// the material reflects nothing along it or the scene blocks it.
fn environment_light(
    scene: &Scene,
    vertex: &Vertex,
    origin: Vec3,
    u: [f32; 3],
) -> Option<(Vec3, f32, Vec3)> {
    let (wi, pdf) = scene.sample_environment(origin, vertex.normal, Vec3::from(u))?;
    let light_pdf = scene.environment_pmf * pdf;
    if !(light_pdf > 0.0) || vertex.normal.dot(wi) <= 0.0 {
        return None;
    }
    let f_cos = vertex.material.eval(vertex.normal, vertex.wo, wi);
    if f_cos == Vec3::ZERO || scene.occluded(origin, wi, 0.0, f32::INFINITY) {
        return None;
    }
    Some((
        f_cos * scene.environment_radiance(wi) / light_pdf,
        light_pdf,
        wi,
    ))
}

/// One light sample at `vertex` without MIS weight: the estimate `f·cos·L_e / p_light` of the
/// light scattered at `vertex` toward `wo` straight from the emitters, the light sample's
/// solid-angle density and its direction; `None` when the sample carries nothing (occluded,
/// on the emitter's back face, or below the surface). A light is picked by
/// [`Scene::pick_light`] (`u[0]`): an emitter triangle in proportion to its power and a
/// uniform point on it (`u[1]`, `u[2]`), or the environment ([`environment_light`]).
pub(crate) fn direct_light(
    scene: &Scene,
    vertex: &Vertex,
    origin: Vec3,
    u: [f32; 3],
) -> Option<(Vec3, f32, Vec3)> {
    let (t, pmf) = match scene.pick_light(u[0]) {
        Light::Environment => {
            // The pick's uniform, rescaled past it, chooses among the environment's samplers.
            let p = scene.environment_pmf;
            let u0 = if p < 1.0 {
                (u[0] / p).min(ONE_BELOW)
            } else {
                u[0]
            };
            return environment_light(scene, vertex, origin, [u0, u[1], u[2]]);
        }
        Light::Triangle(t, pmf) => (t, pmf),
    };
    let tri = scene.bvh.triangles[t as usize];
    let su = u[1].sqrt();
    let (b1, b2) = (su * (1.0 - u[2]), su * u[2]);
    let y = tri.point(b1, b2);
    let to_light = y - origin;
    let dist2 = to_light.length_squared();
    let dist = dist2.sqrt();
    let wi = to_light / dist;
    let cross = tri.cross();
    let area = 0.5 * cross.length();
    let cos_light = -(cross / (2.0 * area)).dot(wi);
    if !(cos_light > 0.0) || vertex.normal.dot(wi) <= 0.0 {
        return None;
    }
    let f_cos = vertex.material.eval(vertex.normal, vertex.wo, wi);
    if f_cos == Vec3::ZERO
        || !scene.is_surface_at(t, b1, b2)
        || scene.occluded(origin, wi, 0.0, dist * (1.0 - 1e-4))
    {
        return None;
    }
    let light_pdf = pmf / area * dist2 / cos_light;
    let emitted = scene
        .material_at(&Hit {
            t: dist,
            triangle: t,
            b1,
            b2,
        })
        .emission();
    Some((f_cos * emitted / light_pdf, light_pdf, wi))
}

/// Renders one frame: `spp` paths per pixel, returns the per-pixel mean radiance, row-major
/// from the top-left, `width × height` entries. `new_sampler` makes one sampler per row task;
/// `row_done` is called after each row (for progress bars).
pub fn render_frame<S: VertexSampler>(
    scene: &Scene,
    settings: &RenderSettings,
    frame: u32,
    new_sampler: impl Fn() -> S + Sync,
    row_done: impl Fn() + Sync,
) -> Vec<Vec3> {
    let (method, bounces) = (settings.method, settings.bounces);
    render_pixels(
        scene,
        settings,
        frame,
        new_sampler,
        |sampler, d, rng| {
            trace_path(
                scene,
                sampler,
                method,
                bounces,
                scene.camera.position,
                d,
                rng,
            )
        },
        row_done,
    )
}

/// The pixel loop of a frame: for each pixel and each of `spp` samples, a camera ray through a
/// uniformly jittered point of the pixel (box filter), its radiance from `radiance(state,
/// direction, rng)` with the path's random stream ([`path_seed`]); returns the per-pixel means,
/// row-major from the top-left. One `new_state()` per row task (rayon); `row_done` after each
/// row.
pub fn render_pixels<S>(
    scene: &Scene,
    settings: &RenderSettings,
    frame: u32,
    new_state: impl Fn() -> S + Sync,
    radiance: impl Fn(&mut S, Vec3, &mut u32) -> Vec3 + Sync,
    row_done: impl Fn() + Sync,
) -> Vec<Vec3> {
    let RenderSettings {
        width,
        height,
        spp,
        seed,
        ..
    } = *settings;
    let mut image = vec![Vec3::ZERO; (width * height) as usize];
    image
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let mut state = new_state();
            for (x, pixel) in row.iter_mut().enumerate() {
                let index = y as u32 * width + x as u32;
                let mut sum = Vec3::ZERO;
                for s in 0..spp {
                    let mut rng = path_seed(seed, frame, index, s);
                    let jx = next_uniform(&mut rng);
                    let jy = next_uniform(&mut rng);
                    let d = scene
                        .camera
                        .direction(x as f32 + jx, y as f32 + jy, width, height);
                    sum += radiance(&mut state, d, &mut rng);
                }
                *pixel = sum / spp as f32;
            }
            row_done();
        });
    image
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::SceneFile;

    /// `emission_uniforms`: each direction's uniforms are uniform, and a vertex's directions
    /// spread more evenly than independent ones. Sample: 4,096 random rotations (seed 11) of
    /// K = 8 points. Hypotheses and thresholds: every coordinate lies in [0, 1) and i = 0 gives
    /// the rotation itself; the points in the octant [0, ½)³ average 1 per rotation (|z| < 5
    /// with the measured variance); their variance over rotations is below 0.7, where
    /// independent points give the binomial 8·⅛·⅞ = 0.875 (R₃ gives about 0.55), and the
    /// generator (½, ½, ½) fails it at 3.1 (checked once).
    #[test]
    fn emission_uniforms_spread_a_vertexs_directions() {
        let mut state = 11_u32;
        let n = 4096;
        let counts: Vec<f64> = (0..n)
            .map(|_| {
                let first = Vec3::new(
                    next_uniform(&mut state),
                    next_uniform(&mut state),
                    next_uniform(&mut state),
                );
                assert_eq!(emission_uniforms(first, 0), first);
                // Rotations by any offset, negative ones too, stay mod 1 as with `floor`.
                let shifted = first - Vec3::new(1.5, 0.25, 3.0);
                let v = shifted + 3.0 * EMISSION_LATTICE;
                let fract = (v - v.floor()).min(Vec3::splat(1.0 - f32::EPSILON / 2.0));
                assert_eq!(emission_uniforms(shifted, 3), fract);
                (0..8)
                    .map(|i| {
                        let u = emission_uniforms(first, i);
                        // The truncation is the floor: bit for bit the WGSL's v − ⌊v⌋.
                        let v = first + i as f32 * EMISSION_LATTICE;
                        let fract = (v - v.floor()).min(Vec3::splat(1.0 - f32::EPSILON / 2.0));
                        assert_eq!(
                            u.to_array().map(f32::to_bits),
                            fract.to_array().map(f32::to_bits)
                        );
                        u
                    })
                    .inspect(|u| assert!(u.cmpge(Vec3::ZERO).all() && u.cmplt(Vec3::ONE).all()))
                    .filter(|u| u.cmplt(Vec3::splat(0.5)).all())
                    .count() as f64
            })
            .collect();
        let mean = counts.iter().sum::<f64>() / f64::from(n);
        let var = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / f64::from(n - 1);
        let z = (mean - 1.0) / (var / f64::from(n)).sqrt();
        assert!(z.abs() < 5.0, "mean {mean} (z = {z})");
        assert!(var < 0.7, "variance {var}");
    }

    /// The first hit's emission as the tracer's main loop finds it: the scene's closest hit,
    /// then its front-face emission.
    fn first_hit_emission(scene: &Scene, origin: Vec3, d: Vec3) -> Vec3 {
        let Some(hit) = scene.intersect(origin, d, 0.0, f32::INFINITY) else {
            return Vec3::ZERO;
        };
        let (_, _, cos_front) = front_face(&scene.bvh.triangles[hit.triangle as usize], d);
        front_emission(&scene.material_at(&hit), cos_front)
    }

    /// Hypothesis: [`emission_along`] (nearest emitter facing the ray, then an occlusion test)
    /// gives exactly the first hit's emission. 20 000 rays of fixed seed per built-in scene,
    /// from points spread over the scene's bounds in uniform directions; any difference fails,
    /// and enough rays must see emission (and enough must have an emitter blocked or seen
    /// from behind) for the comparison to decide.
    #[test]
    fn emission_along_is_the_first_hits_emission() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let (mut lit, mut hidden) = (0, 0);
        for name in ["hidden_light_room.gltf", "many_lights_room.gltf"] {
            let scene = SceneFile::open(dir.join(name))
                .and_then(|f| f.build(0.0))
                .expect("built-in scene");
            let root = scene.bvh.nodes[0];
            let (lo, hi) = (Vec3::from(root.min), Vec3::from(root.max));
            let mut rng = 0x00c0_ffeeu32;
            for _ in 0..20_000 {
                let mut u = || next_uniform(&mut rng);
                let origin = lo + (hi - lo) * Vec3::new(u(), u(), u());
                // Every other ray aims at a point of a random emitter, past the triangle's
                // edges now and then.
                let d = if u() < 0.5 {
                    let z = 2.0 * u() - 1.0;
                    let phi = std::f32::consts::TAU * u();
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    Vec3::new(r * phi.cos(), r * phi.sin(), z)
                } else {
                    let k = ((u() * scene.emitters.len() as f32) as usize)
                        .min(scene.emitters.len() - 1);
                    let tri = scene.bvh.triangles[scene.emitters[k] as usize];
                    let (b1, b2) = (1.2 * u() - 0.1, 1.2 * u() - 0.1);
                    let (b1, b2) = if b1 + b2 > 1.0 {
                        (1.0 - b1, 1.0 - b2)
                    } else {
                        (b1, b2)
                    };
                    (tri.point(b1, b2) - origin).normalize()
                };
                let expected = first_hit_emission(&scene, origin, d);
                assert_eq!(
                    emission_along(&scene, origin, d),
                    expected,
                    "{name}: ray {origin} along {d}"
                );
                let facing = scene.intersect_emitter(origin, d);
                lit += usize::from(expected != Vec3::ZERO);
                hidden += usize::from(facing.is_some() && expected == Vec3::ZERO);
            }
        }
        assert!(lit > 200 && hidden > 100, "{lit} lit, {hidden} hidden rays");
    }
}
