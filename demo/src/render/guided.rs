//! MCPG in the CPU tracer: [`McpgSampler`], the [`VertexSampler`] that draws each bounce from
//! an [`mcpg::Guide`](Guide) shared by all rayon threads, and [`new_guide`], the guide's
//! configuration for a scene and image.
//!
//! Per scattering vertex (MCPG, Alber et al. 2025, Alg. 1-3): [`Guide::begin`] loads the
//! candidate chain states around the hit and picks one; [`GuidedVertex::sample`] draws the
//! direction from its vMF lobe or, with probability p_bsdf, from the material; the path goes
//! on, and when it is complete [`GuidedVertex::finish`] updates the chain with what the ray
//! hit (position, normal, emission; the radiance reflected there comes from the guide's
//! irradiance cache, MCPG sec. 4, so that training does not depend on the path length left).
//! [`Guide::end_frame`] between frames folds the cache and ages the states.
//!
//! The material is the guide's fallback technique ([`MaterialScatter`]); lobes are multiplied
//! by the clamped cosine ([`Hemisphere::CosineProduct`](mcg_markov_guide::mcpg::Hemisphere)).
//! The guided estimator stays unbiased for any state of the guide: its density is the exact
//! mixture of the lobes and the material (MCPG eq. 6-7), and the material's share p_bsdf > 0
//! covers every direction the material scatters into.

use glam::{Vec2, Vec3};
use mcg_markov_guide::mcpg::{
    BeginUniforms, CandidateUniforms, EMISSION_DEPTHS, EmissionAllocation, EmissionClass,
    EmissionMoments, EmissionPolicy, FinishUniforms, GridUniforms, Guide, GuideConfig, GuideError,
    GuidedSample, GuidedVertex, PendingFinish, SampleUniforms, Scatter, Vertex as GuideVertex,
    VertexObservation, luminance,
};

use super::cpu::{MAX_RECORDED, Observation, Vertex, VertexSampler};
use super::material::{BsdfSample, Material};
use super::scene::Scene;

/// The material at a vertex as the guide's fallback technique: [`Material::sample`] with the
/// lobe choice and the first direction uniform taken from one uniform (the part of `u.x` below
/// `metallic` picks the GGX lobe and is stretched back to [0, 1)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialScatter {
    /// The material.
    pub material: Material,
    /// The unit normal, turned towards `wo`.
    pub normal: Vec3,
    /// The unit outgoing direction.
    pub wo: Vec3,
}

impl Scatter for MaterialScatter {
    fn sample(&self, u: Vec2) -> Vec3 {
        let m = self.material.metallic;
        let (lobe, x) = if u.x < m {
            (0.0, u.x / m)
        } else {
            (1.0, (u.x - m) / (1.0 - m))
        };
        let x = x.clamp(0.0, 1.0 - f32::EPSILON);
        self.material
            .sample_direction(self.normal, self.wo, Vec3::new(lobe, x, u.y))
            // A direction the material cannot scatter into: its weight is 0 and ends the path.
            .unwrap_or(-self.normal)
    }

    fn pdf(&self, w: Vec3) -> f32 {
        self.material.pdf(self.normal, self.wo, w)
    }
}

/// N_c of the renderer's guide ([`McpgParams::confidence_samples`](mcg_markov_guide::mcpg::McpgParams::confidence_samples),
/// mcg's extension of MCPG Alg. 2): a chain of fewer samples lends part of its mixture share
/// to the material and continues after the material's samples. Measured with
/// `mcg-demo render --method mcpg --device cpu --seed S --reference REF` (seeds 1-6, relMSE
/// after 64 frames; the paper's rule, N_c = 0, in brackets): `hidden_light_room` 128², 8 spp,
/// 3 bounces 0.028-0.030 (0.030-0.041); `many_lights_room` 64², 4 spp, 1 bounce,
/// `--no-irradiance-cache` 0.41-0.46 (1.60-1.91). 8 and 32 gave the same within noise.
pub const CONFIDENCE_SAMPLES: f32 = 16.0;

/// α_min of the renderer's guide, the smallest blend factor of MCPG Alg. 3's maximum-likelihood
/// update ([`FitParams::alpha_min`](mcg_markov_guide::mcg_vmf::FitParams::alpha_min)): a chain
/// averages its last ~1/α_min = 10 samples once it has that many. MCPG Alg. 3 line 5 takes the
/// blend factor from Dittebrandt et al. \[2023\], whose α_min this is (MCMM Alg. 3 line 12:
/// 0.1); the MCPG authors' engine uses 0.01, which [`McpgParams::PAPER`](mcg_markov_guide::mcpg::McpgParams::PAPER)
/// keeps. With 0.01 the guide gets *worse* as it trains in `hidden_light_room`: the per-frame
/// relMSE falls to 1.4 by frames 8-23 and climbs back to 1.55-1.64 after frame 32, so each
/// state's long memory of its target point ȳ and mean cosine r̄ (weighted by the cache's
/// early, noisy radiance) costs more than it averages. Measured with `mcg-demo render --scene
/// demo/scenes/hidden_light_room.gltf --method mcpg --device cpu --width 128 --height 128 --spp
/// 8 --frames 64 --bounces 3 --seed S --reference REF --mcpg-alpha-min A` (REF: 4 096 spp of
/// `nee` at another seed; relMSE after 64 frames, seeds 7-9): 0.01 gives 0.0278-0.0299 (late
/// frames 1.55-1.64), 0.05 0.0266-0.0270, 0.1 0.0250-0.0271 (late frames 1.31-1.36), 0.2
/// 0.0254. Neutral on `many_lights_room` (64², 4 spp, 1 bounce, no cache, seeds 1-2: 0.426 and
/// 0.468 against 0.439 and 0.456). Not a general rule: in mcg-markov-guide's `guided_room`
/// example (the paper's N_c = 0, `--alpha-min`) 0.1 was neutral to worse (per-frame MSE
/// 0.52/0.63 → 0.55/0.74, seeds 1-2), which is why the crate keeps the engine's value.
pub const ALPHA_MIN: f32 = 0.1;

/// The share of guided vertices whose sample goes into `mcpg`'s irradiance cache
/// ([`mcg_markov_guide::mcpg::CacheConfig::add_probability`], mcg's extension; the paper adds
/// every one). Scene (a) at 128², 8 spp, 3 bounces has ~60 samples per cache cell and frame;
/// one in four or one in sixteen rendered it with the same error after 64 frames (seeds 7-9,
/// CPU) for 4 % fewer instructions per frame at one in sixteen, most of them the adds'
/// compare-and-swap loops (`markov-guide/benches/README.md`).
pub const CACHE_ADD_PROBABILITY: f32 = 0.125;

/// The warm-up ramp R that suits `mcpg`'s accumulated mean on scene (a), for `--ramp-frames R`
/// (off by default: the output and the report's targets are the plain mean over all frames,
/// as issue 18 defines it). With [`frame_weight`](super::frame_weight) frame i counts
/// min(1, (i + 1)/R), so the first
/// frames, drawn while the guide is still learning, weigh less. The mean stays unbiased for
/// any fixed weights (each frame is unbiased given the guide of the frames before it); with
/// uncorrelated frame errors of variance v_i its variance Σ w_i² v_i / (Σ w_i)² is smallest
/// for w_i ∝ 1/v_i, and a ramp follows the guide's falling per-frame error without
/// estimating it. Not MCPG's (the paper shows each frame; a renderer that accumulates
/// frames chooses their weights). Measured with `mcg-demo render --scene
/// demo/scenes/hidden_light_room.gltf --method mcpg --device cpu --width 128 --height 128
/// --spp 8 --frames 64 --bounces 3 --seed S --reference REF --ramp-frames R` (one thread, so
/// the frames are the same for every R; relMSE after 64 frames): R = 6 is 4.9-7.3 % below
/// the plain mean (R = 1) on seeds 7-12 (seed 7: 0.0250 → 0.0235), R = 8 the same on
/// average, R = 2 2.5-3.8 %, R = 16 1.3-7.0 %. The price where a guide does not warm up: for
/// frames of equal variance the ramp's mean has 1.024× the plain mean's variance over 64
/// frames and 1.10× over 16 (`many_lights_room`, 64², 4 spp, 1 bounce, no cache, seeds 1-2:
/// +2.0 % and +2.8 %); `mcpg-nee` on `hidden_light_room`: −1.7 % and −1.2 %
/// (`markov-guide/benches/README.md`).
pub const RAMP_FRAMES: u32 = 6;

/// The guide's configuration for `scene` rendered at `width` × `height` pixels (both
/// devices): [`GuideConfig::for_scene`] over the scene's bounds, [`GuideConfig::for_camera`]
/// for its field of view, [`GuideConfig::for_pixels`] for the adaptive table's size, young
/// chains' confidence [`CONFIDENCE_SAMPLES`], the update's [`ALPHA_MIN`] and the cache's
/// [`CACHE_ADD_PROBABILITY`].
#[must_use]
pub fn guide_config(scene: &Scene, width: u32, height: u32) -> GuideConfig {
    let root = scene.bvh.nodes[0];
    let mut config = GuideConfig::for_scene(Vec3::from(root.min), Vec3::from(root.max))
        .for_camera(scene.camera.yfov, height)
        .for_pixels(u64::from(width) * u64::from(height));
    config.params.confidence_samples = CONFIDENCE_SAMPLES;
    config.params.fit.alpha_min = ALPHA_MIN;
    if let Some(cache) = &mut config.cache {
        cache.add_probability = CACHE_ADD_PROBABILITY;
    }
    config
}

/// The guide for `scene` rendered at `width` × `height` pixels ([`guide_config`]), the camera
/// set.
///
/// # Errors
/// [`GuideError`] when the configuration is invalid (it is not for a finite scene).
pub fn new_guide(scene: &Scene, width: u32, height: u32) -> Result<Guide, GuideError> {
    let mut guide = Guide::new(guide_config(scene, width, height))?;
    guide.set_camera(scene.camera.position);
    Ok(guide)
}

/// The vertex begun last: the guide's state between `sample` and the vertex's emission-only
/// directions and light sample, kept after the tracer moves on so that the next vertex is
/// begun in its place ([`Guide::begin_in`]) instead of being built elsewhere and moved in.
struct Current<'g> {
    vertex: GuidedVertex<'g, MaterialScatter>,
    /// The path depth it was begun at.
    depth: u32,
    /// Begun in the current path (the tracer may still ask its density).
    open: bool,
}

/// MCPG as a [`VertexSampler`]: one per rayon task, all sharing one [`Guide`].
///
/// Its own uniforms (the candidates' lookups, 4 per candidate, and the update's 5) come from a
/// [`GuideUniforms`] stream seeded by [`VertexSampler::begin_path`]; the direction's three are
/// the tracer's.
/// [`VertexSampler::pdf`] answers the guided density of the vertex sampled last at that depth
/// (the material's before): `mcpg` does no light sampling, so the tracer never asks before.
pub struct McpgSampler<'g> {
    guide: &'g Guide,
    rng: GuideUniforms,
    /// The vertex begun last; `None` until the first.
    current: Option<Current<'g>>,
    /// Per depth, the sampled vertex waiting for the path's end ([`PendingFinish`]), valid
    /// where bit `depth` of `pending_mask` is set (cleared per path, not the array).
    pending: [Option<PendingFinish<'g>>; MAX_RECORDED],
    pending_mask: u32,
    reflected: Reflected,
    emission_samples: u32,
    /// Directions per vertex by depth, shared by the frame's samplers, and this sampler's
    /// statistics for it (merged when the sampler is dropped).
    allocation: Option<(&'g EmissionAllocation, EmissionMoments)>,
    /// The class of the vertex whose directions are being gathered.
    class: EmissionClass,
}

impl<'g> McpgSampler<'g> {
    /// A sampler drawing from `guide`, training on [`Reflected::Path`].
    #[must_use]
    pub fn new(guide: &'g Guide) -> Self {
        Self {
            guide,
            rng: GuideUniforms::new(0),
            current: None,
            pending: [None; MAX_RECORDED],
            pending_mask: 0,
            reflected: Reflected::Path,
            emission_samples: 0,
            allocation: None,
            class: EmissionClass::of_depth(0),
        }
    }

    /// The same sampler training on `reflected`.
    #[must_use]
    pub fn with_reflected(mut self, reflected: Reflected) -> Self {
        self.reflected = reflected;
        self
    }

    /// The same sampler with `count` emission-only directions at every vertex
    /// ([`EMISSION_SAMPLES`]; 0: none, the paper's rule).
    #[must_use]
    pub fn with_emission_samples(mut self, count: u32) -> Self {
        self.emission_samples = count;
        self
    }

    /// The same sampler drawing its number of emission-only directions per vertex from
    /// `allocation` (replacing [`with_emission_samples`](Self::with_emission_samples)'s) and
    /// adding what they gather to its statistics.
    #[must_use]
    pub fn with_emission_allocation(mut self, allocation: &'g EmissionAllocation) -> Self {
        self.allocation = Some((allocation, EmissionMoments::default()));
        self
    }
}

impl Drop for McpgSampler<'_> {
    fn drop(&mut self) {
        if let Some((allocation, moments)) = &self.allocation {
            allocation.merge(moments);
        }
    }
}

/// How many directions `mcpg` draws at every vertex, besides the path's own, from the begun
/// vertex's mixture for the emission they meet ([`VertexSampler::sample_emission`]) — mcg's
/// extension, on both devices (the WGSL tracer's `emission_samples`, set by
/// [`super::gpu::GpuTracer::set_mcpg_emission_samples`]); 0 is the paper's one direction.
///
/// A light sample (`nee`) adds direct light at every vertex besides the direction the path
/// continues in; MCPG, knowing no lights, has only that one direction, and must spend it
/// either on the light or on the surfaces that lead on to it. The extra directions give the
/// guide more chances at the light without telling it where the lights are: with K of them,
/// the emission found along each of the K + 1 directions counts 1/(K + 1) (constant weights
/// summing to 1, so the estimate stays unbiased). Each costs a sample of the vertex already
/// begun and a query that needs no first hit (`cpu::emission_along`: a walk of the emitters'
/// own tree, [`Scene::emitter_bvh`](super::scene::Scene::emitter_bvh), then a shadow ray
/// only when the direction meets an emitter facing it); the density and the material are
/// evaluated only for a direction that found emission.
///
/// Scene (a), 128², 8 spp, 64 frames, 2 threads, seeds 7-8 (`markov-guide/benches/README.md`):
/// relMSE 0.0247 with K = 0, 0.0135 (K = 1), 0.0104 (2), 0.0088 (3), 0.0080 (4), 0.0070 (6),
/// 0.0066 (8), each direction adding about 8 % of a K = 0 frame's instructions; error × cost
/// was lowest and flat from K = 4 to 6 then. Measured again once both devices trained on the
/// path's own L_r (seeds 7-12 on the CPU, 64 frames): K = 6 gives 3 % less relMSE × CPU time
/// than 4 on average (lower on four of six seeds, its late frames 11-26 % lower), and 4-7 %
/// less relMSE × frame time on lavapipe (seeds 7-8, 32 frames), so 6 is the default. The
/// directions come from the whole mixture ([`GuidedVertex::sample_mixture`]), not only from
/// the state Alg. 1 chose (4-6 % less error than from that state's lobe), and K is the mean
/// of an allocation ([`EmissionAllocation`], [`Allocation`]): per depth on either device, on the
/// CPU also by each vertex's expected contribution.
pub const EMISSION_SAMPLES: u32 = 6;

// The tracer records as many depths as the allocation tells apart (the WGSL tracer's moment
// entries per recording pixel, `gpu::moment_entries`).
const _: () = assert!(MAX_RECORDED == EMISSION_DEPTHS);

/// `--mcpg-emission-allocation`: how `mcpg` spreads its [`EMISSION_SAMPLES`] over the vertices,
/// the command line's and the JSON's name for [`EmissionPolicy`] ([`EmissionAllocation`] gives
/// the rules).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Allocation {
    /// K̄ at every vertex ([`EmissionPolicy::Uniform`]).
    #[value(help = "The same number at every vertex")]
    Uniform,
    /// K(d) + 1 ∝ σ(d) over the depths ([`EmissionPolicy::Adaptive`]).
    #[value(help = "K(d) + 1 in proportion to depth d's spread in the frame before, the same mean")]
    Adaptive,
    /// K + 1 ∝ σ over classes of depth and expected contribution
    /// ([`EmissionPolicy::Contribution`]) — the default. The GPU tracer, whose vertices of one
    /// depth draw one count, measures no contributions and spreads by depth, as `Adaptive`
    /// (per-vertex counts would make a SIMD group run its longest lane's loop:
    /// `markov-guide/benches/README.md`).
    #[value(
        help = "Like adaptive, over classes of depth and the vertex's expected contribution (throughput times the guide's radiance; adaptive on the GPU)"
    )]
    #[default]
    Contribution,
}

impl From<Allocation> for EmissionPolicy {
    fn from(a: Allocation) -> Self {
        match a {
            Allocation::Uniform => Self::Uniform,
            Allocation::Adaptive => Self::Adaptive,
            Allocation::Contribution => Self::Contribution,
        }
    }
}

/// The guide's own uniforms in the CPU tracer: two 24-bit uniforms from each 64-bit output of
/// WyRand (Wang Yi's wyhash generator, through `fastrand`), seeded per path.
///
/// A vertex takes 25 (Alg. 1's four per candidate, Alg. 3's five); drawn one per 32-bit
/// `pcg_hash` step, as the tracer's own stream is, they were ~4 % of a guided frame's
/// instructions (callgrind), half of that now. Each uniform keeps the 24-bit resolution of
/// [`uniform_float`](mcg_gpu_backend::sampling::uniform_float), the largest an f32 in [0, 1)
/// holds evenly spaced.
#[derive(Clone, Debug)]
pub struct GuideUniforms {
    rng: fastrand::Rng,
}

impl GuideUniforms {
    /// The stream of path `seed`.
    #[must_use]
    pub fn new(seed: u32) -> Self {
        Self {
            rng: fastrand::Rng::with_seed(u64::from(seed)),
        }
    }

    /// The next two uniforms in [0, 1): the output's top and next 24 bits.
    #[inline]
    pub fn pair(&mut self) -> [f32; 2] {
        const SCALE: f32 = 1.0 / (1u32 << 24) as f32;
        let bits = self.rng.u64(..);
        let hi = (bits >> 40) as u32;
        let lo = (bits >> 16) as u32 & 0x00ff_ffff;
        [hi as f32 * SCALE, lo as f32 * SCALE]
    }

    /// [`Guide::begin`]'s uniforms for `count` candidates (grid, level, corner, reservoir).
    #[inline]
    pub fn begin(&mut self, count: usize) -> BeginUniforms {
        let mut u = BeginUniforms::default();
        for c in u.candidates.iter_mut().take(count) {
            let [grid, level] = self.pair();
            let [corner, reservoir] = self.pair();
            *c = CandidateUniforms {
                grid,
                level,
                corner,
                reservoir,
            };
        }
        u
    }

    /// [`GuidedVertex::finish`]'s uniforms (accept, the store's grid, level and corner, the
    /// cache's corner).
    #[inline]
    pub fn finish(&mut self) -> FinishUniforms {
        let [accept, grid] = self.pair();
        let [level, corner] = self.pair();
        let [cache, _] = self.pair();
        FinishUniforms {
            accept,
            store: GridUniforms {
                grid,
                level,
                corner,
            },
            cache,
        }
    }
}

/// Where `mcpg` takes L_r(hit_next, −ω), the radiance reflected at the next hit that its
/// training signal f_mc = lum(weight·(L_e + L_r)) needs (MCPG Alg. 3 line 1).
///
/// The paper reads it from the irradiance cache at every vertex (sec. 4, "Irradiance
/// Caching"): a real-time tracer finishes a vertex as soon as its ray is traced, before the
/// path knows more. A tracer that finishes its vertices when the path is complete also has
/// the path's own estimate of L_r: what the path gathered from the next hit on. The CPU tracer
/// keeps every vertex of a path for it; the GPU tracer too up to 3 bounces, and the first two
/// of deeper paths ([`super::gpu::GpuTracer::set_mcpg_reflected`],
/// `mcg_markov_guide::mcpg::PendingFinish`'s WGSL twin). Scene (a), 128², 8 spp, 64 frames,
/// seeds 7-12: on the CPU the path's estimate gave a lower relMSE than the cache on all six
/// seeds (0.0239-0.0262 against 0.0255-0.0284) and a 3-12 % cheaper guided frame, as two of
/// three cache queries are gone; on lavapipe the frame costs the same and the relMSE after 16
/// frames is 9 % lower (`markov-guide/benches/README.md`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Reflected {
    /// The path's estimate ([`Observation::reflected`]) where the path scattered at the next
    /// hit, the cache where it ended there — mcg's extension.
    #[value(
        help = "The path's own estimate where it went on, the cache where it ended (mcg's extension)"
    )]
    #[default]
    Path,
    /// The irradiance cache at every vertex (MCPG sec. 4).
    #[value(help = "The irradiance cache at every vertex (the paper's rule)")]
    Cache,
}

/// The tracer's three uniforms as the guide's sample takes them (choice, then direction).
fn sample_uniforms(u: Vec3) -> SampleUniforms {
    SampleUniforms {
        choice: u.x,
        direction: Vec2::new(u.y, u.z),
    }
}

/// A guided sample at `v` as the tracer's sample: f·cos/p with the material at `v`; `None`
/// for a direction of density 0.
fn material_weighted(v: &Vertex, s: &GuidedSample) -> Option<BsdfSample> {
    if !(s.pdf > 0.0) {
        return None;
    }
    let f_cos = v.material.eval(v.normal, v.wo, s.direction);
    Some(BsdfSample {
        direction: s.direction,
        pdf: s.pdf,
        weight: f_cos / s.pdf,
    })
}

impl VertexSampler for McpgSampler<'_> {
    fn begin_path(&mut self, seed: u32) {
        self.rng = GuideUniforms::new(seed);
        if let Some(current) = &mut self.current {
            current.open = false;
        }
        self.pending_mask = 0;
    }

    fn sample(&mut self, v: &Vertex, u: Vec3) -> Option<BsdfSample> {
        let scatter = MaterialScatter {
            material: v.material,
            normal: v.normal,
            wo: v.wo,
        };
        let begin = self.rng.begin(self.guide.params().candidates as usize);
        let vertex = GuideVertex::surface(v.position, v.normal);
        let current = match &mut self.current {
            // Begun in place (a begun vertex moved into the slot cost a copy of it).
            Some(current) => {
                self.guide
                    .begin_in(&mut current.vertex, vertex, scatter, &begin);
                current
            }
            slot @ None => slot.insert(Current {
                vertex: self.guide.begin(vertex, scatter, &begin),
                depth: 0,
                open: false,
            }),
        };
        current.depth = v.depth;
        current.open = true;
        let s = current.vertex.sample(&sample_uniforms(u));
        if let Some(p) = self.pending.get_mut(v.depth as usize) {
            *p = Some(current.vertex.pending(&s));
            self.pending_mask |= 1 << v.depth;
        }
        material_weighted(v, &s)
    }

    fn emission_samples(&mut self, depth: u32, throughput: Vec3) -> u32 {
        // The expected contribution: the guide's radiance at the vertex (sum_mc, 0 where no
        // candidate is valid) carried to the pixel by the throughput.
        let guided = self.open_at(depth).map_or(0.0, GuidedVertex::weight_sum);
        let contribution = luminance(throughput) * guided;
        match &mut self.allocation {
            Some((allocation, moments)) => {
                let at = allocation.class(depth, contribution);
                moments.add_vertex(at, contribution);
                self.class = at;
                allocation.samples_at(at, self.rng.pair()[0])
            }
            None => self.emission_samples,
        }
    }

    fn emission_gathered(&mut self, value: Vec3) {
        if let Some((_, moments)) = &mut self.allocation {
            // A direction of the vertex whose class `emission_samples` set.
            moments.add_direction(self.class, value);
        }
    }

    fn sample_emission(&mut self, v: &Vertex, u: Vec3) -> Option<Vec3> {
        match self.open_at(v.depth) {
            Some(vertex) => Some(vertex.sample_mixture(&sample_uniforms(u))),
            None => v.material.sample_direction(v.normal, v.wo, u),
        }
    }

    fn pdf(&self, v: &Vertex, wi: Vec3) -> f32 {
        match self.open_at(v.depth) {
            Some(vertex) => vertex.pdf(wi),
            None => v.material.pdf(v.normal, v.wo, wi),
        }
    }

    fn finish(&mut self, o: &Observation) {
        let depth = o.vertex.depth;
        let bit = 1u32.checked_shl(depth).unwrap_or(0);
        let Some(Some(pending)) = self
            .pending
            .get(depth as usize)
            .filter(|_| self.pending_mask & bit != 0)
            .copied()
        else {
            return;
        };
        self.pending_mask &= !bit;
        let weight = o.sample.weight;
        let mut seen = match o.next {
            Some(hit) => VertexObservation::hit(hit.position, hit.normal, hit.emitted, weight),
            None => VertexObservation::escaped(o.escaped.0, weight),
        };
        if self.reflected == Reflected::Path {
            seen.reflected = o.reflected;
        }
        seen.emission_weight = o.next.map_or(o.escaped.1, |hit| hit.emission_weight);
        pending.finish(&seen, &self.rng.finish());
    }
}

impl<'g> McpgSampler<'g> {
    /// The vertex begun at `depth` in the current path, if it is the last one begun (the
    /// tracer asks only about the vertex it is at).
    fn open_at(&self, depth: u32) -> Option<&GuidedVertex<'g, MaterialScatter>> {
        self.current
            .as_ref()
            .filter(|c| c.open && c.depth == depth)
            .map(|c| &c.vertex)
    }
}
