//! The GPU path tracer: the WGSL twin of [`super::cpu`] (`shaders/path_tracer.wgsl`, composed
//! with mcg's shader library — `mcg::sampling` for the random stream and the cosine-weighted
//! hemisphere, `mcg::constants`), run as a wgpu compute shader.
//!
//! The scene is uploaded as the CPU tracer holds it: the flat [`BvhNode`] and [`Triangle`]
//! arrays of [`super::bvh`], the [`Material`]s, the emitter table, texture coordinates and
//! texels — no conversion, so both devices walk the same tree. The conventions are the CPU's
//! (see [`super::cpu`]): `bounces` counts scattering events, no Russian roulette, box filter,
//! methods `bsdf` and `nee` with the same light selection and MIS, and every path seeded by
//! [`super::cpu::path_seed`] and drawing its uniforms in the same order, so the two devices
//! trace the same paths up to floating-point rounding.
//!
//! `mcpg` runs a second pipeline of the same shader, composed with the def [`MCPG_DEF`]: the
//! GPU guide of [`mcg_gpu_backend::guides::mcpg`] ([`GpuMcpgGuide`], the twin of the CPU
//! guide of [`super::guided`], built from the same [`GuideConfig`]) bound at group
//! [`GUIDE_GROUP`], begun, sampled and finished at every scattering vertex, and its per-frame
//! pass recorded after each frame's tiles.
//!
//! `mcmm` runs the entry point `render_mcmm` of the shader composed with [`MCMM_DEF`]: the chain
//! states of [`GpuMcmmGuide`] at group [`GUIDE_GROUP`] (the MCPG module's bindings move to the
//! unused group [`UNUSED_GROUP`]), workgroups of 8 × 8 invocations, one tile of 64 chains
//! each, the twin of [`super::mcmm::McmmRenderer`]; the guide's buffers swap after each frame.
//!
//! `ddgi`, `adgi` and `adgi-refill` run `render` of the shader composed with [`PROBE_GI_DEF`]
//! (each first hit shaded from the probe cache `mcg::adgi` at group [`GUIDE_GROUP`]) and the
//! kernel `trace_probe_rays`, after a probe update per frame ([`GpuTracer::start_probes`]; frame times
//! on the wall clock).
//!
//! A frame is dispatched in square tiles of [`TILE`] pixels (one submission each, workgroups of
//! 8 × 8 invocations, far below the 65 535 workgroups per dimension of WebGPU), so a large image
//! never becomes one long-running submission. Frame times come from timestamp queries around
//! each tile's pass when the adapter has `TIMESTAMP_QUERY`, else from the wall clock around
//! the submissions and the wait for them.

use std::borrow::Cow;
use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use mcg_gpu_backend::guides::adgi::GpuProbeCache;
use mcg_gpu_backend::guides::mcmm::GpuMcmmGuide;
use mcg_gpu_backend::guides::mcpg::GpuMcpgGuide;
use mcg_gpu_backend::sampling::{pcg_hash, uniform_float};
use mcg_gpu_backend::{ComputeKernel, GpuBuffer, GpuContext, GpuError, shaders, wgpu};
use mcg_markov_guide::mcmm::McmmParams;
use mcg_markov_guide::mcpg::GuideConfig;

mod probes;

pub use probes::{
    CHAIN_TRACE_STORAGE_BUFFERS, GpuChainTrace, GpuProbeFrame, GpuProbeRequest, NO_PROBE,
    PROBE_GI_DEF, PROBE_STORAGE_BUFFERS, composed_probe_shader,
};

use mcg_markov_guide::mcpg::{
    EmissionAllocation, EmissionMoments, EmissionPolicy, round_stochastically,
};

use super::bvh::{BvhNode, Triangle};
use super::cpu::{MAX_RECORDED, Method, RenderSettings};
use super::guided::Reflected;
use super::material::Material;
use super::scene::{Camera, Scene, TextureInfo, TriangleAttributes};
use crate::Result;

/// The WGSL source of the tracer, before composition with mcg's modules.
pub const SHADER: &str = include_str!("shaders/path_tracer.wgsl");

/// Side of the square pixel tiles a frame is dispatched in (one submission per tile).
pub const TILE: u32 = 512;

/// The bind group of the MCPG guide in the `mcpg` pipeline.
pub const GUIDE_GROUP: u32 = 1;

/// The shader def that turns the tracer's `render` into `mcpg`'s (guided sampling at group
/// [`GUIDE_GROUP`]).
pub const MCPG_DEF: &str = "MCG_DEMO_MCPG";

/// The shader def of the methods that take a light sample per vertex (`nee`, `mcpg-nee`):
/// light sampling is compiled into their pipelines and out of `bsdf`'s and `mcpg`'s, so that
/// no method runs another's code. (A run-time branch on the method cost lavapipe's `bsdf`
/// frames 25 % and its `mcpg` frames 3 %: llvmpipe executes every block, masked or not; a
/// real GPU skips the branch but still allocates registers for it.)
pub const LIGHTS_DEF: &str = "MCG_DEMO_LIGHTS";

/// The shader def of the guided pipelines for paths of at most [`HELD_VERTICES`] bounces:
/// every vertex waits for the end of its path and all are finished after the path's loop,
/// through one call site (without it, a vertex past the first two held is finished inside
/// the loop, whose finish code a SIMD group then runs at every bounce: llvmpipe's `mcpg`
/// frames are 5 % shorter with it).
pub const HOLD_ALL_DEF: &str = "MCG_DEMO_HOLD_ALL";

/// The vertices a path holds under [`HOLD_ALL_DEF`] (the WGSL `HeldVertex` records).
pub const HELD_VERTICES: u32 = 3;

/// The shader def of the guided pipelines for scenes of at most [`EMITTER_LIST_MAX`] emitter
/// triangles: `mcpg`'s emission-only directions test the emitters' triangles one after the
/// other (WGSL `emitter_list_hit`, the same triangles in the same order in every invocation)
/// instead of walking their tree (lavapipe's `mcpg` frames on scene (a), two emitter
/// triangles, 7 % shorter).
pub const EMITTER_LIST_DEF: &str = "MCG_DEMO_EMITTER_LIST";

/// The shader def of the `mcpg` pipeline when its frames draw emission-only directions (a
/// mean K above 0, [`GpuTracer::set_mcpg_emission_samples`]): without it the directions'
/// loop is not compiled, so the paper's one direction per vertex carries none of its code.
/// llvmpipe runs all of a kernel's code whether or not an invocation takes it, and the loop
/// is about 3,600 of the K = 0 kernel's 29,100 instructions there (`scripts/gpu-instructions`:
/// left out, K = 0 frames of scene (a) execute 5 % fewer instructions with 15 % fewer L1i
/// misses, and take 5-9 % less time); a GPU allots registers for all of a kernel's code.
pub const EMISSION_DIRECTIONS_DEF: &str = "MCG_DEMO_EMISSION_DIRECTIONS";

/// The shader def that compiles the reading of vertex colours and textures (WGSL
/// `material_at`, `triangle_emission`), set where the uploaded scene has
/// [`Scene::attributes`]: without it a scene without textures would pay for that code on
/// llvmpipe, which runs it in every kernel that contains it (+11 % on a `nee` frame, +4 % on
/// `bsdf`, +3 % on `mcmm`). The `bsdf`, `nee`, `mcpg`, `mcpg-nee` and `mcmm` kernels follow
/// the scene ([`GpuTracer::upload`] rebuilds them when it changes); the probes' are always
/// compiled with it.
pub const ATTRIBUTES_DEF: &str = "MCG_DEMO_ATTRIBUTES";

/// The shader def that compiles the alpha test of masked materials (glTF `alphaMode` MASK)
/// into every walk of the scene and light sample (WGSL `is_surface_hit`, `is_surface_at`; CPU
/// [`Scene::is_surface_at`]), set where the uploaded scene has a material with
/// [`Material::alpha_cutoff`](super::material::Material::alpha_cutoff) above 0 and the
/// attributes it reads: like [`ATTRIBUTES_DEF`], so that the walks of other scenes carry none
/// of its code. Every kernel follows the scene ([`GpuTracer::upload`]).
pub const ALPHA_MASK_DEF: &str = "MCG_DEMO_ALPHA_MASK";

/// The shader def that compiles the environment (`render --environment`,
/// [`Scene::environment`]) into the light sample and the paths' escapes (WGSL `light_sample`,
/// `trace_path`), set where the uploaded scene has one, as [`ATTRIBUTES_DEF`]: lavapipe's
/// `nee` frame took 2-3 % longer with the code present in a scene without environment.
pub const ENVIRONMENT_DEF: &str = "MCG_DEMO_ENVIRONMENT";

/// The shader def that compiles the environment map's lookup and sampling (WGSL
/// `environment_radiance`, `environment_sample`, `environment_map_pdf`;
/// [`Scene::environment_map`]) in place of the uniform environment's, set with
/// [`ENVIRONMENT_DEF`] where the uploaded scene has a map.
pub const ENVIRONMENT_MAP_DEF: &str = "MCG_DEMO_ENVIRONMENT_MAP";

/// The shader def that compiles light samples of a uniform environment toward the scene's
/// portals (WGSL `portals_sample`, `portals_pdf`; [`Scene::portals`]) in place of
/// cosine-distributed ones, set with [`ENVIRONMENT_DEF`] where the uploaded scene has portals
/// and no environment map.
pub const PORTALS_DEF: &str = "MCG_DEMO_PORTALS";

/// The compile-time choices that the uploaded scene makes for the kernels that read it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneDefs {
    /// [`ATTRIBUTES_DEF`]: the scene has vertex colours or textures.
    pub attributes: bool,
    /// [`ALPHA_MASK_DEF`]: the scene has alpha masks (and the attributes they read).
    pub alpha_mask: bool,
    /// [`ENVIRONMENT_DEF`]: the scene has an environment.
    pub environment: bool,
    /// [`ENVIRONMENT_MAP_DEF`]: the environment is a map.
    pub environment_map: bool,
    /// [`PORTALS_DEF`]: a uniform environment's light samples aim at portals.
    pub portals: bool,
}

impl SceneDefs {
    /// The defs `scene` asks for.
    #[must_use]
    pub fn of(scene: &Scene) -> Self {
        let attributes = !scene.attributes.is_empty();
        let environment = scene.environment != Vec3::ZERO;
        Self {
            attributes,
            alpha_mask: attributes && scene.materials.iter().any(|m| m.alpha_cutoff > 0.0),
            environment,
            environment_map: environment && scene.environment_map.is_some(),
            portals: environment && scene.environment_map.is_none() && !scene.portals.is_empty(),
        }
    }

    /// Appends the defs that are set to `defs`.
    fn push_to(self, defs: &mut Vec<(&'static str, u32)>) {
        if self.attributes {
            defs.push((ATTRIBUTES_DEF, 1));
        }
        if self.alpha_mask {
            defs.push((ALPHA_MASK_DEF, 1));
        }
        if self.environment {
            defs.push((ENVIRONMENT_DEF, 1));
        }
        if self.environment_map {
            defs.push((ENVIRONMENT_MAP_DEF, 1));
        }
        if self.portals {
            defs.push((PORTALS_DEF, 1));
        }
    }
}

/// The most emitter triangles a scene may have for [`EMITTER_LIST_DEF`].
pub const EMITTER_LIST_MAX: usize = 8;

/// The compile-time choices of the guided (`mcpg`, `mcpg-nee`) shaders, made from the
/// frame's bounces and the uploaded scene; the tracer rebuilds its guided pipelines when they
/// change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuidedDefs {
    /// [`HOLD_ALL_DEF`]: paths of at most [`HELD_VERTICES`] bounces.
    pub hold_all: bool,
    /// [`EMITTER_LIST_DEF`]: at most [`EMITTER_LIST_MAX`] emitter triangles.
    pub emitter_list: bool,
    /// [`EMISSION_DIRECTIONS_DEF`]: `mcpg` draws emission-only directions (a mean K > 0).
    pub emission_directions: bool,
    /// What the uploaded scene asks of every kernel (attributes, alpha masks, environment).
    pub scene: SceneDefs,
}

impl Default for GuidedDefs {
    /// Held vertices for short paths, the emitters' tree, no emission-only directions (the
    /// tracer's default K = 0), no attributes, no masks.
    fn default() -> Self {
        Self {
            hold_all: true,
            emitter_list: false,
            emission_directions: false,
            scene: SceneDefs::default(),
        }
    }
}

/// The shader def that compiles `render_mcmm`, MCMM at group [`GUIDE_GROUP`].
pub const MCMM_DEF: &str = "MCG_DEMO_MCMM";

/// The group a shader composes the other guide's module at (no pipeline binds it).
pub const UNUSED_GROUP: u32 = 2;

/// The group the `bsdf`/`nee`, `mcpg` and `mcmm` shaders compose the probe cache `mcg::adgi` at
/// (no pipeline of theirs binds it).
pub const PROBE_UNUSED_GROUP: u32 = 3;

/// Storage buffers the `mcpg` pipeline binds: the tracer's 8 and the guide's 3 (its hash
/// words, its words and their vec4 view; more than
/// WebGPU's default of 8; [`GpuTracer::new`] asks the adapter for its own maximum).
pub const MCPG_STORAGE_BUFFERS: u32 = 11;

/// Invocations per workgroup side of the `render` kernel (`@workgroup_size(8, 8)`).
const GROUP: u32 = 8;

/// Invocations per workgroup of the `render_mcmm` kernel (`@workgroup_size(8, 8)`): one tile
/// of [`super::mcmm::TILE_SIZE`] chains.
const MCMM_GROUP: (u32, u32) = (super::mcmm::TILE_WIDTH, super::mcmm::TILE_HEIGHT);

/// Invocations per workgroup of the `trace_rays` and `trace_segments` kernels.
const RAY_GROUP: u32 = 64;

/// The most segments that [`GpuTracer::unoccluded_segments`] walks from one origin: the
/// emission-only directions of a vertex whose shadow rays the tracer walks together (WGSL
/// `EMISSION_BATCH`).
pub const SEGMENT_BATCH: u32 = 8;

/// The method's code in the shader (`METHOD_*`), or `None` when the GPU tracer does not have
/// the method yet.
#[must_use]
pub fn method_code(method: Method) -> Option<u32> {
    #[allow(unreachable_patterns)] // methods added to the CPU tracer before their WGSL twin
    match method {
        Method::Bsdf => Some(0),
        Method::Nee => Some(1),
        Method::Mcpg => Some(2),
        Method::McpgNee => Some(4),
        Method::Mcmm => Some(3),
        m if m.uses_probes() => Some(5),
        _ => None,
    }
}

/// The uniform block of the `render` kernel (`Params` in WGSL): the camera, the frame's
/// settings and the tile of one dispatch. 240 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuParams {
    /// Eye position.
    pub camera_position: [f32; 3],
    /// `tan(yfov/2)·width/height`.
    pub tan_x: f32,
    /// Unit vector to the image's right.
    pub camera_right: [f32; 3],
    /// `tan(yfov/2)`.
    pub tan_y: f32,
    /// Unit vector to the image's top.
    pub camera_up: [f32; 3],
    /// Image width.
    pub width: u32,
    /// Unit viewing direction.
    pub camera_forward: [f32; 3],
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Scattering events per path.
    pub bounces: u32,
    /// Seed of the random stream.
    pub seed: u32,
    /// Frame index (part of the path seed).
    pub frame: u32,
    /// [`method_code`] of the method.
    pub method: u32,
    /// Entries of the emitter table.
    pub emitter_count: u32,
    /// Left column of the tile.
    pub tile_x: u32,
    /// Top row of the tile.
    pub tile_y: u32,
    /// Tile width.
    pub tile_width: u32,
    /// Tile height.
    pub tile_height: u32,
    /// Entries of the triangle-attribute array (0 when the scene has none:
    /// [`Scene::attributes`]).
    pub attribute_count: u32,
    /// Number of textures.
    pub texture_count: u32,
    /// Every how many pixels one records the statistics of `mcpg`'s emission-only directions
    /// ([`EmissionMoments`], after the pixels in the image buffer: [`moment_entries`]); 0
    /// records none (a uniform allocation needs none).
    pub moment_stride: u32,
    /// The root of the emitters' tree ([`Scene::emitter_bvh`]) in the node buffer, which
    /// holds it after the scene's ([`joined_trees`]).
    pub emitter_root: u32,
    /// 1 when `mcpg`'s chains learn the radiance reflected at the next hit from the path
    /// ([`Reflected::Path`]: the GPU tracer then finishes a path's vertices at its end, the
    /// first two of a path deeper than [`HELD_VERTICES`]), 0 from the irradiance cache at
    /// every vertex ([`Reflected::Cache`]).
    pub mcpg_reflected: u32,
    /// The emitters' first triangle in the triangle buffer ([`joined_trees`]: the
    /// `emitter_count` triangles from it are the emitters' tree's, in its order).
    pub emitter_first: u32,
    /// `mcpg`'s emission-only directions per vertex of depth d in this frame (depth `4i + j`
    /// in `[i][j]`): [`frame_counts`] of the allocation's K(d); 0 for the other methods.
    pub emission_counts: [[u32; 4]; 4],
    /// [`Scene::environment`]: the radiance of a ray that leaves the scene.
    pub environment: [f32; 3],
    /// [`Scene::environment_pmf`]: the probability that a light sample picks the environment.
    pub environment_pmf: f32,
    /// The [`Scene::environment_map`]: the index of its first word in the texel buffer
    /// ([`EnvironmentMap::gpu_words`](super::environment::EnvironmentMap::gpu_words), after
    /// the textures' texels), its width, its height and its rotation (`f32` bits); zeros
    /// without one.
    pub environment_map: [u32; 4],
    /// The [`Scene::portals`]: the index of their first word in the texel buffer (after the
    /// textures' texels and the environment map's words, 12 per portal as
    /// [`Portal`](super::environment::Portal) lays them out) and their number; zeros without.
    pub portals: [u32; 4],
}

/// The salt of [`frame_counts`]' draws.
const COUNT_SALT: u32 = 0x2545_f491;

/// The number of `mcpg`'s emission-only directions at every vertex of depth d in one frame of
/// the GPU tracer: [`round_stochastically`] of K(d), drawn once per depth and frame from
/// `seed` and `frame` (so its mean over frames is K(d)). The CPU tracer draws per
/// vertex ([`EmissionAllocation::samples_at`]); on the GPU every vertex of a depth draws the
/// same number, so that the invocations of a SIMD group or warp run one loop length instead
/// of the longest of theirs (drawn per vertex, lavapipe's frames took 10-15 % longer for the
/// same mean). A depth with K(d) > 0 gets at least one direction, so that every frame measures
/// it: a depth left without directions for a frame gets the largest σ of the others in the
/// next allocation ([`mcg_markov_guide::mcpg::allocate`]), and K(0) ≈ 0.5 then swung to
/// about 4.4 for a frame. The number is fixed before the frame's samples, so the estimate
/// stays unbiased.
#[must_use]
pub fn frame_counts(per_depth: &[f32; MAX_RECORDED], seed: u32, frame: u32) -> [u32; MAX_RECORDED] {
    core::array::from_fn(|d| {
        let k = per_depth[d].max(0.0);
        let bits = pcg_hash(seed ^ pcg_hash(frame ^ pcg_hash(d as u32 ^ COUNT_SALT)));
        let count = round_stochastically(k, uniform_float(bits));
        if k > 0.0 { count.max(1) } else { count }
    })
}

/// Pixels that record emission statistics (see [`GpuParams::moment_stride`]) in a frame of
/// `pixels`: about this many, one in every ⌈pixels / this⌉.
pub const MOMENT_PIXELS: u32 = 4096;

/// The image buffer's entries after the `pixels` pixels that hold the statistics of
/// `mcpg`'s emission-only directions, with `stride` [`GpuParams::moment_stride`]: for the
/// pixel `i·stride`, one `(vertices, directions, Σ luminance, Σ luminance²)` entry per depth
/// d < 16 (the depths a guide learns at) at `pixels + 16i + d` (the twin of
/// [`EmissionMoments`]; the recording invocation zeroes its entries first).
#[must_use]
pub fn moment_entries(pixels: u32, stride: u32) -> usize {
    if stride == 0 {
        0
    } else {
        pixels.div_ceil(stride) as usize * MAX_RECORDED
    }
}

/// Adds the statistics that a frame's recording pixels left in `entries` ([`moment_entries`])
/// to `moments`.
pub fn gather_moments(entries: &[[f32; 4]], moments: &mut EmissionMoments) {
    for pixel in entries.chunks_exact(MAX_RECORDED) {
        for (d, e) in pixel.iter().enumerate() {
            // Counts below 2²⁴ per pixel are exact in f32.
            let m = &mut moments.depths[d];
            m.vertices += f64::from(e[0]);
            m.directions += f64::from(e[1]);
            if e[2].is_finite() && e[3].is_finite() {
                m.first += f64::from(e[2]);
                m.second += f64::from(e[3]);
            }
        }
    }
}

/// The scene's BVH and the emitters' ([`Scene::emitter_bvh`]) in one node array and one
/// triangle array, as the shader binds them: the emitters' nodes follow the scene's (from
/// index `scene.bvh.nodes.len()`, the emitters' root), their child indices shifted past the
/// scene's nodes and their leaves' first triangles past the scene's triangles. The scene's
/// own entries are unchanged, so every index into them stays valid.
#[must_use]
pub fn joined_trees(scene: &Scene) -> (Vec<BvhNode>, Vec<Triangle>) {
    let node_offset = scene.bvh.nodes.len() as u32;
    let triangle_offset = scene.bvh.triangles.len() as u32;
    let emitter_nodes = scene.emitter_bvh.nodes.iter().map(|n| BvhNode {
        index: n.index
            + if n.count > 0 {
                triangle_offset
            } else {
                node_offset
            },
        ..*n
    });
    let nodes = scene
        .bvh
        .nodes
        .iter()
        .copied()
        .chain(emitter_nodes)
        .collect();
    let triangles = scene
        .bvh
        .triangles
        .iter()
        .chain(&scene.emitter_bvh.triangles)
        .copied()
        .collect();
    (nodes, triangles)
}

/// One entry of the emitter table as the shader reads it: [`Scene::emitters`] and
/// [`Scene::emitter_cdf`] side by side.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuEmitter {
    /// Index of the triangle (leaf order).
    pub triangle: u32,
    /// Inclusive cumulative probability.
    pub cdf: f32,
}

/// A BVH query of [`GpuTracer::trace_rays`]: the ray `origin + t·direction`, `t ∈ (0, t_max)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    /// Origin.
    pub origin: [f32; 3],
    /// Upper end of the ray's interval.
    pub t_max: f32,
    /// Unit direction.
    pub direction: [f32; 3],
    /// 1: any hit (a shadow ray, [`super::bvh::Bvh::occluded`]); 0: the closest hit
    /// ([`super::bvh::Bvh::intersect`]).
    pub any_hit: u32,
    /// The root of the tree to walk in the node buffer: 0 for the scene's, or
    /// [`GpuTracer::emitter_root`] for the emitters' ([`joined_trees`]).
    pub root: u32,
    /// 1: front faces only ([`super::bvh::Bvh::intersect_front`]); 0: both faces.
    pub front_only: u32,
    /// `[first, count]`: with `count` > 0 no tree is walked, the triangles `first..first +
    /// count` are tested one after the other, front faces only, with no upper end (the WGSL
    /// `emitter_list_hit` of [`EMITTER_LIST_DEF`]; [`GpuTracer::emitter_list`] gives the
    /// emitters'); `[0, 0]` walks the tree.
    pub list: [u32; 2],
}

/// The answer to a [`GpuRay`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuHit {
    /// Distance of the hit (`t_max` on a miss).
    pub t: f32,
    /// Index of the triangle, [`GpuHit::MISS`] when nothing was hit.
    pub triangle: u32,
    /// Barycentric weight of `v1`.
    pub b1: f32,
    /// Barycentric weight of `v2`.
    pub b2: f32,
}

impl GpuHit {
    /// [`GpuHit::triangle`] of a miss.
    pub const MISS: u32 = u32::MAX;
}

/// The scene's buffers on the device.
struct SceneBuffers {
    camera: Camera,
    /// [`GpuParams::emitter_root`].
    emitter_root: u32,
    /// [`GpuParams::emitter_first`].
    emitter_first: u32,
    /// [`GpuParams::environment`].
    environment: Vec3,
    /// [`GpuParams::environment_pmf`].
    environment_pmf: f32,
    /// [`GpuParams::environment_map`].
    environment_map: [u32; 4],
    /// [`GpuParams::portals`].
    portals: [u32; 4],
    nodes: GpuBuffer<BvhNode>,
    triangles: GpuBuffer<Triangle>,
    materials: GpuBuffer<Material>,
    emitters: GpuBuffer<GpuEmitter>,
    attributes: GpuBuffer<TriangleAttributes>,
    textures: GpuBuffer<TextureInfo>,
    texels: GpuBuffer<u32>,
}

impl SceneBuffers {
    /// The fields of [`GpuParams`] that describe the scene (the rest zero): what every kernel
    /// reads of it, written by [`GpuTracer::upload`] for kernels dispatched outside a frame
    /// and by every frame.
    fn params(&self) -> GpuParams {
        GpuParams {
            emitter_count: self.emitters.len() as u32,
            emitter_first: self.emitter_first,
            attribute_count: self.attributes.len() as u32,
            texture_count: self.textures.len() as u32,
            emitter_root: self.emitter_root,
            environment: self.environment.to_array(),
            environment_pmf: self.environment_pmf,
            environment_map: self.environment_map,
            portals: self.portals,
            ..GpuParams::default()
        }
    }
}

/// How the guide's end of a frame was timed ([`GpuTracer::render_frame`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum GuideEnd {
    /// No per-frame pass (not `mcpg`).
    None,
    /// In the timer's query pair after the tiles'.
    Timestamped,
    /// On the wall clock: these seconds.
    Wall(f64),
}

/// Timestamp queries around each tile's pass.
struct Timer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
    /// Query pairs the set holds.
    pairs: u32,
}

/// How [`GpuTracer`] measures frame times.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GpuTiming {
    /// Timestamp queries at the beginning and end of every pass (GPU time only).
    Timestamps,
    /// Wall-clock time from the first submission to the end of the wait for the last.
    Wall,
}

/// A guided pipeline: the guided entry point with an explicit layout (the tracer's group 0 and
/// the guide's group [`GUIDE_GROUP`]), and the guide.
struct Guided<G> {
    guide: G,
    pipeline: wgpu::ComputePipeline,
    /// Group 0 of `pipeline`.
    layout: wgpu::BindGroupLayout,
}

/// A pipeline with its group 0 layout.
type Pipeline = (wgpu::ComputePipeline, wgpu::BindGroupLayout);

/// The GPU path tracer: a device, the compiled kernels and the uploaded scene.
pub struct GpuTracer {
    ctx: GpuContext,
    render: ComputeKernel,
    rays: ComputeKernel,
    params: GpuBuffer<GpuParams>,
    scene: Option<SceneBuffers>,
    image: Option<GpuBuffer<[f32; 4]>>,
    timer: Option<Timer>,
    guided: Option<Guided<GpuMcpgGuide>>,
    /// `mcpg`'s emission-only directions per vertex ([`GpuTracer::set_mcpg_emission_samples`],
    /// [`GpuTracer::set_mcpg_emission_allocation`]).
    mcpg_emission: EmissionAllocation,
    /// Where `mcpg`'s chains take L_r at the next hit ([`GpuTracer::set_mcpg_reflected`]).
    mcpg_reflected: Reflected,
    /// What the last `mcpg` frame's recording pixels gathered (adaptive allocation only).
    mcpg_moments: Option<EmissionMoments>,
    /// The compiled `mcpg` shader, kept for rebuilding its pipeline with a new guide.
    guided_module: Option<wgpu::ShaderModule>,
    /// What the guided shaders are compiled with (rebuilt when a frame's bounces cross
    /// [`HELD_VERTICES`] or an uploaded scene's emitters cross [`EMITTER_LIST_MAX`]).
    guided_defs: GuidedDefs,
    /// `nee`'s `render` ([`LIGHTS_DEF`]), compiled on its first frame.
    nee: Option<ComputeKernel>,
    /// `trace_segments`, compiled on the first [`GpuTracer::unoccluded_segments`].
    segments: Option<ComputeKernel>,
    /// `mcpg-nee`'s shader and its pipeline around the current guide, made on its first frame.
    guided_lights_module: Option<wgpu::ShaderModule>,
    guided_lights: Option<Pipeline>,
    mcmm: Option<Guided<GpuMcmmGuide>>,
    /// The compiled `mcmm` shader.
    mcmm_module: Option<wgpu::ShaderModule>,
    /// The probe GI of `ddgi`/`adgi` and its camera pipeline (`render` of the probe shader).
    probes: Option<Guided<Box<probes::GpuProbes>>>,
    /// The compiled probe shader.
    probe_module: Option<wgpu::ShaderModule>,
    /// Wall-clock seconds of the last `mcpg` frame's guide pass.
    last_end_frame_s: Option<f64>,
}

impl std::fmt::Debug for GpuTracer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuTracer")
            .field("adapter", &self.ctx.adapter_info().name)
            .finish_non_exhaustive()
    }
}

/// The tracer's WGSL for `bsdf` (`lights` false) or `nee` (true, [`LIGHTS_DEF`]), composed
/// with the modules of [`mcg_gpu_backend::shaders`] it imports (`mcg::mcpg` among them, at
/// group [`GUIDE_GROUP`], unused by `render` without [`MCPG_DEF`]).
///
/// # Errors
/// When composition fails (an unknown import).
pub fn composed_shader(lights: bool, scene: SceneDefs) -> Result<String> {
    let mut defs = guide_defs(GUIDE_GROUP, UNUSED_GROUP, PROBE_UNUSED_GROUP);
    if lights {
        defs.push((LIGHTS_DEF, 1));
    }
    scene.push_to(&mut defs);
    Ok(shaders::compose(SHADER, &defs)?)
}

/// The shader defs placing `mcg::mcpg` at group `mcpg`, `mcg::mcmm` at group `mcmm` and
/// `mcg::adgi` at group `adgi`.
fn guide_defs(mcpg: u32, mcmm: u32, adgi: u32) -> Vec<(&'static str, u32)> {
    let mut defs = GpuMcpgGuide::shader_defs(mcpg).to_vec();
    defs.extend(GpuMcmmGuide::shader_defs(mcmm));
    defs.extend(GpuProbeCache::shader_defs(adgi));
    defs
}

/// The tracer's WGSL for `mcmm`: `render_mcmm` ([`MCMM_DEF`]) with `mcg::mcmm` at group
/// [`GUIDE_GROUP`], with the defs of `scene`.
///
/// # Errors
/// When composition fails (an unknown import).
pub fn composed_mcmm_shader(scene: SceneDefs) -> Result<String> {
    let mut defs = guide_defs(UNUSED_GROUP, GUIDE_GROUP, PROBE_UNUSED_GROUP);
    defs.push((MCMM_DEF, 1));
    scene.push_to(&mut defs);
    Ok(shaders::compose(SHADER, &defs)?)
}

/// The tracer's WGSL for `mcpg` (`lights` false) or `mcpg-nee` (true): [`composed_shader`]
/// with [`MCPG_DEF`] defined, and [`HOLD_ALL_DEF`], [`EMITTER_LIST_DEF`] and
/// [`EMISSION_DIRECTIONS_DEF`] as `guided` says.
///
/// # Errors
/// When composition fails (an unknown import).
pub fn composed_mcpg_shader(lights: bool, guided: GuidedDefs) -> Result<String> {
    let mut defs = guide_defs(GUIDE_GROUP, UNUSED_GROUP, PROBE_UNUSED_GROUP);
    defs.push((MCPG_DEF, 1));
    guided.scene.push_to(&mut defs);
    if lights {
        defs.push((LIGHTS_DEF, 1));
    }
    if guided.hold_all {
        defs.push((HOLD_ALL_DEF, 1));
    }
    if guided.emitter_list {
        defs.push((EMITTER_LIST_DEF, 1));
    }
    if guided.emission_directions {
        defs.push((EMISSION_DIRECTIONS_DEF, 1));
    }
    Ok(shaders::compose(SHADER, &defs)?)
}

impl GpuTracer {
    /// A tracer on its own device, on the adapter [`GpuContext::new`] picks (honouring
    /// `WGPU_BACKEND` and friends), with `TIMESTAMP_QUERY` when the adapter has it, the
    /// adapter's largest storage buffers (so large scenes and images fit) and its number of
    /// storage buffers per stage.
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when there is no adapter, other [`GpuError`]s when the device
    /// cannot be created or the shader does not compile.
    pub fn new() -> Result<Self> {
        let adapter = GpuContext::new()?
            .adapter()
            .cloned()
            .ok_or("GpuContext::new returned no adapter")?;
        let available = adapter.limits();
        let mut limits = wgpu::Limits::default()
            .using_resolution(available.clone())
            .using_alignment(available.clone());
        limits.max_storage_buffer_binding_size = available.max_storage_buffer_binding_size;
        limits.max_buffer_size = available.max_buffer_size;
        // `render` binds 8 storage buffers, WebGPU's default maximum; a guide's tables need
        // more, which every desktop adapter offers.
        limits.max_storage_buffers_per_shader_stage =
            available.max_storage_buffers_per_shader_stage;
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("mcg-demo render"),
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: limits,
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| {
                GpuError::RequestDevice {
                    reason: e.to_string(),
                }
            })?;
        Self::on(GpuContext::from_device(device, queue)?)
    }

    /// A tracer on `ctx`'s device (e.g. [`GpuContext::shared`] in tests); timestamps when the
    /// device was created with `TIMESTAMP_QUERY`.
    ///
    /// # Errors
    /// When the shader does not compile.
    pub fn on(ctx: GpuContext) -> Result<Self> {
        let source = composed_shader(false, SceneDefs::default())?;
        let render = ctx.compute_kernel(&source, "render")?;
        let rays = ctx.compute_kernel(&source, "trace_rays")?;
        let params = ctx.uniform_buffer("mcg-demo params", &GpuParams::default());
        let timer = ctx
            .device()
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| Timer::new(&ctx));
        Ok(Self {
            ctx,
            render,
            rays,
            params,
            scene: None,
            image: None,
            timer,
            guided: None,
            mcpg_emission: EmissionAllocation::new(0, EmissionPolicy::Uniform),
            mcpg_reflected: Reflected::Cache,
            mcpg_moments: None,
            guided_module: None,
            guided_defs: GuidedDefs::default(),
            nee: None,
            segments: None,
            guided_lights_module: None,
            guided_lights: None,
            mcmm: None,
            mcmm_module: None,
            probes: None,
            probe_module: None,
            last_end_frame_s: None,
        })
    }

    /// Starts `mcpg` with an empty guide of `config` (the CPU's
    /// [`super::guided::guide_config`] for the same scene and image): a guide equal in
    /// configuration to the current one is emptied ([`GpuMcpgGuide::reset`]), otherwise a new
    /// one is made (its per-frame pass's pipelines built) and the `mcpg` pipeline (compiled
    /// on the first call) is rebuilt around it. The emission-only directions' allocation
    /// starts again at K̄ at every depth.
    /// [`GpuTracer::render_frame`] with [`Method::Mcpg`] then learns from frame to frame.
    /// An adaptive table larger than the device binds is halved until it fits
    /// ([`GpuMcpgGuide::fitted_config`]; lavapipe holds 2²¹ slots, a 1920 × 1080 image asks
    /// for 2²²), and a line on standard error says so.
    ///
    /// # Errors
    /// When the device binds fewer than [`MCPG_STORAGE_BUFFERS`] storage buffers per stage,
    /// the configuration is invalid or too large for the device, or the shader fails.
    pub fn start_mcpg(&mut self, config: &GuideConfig) -> Result<()> {
        // A fresh render's first frame spends K̄ at every depth, as on the CPU.
        self.set_mcpg_emission_allocation(self.mcpg_emission.policy());
        self.mcpg_moments = None;
        let fitted = GpuMcpgGuide::fitted_config(&self.ctx, config);
        if fitted.adaptive_capacity < config.adaptive_capacity {
            eprintln!(
                "mcg-demo: the device binds at most {} MiB per buffer, so the GPU guide's \
                 adaptive table has {} slots instead of {} (the CPU guide's)",
                GpuMcpgGuide::max_buffer_bytes(&self.ctx) >> 20,
                fitted.adaptive_capacity,
                config.adaptive_capacity
            );
        }
        let config = &fitted;
        if let Some(g) = &mut self.guided
            && g.guide.config() == config
        {
            g.guide.reset(&self.ctx);
            return Ok(());
        }
        self.check_storage_buffers("mcpg", MCPG_STORAGE_BUFFERS)?;
        let mut guide = GpuMcpgGuide::new(&self.ctx, config)?;
        // Builds the per-frame pass's pipelines now (seconds on a software adapter), not in
        // the first frame's time; `reset` then empties the guide again.
        guide.end_frame(&self.ctx)?;
        guide.reset(&self.ctx);
        // `mcpg-nee`'s pipeline is rebuilt around the new guide on its first frame.
        self.guided_lights = None;
        self.guided = Some(self.mcpg_guided(guide)?);
        Ok(())
    }

    /// `mcpg`'s pipeline around `guide`, its shader compiled first where it is not (with
    /// the defs of `guided_defs`).
    fn mcpg_guided(&mut self, guide: GpuMcpgGuide) -> Result<Guided<GpuMcpgGuide>> {
        if self.guided_module.is_none() {
            let source = composed_mcpg_shader(false, self.guided_defs)?;
            self.guided_module = Some(self.module("mcg-demo render mcpg", source));
        }
        let module = self.guided_module.as_ref().expect("compiled above");
        let (pipeline, layout) =
            self.guided_pipeline(module, "render", guide.bind_group_layout())?;
        Ok(Guided {
            guide,
            pipeline,
            layout,
        })
    }

    /// Where `mcpg`'s chains take the radiance reflected at the next hit, as the CPU tracer's
    /// [`super::guided::McpgSampler::with_reflected`] (the default: [`Reflected::Cache`], the
    /// paper's rule, each vertex finished as soon as its ray is traced). With
    /// [`Reflected::Path`] a vertex whose next hit scatters again waits for the end of its
    /// path (a `HeldVertex`) and is finished with what the path gathered from that
    /// hit on: every vertex but the last, as on the CPU, for paths of at most
    /// [`HELD_VERTICES`] bounces (deeper paths: the first two); the next frame uses it.
    pub fn set_mcpg_reflected(&mut self, reflected: Reflected) {
        self.mcpg_reflected = reflected;
    }

    /// How many emission-only directions `mcpg` draws per vertex on average, as the CPU
    /// tracer's [`super::guided::McpgSampler::with_emission_samples`] (the default: 0, the
    /// paper's one direction), spread over the depths as before
    /// ([`GpuTracer::set_mcpg_emission_allocation`]); the next frame starts a new measurement
    /// (and compiles the guided shaders again when the mean crosses 0,
    /// [`EMISSION_DIRECTIONS_DEF`]).
    pub fn set_mcpg_emission_samples(&mut self, count: u32) {
        self.mcpg_emission = EmissionAllocation::new(count, self.mcpg_emission.policy());
    }

    /// How `mcpg` spreads its emission-only directions over the depths, as the CPU tracer does
    /// ([`EmissionAllocation`]; the default: [`EmissionPolicy::Uniform`]): with
    /// [`EmissionPolicy::Adaptive`] a frame records the directions' statistics (in pixels
    /// [`GpuParams::moment_stride`] apart) and the next spends K(d) by them.
    /// [`EmissionPolicy::Contribution`] does the same here: the GPU tracer measures no
    /// contributions, and its vertices of one depth draw one count.
    pub fn set_mcpg_emission_allocation(&mut self, policy: impl Into<EmissionPolicy>) {
        self.mcpg_emission = EmissionAllocation::new(self.mcpg_emission.mean(), policy.into());
    }

    /// K(d) of `mcpg`'s next frame, per depth.
    #[must_use]
    pub fn mcpg_emission_per_depth(&self) -> &[f32; MAX_RECORDED] {
        self.mcpg_emission.per_depth()
    }

    /// The statistics of the emission-only directions that the last `mcpg` frame recorded,
    /// summed over its recording pixels (`None` before one, and under
    /// [`EmissionPolicy::Uniform`]).
    #[must_use]
    pub fn mcpg_emission_moments(&self) -> Option<&EmissionMoments> {
        self.mcpg_moments.as_ref()
    }

    /// Starts `mcmm` with empty chains for a `width × height` image and `params` (the CPU's
    /// [`super::mcmm::mcmm_params`]): a guide of the same size is emptied and given `params`,
    /// otherwise a new one is made and the `mcmm` pipeline (compiled on the first call)
    /// rebuilt around it. [`GpuTracer::render_frame`] with [`Method::Mcmm`] then learns from
    /// frame to frame.
    ///
    /// # Errors
    /// When the device binds fewer than [`MCPG_STORAGE_BUFFERS`] storage buffers per stage,
    /// `params` are invalid, the states do not fit the device, or the shader fails.
    pub fn start_mcmm(&mut self, params: &McmmParams, width: u32, height: u32) -> Result<()> {
        if let Some(g) = &mut self.mcmm
            && (g.guide.width(), g.guide.height()) == (width, height)
        {
            g.guide.set_params(&self.ctx, params)?;
            g.guide.clear(&self.ctx)?;
            return Ok(());
        }
        self.check_storage_buffers("mcmm", MCPG_STORAGE_BUFFERS)?;
        let guide = GpuMcmmGuide::new(&self.ctx, width, height, params)?;
        self.mcmm = Some(self.mcmm_guided(guide)?);
        Ok(())
    }

    /// `mcmm`'s pipeline around `guide`, its shader compiled first where it is not (with
    /// [`GuidedDefs::scene`] of `guided_defs`).
    fn mcmm_guided(&mut self, guide: GpuMcmmGuide) -> Result<Guided<GpuMcmmGuide>> {
        if self.mcmm_module.is_none() {
            let source = composed_mcmm_shader(self.guided_defs.scene)?;
            self.mcmm_module = Some(self.module("mcg-demo render mcmm", source));
        }
        let module = self.mcmm_module.as_ref().expect("compiled above");
        let (pipeline, layout) =
            self.guided_pipeline(module, "render_mcmm", guide.bind_group_layout())?;
        Ok(Guided {
            guide,
            pipeline,
            layout,
        })
    }

    /// The guide of `mcmm` ([`GpuTracer::start_mcmm`]), e.g. for reading its states.
    #[must_use]
    pub fn mcmm_guide(&self) -> Option<&GpuMcmmGuide> {
        self.mcmm.as_ref().map(|g| &g.guide)
    }

    /// An error unless the device binds the `needed` storage buffers per stage that a guided
    /// pipeline (`method`) needs.
    fn check_storage_buffers(&self, method: &str, needed: u32) -> Result<()> {
        let available = self
            .ctx
            .device()
            .limits()
            .max_storage_buffers_per_shader_stage;
        if available < needed {
            return Err(format!(
                "{method} on the GPU binds {needed} storage buffers per stage; \
                 this device allows {available}"
            )
            .into());
        }
        Ok(())
    }

    /// Compiles composed WGSL.
    fn module(&self, label: &str, source: String) -> wgpu::ShaderModule {
        self.ctx
            .device()
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(label),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
    }

    /// The pipeline of `entry` in `module` with the tracer's group 0 (bindings 0–8) and
    /// `guide` at [`GUIDE_GROUP`]; the pipeline and its group 0 layout.
    fn guided_pipeline(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        guide: &wgpu::BindGroupLayout,
    ) -> Result<(wgpu::ComputePipeline, wgpu::BindGroupLayout)> {
        let entry_layout = |binding: u32| match binding {
            0 => mcg_gpu_backend::buffer_entry(binding, wgpu::BufferBindingType::Uniform),
            8 => mcg_gpu_backend::storage_entry(binding, false),
            _ => mcg_gpu_backend::storage_entry(binding, true),
        };
        let entries: Vec<wgpu::BindGroupLayoutEntry> = (0..=8).map(entry_layout).collect();
        let layout = self
            .ctx
            .device()
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(entry),
                entries: &entries,
            });
        let pipeline = self.pipeline_with(module, entry, &[&layout, guide])?;
        Ok((pipeline, layout))
    }

    /// The pipeline of `entry` in `module` with `groups[i]` at group i.
    fn pipeline_with(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        groups: &[&wgpu::BindGroupLayout],
    ) -> Result<wgpu::ComputePipeline> {
        let device = self.ctx.device();
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let label = Some(entry);
        let layouts: Vec<Option<&wgpu::BindGroupLayout>> =
            groups.iter().map(|&g| Some(g)).collect();
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label,
            bind_group_layouts: &layouts,
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label,
            layout: Some(&pipeline_layout),
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        });
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader {
                entry_point: entry.to_owned(),
                message: error.to_string(),
            }
            .into());
        }
        Ok(pipeline)
    }

    /// The guide of `mcpg` ([`GpuTracer::start_mcpg`]), e.g. for
    /// [`GpuMcpgGuide::read_back`] on [`GpuTracer::context`].
    #[must_use]
    pub fn mcpg_guide(&self) -> Option<&GpuMcpgGuide> {
        self.guided.as_ref().map(|g| &g.guide)
    }

    /// Seconds of the guide's per-frame pass in the last [`GpuTracer::render_frame`] (part of
    /// its time; timestamped when the frame's passes are, else on the wall clock), `None` when
    /// that frame was not `mcpg`.
    #[must_use]
    pub fn last_end_frame_s(&self) -> Option<f64> {
        self.last_end_frame_s
    }

    /// The tracer's device and queue.
    #[must_use]
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// A tracer on the device of `ctx`, sharing it (wgpu handles are reference-counted).
    ///
    /// # Errors
    /// As [`GpuTracer::on`].
    pub fn on_shared(ctx: &GpuContext) -> Result<Self> {
        Self::on(GpuContext::from_device(
            ctx.device().clone(),
            ctx.queue().clone(),
        )?)
    }

    /// The adapter's description (name, backend, device type).
    #[must_use]
    pub fn adapter_info(&self) -> wgpu::AdapterInfo {
        self.ctx.adapter_info()
    }

    /// Name and backend of the adapter, e.g. `"llvmpipe (LLVM 15.0.7, 256 bits) (Vulkan)"`.
    #[must_use]
    pub fn adapter_name(&self) -> String {
        let info = self.ctx.adapter_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    /// How frame times of `method` are measured on this device: the probe methods always on
    /// the wall clock (their frames include the probe update's submissions and, for `adgi`,
    /// its host work and read-backs).
    #[must_use]
    pub fn timing_of(&self, method: Method) -> GpuTiming {
        if method.uses_probes() {
            GpuTiming::Wall
        } else {
            self.timing()
        }
    }

    /// How frame times are measured on this device.
    #[must_use]
    pub fn timing(&self) -> GpuTiming {
        if self.timer.is_some() {
            GpuTiming::Timestamps
        } else {
            GpuTiming::Wall
        }
    }

    /// Uploads `scene` (replacing the previous one): its BVH nodes, triangles and materials
    /// as they are, the emitter table, texture coordinates and texels.
    ///
    /// # Errors
    /// When a buffer exceeds the device's largest storage binding.
    pub fn upload(&mut self, scene: &Scene) -> Result<()> {
        let emitters: Vec<GpuEmitter> = scene
            .emitters
            .iter()
            .zip(&scene.emitter_cdf)
            .map(|(&triangle, &cdf)| GpuEmitter { triangle, cdf })
            .collect();
        let (nodes, triangles) = joined_trees(scene);
        // The environment map's tables and texels, then the portals, follow the textures'
        // texels.
        let (texels, environment_map, portals) =
            if scene.environment_map.is_none() && scene.portals.is_empty() {
                (Cow::Borrowed(&scene.texels), [0; 4], [0; 4])
            } else {
                let mut words = scene.texels.clone();
                let mut environment_map = [0; 4];
                if let Some(map) = &scene.environment_map {
                    environment_map = [
                        words.len() as u32,
                        map.width(),
                        map.height(),
                        map.rotation().to_bits(),
                    ];
                    words.extend(map.gpu_words());
                }
                let portals = [words.len() as u32, scene.portals.len() as u32, 0, 0];
                words.extend_from_slice(bytemuck::cast_slice(&scene.portals));
                (Cow::Owned(words), environment_map, portals)
            };
        let max = self.ctx.device().limits().max_storage_buffer_binding_size;
        let largest = [
            size_of_val(nodes.as_slice()),
            size_of_val(triangles.as_slice()),
            size_of_val(texels.as_slice()),
        ]
        .into_iter()
        .max()
        .unwrap_or(0) as u64;
        if largest > max {
            return Err(format!(
                "the scene needs a {largest}-byte storage buffer; this GPU binds at most {max} \
                 (--device cpu renders it on the CPU)"
            )
            .into());
        }
        let ctx = &self.ctx;
        self.scene = Some(SceneBuffers {
            camera: scene.camera,
            emitter_root: scene.bvh.nodes.len() as u32,
            emitter_first: scene.bvh.triangles.len() as u32,
            environment: scene.environment,
            environment_pmf: scene.environment_pmf,
            environment_map,
            portals,
            nodes: ctx.storage_buffer("mcg-demo nodes", &nodes),
            triangles: ctx.storage_buffer("mcg-demo triangles", &triangles),
            materials: ctx.storage_buffer("mcg-demo materials", &scene.materials),
            emitters: ctx.storage_buffer("mcg-demo emitters", &emitters),
            attributes: ctx.storage_buffer("mcg-demo attributes", &scene.attributes),
            textures: ctx.storage_buffer("mcg-demo textures", &scene.textures),
            texels: ctx.storage_buffer("mcg-demo texels", &texels),
        });
        self.ctx.write(&self.params, &[self.scene()?.params()])?;
        self.set_guided_defs(GuidedDefs {
            emitter_list: scene.emitters.len() <= EMITTER_LIST_MAX,
            scene: SceneDefs::of(scene),
            ..self.guided_defs
        })
    }

    fn scene(&self) -> Result<&SceneBuffers> {
        self.scene
            .as_ref()
            .ok_or_else(|| "GpuTracer: no scene uploaded".into())
    }

    /// Renders one frame of the uploaded scene: `spp` paths per pixel; returns the per-pixel
    /// mean radiance (row-major from the top-left, as [`super::cpu::render_frame`]) and the
    /// frame's time in seconds (see [`GpuTracer::timing`]).
    ///
    /// With [`Method::Mcpg`] the guide of [`GpuTracer::start_mcpg`] follows the camera, guides
    /// and learns in the frame's passes, and its per-frame pass ([`GpuMcpgGuide::end_frame`])
    /// runs after them; the frame's time includes that pass (timestamped like the tiles when
    /// the adapter has timestamps, else its wall clock, submission to the end of the wait;
    /// also [`GpuTracer::last_end_frame_s`]). With [`Method::Mcmm`] (`bounces` 1) the chains of
    /// [`GpuTracer::start_mcmm`] guide and learn, and their buffers swap after the frame.
    ///
    /// # Errors
    /// No scene uploaded, a method without WGSL twin, a guided method without a started
    /// guide (or `mcmm` for another image size or bounce count), an image larger than the
    /// device's largest storage binding, or a device error.
    pub fn render_frame(
        &mut self,
        settings: &RenderSettings,
        frame: u32,
    ) -> Result<(Vec<Vec3>, f64)> {
        self.prepare_pipeline(settings.method, settings.bounces)?;
        let base = self.frame_params(settings, frame)?;
        let scope = self
            .ctx
            .device()
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let started = Instant::now();
        if settings.method.uses_probes() {
            self.ctx.write(&self.params, &[base])?;
            self.update_probes(frame)?;
        }
        let (timed_tiles, tiles) = self.dispatch_tiles(settings.method, &base)?;
        let end = self.end_guide_frame(settings.method, timed_tiles)?;
        self.wait()?;
        let wall = started.elapsed().as_secs_f64();
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(format!("the GPU tracer failed: {error}").into());
        }
        let seconds = match &self.timer {
            Some(timer)
                if timed_tiles == tiles
                    && self.timing_of(settings.method) == GpuTiming::Timestamps =>
            {
                let timed = timed_tiles + u32::from(end == GuideEnd::Timestamped);
                let passes = timer.read(&self.ctx, timed)?;
                if end == GuideEnd::Timestamped {
                    self.last_end_frame_s = passes.last().copied();
                }
                let wall_end = match end {
                    GuideEnd::Wall(seconds) => seconds,
                    GuideEnd::None | GuideEnd::Timestamped => 0.0,
                };
                passes.iter().sum::<f64>() + wall_end
            }
            _ => wall,
        };
        let image = self.image.as_ref().expect("allocated in frame_params");
        let texels = self.ctx.read_back(image)?;
        let (pixels, moments) = texels.split_at((base.width * base.height) as usize);
        self.mcpg_moments = None;
        if base.moment_stride > 0 {
            let mut gathered = EmissionMoments::default();
            gather_moments(moments, &mut gathered);
            self.mcpg_emission.merge(&gathered);
            self.mcpg_emission.end_frame();
            self.mcpg_moments = Some(gathered);
        }
        Ok((
            pixels.iter().map(|t| Vec3::new(t[0], t[1], t[2])).collect(),
            seconds,
        ))
    }

    /// Keeps the GPU busy with untimed `bsdf` frames of `settings`' size for at least
    /// `seconds` of wall clock, so that the timed frames after it do not run at the clocks of
    /// an idle GPU; returns the frames rendered. [`render`](super::render) calls it on hardware
    /// adapters only (a software adapter such as lavapipe runs at its cores' clocks).
    ///
    /// A GPU lowers its clocks while it idles and raises them over some hundreds of
    /// milliseconds of load. A short render (64 frames of 128² take 25 ms of an H200's time,
    /// between read-backs) may run entirely at the idle clocks. The likeliest reading of the
    /// default report on an H200, whose GPU renders follow minutes of CPU work: there `bsdf`
    /// measured 2.1 ms a frame (5.6×, about an H200's idle-to-boost clock ratio) against
    /// 0.38 ms when rendered alone, and the methods' costs fell in the order they ran
    /// (`scripts/device-check` tests it). The warm-up writes only the image buffer, which
    /// every frame overwrites; no guide sees it.
    ///
    /// # Errors
    /// No scene uploaded, an image larger than the device's largest storage binding, or a
    /// device error.
    pub fn warm_up(&mut self, settings: &RenderSettings, seconds: f64) -> Result<u32> {
        let bsdf = RenderSettings {
            method: Method::Bsdf,
            ..*settings
        };
        let base = self.frame_params(&bsdf, 0)?;
        let started = Instant::now();
        let mut frames = 0;
        while started.elapsed().as_secs_f64() < seconds {
            self.dispatch_tiles(Method::Bsdf, &base)?;
            self.wait()?;
            frames += 1;
        }
        Ok(frames)
    }

    /// The image buffer's entries for `settings` (the pixels, then the `mcpg` moments every
    /// `moment_stride` pixels where its emission directions are allocated adaptively) and that
    /// stride; checking it early spares a caller the host memory of a render the device could
    /// not hold.
    ///
    /// # Errors
    /// When the image exceeds the device's largest storage binding.
    pub fn image_entries(&self, settings: &RenderSettings) -> Result<(usize, u32)> {
        let (width, height) = (settings.width, settings.height);
        let mcpg = settings.method == Method::Mcpg;
        let moment_stride = if mcpg && self.mcpg_emission.policy() != EmissionPolicy::Uniform {
            (width * height).div_ceil(MOMENT_PIXELS).max(1)
        } else {
            0
        };
        let pixels = width as usize * height as usize;
        let entries = pixels + moment_entries(width * height, moment_stride);
        let bytes = (entries * size_of::<[f32; 4]>()) as u64;
        let max = self.ctx.device().limits().max_storage_buffer_binding_size;
        if bytes > max {
            return Err(format!(
                "a {width}×{height} image needs {bytes} bytes; this GPU binds at most {max} \
                 (--device cpu renders it on the CPU)"
            )
            .into());
        }
        Ok((entries, moment_stride))
    }

    /// Checks `settings` against the device and the started guides, allocates the image and
    /// returns the frame's uniform (tile fields zero); the `mcpg` guide follows the camera.
    fn frame_params(&mut self, settings: &RenderSettings, frame: u32) -> Result<GpuParams> {
        let method = method_code(settings.method).ok_or_else(|| {
            format!(
                "the GPU tracer has no method {} yet (use --device cpu)",
                settings.method.name()
            )
        })?;
        let (width, height) = (settings.width, settings.height);
        let mcpg = settings.method == Method::Mcpg;
        let (entries, moment_stride) = self.image_entries(settings)?;
        if self.image.as_ref().is_none_or(|b| b.len() != entries) {
            self.image = Some(self.ctx.zeroed_buffer("mcg-demo image", entries));
        }
        match settings.method {
            Method::Mcpg | Method::McpgNee if self.guided.is_none() => {
                return Err("GpuTracer: mcpg needs GpuTracer::start_mcpg first".into());
            }
            m if m.uses_probes() && self.probes.is_none() => {
                return Err("GpuTracer: probe GI needs GpuTracer::start_probes first".into());
            }
            Method::Mcmm => match &self.mcmm {
                None => return Err("GpuTracer: mcmm needs GpuTracer::start_mcmm first".into()),
                Some(g) => {
                    super::mcmm::check_settings(settings, g.guide.width(), g.guide.height())?
                }
            },
            _ => {}
        }
        let camera = self.scene()?.camera;
        if let Some(g) = self.guided.as_mut().filter(|_| settings.method.is_guided()) {
            g.guide.set_camera(&self.ctx, camera.position);
        }
        let scene = self.scene()?;
        let tan_y = (0.5 * camera.yfov).tan();
        Ok(GpuParams {
            camera_position: camera.position.to_array(),
            tan_x: tan_y * width as f32 / height as f32,
            camera_right: camera.right.to_array(),
            tan_y,
            camera_up: camera.up.to_array(),
            width,
            camera_forward: camera.forward.to_array(),
            height,
            spp: settings.spp,
            bounces: settings.bounces,
            seed: settings.seed,
            frame,
            method,
            // Read by the guided pipelines only (`MCPG_DEF`).
            mcpg_reflected: u32::from(self.mcpg_reflected == Reflected::Path),
            moment_stride,
            emission_counts: if mcpg {
                bytemuck::cast(frame_counts(
                    self.mcpg_emission.per_depth(),
                    settings.seed,
                    frame,
                ))
            } else {
                [[0; 4]; 4]
            },
            ..scene.params()
        })
    }

    /// The pipeline, its group 0 layout, the guide's bind group and the workgroup size of
    /// `method`.
    fn pipeline_of(
        &self,
        method: Method,
    ) -> (
        &wgpu::ComputePipeline,
        &wgpu::BindGroupLayout,
        Option<&wgpu::BindGroup>,
        (u32, u32),
    ) {
        if let Some(g) = self.probes.as_ref().filter(|_| method.uses_probes()) {
            return (
                &g.pipeline,
                &g.layout,
                Some(g.guide.cache.bind_group()),
                (GROUP, GROUP),
            );
        }
        match (method, &self.guided, &self.mcmm) {
            (Method::McpgNee, Some(g), _) => {
                let (pipeline, layout) = self
                    .guided_lights
                    .as_ref()
                    .expect("made by prepare_pipeline");
                (pipeline, layout, Some(g.guide.bind_group()), (GROUP, GROUP))
            }
            (Method::Mcpg, Some(g), _) => (
                &g.pipeline,
                &g.layout,
                Some(g.guide.bind_group()),
                (GROUP, GROUP),
            ),
            (Method::Mcmm, _, Some(g)) => (
                &g.pipeline,
                &g.layout,
                Some(g.guide.bind_group()),
                (MCMM_GROUP.0, MCMM_GROUP.1),
            ),
            (Method::Nee, _, _) => {
                let nee = self.nee.as_ref().expect("made by prepare_pipeline");
                (
                    nee.pipeline(),
                    nee.bind_group_layout(),
                    None,
                    (GROUP, GROUP),
                )
            }
            _ => (
                self.render.pipeline(),
                self.render.bind_group_layout(),
                None,
                (GROUP, GROUP),
            ),
        }
    }

    /// Compiles the light-sampling pipeline `method` needs on its first frame (`nee`, or
    /// `mcpg-nee` around the current guide; the other methods' are made up front), and the
    /// guided shaders again when a frame of `bounces` falls on the other side of
    /// [`HELD_VERTICES`] than they were compiled for ([`HOLD_ALL_DEF`]), or the mean K of
    /// `mcpg`'s emission-only directions on the other side of 0 ([`EMISSION_DIRECTIONS_DEF`]).
    fn prepare_pipeline(&mut self, method: Method, bounces: u32) -> Result<()> {
        if matches!(method, Method::Mcpg | Method::McpgNee) {
            self.set_guided_defs(GuidedDefs {
                hold_all: bounces <= HELD_VERTICES,
                emission_directions: self.mcpg_emission.mean() > 0,
                ..self.guided_defs
            })?;
        }
        match method {
            Method::Nee if self.nee.is_none() => {
                let source = composed_shader(true, self.guided_defs.scene)?;
                self.nee = Some(self.ctx.compute_kernel(&source, "render")?);
            }
            Method::McpgNee if self.guided_lights.is_none() => {
                let Some(g) = &self.guided else {
                    return Ok(());
                };
                if self.guided_lights_module.is_none() {
                    let source = composed_mcpg_shader(true, self.guided_defs)?;
                    self.guided_lights_module =
                        Some(self.module("mcg-demo render mcpg-nee", source));
                }
                let module = self.guided_lights_module.as_ref().expect("compiled above");
                let pipeline =
                    self.guided_pipeline(module, "render", g.guide.bind_group_layout())?;
                self.guided_lights = Some(pipeline);
            }
            _ => {}
        }
        Ok(())
    }

    /// Both guided shaders again, and `mcpg`'s pipeline around its guide, when `defs` differ
    /// from what they were compiled with (`mcpg-nee`'s pipeline is made on its next frame);
    /// with [`GuidedDefs::scene`] changed, the `bsdf` kernels and `mcmm`'s pipeline around its
    /// guide too (`nee`'s and the segments' kernels are made on their next use), and the
    /// probes' when the scene's masks or environment change (made on the next probe frame,
    /// with a fresh cache).
    fn set_guided_defs(&mut self, defs: GuidedDefs) -> Result<()> {
        if defs == self.guided_defs {
            return Ok(());
        }
        let scene_changed = defs.scene != self.guided_defs.scene;
        let probe_defs = |d: GuidedDefs| {
            let s = d.scene;
            (s.alpha_mask, s.environment, s.environment_map, s.portals)
        };
        if probe_defs(defs) != probe_defs(self.guided_defs) {
            self.probe_module = None;
            self.probes = None;
        }
        self.guided_defs = defs;
        if scene_changed {
            let source = composed_shader(false, defs.scene)?;
            self.render = self.ctx.compute_kernel(&source, "render")?;
            self.rays = self.ctx.compute_kernel(&source, "trace_rays")?;
            self.nee = None;
            self.segments = None;
            self.mcmm_module = None;
            if let Some(g) = self.mcmm.take() {
                self.mcmm = Some(self.mcmm_guided(g.guide)?);
            }
        }
        self.guided_module = None;
        self.guided_lights_module = None;
        self.guided_lights = None;
        if let Some(g) = self.guided.take() {
            self.guided = Some(self.mcpg_guided(g.guide)?);
        }
        Ok(())
    }

    /// Records and submits one pass per tile of [`TILE`] pixels with `base`'s settings;
    /// returns the timed tiles and the tiles.
    fn dispatch_tiles(&self, method: Method, base: &GpuParams) -> Result<(u32, u32)> {
        let (width, height) = (base.width, base.height);
        let scene = self.scene()?;
        let image = self.image.as_ref().expect("allocated in frame_params");
        let (pipeline, layout, guide, group) = self.pipeline_of(method);
        let bind_group = self.bind_group(
            "render",
            layout,
            &[0, 1, 2, 3, 4, 5, 6, 7, 8],
            &[
                self.params.raw(),
                scene.nodes.raw(),
                scene.triangles.raw(),
                scene.materials.raw(),
                scene.emitters.raw(),
                scene.attributes.raw(),
                scene.textures.raw(),
                scene.texels.raw(),
                image.raw(),
            ],
        );
        let tiles: Vec<(u32, u32)> = (0..height.div_ceil(TILE))
            .flat_map(|ty| (0..width.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE)))
            .collect();
        let limits = self.ctx.device().limits();
        let groups = TILE.div_ceil(group.0.min(group.1));
        if groups > limits.max_compute_workgroups_per_dimension {
            return Err(format!(
                "{groups} workgroups per dimension exceed this GPU's {}",
                limits.max_compute_workgroups_per_dimension
            )
            .into());
        }
        let mut timed_tiles = 0u32;
        for (i, &(x, y)) in tiles.iter().enumerate() {
            let params = GpuParams {
                tile_x: x,
                tile_y: y,
                tile_width: TILE.min(width - x),
                tile_height: TILE.min(height - y),
                ..*base
            };
            // Ordered before the next submission (queue writes land before later submits).
            self.ctx.write(&self.params, &[params])?;
            let mut encoder = self
                .ctx
                .device()
                .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
            let timestamp_writes = self.timer.as_ref().and_then(|t| t.pass_writes(i as u32));
            timed_tiles += u32::from(timestamp_writes.is_some());
            {
                let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("mcg-demo render"),
                    timestamp_writes,
                });
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                if let Some(g) = guide {
                    pass.set_bind_group(GUIDE_GROUP, g, &[]);
                }
                pass.dispatch_workgroups(
                    params.tile_width.div_ceil(group.0),
                    params.tile_height.div_ceil(group.1),
                    1,
                );
            }
            self.ctx.queue().submit([encoder.finish()]);
        }
        Ok((timed_tiles, tiles.len() as u32))
    }

    /// The guide's end of frame after the tiles: `mcpg`'s per-frame pass, or `mcmm`'s buffer
    /// swap. The pass is timestamped in the timer's query pair `free_pair` when the timer has
    /// it (read with the tiles' pairs in [`GpuTracer::render_frame`]), else timed on the wall
    /// clock (also [`GpuTracer::last_end_frame_s`]).
    fn end_guide_frame(&mut self, method: Method, free_pair: u32) -> Result<GuideEnd> {
        self.last_end_frame_s = None;
        match method {
            Method::Mcpg | Method::McpgNee => {
                if let Some(writes) = self.timer.as_ref().and_then(|t| t.pass_writes(free_pair)) {
                    let g = self.guided.as_mut().expect("checked in frame_params");
                    let mut encoder = self
                        .ctx
                        .device()
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
                    g.guide
                        .record_end_frame_timed(&self.ctx, &mut encoder, Some(writes))?;
                    self.ctx.queue().submit([encoder.finish()]);
                    return Ok(GuideEnd::Timestamped);
                }
                self.wait()?;
                let ended = Instant::now();
                let g = self.guided.as_mut().expect("checked in frame_params");
                g.guide.end_frame(&self.ctx)?;
                self.wait()?;
                let seconds = ended.elapsed().as_secs_f64();
                self.last_end_frame_s = Some(seconds);
                Ok(GuideEnd::Wall(seconds))
            }
            Method::Mcmm => {
                self.mcmm
                    .as_mut()
                    .expect("checked in frame_params")
                    .guide
                    .swap();
                Ok(GuideEnd::None)
            }
            // The probe methods update their probes before the tiles (`update_probes`).
            Method::Bsdf
            | Method::Nee
            | Method::Adgi
            | Method::AdgiRefill
            | Method::AdgiBlend
            | Method::Ddgi => Ok(GuideEnd::None),
        }
    }

    /// The root of the uploaded emitters' tree in the node buffer ([`joined_trees`]): the
    /// [`GpuRay::root`] that walks it.
    ///
    /// # Errors
    /// No scene uploaded.
    pub fn emitter_root(&self) -> Result<u32> {
        Ok(self.scene()?.emitter_root)
    }

    /// The uploaded emitters' triangles as a [`GpuRay::list`]: `[first, count]` in the
    /// triangle buffer.
    ///
    /// # Errors
    /// No scene uploaded.
    pub fn emitter_list(&self) -> Result<[u32; 2]> {
        let scene = self.scene()?;
        Ok([scene.emitter_first, scene.emitters.len() as u32])
    }

    /// Walks the uploaded scene's BVH (or the emitters', [`GpuRay::root`]) for each ray on the
    /// GPU (the WGSL `bvh_walk_tree` that the tracer uses), for comparing with
    /// [`super::bvh::Bvh::intersect`], [`super::bvh::Bvh::intersect_front`] and
    /// [`super::bvh::Bvh::occluded`].
    ///
    /// # Errors
    /// No scene uploaded, more rays than one dispatch row holds, or a device error.
    pub fn trace_rays(&self, rays: &[GpuRay]) -> Result<Vec<GpuHit>> {
        self.dispatch_rays(&self.rays, rays, rays.len() as u32)
    }

    /// Walks the uploaded scene's BVH for the occlusion of up to [`SEGMENT_BATCH`] segments
    /// from one origin at a time, `origin + t·direction` for `t ∈ (0, t_max)`, as the tracer
    /// walks the shadow rays of `mcpg`'s emission-only directions (the WGSL
    /// `unoccluded_segments`: the segments one after the other in one traversal loop), for
    /// comparing with [`super::bvh::Bvh::occluded`]. Each batch is `(origin, segments)` with
    /// segments `(direction, t_max)`; the answer holds, per batch, bit j set when segment j
    /// is unoccluded.
    ///
    /// # Errors
    /// No scene uploaded, a batch of more than [`SEGMENT_BATCH`] segments, more batches than
    /// one dispatch row holds, or a device error.
    pub fn unoccluded_segments(
        &mut self,
        batches: &[(Vec3, Vec<(Vec3, f32)>)],
    ) -> Result<Vec<u32>> {
        let mut rays = Vec::with_capacity(batches.len() * SEGMENT_BATCH as usize);
        for (i, (origin, segments)) in batches.iter().enumerate() {
            if segments.len() > SEGMENT_BATCH as usize {
                return Err(format!(
                    "batch {i} holds {} segments, more than {SEGMENT_BATCH}",
                    segments.len()
                )
                .into());
            }
            let ray = GpuRay {
                origin: origin.to_array(),
                ..GpuRay::default()
            };
            rays.extend(segments.iter().map(|&(d, t_max)| GpuRay {
                direction: d.to_array(),
                t_max,
                any_hit: 1,
                ..ray
            }));
            rays.resize((i + 1) * SEGMENT_BATCH as usize, ray);
        }
        if self.segments.is_none() {
            let source = composed_shader(false, self.guided_defs.scene)?;
            self.segments = Some(self.ctx.compute_kernel(&source, "trace_segments")?);
        }
        let kernel = self.segments.as_ref().expect("compiled above");
        let hits = self.dispatch_rays(kernel, &rays, batches.len() as u32)?;
        Ok(batches
            .iter()
            .zip(hits.chunks_exact(SEGMENT_BATCH as usize))
            .map(|((_, segments), hits)| {
                (0..segments.len())
                    .filter(|&j| hits[j].triangle == GpuHit::MISS)
                    .fold(0, |mask, j| mask | 1 << j)
            })
            .collect())
    }

    /// Runs `kernel` (`trace_rays` or `trace_segments`, bindings 1, 2, 9 and 10) over
    /// `invocations` invocations with `rays` and reads back one hit per ray.
    fn dispatch_rays(
        &self,
        kernel: &ComputeKernel,
        rays: &[GpuRay],
        invocations: u32,
    ) -> Result<Vec<GpuHit>> {
        let scene = self.scene()?;
        let groups = invocations.div_ceil(RAY_GROUP).max(1);
        let max_groups = self
            .ctx
            .device()
            .limits()
            .max_compute_workgroups_per_dimension;
        if groups > max_groups {
            return Err(format!("{} rays exceed one dispatch row", rays.len()).into());
        }
        let queries = self.ctx.storage_buffer("mcg-demo rays", rays);
        let hits: GpuBuffer<GpuHit> = self.ctx.zeroed_buffer("mcg-demo hits", rays.len());
        let bind_group = if self.guided_defs.scene.alpha_mask {
            // The alpha test reads the scene's materials, attributes and textures, and where
            // they end (`GpuParams`, which holds the scene's fields from `upload` on).
            self.bind_group(
                kernel.entry_point(),
                kernel.bind_group_layout(),
                &[0, 1, 2, 3, 5, 6, 7, 9, 10],
                &[
                    self.params.raw(),
                    scene.nodes.raw(),
                    scene.triangles.raw(),
                    scene.materials.raw(),
                    scene.attributes.raw(),
                    scene.textures.raw(),
                    scene.texels.raw(),
                    queries.raw(),
                    hits.raw(),
                ],
            )
        } else {
            self.bind_group(
                kernel.entry_point(),
                kernel.bind_group_layout(),
                &[1, 2, 9, 10],
                &[
                    scene.nodes.raw(),
                    scene.triangles.raw(),
                    queries.raw(),
                    hits.raw(),
                ],
            )
        };
        let mut encoder = self
            .ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(kernel.pipeline());
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(groups, 1, 1);
        }
        self.ctx.queue().submit([encoder.finish()]);
        self.wait()?;
        Ok(self.ctx.read_back(&hits)?)
    }

    /// A bind group of group 0 with `layout`, `buffers` at the WGSL `bindings`: `render` uses
    /// 0–8, `trace_rays` and `trace_segments` 1, 2, 9 and 10 (and 0, 3, 5, 6 and 7 for the
    /// alpha test of a scene with masks).
    fn bind_group(
        &self,
        label: &str,
        layout: &wgpu::BindGroupLayout,
        bindings: &[u32],
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry<'_>> = bindings
            .iter()
            .zip(buffers)
            .map(|(&binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect();
        self.ctx
            .device()
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries: &entries,
            })
    }

    fn wait(&self) -> Result<()> {
        self.ctx
            .device()
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| format!("GPU wait failed: {e}"))?;
        Ok(())
    }
}

impl Timer {
    /// Query pairs per frame: one per tile, enough for a 16384 × 16384 image in tiles of
    /// [`TILE`] (wgpu allows 4096 queries per set).
    const PAIRS: u32 = 1024;

    fn new(ctx: &GpuContext) -> Self {
        let device = ctx.device();
        let bytes = u64::from(2 * Self::PAIRS) * u64::from(wgpu::QUERY_SIZE);
        Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("mcg-demo timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * Self::PAIRS,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("mcg-demo timestamps resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            staging: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("mcg-demo timestamps read-back"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            period_ns: f64::from(ctx.queue().get_timestamp_period()),
            pairs: Self::PAIRS,
        }
    }

    /// The timestamp writes of a pass into query pair `slot`, `None` past the set's pairs.
    fn pass_writes(&self, slot: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        (slot < self.pairs).then(|| wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(2 * slot),
            end_of_pass_write_index: Some(2 * slot + 1),
        })
    }

    /// The GPU time of each of the first `pairs` query pairs, in seconds.
    fn read(&self, ctx: &GpuContext, pairs: u32) -> Result<Vec<f64>> {
        let bytes = u64::from(2 * pairs) * u64::from(wgpu::QUERY_SIZE);
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.resolve_query_set(&self.queries, 0..2 * pairs, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.staging, 0, bytes);
        ctx.queue().submit([encoder.finish()]);
        let slice = self.staging.slice(..bytes);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        ctx.device()
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| format!("GPU wait failed: {e}"))?;
        receiver.recv()??;
        let ticks: Vec<u64> = {
            let view = slice.get_mapped_range()?;
            bytemuck::pod_collect_to_vec(&view[..])
        };
        self.staging.unmap();
        Ok(ticks
            .chunks_exact(2)
            .map(|p| p[1].saturating_sub(p[0]) as f64 * self.period_ns * 1e-9)
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parses and validates `source` under WebGPU's capabilities alone; the module and the
    /// storage buffers `render` binds in groups 0 and [`GUIDE_GROUP`].
    fn validate(source: &str) -> (naga::Module, usize, usize) {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
        let render = module
            .entry_points
            .iter()
            .position(|e| e.name == "render")
            .expect("render entry point");
        let used = info.get_entry_point(render);
        let storage = |group: u32| {
            module
                .global_variables
                .iter()
                .filter(|(h, g)| {
                    !used[*h].is_empty()
                        && matches!(g.space, naga::AddressSpace::Storage { .. })
                        && g.binding.as_ref().is_some_and(|b| b.group == group)
                })
                .count()
        };
        let (tracer, guide) = (storage(0), storage(GUIDE_GROUP));
        (module, tracer, guide)
    }

    /// `frame_counts` draws ⌊K(d)⌋ or ⌈K(d)⌉ with mean K(d), and at least one direction where
    /// K(d) > 0. Sample: 20,000 frames (seed 9) of K = (0, 1.25, 6.5, 4.9, 16) at depths 0-4
    /// and 0.4 at depth 5. Threshold: every count is ⌊K⌋ or ⌈K⌉, and the mean over frames is
    /// within 5 binomial standard deviations of K; depth 5 always draws 1. Never rounding up
    /// fails it (z = −82 at depth 1; checked once).
    #[test]
    fn frame_counts_draw_k_on_average() {
        let mut k = [0.0_f32; MAX_RECORDED];
        k[..6].copy_from_slice(&[0.0, 1.25, 6.5, 4.9, 16.0, 0.4]);
        let n = 20_000_u32;
        let mut sums = [0_u64; MAX_RECORDED];
        for frame in 0..n {
            let counts = frame_counts(&k, 9, frame);
            assert_eq!(counts[5], 1);
            for (d, c) in counts.into_iter().enumerate().take(5) {
                assert!(
                    c == k[d].floor() as u32 || c == k[d].ceil() as u32,
                    "{d}: {c}"
                );
                sums[d] += u64::from(c);
            }
        }
        for d in 0..5 {
            let mean = sums[d] as f64 / f64::from(n);
            let f = f64::from(k[d] - k[d].floor());
            let sigma = (f * (1.0 - f) / f64::from(n)).sqrt().max(1e-12);
            let z = (mean - f64::from(k[d])) / sigma;
            assert!(
                z.abs() < 5.0,
                "depth {d}: mean {mean} against {} (z = {z:.1})",
                k[d]
            );
        }
    }

    /// The composed tracer parses and validates with naga under WebGPU's capabilities alone
    /// (no adapter needed, so CI without a GPU still checks the shader), both entry points
    /// exist, and the `render` kernel of `bsdf`/`nee` binds the 8 storage buffers WebGPU
    /// guarantees and nothing of the guide's group; `mcpg`'s adds the guide's 3.
    #[test]
    fn shader_validates_without_an_adapter() {
        let (module, tracer, guide) =
            validate(&composed_shader(false, SceneDefs::default()).unwrap());
        let masked = SceneDefs {
            attributes: true,
            alpha_mask: true,
            environment: true,
            environment_map: true,
            portals: false,
        };
        let textured = SceneDefs {
            attributes: true,
            ..SceneDefs::default()
        };
        let portals = SceneDefs {
            environment: true,
            portals: true,
            ..SceneDefs::default()
        };
        for (lights, scene) in [
            (true, SceneDefs::default()),
            (false, textured),
            (true, masked),
            (true, portals),
        ] {
            assert_eq!(
                validate(&composed_shader(lights, scene).unwrap()).1,
                8,
                "render with lights {lights}, {scene:?}"
            );
        }
        let names: Vec<&str> = module
            .entry_points
            .iter()
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(names, ["render", "trace_rays", "trace_segments"]);
        let batch = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some("EMISSION_BATCH"))
            .map(|(_, c)| &module.global_expressions[c.init]);
        assert!(
            matches!(
                batch,
                Some(naga::Expression::Literal(naga::Literal::U32(SEGMENT_BATCH)))
            ),
            "the WGSL EMISSION_BATCH is SEGMENT_BATCH: {batch:?}"
        );
        assert_eq!((tracer, guide), (8, 0), "render binds 1–8 as storage");
        for lights in [false, true] {
            for (hold_all, emitter_list, emission_directions, scene) in [
                (false, false, true, SceneDefs::default()),
                (true, false, false, textured),
                (true, true, true, masked),
            ] {
                let defs = GuidedDefs {
                    hold_all,
                    emitter_list,
                    emission_directions,
                    scene,
                };
                let (_, tracer, guide) = validate(&composed_mcpg_shader(lights, defs).unwrap());
                assert_eq!(tracer + guide, MCPG_STORAGE_BUFFERS as usize);
                assert_eq!(guide, 3, "the mcpg render binds the guide");
            }
        }
        // `mcmm`'s shader, with and without the attribute and mask code.
        for scene in [SceneDefs::default(), textured, masked] {
            let source = composed_mcmm_shader(scene).unwrap();
            let module = naga::front::wgsl::parse_str(&source)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
        }
        // `GpuParams` is `Params` in WGSL, byte for byte.
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let params = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Params"))
            .map(|(h, _)| h)
            .unwrap();
        assert_eq!(layouter[params].size as usize, size_of::<GpuParams>());
        assert_eq!(size_of::<GpuParams>(), 240);
    }
}
