// The WGSL path tracer of `mcg-demo render --device gpu`: a line-by-line twin of the CPU tracer
// (`demo/src/render/{cpu,bvh,material}.rs`) over the same flat buffers — BVH nodes (32 bytes),
// triangles in leaf order (48 bytes), materials (48 bytes) — uploaded as the CPU holds them.
//
// Conventions (as on the CPU): `bounces` counts scattering events; no Russian roulette; a box
// pixel filter; rays that leave the scene see the environment (`environment_radiance`);
// emission from front faces only; both faces scatter. The
// random stream of a path is seeded by `path_seed` and drawn in the same order as on the CPU,
// so both devices trace the same paths up to floating-point rounding.
//
// Methods: 0 = `bsdf` (BSDF sampling, lights found by chance), 1 = `nee` (BSDF sampling plus one
// light sample per scattering event, power-heuristic MIS, Veach and Guibas 1995, eq. 9, β = 2).
// 2 = `mcpg`, composed with the shader def MCG_DEMO_MCPG (and `GpuMcpgGuide::shader_defs(1)`): the
// MCPG guide of `mcg::mcpg`, bound at group 1, at every scattering vertex (`guided_sample`
// below), with the material as its fallback technique, and no light sampling. 4 = `mcpg-nee`,
// the same guide plus `nee`'s light sample, weighted against the guide's exact mixture density
// (mcg's extension). Without MCG_DEMO_MCPG the `render` entry point uses no binding of group 1.
// 3 = `mcmm`, composed with the shader def MCG_DEMO_MCMM (and `GpuMcmmGuide::shader_defs(1)`):
// the entry point `render_mcmm` (direct light only), the twin of `mcmm::McmmRenderer`, with the
// chain states of `mcg::mcmm` bound at group 1 (`mcg::mcpg` then goes to the unused group 2).

#import mcg::constants::{MCG_F32_MAX, MCG_FRAC_1_PI, MCG_PI, MCMM_PRIOR_LIGHT_SIZE, MCMM_SCORE_TECHNIQUE,
    MCPG_MAX_CANDIDATES, MCPG_NO_LOBE, MCPG_SCATTER_CUSTOM}
#import mcg::markov::{MarkovPixelState, markov_pixel_state_is_valid}
#import mcg::math::{mcg_is_finite, mcg_is_positive}
#import mcg::mcmm::{
    mcg_mcmm_params, mcmm_choose_technique, mcmm_collaborative_discovery, mcmm_empty_state,
    mcmm_load_previous, mcmm_ratio, mcmm_select_uniform, mcmm_store_current, mcmm_technique_pdf,
    mcmm_update, mcmm_xor_source_lane
}
#import mcg::vmf::{
    Vmf, VmfMapPrior, vmf_kappa_from_one_minus_mean_cosine, vmf_normalization,
    vmf_posterior_one_minus_mean_cosine, vmf_sample, vmf_try_normalize
}
#import mcg::mcpg::{
    McpgBeginUniforms, McpgFinishUniforms, McpgGuidedVertex, McpgObservation, McpgPending,
    McpgSample, McpgVertex, mcpg_begin_at, mcpg_choose, mcpg_finish_pending,
    mcpg_observation_escaped, mcpg_observation_hit, mcpg_params, mcpg_pdf_with, mcpg_pending,
    mcpg_sample_lobe
}
#import mcg::adgi::{
    AdgiRaySample, adgi_irradiance_at, adgi_params, adgi_pilot_direction, adgi_probe_position,
    adgi_sign_not_zero
}
#import mcg::adgi_chains::{AdgiProbeSample, adgi_pilot_uniforms}
#import mcg::sampling::{
    mcg_cosine_hemisphere_pdf, mcg_cosine_hemisphere_sample, mcg_frame_to_world, mcg_pcg_hash,
    mcg_rng_uniform, mcg_uniform_float
}

// `bvh::BvhNode`: inner node (count 0) with children index, index + 1; or a leaf over
// triangles[index .. index + count].
struct BvhNode {
    lo: vec3<f32>,
    index: u32,
    hi: vec3<f32>,
    count: u32,
}

// `bvh::Triangle`: v0, the edges v1 − v0 and v2 − v0, material and light-sampling probability.
struct Triangle {
    v0: vec3<f32>,
    material: u32,
    e1: vec3<f32>,
    emitter_pmf: f32,
    e2: vec3<f32>,
    source: u32,
}

// `material::Material`.
struct Material {
    base_color: vec3<f32>,
    metallic: f32,
    emission: vec3<f32>,
    roughness: f32,
    base_color_texture: u32,
    emissive_texture: u32,
    metallic_roughness_texture: u32,
    // `Material::alpha_cutoff`: 0 for opaque materials.
    alpha_cutoff: f32,
}

// One entry of the emitter table: the triangle and the inclusive cumulative probability
// (`Scene::emitters`, `Scene::emitter_cdf`).
struct Emitter {
    triangle: u32,
    cdf: f32,
}

// `scene::TriangleAttributes`.
struct TriangleAttributes {
    uv_a: vec2<f32>,
    uv_b: vec2<f32>,
    uv_c: vec2<f32>,
    color_a: vec2<u32>,
    color_b: vec2<u32>,
    color_c: vec2<u32>,
}

// `scene::TextureInfo`.
struct TextureInfo {
    offset: u32,
    width: u32,
    height: u32,
    wrap: u32,
    map_u: vec4<f32>,
    map_v: vec4<f32>,
}

// `gpu::GpuParams`: the camera, the settings of the frame, and the tile of this dispatch.
struct Params {
    camera_position: vec3<f32>,
    tan_x: f32,
    camera_right: vec3<f32>,
    tan_y: f32,
    camera_up: vec3<f32>,
    width: u32,
    camera_forward: vec3<f32>,
    height: u32,
    spp: u32,
    bounces: u32,
    seed: u32,
    frame: u32,
    method: u32,
    emitter_count: u32,
    tile_x: u32,
    tile_y: u32,
    tile_width: u32,
    tile_height: u32,
    attribute_count: u32,
    texture_count: u32,
    // Every how many pixels one records the statistics of `mcpg`'s emission-only directions
    // after the pixels in `image` (`gpu::moment_entries`); 0: none.
    moment_stride: u32,
    // The root of the emitters' tree in `nodes` (`gpu::joined_trees`).
    emitter_root: u32,
    // 1: `mcpg` trains on the path's own L_r (`guided::Reflected::Path`), 0: on the cache's.
    mcpg_reflected: u32,
    // The emitters' first triangle in `triangles` (`gpu::joined_trees`: the emitter_count
    // triangles from it are the emitters' tree's).
    emitter_first: u32,
    // `mcpg`'s emission-only directions per vertex of depth d = 4i + j in [i][j] this frame
    // (`gpu::frame_counts`).
    emission_counts: array<vec4<u32>, 4>,
    // `Scene::environment`: the radiance of a ray that leaves the scene.
    environment: vec3<f32>,
    // `Scene::environment_pmf`: the probability that a light sample picks the environment.
    environment_pmf: f32,
    // The environment map (`GpuParams::environment_map`): its first word in `texels`, its
    // width and height, and its rotation about +Y (`f32` bits); zeros without one.
    environment_map: vec4<u32>,
    // The portals (`GpuParams::portals`): their first word in `texels` and their number.
    portals: vec4<u32>,
}

// `gpu::GpuRay`: a query of the `trace_rays` kernel (closest hit, or any hit when `any_hit`).
struct Ray {
    origin: vec3<f32>,
    t_max: f32,
    direction: vec3<f32>,
    any_hit: u32,
    root: u32,
    front_only: u32,
    // With list.y > 0: the triangles list.x … list.x + list.y − 1 one after the other
    // (`emitter_list_hit`), front faces only, instead of a tree.
    list: vec2<u32>,
}

// `gpu::GpuHit`: the answer to a `Ray`; `triangle` is 0xffffffff for a miss.
struct RayHit {
    t: f32,
    triangle: u32,
    b1: f32,
    b2: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> emitters: array<Emitter>;
@group(0) @binding(5) var<storage, read> attributes: array<TriangleAttributes>;
@group(0) @binding(6) var<storage, read> textures: array<TextureInfo>;
@group(0) @binding(7) var<storage, read> texels: array<u32>;
@group(0) @binding(8) var<storage, read_write> image: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read> rays: array<Ray>;
@group(0) @binding(10) var<storage, read_write> ray_hits: array<RayHit>;

// `gpu::method_code` of `mcpg` (light sampling is a shader def, `gpu::LIGHTS_DEF`).
const METHOD_MCPG: u32 = 2u;
// `cpu::MAX_RECORDED`: the deepest vertex a guide learns from.
const MAX_RECORDED: u32 = 16u;
// `cpu::SAMPLER_SALT`: the guide's stream starts away from the path's.
const SAMPLER_SALT: u32 = 0x5bd1e995u;
// `bvh::STACK_SIZE`.
const STACK_SIZE: u32 = 64u;
const NO_HIT: u32 = 0xffffffffu;
// `material::NO_TEXTURE`.
const NO_TEXTURE: u32 = 0xffffffffu;
// `material::MIN_ALPHA`.
const MIN_ALPHA: f32 = 1e-3;
// `cpu::RAY_OFFSET`.
const RAY_OFFSET: f32 = 1e-4;
// +∞ of the CPU (no infinity literal in WGSL): the distance of a miss.
const FAR: f32 = MCG_F32_MAX;

// ---------------------------------------------------------------------------------------------
// BVH traversal (`bvh::Bvh::walk`)

// `Triangle::intersect`: Möller and Trumbore 1997; (t, b1, b2) in .xyz, .w = 1 on a hit.
fn triangle_intersect(tri: Triangle, origin: vec3<f32>, direction: vec3<f32>, t_min: f32,
                      t_max: f32, front_only: bool) -> vec4<f32> {
    let p = cross(direction, tri.e2);
    let det = dot(tri.e1, p);
    // `Triangle::intersect_front`: det = −d·(e1 × e2) > 0 exactly on the front face.
    if select(abs(det), det, front_only) < 1e-12 {
        return vec4<f32>(0.0);
    }
    let inv = 1.0 / det;
    let s = origin - tri.v0;
    let b1 = dot(s, p) * inv;
    if !(b1 >= 0.0 && b1 <= 1.0) {
        return vec4<f32>(0.0);
    }
    let q = cross(s, tri.e1);
    let b2 = dot(direction, q) * inv;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return vec4<f32>(0.0);
    }
    let t = dot(tri.e2, q) * inv;
    if t > t_min && t < t_max {
        return vec4<f32>(t, b1, b2, 1.0);
    }
    return vec4<f32>(0.0);
}

// Whether the hit `h` (`triangle_intersect`'s) of triangle `i` counts: `is_surface_at` in
// scenes with alpha masks (MCG_DEMO_ALPHA_MASK, `gpu::ALPHA_MASK_DEF`), always elsewhere, so
// that the walks of other scenes carry none of its code.
fn is_surface_hit(i: u32, h: vec4<f32>) -> bool {
#ifdef MCG_DEMO_ALPHA_MASK
    let tri = triangles[i];
    // An emitters' copy reads its scene triangle's attributes (`Triangle::source`).
    let scene_triangle = select(i, tri.source, i >= params.emitter_first);
    return is_surface_at(tri.material, RayHit(h.x, scene_triangle, h.y, h.z));
#else
    return true;
#endif
}

// `box_entry`: the slab test's entry distance, FAR on a miss.
fn box_entry(node: BvhNode, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let t0 = (node.lo - origin) * inv;
    let t1 = (node.hi - origin) * inv;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(max(near.x, near.y), near.z), t_min);
    let exit = min(min(min(far.x, far.y), far.z), t_max);
    return select(FAR, enter, enter <= exit);
}

// The closest hit within (t_min, t_max) or, with `any_hit`, the first one found (shadow rays).
// `triangle` is NO_HIT on a miss.
fn bvh_walk(origin: vec3<f32>, direction: vec3<f32>, t_min: f32, t_max: f32,
            any_hit: bool) -> RayHit {
    return bvh_walk_tree(0u, false, origin, direction, t_min, t_max, any_hit);
}

// The walks' node stack (`bvh_walk_tree`, `unoccluded_segments`; they never nest). A private
// variable is zero-initialised once per invocation, where a function's `var` array is
// zero-initialised on every call (WGSL's rule), which llvmpipe executes as STACK_SIZE stores
// per walk.
var<private> walk_stack: array<u32, STACK_SIZE>;

// 1/d with zero components replaced by a tiny signed value: the CPU's ±∞ times a zero slab
// distance is NaN, which GPUs compare inconsistently.
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    return 1.0 / select(d, select(tiny, -tiny, d < vec3<f32>(0.0)), abs(d) < tiny);
}

// `bvh_walk` in the tree whose root is `nodes[root]` (0: the scene's; `params.emitter_root`:
// the emitters', `gpu::joined_trees`), with `front_only` hitting front faces only.
fn bvh_walk_tree(root: u32, front_only: bool, origin: vec3<f32>, direction: vec3<f32>,
                 t_min: f32, t_max: f32, any_hit: bool) -> RayHit {
    var best = RayHit(t_max, NO_HIT, 0.0, 0.0);
    let inv = safe_inverse(direction);
    // `Bvh::walk`: front-face queries (emission from the emitters' small tree, which most of
    // their rays miss) test the root's box first.
    if front_only && box_entry(nodes[root], origin, inv, t_min, best.t) >= FAR {
        return best;
    }
    walk_stack[0] = root;
    var top = 1u;
    while top > 0u {
        top -= 1u;
        let node = nodes[walk_stack[top]];
        if node.count > 0u {
            for (var i = node.index; i < node.index + node.count; i++) {
                let h = triangle_intersect(triangles[i], origin, direction, t_min, best.t,
                                           front_only);
                if h.w > 0.0 && is_surface_hit(i, h) {
                    best = RayHit(h.x, i, h.y, h.z);
                    if any_hit {
                        return best;
                    }
                }
            }
            continue;
        }
        push_children(node, origin, inv, t_min, best.t, &top);
    }
    return best;
}

// The children of the interior `node` whose boxes the ray meets within (t_min, t_max) onto
// `walk_stack` above `*top`: the farther first, so the nearer one is popped next.
fn push_children(node: BvhNode, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32,
                 top: ptr<function, u32>) {
    let a = node.index;
    let ta = box_entry(nodes[a], origin, inv, t_min, t_max);
    let tb = box_entry(nodes[a + 1u], origin, inv, t_min, t_max);
    let a_first = ta <= tb;
    if max(ta, tb) < FAR && *top < STACK_SIZE {
        walk_stack[*top] = select(a, a + 1u, a_first);
        *top += 1u;
    }
    if min(ta, tb) < FAR && *top < STACK_SIZE {
        walk_stack[*top] = select(a + 1u, a, a_first);
        *top += 1u;
    }
}

// The closest emitter whose front face the ray from `origin` along `direction` meets
// (`Scene::emitter_bvh`'s `intersect_front`), for `mcpg`'s emission-only directions. With
// MCG_DEMO_EMITTER_LIST (`gpu::EMITTER_LIST_DEF`, scenes of at most `gpu::EMITTER_LIST_MAX`
// emitter triangles) the emitters' triangles one after the other, else a walk of their tree.
fn emitter_hit(origin: vec3<f32>, direction: vec3<f32>) -> RayHit {
#ifdef MCG_DEMO_EMITTER_LIST
    return emitter_list_hit(params.emitter_first, params.emitter_count, origin, direction);
#else
    return bvh_walk_tree(params.emitter_root, true, origin, direction, 0.0, FAR, false);
#endif
}

// The closest front face among triangles[first … first + count − 1] along the ray, as the
// emitters' tree walk finds it. Every invocation reads the same triangles in the same order
// (uniform addresses): a SIMD group loads each once, where a walk's node and triangle loads
// are per invocation (on llvmpipe a loop over the group's lanes each), and a tree of a few
// triangles is mostly that overhead (`mcg-markov-guide`'s benches README, 2026-11-29, fifth
// session: lavapipe's `mcpg` frames 7 % shorter on scene (a)).
fn emitter_list_hit(first: u32, count: u32, origin: vec3<f32>, direction: vec3<f32>) -> RayHit {
    var best = RayHit(FAR, NO_HIT, 0.0, 0.0);
    for (var i = first; i < first + count; i++) {
        let h = triangle_intersect(triangles[i], origin, direction, 0.0, best.t, true);
        if h.w > 0.0 && is_surface_hit(i, h) {
            best = RayHit(h.x, i, h.y, h.z);
        }
    }
    return best;
}

// The segments of one batch of emission-only directions (`EMISSION_BATCH` at most): a
// direction in .xyz and the distance to the emitter it meets in .w.
struct Segments {
    ray: array<vec4<f32>, EMISSION_BATCH>,
    // The emitting triangle at the end of each segment (an emitters' copy) and where on it
    // (barycentrics).
    triangle: array<u32, EMISSION_BATCH>,
    bary: array<vec2<f32>, EMISSION_BATCH>,
}

// The batch being walked: private, as `walk_stack`, so that it is not zero-initialised at
// every vertex.
var<private> segments: Segments;

// The first `n` of `segments` from `origin` walked for occlusion (`bvh_walk(origin, d, 0.0,
// t, true)` each, the CPU's test in `cpu::emission_along`) in one traversal loop that moves
// on to the next segment when a walk ends: a SIMD group (a GPU's warp, llvmpipe's lanes) then
// runs as many steps as its busiest invocation's segments take together, where a walk per
// segment costs, segment after segment, the longest walk of any invocation. Bit j of the
// result is set when segment j is unoccluded.
fn unoccluded_segments(origin: vec3<f32>, n: u32) -> u32 {
    var visible = 0u;
    var top = 0u;
    // The segment being walked; n once all are.
    var r = 0u;
    var d = vec3<f32>(0.0);
    var inv = vec3<f32>(0.0);
    var t_max = 0.0;
    loop {
        if top == 0u {
            if r >= n {
                break;
            }
            d = segments.ray[r].xyz;
            t_max = segments.ray[r].w;
            inv = safe_inverse(d);
            walk_stack[0] = 0u;
            top = 1u;
            visible |= 1u << r;
        }
        top -= 1u;
        let node = nodes[walk_stack[top]];
        if node.count > 0u {
            for (var i = node.index; i < node.index + node.count; i++) {
                let h = triangle_intersect(triangles[i], origin, d, 0.0, t_max, false);
                if h.w > 0.0 && is_surface_hit(i, h) {
                    visible &= ~(1u << r);
                    top = 0u;
                    break;
                }
            }
        } else {
            push_children(node, origin, inv, 0.0, t_max, &top);
        }
        // This segment's walk ended: the next one starts in the next step.
        r += u32(top == 0u);
    }
    return visible;
}

// ---------------------------------------------------------------------------------------------
// Materials (`material::Material`): Lambert + GGX conductor blended by `metallic`.

// A sampled direction, its density and `f·cos/pdf`; `valid` is false when the sample ends the
// path (`None` on the CPU).
struct BsdfSample {
    direction: vec3<f32>,
    pdf: f32,
    weight: vec3<f32>,
    valid: bool,
}

fn material_alpha(m: Material) -> f32 {
    return max(m.roughness * m.roughness, MIN_ALPHA);
}

// GGX D (Walter et al. 2007, eq. 33).
fn ggx_d(cos_h: f32, a2: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let k = cos_h * cos_h * (a2 - 1.0) + 1.0;
    return a2 / (MCG_PI * k * k);
}

// Smith G₁ for GGX (Walter et al. 2007, eq. 34).
fn smith_g1(c: f32, a2: f32) -> f32 {
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

// Schlick 1994, eq. 24. The fifth power by multiplications, as the CPU's `powi(5)`: `pow`
// is exp2(5·log2(x)), which at x = 0 passes through −∞, a value WGSL lets a driver assume
// never occurs.
fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let x = 1.0 - clamp(c, 0.0, 1.0);
    let x2 = x * x;
    let k = x2 * x2 * x;
    return f0 + (vec3<f32>(1.0) - f0) * k;
}

// `Material::eval`: f(ωo, ωi)·(n·ωi).
fn material_eval(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let cos_i = dot(n, wi);
    let cos_o = dot(n, wo);
    if cos_i <= 0.0 || cos_o <= 0.0 {
        return vec3<f32>(0.0);
    }
    var f = (1.0 - m.metallic) * m.base_color * MCG_FRAC_1_PI;
    if m.metallic > 0.0 {
        let h = normalize(wo + wi);
        let alpha = material_alpha(m);
        let a2 = alpha * alpha;
        let d = ggx_d(dot(n, h), a2);
        let g = smith_g1(cos_o, a2) * smith_g1(cos_i, a2);
        let fresnel = schlick(m.base_color, dot(wo, h));
        f += m.metallic * fresnel * (d * g / (4.0 * cos_o * cos_i));
    }
    return f * cos_i;
}

// `Material::pdf`: m·p_GGX + (1 − m)·cos θ/π (Walter et al. 2007, eq. 14 and 38).
fn material_pdf(m: Material, n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if dot(n, wi) <= 0.0 || dot(n, wo) <= 0.0 {
        return 0.0;
    }
    var pdf = (1.0 - m.metallic) * mcg_cosine_hemisphere_pdf(n, wi);
    if m.metallic > 0.0 {
        let h = normalize(wo + wi);
        let alpha = material_alpha(m);
        let a2 = alpha * alpha;
        pdf += m.metallic * ggx_d(dot(n, h), a2) * dot(n, h) / (4.0 * abs(dot(wo, h)));
    }
    return pdf;
}

// `Material::sample`: u.x picks the lobe, u.yz sample it (Walter et al. 2007, eq. 35–36).
fn material_sample(m: Material, n: vec3<f32>, wo: vec3<f32>, u: vec3<f32>) -> BsdfSample {
    var wi: vec3<f32>;
    if u.x < m.metallic {
        let alpha = material_alpha(m);
        let a2 = alpha * alpha;
        let cos2 = (1.0 - u.y) / (1.0 + u.y * (a2 - 1.0));
        let cos_h = sqrt(max(cos2, 0.0));
        let sin_h = sqrt(max(1.0 - cos2, 0.0));
        let phi = 2.0 * MCG_PI * u.z;
        let h = mcg_frame_to_world(n, vec3<f32>(sin_h * cos(phi), sin_h * sin(phi), cos_h));
        wi = 2.0 * dot(wo, h) * h - wo;
    } else {
        wi = mcg_cosine_hemisphere_sample(n, clamp(u.yz, vec2<f32>(0.0), vec2<f32>(1.0))).direction;
    }
    let pdf = material_pdf(m, n, wo, wi);
    // From the bits: a degenerate half vector can make the pdf NaN.
    if !mcg_is_positive(pdf) {
        return BsdfSample(wi, 0.0, vec3<f32>(0.0), false);
    }
    return BsdfSample(wi, pdf, material_eval(m, n, wo, wi) / pdf, true);
}

// `TriangleAttributes::uv_at`: the texture coordinates of `a`'s triangle at `hit`.
fn uv_at(a: TriangleAttributes, hit: RayHit) -> vec2<f32> {
    return (1.0 - hit.b1 - hit.b2) * a.uv_a + hit.b1 * a.uv_b + hit.b2 * a.uv_c;
}

// `TriangleAttributes::color_at`: the vertex colour of `a`'s triangle at `hit`, exactly white
// where the three are white.
fn color_at(a: TriangleAttributes, hit: RayHit) -> vec3<f32> {
    let c0 = vec3<f32>(unpack2x16unorm(a.color_a.x), unpack2x16unorm(a.color_a.y).x);
    let c1 = vec3<f32>(unpack2x16unorm(a.color_b.x), unpack2x16unorm(a.color_b.y).x);
    let c2 = vec3<f32>(unpack2x16unorm(a.color_c.x), unpack2x16unorm(a.color_c.y).x);
    return c0 + hit.b1 * (c1 - c0) + hit.b2 * (c2 - c0);
}

// `Scene::texel`: texture `texture`'s RGBA8 at texture coordinates `uv` (mapped by
// `TextureInfo::map`, wrapped by `TextureInfo::wrap`, nearest texel) as values in [0, 1], not
// decoded; white without texture.
fn texel_at(texture: u32, uv: vec2<f32>) -> vec4<f32> {
    if texture >= params.texture_count {
        return vec4<f32>(1.0);
    }
    let tex = textures[texture];
    let h = vec3<f32>(uv, 1.0);
    let c = vec2<f32>(dot(tex.map_u.xyz, h), dot(tex.map_v.xyz, h));
    let x = wrapped_texel(c.x, tex.wrap & 0xffffu, tex.width);
    let y = wrapped_texel(c.y, tex.wrap >> 16u, tex.height);
    return unpack4x8unorm(texels[tex.offset + y * tex.width + x]);
}

// `TriangleAttributes::alpha_at`: the vertex colours' alpha of `a`'s triangle at `hit`.
fn alpha_at(a: TriangleAttributes, hit: RayHit) -> f32 {
    let a0 = unpack2x16unorm(a.color_a.y).y;
    let a1 = unpack2x16unorm(a.color_b.y).y;
    let a2 = unpack2x16unorm(a.color_c.y).y;
    return a0 + hit.b1 * (a1 - a0) + hit.b2 * (a2 - a0);
}

// `scene::wrapped_texel`: coordinate `c` wrapped by `mode` (0 REPEAT, 1 CLAMP_TO_EDGE,
// 2 MIRRORED_REPEAT) to the nearest texel's index below `size`.
fn wrapped_texel(c: f32, mode: u32, size: u32) -> u32 {
    let t = c - 2.0 * floor(0.5 * c);
    let mirrored = select(t, 2.0 - t, t > 1.0);
    let f = select(select(c - floor(c), clamp(c, 0.0, 1.0), mode == 1u), mirrored, mode == 2u);
    return min(u32(f * f32(size)), size - 1u);
}

// `scene::srgb_to_linear` per channel (IEC 61966-2-1); 1 stays 1, so a colour without texture
// (`texel_at`'s white) is unchanged.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

// `Scene::material_at`: the triangle's material with its vertex colour and its base-colour,
// emissive and metallic-roughness textures (`texel_at`) multiplied in. Compiled only where
// the scene has attributes (`MCG_DEMO_ATTRIBUTES`, `gpu::ATTRIBUTES_DEF`): llvmpipe pays for
// this code in every kernel that contains it, taken or not (+11 % on a `nee` frame).
fn material_at(hit: RayHit) -> Material {
    var m = materials[triangles[hit.triangle].material];
#ifdef MCG_DEMO_ATTRIBUTES
    if params.attribute_count == 0u {
        return m;
    }
    let a = attributes[hit.triangle];
    m.base_color *= color_at(a, hit);
    if params.texture_count == 0u {
        return m;
    }
    let c = uv_at(a, hit);
    m.base_color *= srgb_to_linear(texel_at(m.base_color_texture, c).rgb);
    m.emission *= srgb_to_linear(texel_at(m.emissive_texture, c).rgb);
    let metallic_roughness = texel_at(m.metallic_roughness_texture, c);
    m.roughness *= metallic_roughness.g;
    m.metallic *= metallic_roughness.b;
#else
    // The bindings stay in the pipeline's layout, which the tracer binds whole.
    _ = arrayLength(&attributes) + arrayLength(&textures) + arrayLength(&texels);
#endif
    return m;
}

// `Scene::emitter_emission`: the emission of the emitters' copy `t` (the list's or the tree's
// triangle) at barycentrics `b`, textured as its scene triangle (`Triangle::source`).
fn emitter_emission(t: u32, b: vec2<f32>) -> vec3<f32> {
    let tri = triangles[t];
    return triangle_emission(tri.material, RayHit(0.0, tri.source, b.x, b.y));
}

// The emission of triangle `hit.triangle`'s material `material` at `hit`: its factor alone
// (one 12-byte load) in a scene without textures.
fn triangle_emission(material: u32, hit: RayHit) -> vec3<f32> {
    let emission = materials[material].emission;
#ifdef MCG_DEMO_ATTRIBUTES
    if params.texture_count > 0u {
        let uv = uv_at(attributes[hit.triangle], hit);
        let texel = texel_at(materials[material].emissive_texture, uv);
        return emission * srgb_to_linear(texel.rgb);
    }
#endif
    return emission;
}

// `Scene::is_surface_at`: whether `hit.triangle` (the scene's), of material `material`, is a
// surface at `hit`: always for an opaque material; for an alpha mask where the base-colour
// texture's alpha × the vertex colour's alpha reaches `Material::alpha_cutoff`.
fn is_surface_at(material: u32, hit: RayHit) -> bool {
    let m = materials[material];
    if m.alpha_cutoff <= 0.0 || params.attribute_count == 0u {
        return true;
    }
    let a = attributes[hit.triangle];
    return texel_at(m.base_color_texture, uv_at(a, hit)).a * alpha_at(a, hit) >= m.alpha_cutoff;
}

// ---------------------------------------------------------------------------------------------
// The vertex sampler: the guide's seam (`cpu::VertexSampler`).

// A scattering vertex as the sampler sees it (`cpu::Vertex`).
struct Vertex {
    position: vec3<f32>,
    // Unit geometric normal, turned towards `wo`.
    normal: vec3<f32>,
    wo: vec3<f32>,
    material: Material,
    depth: u32,
}

// The next direction at `v` from three uniforms: BSDF sampling for `bsdf` and `nee` (`mcpg`
// samples with `guided_sample`).
fn vertex_sample(v: Vertex, u: vec3<f32>) -> BsdfSample {
    return material_sample(v.material, v.normal, v.wo, u);
}

// The density with which `vertex_sample` picks `wi` at `v` (the MIS weights of `nee` need it;
// `mcpg` samples no lights, so never asks).
fn vertex_pdf(v: Vertex, wi: vec3<f32>) -> f32 {
    return material_pdf(v.material, v.normal, v.wo, wi);
}

// `guided::MaterialScatter::sample`: `material_sample` with the lobe choice and the first
// direction uniform taken from u.x (the part below `metallic` picks GGX and is stretched back to
// [0, 1)); a direction the material cannot scatter into becomes −n (weight 0, ends the path).
fn material_scatter_sample(m: Material, n: vec3<f32>, wo: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    var lobe = 1.0;
    var x = (u.x - m.metallic) / (1.0 - m.metallic);
    if u.x < m.metallic {
        lobe = 0.0;
        x = u.x / m.metallic;
    }
    x = clamp(x, 0.0, 1.0 - 1.1920929e-7); // 1 − f32::EPSILON
    let s = material_sample(m, n, wo, vec3<f32>(lobe, x, u.y));
    return select(-n, s.direction, s.valid);
}

#ifdef MCG_DEMO_MCPG
// `guided_begin`'s uniforms (private: not zero-initialised at every vertex).
var<private> begin_uniforms: McpgBeginUniforms;

// MCPG (Alber et al. 2025) at a vertex, the twin of `guided::McpgSampler`: `mcpg_begin` (Alg. 1)
// into `g` (`mcpg_begin_at`, the path's one begun vertex) with four uniforms per candidate from
// the guide's own stream `grng`, then Alg. 2 with the material as the fallback technique
// (`MCPG_SCATTER_CUSTOM`: `mcpg_choose`, the chosen lobe or `material_scatter_sample`, and the
// exact mixture density of MCPG eq. 6-7 from `mcpg_pdf_with` and the material's pdf).
fn guided_begin(v: Vertex, g: ptr<function, McpgGuidedVertex>, grng: ptr<function, u32>) {
    let count = min(mcpg_params.candidates, MCPG_MAX_CANDIDATES);
    for (var k = 0u; k < count; k++) {
        let grid = mcg_rng_uniform(grng);
        let level = mcg_rng_uniform(grng);
        let corner = mcg_rng_uniform(grng);
        let reservoir = mcg_rng_uniform(grng);
        begin_uniforms.candidates[k] = vec4<f32>(grid, level, corner, reservoir);
    }
    mcpg_begin_at(McpgVertex(v.position, MCPG_SCATTER_CUSTOM, v.normal, 1u, v.normal),
                  begin_uniforms, g);
}

// Alg. 2 at the begun vertex `g` from the path's three uniforms (ξ against p_bsdf, then the
// direction's two): the direction, its exact mixture density and the lobe (`McpgSample`).
fn guided_sample(g: ptr<function, McpgGuidedVertex>, v: Vertex, u: vec3<f32>) -> McpgSample {
    let k = mcpg_choose(g, u.x);
    let w = guided_lobe_direction(g, v, k, u.yz);
    let pdf = mcpg_pdf_with(g, w, material_pdf(v.material, v.normal, v.wo, w));
    return McpgSample(w, pdf, k);
}

// `GuidedVertex::sample_mixture`: a direction from the whole mixture of `mcpg_pdf_with`, its
// lobe chosen afresh (not the state Alg. 1 chose), without its density.
fn guided_mixture_direction(g: ptr<function, McpgGuidedVertex>, v: Vertex,
                            u: vec3<f32>) -> vec3<f32> {
    return guided_lobe_direction(g, v, mcpg_choose_mixture(g, u.x), u.yz);
}

// Lobe `k`'s sample, or the material's for MCPG_NO_LOBE.
fn guided_lobe_direction(g: ptr<function, McpgGuidedVertex>, v: Vertex, k: u32,
                         u: vec2<f32>) -> vec3<f32> {
    if k == MCPG_NO_LOBE {
        return material_scatter_sample(v.material, v.normal, v.wo, u);
    }
    return mcpg_sample_lobe(g, k, u);
}

// Alg. 3 for the vertex `p` once its ray is traced, with five uniforms from `grng` (accept,
// store grid, level, corner, cache corner).
fn guided_finish(p: McpgPending, obs: McpgObservation, grng: ptr<function, u32>) {
    let accept = mcg_rng_uniform(grng);
    let grid = mcg_rng_uniform(grng);
    let level = mcg_rng_uniform(grng);
    let corner = mcg_rng_uniform(grng);
    let cache = mcg_rng_uniform(grng);
    mcpg_finish_pending(p, obs, McpgFinishUniforms(accept, grid, level, corner, cache));
}

// A vertex whose finish waits for the end of its path (`guided::Reflected::Path`): what the
// ray found, and the path's radiance and throughput at that hit, from which the end of the
// path gives L_r there (`cpu::report_recorded`): incident = (radiance_end − offset)/throughput,
// offset = the radiance before the hit less the part of the hit's emission its MIS weight
// (or share beside the emission-only directions) left out, and L_r = incident − L_e.
struct HeldVertex {
    pending: McpgPending,
    observation: McpgObservation,
    offset: vec3<f32>,
    throughput: vec3<f32>,
    // 1: L_r from the path; 0: the observation as it is (L_r from the cache at a path's last
    // hit or with `params.mcpg_reflected` 0, nothing after an escape).
    by_path: u32,
}

// `guided_finish` of a held vertex, with L_r from the path's final `radiance` (`by_path`).
fn finish_held(h: HeldVertex, radiance: vec3<f32>, grng: ptr<function, u32>) {
    let incident = select(vec3<f32>(0.0), (radiance - h.offset) / h.throughput,
                          h.throughput > vec3<f32>(0.0));
    var obs = h.observation;
    if h.by_path != 0u {
        obs.has_reflected = 1u;
        obs.reflected = max(incident - obs.emitted, vec3<f32>(0.0));
    }
    guided_finish(h.pending, obs, grng);
}

#ifdef MCG_DEMO_HOLD_ALL
// `h` into the path's held record `i` (< `gpu::HELD_VERTICES`).
fn hold(h: HeldVertex, i: u32, r0: ptr<function, HeldVertex>, r1: ptr<function, HeldVertex>,
        r2: ptr<function, HeldVertex>) {
    if i == 0u {
        *r0 = h;
    } else if i == 1u {
        *r1 = h;
    } else {
        *r2 = h;
    }
}
#endif
#endif

// A learning guide needs `finish`: what arrived along each sampled direction. MCPG's
// observation is the next hit (position, normal, emission), the sample's weight f·cos/p and
// L_r, the radiance reflected at the hit: the paper reads it from the guide's irradiance cache,
// so that a vertex is finished as soon as its ray is traced (`params.mcpg_reflected` 0,
// `guided::Reflected::Cache`). With `params.mcpg_reflected` 1 (`Reflected::Path`, mcg's
// extension and the CPU tracer's default) a vertex whose next hit scatters again waits for the
// end of the path and learns the path's own estimate of L_r there, as on the CPU. With at most
// `gpu::HELD_VERTICES` (3) bounces the pipeline is built with MCG_DEMO_HOLD_ALL
// (`gpu::HOLD_ALL_DEF`): every vertex of a path waits in a `HeldVertex` and all are finished
// after the path's loop through one call site (a SIMD group runs a finish's code once per
// call site and loop trip, taken or not). Deeper paths hold the first two such vertices,
// deeper ones read the cache and are finished as soon as their ray is traced. Vertices deeper
// than MAX_RECORDED are not finished, as on the CPU. The guide's uniforms come from a stream
// of their own, seeded like the CPU sampler's (`cpu::SAMPLER_SALT`); they are drawn per vertex
// (begin, finish) rather than all begins before all finishes, so the guide's updates are not
// bit-equal to the CPU's (they race across invocations anyway), only the same in
// distribution.

// ---------------------------------------------------------------------------------------------
// The integrator (`cpu::trace_path`)

// `cpu::path_seed`.
fn path_seed(seed: u32, frame: u32, pixel: u32, sample: u32) -> u32 {
    return mcg_pcg_hash(seed ^ mcg_pcg_hash(pixel ^ mcg_pcg_hash((frame * 0x9e3779b9u)
        ^ mcg_pcg_hash(sample))));
}

// Power heuristic a²/(a² + b²) (Veach and Guibas 1995, eq. 9, β = 2).
fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    return select(0.0, a2 / (a2 + b2), a2 + b2 > 0.0);
}

// `cpu::offset`: p moved off its surface along n.
fn offset_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let a = abs(p);
    return p + n * (RAY_OFFSET * max(max(max(a.x, a.y), a.z), 1.0));
}

// `Scene::pick_light` among the triangles: the first entry whose cumulative probability
// exceeds u.
fn pick_emitter(u: f32) -> u32 {
    var lo = 0u;
    var hi = params.emitter_count;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if emitters[mid].cdf <= u {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return emitters[min(lo, params.emitter_count - 1u)].triangle;
}

// A light sample before its MIS weight: f·cos·L_e / p_light, the direction and p_light (0 when
// the sample carries nothing).
struct LightSample {
    value: vec3<f32>,
    direction: vec3<f32>,
    pdf: f32,
}

// `mcpg::luminance`: Rec. 709 luminance of linear RGB.
fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Whether the method takes a light sample per vertex (`Method::samples_lights`).
fn samples_lights() -> bool {
    // Compiled per method (`gpu::LIGHTS_DEF`): no pipeline runs another method's code.
#ifdef MCG_DEMO_LIGHTS
    return true;
#else
    return false;
#endif
}

// How many directions `mcpg` draws at a vertex of `depth`, besides the path's, for the emission
// they meet (`VertexSampler::emission_samples`, K; the same at every vertex of a depth in a
// frame, `gpu::frame_counts`); the emission along each of the K + 1 directions then counts
// 1/(K + 1).
fn emission_samples(depth: u32) -> u32 {
    if params.method != METHOD_MCPG {
        return 0u;
    }
    let d = min(depth, MAX_RECORDED - 1u);
    return params.emission_counts[d / 4u][d % 4u];
}

// The emission-only directions whose shadow rays are walked together (`unoccluded_segments`).
const EMISSION_BATCH: u32 = 8u;

// `cpu::EMISSION_LATTICE`: the generator of the R3 lattice (1/φ₃, 1/φ₃², 1/φ₃³).
const EMISSION_LATTICE: vec3<f32> = vec3<f32>(0.8191725, 0.6710436, 0.5497005);

// `cpu::emission_uniforms`: the uniforms of a vertex's `i`-th emission-only direction, `first`
// + i·EMISSION_LATTICE mod 1 (a Cranley–Patterson rotation of the R3 lattice).
fn emission_uniforms(first: vec3<f32>, i: u32) -> vec3<f32> {
    let v = first + f32(i) * EMISSION_LATTICE;
    return min(v - floor(v), vec3<f32>(0.99999994));
}

// The pixel's first entry of emission statistics after the pixels of `image`
// (`gpu::moment_entries`), NO_MOMENTS for a pixel that records none.
var<private> moment_base: u32;
const NO_MOMENTS: u32 = 0xffffffffu;

// `Scene::environment_radiance`: the radiance seen looking along the unit direction `d` out of
// the scene (`params.environment`, times the environment map's texel where there is one).
fn environment_radiance(d: vec3<f32>) -> vec3<f32> {
#ifdef MCG_DEMO_ENVIRONMENT_MAP
    let texel = environment_texel(environment_coordinates(environment_turn(d, -1.0)));
    let h = params.environment_map.z;
    let at = (h + 1u) + h * (params.environment_map.y + 1u)
        + 3u * (texel.y * params.environment_map.y + texel.x);
    return params.environment
        * vec3<f32>(environment_word(at), environment_word(at + 1u), environment_word(at + 2u));
#else
    return params.environment;
#endif
}

#ifdef MCG_DEMO_ENVIRONMENT_MAP
// Word `i` of the environment map in `texels` (`EnvironmentMap::gpu_words`: the row table,
// the column tables, the texels' RGB), as the `f32` it holds.
fn environment_word(i: u32) -> f32 {
    return bitcast<f32>(texels[params.environment_map.x + i]);
}

// `EnvironmentMap::to_world` (`sign` 1) and `EnvironmentMap::to_map` (`sign` −1): `d` turned by
// ± the map's rotation about +Y.
fn environment_turn(d: vec3<f32>, sign: f32) -> vec3<f32> {
    let a = bitcast<f32>(params.environment_map.w);
    if a == 0.0 {
        return d;
    }
    let s = sign * sin(a);
    let c = cos(a);
    return vec3<f32>(c * d.x + s * d.z, d.y, c * d.z - s * d.x);
}

// `EnvironmentMap::coordinates`: the image coordinates (u, v) of the unit direction `d`; θ
// as atan2(sin θ, cos θ), well conditioned at the poles where acos(d.y) is not.
fn environment_coordinates(d: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(atan2(d.x, -d.z) * (0.5 / MCG_PI) + 0.5,
                     atan2(length(d.xz), d.y) * (1.0 / MCG_PI));
}

// `EnvironmentMap::texel_of`: the texel (column, row) that holds the image coordinates `uv`.
fn environment_texel(uv: vec2<f32>) -> vec2<u32> {
    let size = params.environment_map.yz;
    let x = min(u32(max(uv.x * f32(size.x), 0.0)), size.x - 1u);
    let y = min(u32(max(uv.y * f32(size.y), 0.0)), size.y - 1u);
    return vec2<u32>(x, y);
}

// `EnvironmentMap::texel_probability`: the row's step in the row table times the column's in
// its row's table.
fn environment_texel_probability(texel: vec2<u32>) -> f32 {
    let h = params.environment_map.z;
    let row = (h + 1u) + texel.y * (params.environment_map.y + 1u);
    return (environment_word(texel.y + 1u) - environment_word(texel.y))
        * (environment_word(row + texel.x + 1u) - environment_word(row + texel.x));
}

// `EnvironmentMap::pdf`: the solid-angle density with which `environment_sample` draws `d`.
fn environment_map_pdf(d: vec3<f32>) -> f32 {
    let turned = environment_turn(d, -1.0);
    let uv = environment_coordinates(turned);
    // sin θ of the unit direction itself: WGSL's `sin` is only accurate to 2⁻¹¹ absolute, so
    // sin(π v) would be off by tens of per cent in the rows at the poles.
    let s = length(turned.xz);
    if !(s > 0.0) {
        return 0.0;
    }
    let size = params.environment_map.yz;
    return environment_texel_probability(environment_texel(uv)) * f32(size.x * size.y)
        / (2.0 * MCG_PI * MCG_PI * s);
}

// `environment::sample_table`: the step of the cumulative table of `n` + 1 entries from word
// `first` that holds `u` (the last entry at or below it) in x, where `u` falls within it in y.
fn environment_table(first: u32, n: u32, u: f32) -> vec2<f32> {
    var lo = 0u;
    var hi = n;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if environment_word(first + mid) <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let c = environment_word(first + lo);
    let step = environment_word(first + lo + 1u) - c;
    var within = 0.5;
    if step > 0.0 {
        within = clamp((u - c) / step, 0.0, 0.99999994);
    }
    return vec2<f32>(f32(lo), within);
}

// `EnvironmentMap::sample`: a direction in proportion to the map's luminance from uniforms
// `u`, and its solid-angle density (0 for none).
fn environment_sample(u: vec2<f32>) -> McgDirectionSample {
    let size = params.environment_map.yz;
    let r = environment_table(0u, size.y, u.y);
    let row = u32(r.x);
    let c = environment_table((size.y + 1u) + row * (size.x + 1u), size.x, u.x);
    let uv = vec2<f32>((c.x + c.y) / f32(size.x), (r.x + r.y) / f32(size.y));
    let phi = 2.0 * MCG_PI * (uv.x - 0.5);
    let theta = MCG_PI * uv.y;
    let st = sin(theta);
    let d = environment_turn(vec3<f32>(st * sin(phi), cos(theta), -st * cos(phi)), 1.0);
    let pdf = environment_texel_probability(vec2<u32>(u32(c.x), row)) * f32(size.x * size.y)
        / (2.0 * MCG_PI * MCG_PI * st);
    return McgDirectionSample(d, select(0.0, pdf, pdf > 0.0 && pdf <= FAR));
}
#endif

#ifdef MCG_DEMO_PORTALS
// `environment::Portal` `i` in `texels` (`GpuParams::portals`, 12 words each).
fn portal_at(i: u32) -> array<vec4<f32>, 3> {
    let at = params.portals.x + 12u * i;
    var rows: array<vec4<f32>, 3>;
    for (var r = 0u; r < 3u; r++) {
        let w = at + 4u * r;
        rows[r] = bitcast<vec4<f32>>(vec4<u32>(texels[w], texels[w + 1u], texels[w + 2u],
                                               texels[w + 3u]));
    }
    return rows;
}

// `Portal::pdf`: the density with which `Portal::sample` from `origin` draws `d` (rows: corner
// and area, edge u and pmf, edge v).
fn portal_pdf(q: array<vec4<f32>, 3>, origin: vec3<f32>, d: vec3<f32>) -> f32 {
    let n = cross(q[1].xyz, q[2].xyz) / q[0].w;
    let c = dot(n, d);
    let t = dot(n, q[0].xyz - origin) / c;
    if !(t > 0.0 && t <= FAR) {
        return 0.0;
    }
    let x = origin + t * d - q[0].xyz;
    let s = dot(cross(x, q[2].xyz), n) / q[0].w;
    let r = dot(cross(q[1].xyz, x), n) / q[0].w;
    if !(s >= 0.0 && s <= 1.0 && r >= 0.0 && r <= 1.0) {
        return 0.0;
    }
    return t * t / (q[0].w * abs(c));
}

// `Scene::environment_pdf` with portals: Σ pmf × `portal_pdf`.
fn portals_pdf(origin: vec3<f32>, d: vec3<f32>) -> f32 {
    var pdf = 0.0;
    for (var i = 0u; i < params.portals.y; i++) {
        let q = portal_at(i);
        pdf += q[1].w * portal_pdf(q, origin, d);
    }
    return pdf;
}

// `Scene::sample_environment` with portals: `u.x` picks a portal by its pmf, `u.yz` a uniform
// point of it; the direction toward it and `portals_pdf` (0 for none).
fn portals_sample(origin: vec3<f32>, u: vec3<f32>) -> McgDirectionSample {
    var v = u.x;
    var k = 0u;
    var q = portal_at(0u);
    let last = params.portals.y - 1u;
    while k < last && v >= q[1].w {
        v -= q[1].w;
        k += 1u;
        q = portal_at(k);
    }
    let to = q[0].xyz + u.y * q[1].xyz + u.z * q[2].xyz - origin;
    let wi = to / sqrt(dot(to, to));
    let pdf = portals_pdf(origin, wi);
    return McgDirectionSample(wi, select(0.0, pdf, pdf > 0.0 && pdf <= FAR));
}
#endif

// `cpu::direct_light`: a light sample before its MIS weight, which the caller applies against
// the density of its own direction sampler (the material's, or the guide's mixture for
// `mcpg-nee`). `Scene::pick_light`: the environment below `environment_pmf` (a direction
// cosine-distributed about the vertex's normal, or from the environment map,
// `cpu::environment_light`), else a triangle.
// Both kinds share one shadow walk, so that the kernel holds one walk's code here, and the
// environment's part is compiled only for scenes that have one (MCG_DEMO_ENVIRONMENT,
// `gpu::ENVIRONMENT_DEF`): llvmpipe pays for code present, taken or not (a walk of its own for
// the environment cost lavapipe's `nee` frame 9 %, the shared walk 2-3 %).
fn light_sample(v: Vertex, origin: vec3<f32>, u: vec3<f32>) -> LightSample {
    let none = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    let p = params.environment_pmf;
    var environment = false;
    var wi: vec3<f32>;
    var t_max = FAR;
    var light_pdf: f32;
    var hit = RayHit(0.0, NO_HIT, 0.0, 0.0);
#ifdef MCG_DEMO_ENVIRONMENT
    environment = u.x < p || params.emitter_count == 0u;
    if environment {
#ifdef MCG_DEMO_ENVIRONMENT_MAP
        let s = environment_sample(u.yz);
#else
#ifdef MCG_DEMO_PORTALS
        // The pick's uniform, rescaled past it, picks the portal (`cpu::direct_light`).
        let u0 = select(u.x, min(u.x / p, 0.99999994), p < 1.0);
        let s = portals_sample(origin, vec3<f32>(u0, u.yz));
#else
        let s = mcg_cosine_hemisphere_sample(v.normal, u.yz);
#endif
#endif
        wi = s.direction;
        light_pdf = p * s.pdf;
        if !(light_pdf > 0.0) || dot(v.normal, wi) <= 0.0 {
            return none;
        }
    }
#endif
    if !environment {
        let t = pick_emitter(select(u.x, (u.x - p) / (1.0 - p), p > 0.0));
        let tri = triangles[t];
        let su = sqrt(u.y);
        let b = vec2<f32>(su * (1.0 - u.z), su * u.z);
        let y = tri.v0 + b.x * tri.e1 + b.y * tri.e2;
        let to_light = y - origin;
        let dist2 = dot(to_light, to_light);
        let dist = sqrt(dist2);
        wi = to_light / dist;
        let c = cross(tri.e1, tri.e2);
        let area = 0.5 * length(c);
        let cos_light = -dot(c / (2.0 * area), wi);
        if !(cos_light > 0.0) || dot(v.normal, wi) <= 0.0 {
            return none;
        }
        hit = RayHit(dist, t, b.x, b.y);
#ifdef MCG_DEMO_ALPHA_MASK
        if !is_surface_at(tri.material, hit) {
            return none;
        }
#endif
        t_max = dist * (1.0 - 1e-4);
        light_pdf = tri.emitter_pmf / area * dist2 / cos_light;
    }
    let f_cos = material_eval(v.material, v.normal, v.wo, wi);
    if all(f_cos == vec3<f32>(0.0)) {
        return none;
    }
    if bvh_walk(origin, wi, 0.0, t_max, true).triangle != NO_HIT {
        return none;
    }
    if environment {
        return LightSample(f_cos * environment_radiance(wi) / light_pdf, wi, light_pdf);
    }
    let emitted = triangle_emission(triangles[hit.triangle].material, hit);
    return LightSample(f_cos * emitted / light_pdf, wi, light_pdf);
}

// `cpu::environment_weight`: the weight of the environment seen along `d` by a ray sampled
// with density `last_pdf` at a vertex of normal `normal` (MIS against its light sample for
// the methods that sample lights, else 1).
fn environment_weight(last_pdf: f32, origin: vec3<f32>, normal: vec3<f32>, d: vec3<f32>) -> f32 {
    if samples_lights() && last_pdf > 0.0 {
#ifdef MCG_DEMO_ENVIRONMENT_MAP
        let light_pdf = params.environment_pmf * environment_map_pdf(d);
#else
#ifdef MCG_DEMO_PORTALS
        let light_pdf = params.environment_pmf * portals_pdf(origin, d);
#else
        let light_pdf = params.environment_pmf * mcg_cosine_hemisphere_pdf(normal, d);
#endif
#endif
        return power_heuristic(last_pdf, light_pdf);
    }
    return 1.0;
}

// One path from the camera ray (origin, direction); its radiance.
fn trace_path(origin: vec3<f32>, direction: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    var throughput = vec3<f32>(1.0);
    var o = origin;
    var d = direction;
    // Density of the direction that produced the ray (0 for the camera ray: no MIS weight).
    var last_pdf = 0.0;
    // 1/(K + 1) of the vertex that sampled the ray, K its emission-only directions.
    var last_share = 1.0;
    // The normal of the vertex that sampled the ray (`environment_weight`).
    var last_normal = vec3<f32>(0.0);
    // The environment seen where the last ray left the scene, and its MIS weight.
    var escaped = vec3<f32>(0.0);
    var escaped_weight = 1.0;
    var depth = 0u;
#ifdef MCG_DEMO_MCPG
    var grng = mcg_pcg_hash(*rng ^ SAMPLER_SALT);
    // The vertex begun last, and what its finish needs once its ray is traced (only this
    // lives across the walk, not the vertex's lobes).
    var open: McpgGuidedVertex;
    var open_sample: McpgSample;
    var open_pending: McpgPending;
    var open_weight = vec3<f32>(0.0);
    var is_open = false;
    // Vertices waiting for the end of the path (`HeldVertex`), the older first.
    var held0: HeldVertex;
    var held1: HeldVertex;
#ifdef MCG_DEMO_HOLD_ALL
    var held2: HeldVertex;
#endif
    var held = 0u;
#endif
    loop {
        let hit = bvh_walk(o, d, 0.0, FAR, false);
        if hit.triangle == NO_HIT {
#ifdef MCG_DEMO_ENVIRONMENT
            escaped = environment_radiance(d);
            escaped_weight = environment_weight(last_pdf, o, last_normal, d);
            radiance += throughput * escaped * escaped_weight;
#endif
            break;
        }
        let tri = triangles[hit.triangle];
        let material = material_at(hit);
        let c = cross(tri.e1, tri.e2);
        let area = 0.5 * length(c);
        let n_front = c / (2.0 * area);
        let cos_front = -dot(n_front, d);
        let position = o + hit.t * d;
        // The emission's MIS weight against a light sample of the same point (1 without; the
        // guide learns with it), and its weight in the estimate (1/(K + 1) beside the K
        // emission-only directions of `mcpg`'s vertex that sampled the ray).
        var emission_weight = 1.0;
        var share = 1.0;
        // The radiance before the hit, less the part of its emission left out below.
        var offset = radiance;
        if cos_front > 0.0 && any(material.emission > vec3<f32>(0.0)) {
            if samples_lights() && last_pdf > 0.0 {
                let light_pdf = tri.emitter_pmf / area * hit.t * hit.t / cos_front;
                emission_weight = power_heuristic(last_pdf, light_pdf);
                share = emission_weight;
            } else if last_pdf > 0.0 {
                share = last_share;
            }
            radiance += throughput * material.emission * share;
            offset -= throughput * material.emission * (1.0 - share);
        }
#ifdef MCG_DEMO_MCPG
        if is_open {
            let emitted = select(vec3<f32>(0.0), material.emission, cos_front > 0.0);
            let n_hit = select(-n_front, n_front, cos_front > 0.0);
            var obs = mcpg_observation_hit(position, n_hit, emitted, open_weight);
            obs.emission_weight = emission_weight;
            // The path scatters again here (`cpu::report_recorded`'s rule).
            let by_path = params.mcpg_reflected != 0u && depth < params.bounces;
#ifdef MCG_DEMO_HOLD_ALL
            // Every vertex waits for the end of the path (`gpu::HOLD_ALL_DEF`), so that the
            // finish code exists once, after the loop.
            hold(HeldVertex(open_pending, obs, offset, throughput, u32(by_path)), held, &held0,
                 &held1, &held2);
            held += 1u;
#else
            let holds = by_path && held < 2u;
            if holds && held == 0u {
                held0 = HeldVertex(open_pending, obs, offset, throughput, 1u);
            } else if holds {
                held1 = HeldVertex(open_pending, obs, offset, throughput, 1u);
            } else {
                guided_finish(open_pending, obs, &grng);
            }
            held += u32(holds);
#endif
            is_open = false;
        }
#endif
        if depth == params.bounces {
            break;
        }
        let normal = select(-n_front, n_front, cos_front > 0.0);
        let vertex = Vertex(position, normal, -d, material, depth);
        let origin_next = offset_origin(position, normal);
        // Three light-sampling uniforms for every method, as on the CPU.
        let ul = mcg_rng_uniform(rng);
        let u1 = mcg_rng_uniform(rng);
        let u2 = mcg_rng_uniform(rng);
        let ux = mcg_rng_uniform(rng);
        let uy = mcg_rng_uniform(rng);
        let uz = mcg_rng_uniform(rng);
#ifdef MCG_DEMO_MCPG
        // The direction before the light sample, whose MIS weight needs the guide's density.
        guided_begin(vertex, &open, &grng);
        open_sample = guided_sample(&open, vertex, vec3<f32>(ux, uy, uz));
        if samples_lights() {
            let l = light_sample(vertex, origin_next, vec3<f32>(ul, u1, u2));
            if l.pdf > 0.0 {
                let p = mcpg_pdf_with(&open, l.direction,
                                      material_pdf(material, normal, -d, l.direction));
                radiance += throughput * l.value * power_heuristic(l.pdf, p);
            }
        } else {
            // `McpgSampler::sample_emission`: directions from the begun vertex, their uniforms
            // the light-sampling ones `mcpg` does not use moved along a lattice
            // (`emission_uniforms`); density and material only where emission is met
            // (`cpu::emission_weighted`).
            // Compiled only where the frame's mean K is above 0 (`gpu::EMISSION_DIRECTIONS_DEF`):
            // the paper's one direction carries none of the loop's code (a SIMD CPU driver runs
            // all of a kernel's code, and a GPU's registers are allotted for all of it).
#ifdef MCG_DEMO_EMISSION_DIRECTIONS
            let count = emission_samples(depth);
#else
            let count = 0u;
#endif
            let share = 1.0 / f32(1u + count);
            last_share = share;
            // `EmissionMoments::add_direction`'s sums of the directions' luminance.
            var first = 0.0;
            var second = 0.0;
#ifdef MCG_DEMO_EMISSION_DIRECTIONS
            // In batches: the directions and their emitters first, then their shadow rays in
            // one walk, then the density and material of the unoccluded ones only (a SIMD
            // group runs every block of its invocations, llvmpipe even those none takes).
            var i = 0u;
            while i < count {
                let end = min(i + EMISSION_BATCH, count);
                var n = 0u;
                for (; i < end; i++) {
                    let ue = emission_uniforms(vec3<f32>(ul, u1, u2), i);
                    let wi = guided_mixture_direction(&open, vertex, ue);
                    let e = emitter_hit(origin_next, wi);
                    if e.triangle != NO_HIT {
                        segments.ray[n] = vec4<f32>(wi, e.t);
                        segments.triangle[n] = e.triangle;
                        segments.bary[n] = vec2<f32>(e.b1, e.b2);
                        n += 1u;
                    }
                }
                let visible = unoccluded_segments(origin_next, n);
                for (var j = 0u; j < n; j++) {
                    let wi = segments.ray[j].xyz;
                    let emitted = emitter_emission(segments.triangle[j], segments.bary[j]);
                    if (visible & (1u << j)) != 0u && any(emitted > vec3<f32>(0.0)) {
                        let p = mcpg_pdf_with(&open, wi, material_pdf(material, normal, -d, wi));
                        if p > 0.0 {
                            let value = throughput * material_eval(material, normal, -d, wi) / p
                                * emitted;
                            radiance += share * value;
                            let l = luminance(value);
                            if mcg_is_finite(l) {
                                first += l;
                                second += l * l;
                            }
                        }
                    }
                }
            }
#endif
            if moment_base != NO_MOMENTS {
                let m = moment_base + min(depth, MAX_RECORDED - 1u);
                image[m] += vec4<f32>(1.0, f32(count), first, second);
            }
        }
        if !(open_sample.pdf > 0.0) {
            break;
        }
        let wi = open_sample.direction;
        let s = BsdfSample(wi, open_sample.pdf,
                           material_eval(material, normal, -d, wi) / open_sample.pdf, true);
        is_open = depth < MAX_RECORDED;
        open_pending = mcpg_pending(&open, open_sample);
        open_weight = s.weight;
#else
        if samples_lights() {
            let l = light_sample(vertex, origin_next, vec3<f32>(ul, u1, u2));
            if l.pdf > 0.0 {
                radiance += throughput * l.value * power_heuristic(l.pdf, vertex_pdf(vertex, l.direction));
            }
        }
        let s = vertex_sample(vertex, vec3<f32>(ux, uy, uz));
        if !s.valid {
            break;
        }
#endif
        throughput *= s.weight;
        last_pdf = s.pdf;
        last_normal = normal;
        o = origin_next;
        d = s.direction;
        depth += 1u;
        if all(throughput == vec3<f32>(0.0)) {
            break;
        }
    }
#ifdef MCG_DEMO_MCPG
    // The last ray left the scene, or its weight ended the path (the CPU reports both as
    // escaped, seeing the environment).
    var escape = mcpg_observation_escaped(escaped, open_weight);
    escape.emission_weight = escaped_weight;
#ifdef MCG_DEMO_HOLD_ALL
    if is_open {
        hold(HeldVertex(open_pending, escape, vec3<f32>(0.0), vec3<f32>(0.0), 0u), held, &held0,
             &held1, &held2);
        held += 1u;
    }
    for (var i = 0u; i < held; i++) {
        var h = held0;
        if i == 1u {
            h = held1;
        } else if i == 2u {
            h = held2;
        }
        finish_held(h, radiance, &grng);
    }
#else
    if is_open {
        guided_finish(open_pending, escape, &grng);
    }
    if held > 0u {
        finish_held(held0, radiance, &grng);
    }
    if held > 1u {
        finish_held(held1, radiance, &grng);
    }
#endif
#endif
    return radiance;
}

// `Camera::direction` through the image point (x, y) in pixels.
fn camera_direction(x: f32, y: f32) -> vec3<f32> {
    let sx = (2.0 * x / f32(params.width) - 1.0) * params.tan_x;
    let sy = (1.0 - 2.0 * y / f32(params.height)) * params.tan_y;
    return normalize(params.camera_forward + sx * params.camera_right + sy * params.camera_up);
}

// One invocation per pixel of the tile: `spp` paths, the mean into `image` (row-major).
@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.tile_width || id.y >= params.tile_height {
        return;
    }
    let x = params.tile_x + id.x;
    let y = params.tile_y + id.y;
    if x >= params.width || y >= params.height {
        return;
    }
    let index = y * params.width + x;
    moment_base = NO_MOMENTS;
    if params.moment_stride > 0u && index % params.moment_stride == 0u {
        moment_base = params.width * params.height + (index / params.moment_stride) * MAX_RECORDED;
        for (var m = 0u; m <= min(params.bounces, MAX_RECORDED - 1u); m++) {
            image[moment_base + m] = vec4<f32>(0.0);
        }
    }
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < params.spp; s++) {
        var rng = path_seed(params.seed, params.frame, index, s);
        let jx = mcg_rng_uniform(&rng);
        let jy = mcg_rng_uniform(&rng);
        let d = camera_direction(f32(x) + jx, f32(y) + jy);
#ifdef MCG_DEMO_PROBE_GI
        sum += probe_camera_ray(d, &rng);
#else
        sum += trace_path(params.camera_position, d, &rng);
#endif
    }
    image[index] = vec4<f32>(sum / f32(params.spp), 1.0);
}

// One invocation per ray of `rays`: the BVH query of `bvh_walk_tree` (or, for a ray with a
// list, `emitter_list_hit`), for the CPU/GPU agreement test.
@compute @workgroup_size(64)
fn trace_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&rays) {
        return;
    }
    let r = rays[id.x];
    if r.list.y > 0u {
        ray_hits[id.x] = emitter_list_hit(r.list.x, r.list.y, r.origin, r.direction);
        return;
    }
    ray_hits[id.x] = bvh_walk_tree(r.root, r.front_only != 0u, r.origin, r.direction, 0.0,
                                   r.t_max, r.any_hit != 0u);
}

// `GpuTracer::unoccluded_segments`: invocation i walks, with `unoccluded_segments`, the leading
// rays of rays[8i … 8i + 7] whose `any_hit` is 1, as segments from the first one's origin;
// `ray_hits[8i + j].triangle` is 0 when segment j is occluded, NO_HIT when it is not.
@compute @workgroup_size(64)
fn trace_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    let first = id.x * EMISSION_BATCH;
    let count = arrayLength(&rays);
    if first >= count {
        return;
    }
    var n = 0u;
    for (var j = 0u; j < EMISSION_BATCH && first + j < count; j++) {
        let r = rays[first + j];
        if r.any_hit != 1u {
            break;
        }
        segments.ray[j] = vec4<f32>(r.direction, r.t_max);
        n += 1u;
    }
    let visible = unoccluded_segments(rays[first].origin, n);
    for (var j = 0u; j < n; j++) {
        let hit = select(0u, NO_HIT, ((visible >> j) & 1u) != 0u);
        ray_hits[first + j] = RayHit(segments.ray[j].w, hit, 0.0, 0.0);
    }
}

#ifdef MCG_DEMO_PROBE_GI
// ---------------------------------------------------------------------------------------------
// Probe GI (`adgi`, `ddgi`): the twin of `probe_gi::ShadingProbes`, composed with the shader def
// MCG_DEMO_PROBE_GI and `GpuProbeCache::shader_defs(1)` (the probe cache `mcg::adgi` at group 1).
// `render` then shades each camera ray's first hit with its emission, one light sample and
// albedo/π · the probes' irradiance (`probe_camera_ray`); `trace_probe_rays` traces probe rays
// whose hits bring back albedo/π · (one light sample + the probes' irradiance), never the hit's
// emission (the camera samples the lights itself), 0 at a fifth of the distance for a back face
// and 0 at "infinity" for a miss — every frame adds one bounce (DDGI's multi-bounce).

// `gpu::GpuProbeRequest`: one probe ray, with the 32-bit seed of the light sample at its hit.
struct ProbeRequest {
    origin: vec3<f32>,
    seed: u32,
    direction: vec3<f32>,
    probe: u32,
}

// `gpu::GpuProbeFrame`: the dispatch of `trace_probe_rays`.
struct ProbeFrame {
    count: u32,
    // Invocations per row of the 2D dispatch.
    row: u32,
    // Slots [count, limit) are emptied (probe NO_PROBE).
    limit: u32,
    pad: u32,
}

@group(0) @binding(11) var<storage, read> probe_requests: array<ProbeRequest>;
@group(0) @binding(12) var<storage, read_write> probe_samples: array<AdgiRaySample>;
@group(0) @binding(13) var<uniform> probe_frame: ProbeFrame;

// `probe_gi::BACK_FACE_DISTANCE_SCALE`.
const BACK_FACE_DISTANCE_SCALE: f32 = 0.2;

// `ShadingProbes::reflected`: one light sample (uniforms u, no MIS weight: nothing else samples
// the lights) plus the diffuse albedo (1 − metallic)·base colour over π times the probes'
// irradiance at the vertex (DDGI's query, `mcg::adgi`).
fn probe_reflected(v: Vertex, u: vec3<f32>) -> vec3<f32> {
    let l = light_sample(v, offset_origin(v.position, v.normal), u);
    let direct = select(vec3<f32>(0.0), l.value, l.pdf > 0.0);
    let albedo = (1.0 - v.material.metallic) * v.material.base_color;
    if all(albedo == vec3<f32>(0.0)) {
        return direct;
    }
    return direct + albedo * MCG_FRAC_1_PI * adgi_irradiance_at(v.position, v.normal, v.wo);
}

// `ShadingProbes::probe_ray`: what a probe ray from `origin` along the unit `direction` brings
// back; `seed` seeds the three uniforms of the light sample at its hit.
fn probe_ray(origin: vec3<f32>, direction: vec3<f32>, seed: u32, probe: u32) -> AdgiRaySample {
    var out = AdgiRaySample(direction, FAR, vec3<f32>(0.0), probe);
    let hit = bvh_walk(origin, direction, 0.0, FAR, false);
    if hit.triangle == NO_HIT {
        return out;
    }
    let tri = triangles[hit.triangle];
    let c = cross(tri.e1, tri.e2);
    let n_front = c / (2.0 * (0.5 * length(c)));
    if !(-dot(n_front, direction) > 0.0) {
        out.distance = BACK_FACE_DISTANCE_SCALE * hit.t;
        return out;
    }
    var rng = seed;
    let u = vec3<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
    let v = Vertex(origin + hit.t * direction, n_front, -direction, material_at(hit), 1u);
    out.distance = hit.t;
    out.radiance = probe_reflected(v, u);
    return out;
}

// `ShadingProbes::camera_ray`: the first hit's emission (front faces) plus `probe_reflected`;
// draws three uniforms from `rng` before tracing.
fn probe_camera_ray(d: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let u = vec3<f32>(mcg_rng_uniform(rng), mcg_rng_uniform(rng), mcg_rng_uniform(rng));
    let o = params.camera_position;
    let hit = bvh_walk(o, d, 0.0, FAR, false);
    if hit.triangle == NO_HIT {
        return environment_radiance(d);
    }
    let tri = triangles[hit.triangle];
    let c = cross(tri.e1, tri.e2);
    let n_front = c / (2.0 * (0.5 * length(c)));
    let front = -dot(n_front, d) > 0.0;
    let material = material_at(hit);
    let v = Vertex(o + hit.t * d, select(-n_front, n_front, front), -d, material, 0u);
    return select(vec3<f32>(0.0), material.emission, front) + probe_reflected(v, u);
}

// One invocation per probe ray of `probe_frame`: its `AdgiRaySample` into `probe_samples`.
@compute @workgroup_size(64)
fn trace_probe_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * probe_frame.row;
    if i >= probe_frame.count {
        if i < probe_frame.limit {
            probe_samples[i] = AdgiRaySample(vec3<f32>(0.0), FAR, vec3<f32>(0.0), NO_PROBE);
        }
        return;
    }
    let r = probe_requests[i];
    probe_samples[i] = probe_ray(r.origin, r.direction, r.seed, r.probe);
}

// `gpu::GpuChainTrace`: the dispatch of `trace_chain_samples`.
struct ChainTrace {
    // Slots traced (the phase's ray budget, at most the chains' sample capacity).
    limit: u32,
    // Invocations per row of the 2D dispatch.
    row: u32,
    // The render's seed and the frame, keying `probe_ray_seed`.
    seed: u32,
    frame: u32,
}

// The samples ADGI's Metropolis probe chains emitted (`GpuProbeChains::samples`).
@group(0) @binding(14) var<storage, read> chain_samples: array<AdgiProbeSample>;
// `GpuProbeChains::counters`: [0] the samples the chains wrote this frame.
@group(0) @binding(15) var<storage, read> chain_counters: array<u32>;
@group(0) @binding(16) var<storage, read_write> chain_rounding: array<f32>;
@group(0) @binding(17) var<uniform> chain_trace: ChainTrace;
// [1]: the slots of the budget already spent this frame (the dynamic rays, `dynamic_spent`).
@group(0) @binding(22) var<storage, read> chain_spent: array<u32>;

// `gpu::NO_PROBE`: the probe of an empty slot, outside every grid (the cache's per-sample update
// skips it).
const NO_PROBE: u32 = 0xffffffffu;

// `probe_gi::probe_ray_seed`: the seed of the light sample of ray `ray` of probe `probe` in frame
// `frame` (a stream apart from the camera's paths).
fn probe_ray_seed(seed: u32, frame: u32, probe: u32, ray: u32) -> u32 {
    let salt = 0x70726f62u;
    return path_seed(seed ^ salt, frame, probe, ray) ^ mcg_pcg_hash(salt);
}

// One invocation per slot below `chain_trace.limit` − `chain_spent[1]` of the chains' samples (ADGI sec. 4.8: the
// static chains' samples are the probe rays, taken in slot order up to the budget): slot i below
// the chains' count traces its sample from its probe along its direction (light seed
// `probe_ray_seed(seed, frame, probe, i)`), an empty slot gets probe NO_PROBE; every slot gets
// its rounding uniform (`probe_ray_seed(seed, frame, NO_PROBE, i)` as a uniform float) for
// `GpuProbeCache::record_update_samples`.
@compute @workgroup_size(64)
fn trace_chain_samples(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * chain_trace.row;
    if i >= chain_trace.limit {
        return;
    }
    let t = chain_trace;
    chain_rounding[i] = mcg_uniform_float(probe_ray_seed(t.seed, t.frame, NO_PROBE, i));
    let left = t.limit - min(t.limit, chain_spent[1]);
    if i >= min(chain_counters[0], left) {
        probe_samples[i] = AdgiRaySample(vec3<f32>(0.0), FAR, vec3<f32>(0.0), NO_PROBE);
        return;
    }
    let s = chain_samples[i];
    let seed = probe_ray_seed(t.seed, t.frame, s.probe, i);
    probe_samples[i] = probe_ray(adgi_probe_position(s.probe), s.direction, seed, s.probe);
}

// `gpu::GpuDynamicFrame`: the dispatch of `expand_dynamic_samples`.
struct DynamicFrame {
    // The dynamic phase's ray budget.
    budget: u32,
    // `UpdateConfig::dynamic_rays_per_octant`.
    rays_per_octant: u32,
    seed: u32,
    frame: u32,
}

@group(0) @binding(18) var<storage, read_write> dynamic_requests: array<ProbeRequest>;
// [0] the slots claimed, [1] the rays written (a prefix of the slots).
@group(0) @binding(19) var<storage, read_write> dynamic_spent: array<atomic<u32>>;
// `gpu::dynamic_tables`: [0] where the proxy offsets start; [1..10] the offsets of each octant's
// interior texels (x | y << 16 interior coordinates); at [0] the offsets of each proxy's probes
// (one more than the proxies), then the probes.
@group(0) @binding(20) var<storage, read> dynamic_tables: array<u32>;
@group(0) @binding(21) var<uniform> dynamic_frame: DynamicFrame;

// `octahedral::octahedral_decode`: the unit direction at square coordinates p (clamped).
fn probe_octahedral_decode(p_in: vec2<f32>) -> vec3<f32> {
    let p = clamp(p_in, vec2<f32>(-1.0), vec2<f32>(1.0));
    let z = 1.0 - abs(p.x) - abs(p.y);
    var v = vec3<f32>(p, z);
    if z < 0.0 {
        v = vec3<f32>((vec2<f32>(1.0) - abs(p.yx)) * adgi_sign_not_zero(p), z);
    }
    return normalize(v);
}

// ADGI sec. 4.9, the twin of `ProbeUpdater::dynamic_phase`'s rays: one invocation per dynamic
// chain sample (a proxy and an octant) lays `dynamic_rays_per_octant` rays (rounded up to a whole
// number per texel) over the octant's interior irradiance texels, uniform within each texel's
// square, for every probe of the proxy, into `dynamic_requests` with their rounding uniforms; a
// probe whose rays would pass the budget is left out (the CPU stops at the first such probe, in
// sample order; here in the order the slots are claimed).
@compute @workgroup_size(64)
fn expand_dynamic_samples(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // A 2D dispatch (`GpuContext::workgroup_grid` with `gpu::probes`' PROBE_GROUP): rows of
    // groups.x workgroups of 64.
    let i = id.x + id.y * groups.x * 64u;
    if i >= min(chain_counters[0], arrayLength(&chain_samples)) {
        return;
    }
    let s = chain_samples[i];
    let f = dynamic_frame;
    let t0 = dynamic_tables[1u + s.octant];
    let texels = dynamic_tables[2u + s.octant] - t0;
    let per_texel = (f.rays_per_octant + texels - 1u) / texels;
    let cost = per_texel * texels;
    let proxies = dynamic_tables[0];
    let q0 = dynamic_tables[proxies + s.cell];
    let q1 = dynamic_tables[proxies + s.cell + 1u];
    let start = atomicAdd(&dynamic_spent[0], cost * (q1 - q0));
    let scale = 2.0 / f32(adgi_params.irradiance_interior);
    var written = 0u;
    for (var q = q0; q < q1; q++) {
        let base = start + (q - q0) * cost;
        if base + cost > f.budget {
            break;
        }
        let probe = dynamic_tables[q];
        let origin = adgi_probe_position(probe);
        for (var j = 0u; j < cost; j++) {
            let slot = base + j;
            let packed = dynamic_tables[t0 + j / per_texel];
            let t = vec2<f32>(f32(packed & 0xffffu), f32(packed >> 16u));
            var rng = probe_ray_seed(f.seed, f.frame, NO_PROBE - 1u, slot);
            let jitter = vec2<f32>(mcg_rng_uniform(&rng), mcg_rng_uniform(&rng));
            let direction = probe_octahedral_decode((t + jitter) * scale - vec2<f32>(1.0));
            let seed = probe_ray_seed(f.seed, f.frame, probe, slot);
            dynamic_requests[slot] = ProbeRequest(origin, seed, direction, probe);
            chain_rounding[slot] = mcg_rng_uniform(&rng);
        }
        written += cost;
    }
    atomicAdd(&dynamic_spent[1], written);
}

// `gpu::GpuPilotLayout`: the dispatch of `lay_out_pilot_rays`, two u64 as (low, high) words.
struct PilotLayout {
    // `UpdateConfig::pilot_seed`.
    seed: vec2<u32>,
    // `PilotFrame::pattern` of the frame (sec. 4.4's `AABBCC…`: both frames of a pair share it).
    pattern: vec2<u32>,
}

@group(0) @binding(23) var<uniform> pilot_layout: PilotLayout;

// ADGI sec. 4.4, the twin of `ProbeUpdater::pilot_phase`'s requests (`pilot_rays` over every
// probe): invocation i = 8 probe + octant writes request i of `dynamic_requests` — from the
// probe's position along `pilot_direction(octant, pilot_uniforms(seed, pattern, probe, octant,
// 0))`, with the light-sample seed `probe_gi::request_seed` of the uniforms of k = 2:
// pcg(bits(u.x) ^ pcg(bits(u.y))). The same rays on both frames of a pair, as on the CPU.
@compute @workgroup_size(64)
fn lay_out_pilot_rays(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= adgi_params.probe_count * 8u {
        return;
    }
    let probe = i / 8u;
    let octant = i % 8u;
    let l = pilot_layout;
    let direction = adgi_pilot_direction(octant, adgi_pilot_uniforms(l.seed, l.pattern, probe, octant, 0u));
    let light = adgi_pilot_uniforms(l.seed, l.pattern, probe, octant, 2u);
    let seed = mcg_pcg_hash(bitcast<u32>(light.x) ^ mcg_pcg_hash(bitcast<u32>(light.y)));
    dynamic_requests[i] = ProbeRequest(adgi_probe_position(probe), seed, direction, probe);
}
#endif

#ifdef MCG_DEMO_MCMM
// ---------------------------------------------------------------------------------------------
// MCMM (Dittebrandt et al. 2023) for direct light, the twin of `mcmm::McmmRenderer`: one
// workgroup of 8 × 8 invocations is one tile of 64 chains (MCMM sec. 4.2 uses a subgroup of
// 32; 64 is mcg's choice, see `mcmm::TILE_SIZE`), shuffled through workgroup memory (the
// portable path).

// `mcmm::TILE_WIDTH`, `TILE_HEIGHT` and their product.
const MCMM_TILE_WIDTH: u32 = 8u;
const MCMM_TILE_HEIGHT: u32 = 8u;
const MCMM_LANES: u32 = 64u;
// `mcmm::TILE_SALT`: the per-tile stream of the xor masks.
const MCMM_TILE_SALT: u32 = 0x7f4a7c15u;

// `mcmm::ratio`: value/density, zero where the density is not positive or the quotient not
// finite.
fn ratio3(value: vec3<f32>, density: f32) -> vec3<f32> {
    let r = value / density;
    if density > 0.0 && mcg_is_finite(r.x) && mcg_is_finite(r.y) && mcg_is_finite(r.z) {
        return r;
    }
    return vec3<f32>(0.0);
}

// `mcmm::emitter_along`: the point the ray (origin, w) hits (xyz of `point`) and the radiance
// its front face emits back; origin + w and zero when it leaves the scene.
struct EmitterHit {
    point: vec3<f32>,
    emitted: vec3<f32>,
}

fn emitter_along(origin: vec3<f32>, w: vec3<f32>) -> EmitterHit {
    let hit = bvh_walk(origin, w, 0.0, FAR, false);
    if hit.triangle == NO_HIT {
        return EmitterHit(origin + w, environment_radiance(w));
    }
    let tri = triangles[hit.triangle];
    var emitted = vec3<f32>(0.0);
    if dot(cross(tri.e1, tri.e2), w) < 0.0 {
        emitted = material_at(hit).emission;
    }
    return EmitterHit(origin + hit.t * w, emitted);
}

// The x-independent part of each published state's lobe (fixed prior): ȳ and κ in `.xyz`,
// `.w` (κ < 0: no lobe), and the normalisation C(κ) of `vmf_pdf`. Written by each lane for its
// own state between the exchange's barriers and the publish's, read by the mixture.
var<workgroup> tile_lobes: array<vec4<f32>, MCMM_LANES>;
var<workgroup> tile_norms: array<f32, MCMM_LANES>;
// The tile's published tentative states, read by the mixture of the light-size prior
// (`mcmm_tile` of `mcg::mcmm` holds at most the 32 lanes of a subgroup).
var<workgroup> tile_states: array<MarkovPixelState, MCMM_LANES>;
// The chains (tentative, current) in flight during the xor exchange: arrays of their own, so
// that the exchange and the publish of one step need three barriers in all.
var<workgroup> tile_tentatives: array<MarkovPixelState, MCMM_LANES>;
var<workgroup> tile_currents: array<MarkovPixelState, MCMM_LANES>;

// `mcmm_tile_exchange` of both states of a chain over `tile_tentatives`/`tile_currents`: lane
// `lane` receives the chain of lane `source`. The first barrier ends the last step's reads of
// the tile (the mixture's and the exchange's). Uniform control flow.
fn tile_exchange_chain(lane: u32, source: u32, tentative: ptr<function, MarkovPixelState>,
                       current: ptr<function, MarkovPixelState>) {
    workgroupBarrier();
    tile_tentatives[lane] = *tentative;
    tile_currents[lane] = *current;
    workgroupBarrier();
    *tentative = tile_tentatives[source];
    *current = tile_currents[source];
}

// Writes lane `lane`'s entry of `tile_lobes`/`tile_norms` for `state`: the κ of
// `vmf_from_sufficient_stats` under the fixed prior (no lobe for an invalid or empty state).
fn publish_lobe(lane: u32, state: MarkovPixelState, mp: McmmParams) {
    var lobe = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    var norm = 0.0;
    let stats = state.stats;
    if markov_pixel_state_is_valid(state) && stats.sample_count > 0u && stats.weight_sum > 0.0 {
        let prior = VmfMapPrior(mp.prior_mean_cosine, mp.prior_weight, mp.prior_decay);
        let kappa = vmf_kappa_from_one_minus_mean_cosine(
            vmf_posterior_one_minus_mean_cosine(stats, prior));
        lobe = vec4<f32>(stats.mean_target_x, stats.mean_target_y, stats.mean_target_z, kappa);
        norm = vmf_normalization(kappa);
    }
    tile_lobes[lane] = lobe;
    tile_norms[lane] = norm;
}

// The tile's mixture density (1/n) Σⱼ p(ω | tⱼ) at x (MCMM eq. 9) with the material's density
// `bsdf_pdf` as each technique's defensive branch: `mcmm_technique_pdf` over the published
// states, its x-independent part (κ, C(κ)) taken from `tile_lobes` (computed once per state
// instead of once per state and pixel). The light-size prior's κ depends on x: it takes
// the full path.
fn tile_mixture_pdf(x: vec3<f32>, w: vec3<f32>, bsdf_pdf: f32, mp: McmmParams) -> f32 {
    var sum = 0.0;
    if mp.prior_kind == MCMM_PRIOR_LIGHT_SIZE {
        for (var j = 0u; j < MCMM_LANES; j++) {
            sum += mcmm_technique_pdf(tile_states[j], x, w, bsdf_pdf, mp);
        }
        return min(sum, MCG_F32_MAX) / f32(MCMM_LANES);
    }
    // Σⱼ over the lanes with a lobe of p_h p_bsdf + (1 − p_h) vmfⱼ, and p_bsdf for the others:
    // the lobes' sum and their count in the loop, the BSDF's share after it.
    let p = mp.hemisphere_probability;
    var lobes = 0.0;
    for (var j = 0u; j < MCMM_LANES; j++) {
        let lobe = tile_lobes[j];
        var mu: vec3<f32>;
        if lobe.w >= 0.0 && vmf_try_normalize(lobe.xyz - x, &mu) {
            let d = w - mu;
            let distance_squared = d.x * d.x + d.y * d.y + d.z * d.z;
            sum += tile_norms[j] * exp(-0.5 * lobe.w * distance_squared);
            lobes += 1.0;
        }
    }
    sum = (1.0 - p) * sum + (f32(MCMM_LANES) - (1.0 - p) * lobes) * bsdf_pdf;
    return min(sum, MCG_F32_MAX) / f32(MCMM_LANES);
}

// `McmmRenderer::shade`: one step at pixel (x, y) — the camera ray, the chain's sample
// (Alg. 2, the material as the defensive technique), the one-sample SSMIS estimate over the tile's published states (MCMM eq. 9) and
// the chain's update (Alg. 3) with the score of `score_density`. Uniforms from `rng` in the
// CPU's order: jitter (2), branch, direction (2), acceptance.
fn mcmm_shade(x: u32, y: u32, tentative: ptr<function, MarkovPixelState>,
              current: ptr<function, MarkovPixelState>, rng: ptr<function, u32>) -> vec3<f32> {
    let jx = mcg_rng_uniform(rng);
    let jy = mcg_rng_uniform(rng);
    let d = camera_direction(f32(x) + jx, f32(y) + jy);
    let hit = bvh_walk(params.camera_position, d, 0.0, FAR, false);
    if hit.triangle == NO_HIT {
        return environment_radiance(d);
    }
    let tri = triangles[hit.triangle];
    let material = material_at(hit);
    let c = cross(tri.e1, tri.e2);
    let n_front = c / length(c);
    let front = dot(n_front, d) < 0.0;
    let normal = select(-n_front, n_front, front);
    let position = params.camera_position + hit.t * d;
    var radiance = select(vec3<f32>(0.0), material.emission, front);
    let mp = mcg_mcmm_params;
    let u_select = mcg_rng_uniform(rng);
    let u = vec2<f32>(mcg_rng_uniform(rng), mcg_rng_uniform(rng));
    // Alg. 2 with the material as the defensive ("hemisphere") technique.
    var lobe: Vmf;
    var w: vec3<f32>;
    let from_hemisphere = !mcmm_choose_technique(*tentative, position, u_select, mp, &lobe);
    if from_hemisphere {
        w = material_scatter_sample(material, normal, -d, u);
    } else {
        w = vmf_sample(lobe, u);
    }
    let next = emitter_along(offset_origin(position, normal), w);
    let value = material_eval(material, normal, -d, w) * next.emitted;
    let bsdf_pdf = material_pdf(material, normal, -d, w);
    let mixture = tile_mixture_pdf(position, w, bsdf_pdf, mp);
    radiance += ratio3(value, mixture);
    var density = mixture;
    if mp.score_density == MCMM_SCORE_TECHNIQUE {
        density = mcmm_technique_pdf(*tentative, position, w, bsdf_pdf, mp);
    }
    let score = mcmm_ratio(luminance(value), density);
    let u_accept = mcg_rng_uniform(rng);
    mcmm_update(tentative, current, position, next.point, score, from_hemisphere, u_accept, mp);
    return radiance;
}

// One workgroup per tile of 8 × 8 pixels of the dispatch tile, `spp` MCMM steps per pixel:
// Alg. 1 from the previous frame's states (motion zero: the camera is static), the tile's xor
// permutation of the chains (one mask per tile and step from its own stream), the states
// published for the mixture, `mcmm_shade`; at the end the chain's S_c is stored where it ended
// and the mean into `image`. Lanes past the image's edge hold empty chains and take part in
// the shuffles (every barrier is reached by the whole workgroup).
@compute @workgroup_size(8, 8)
fn render_mcmm(@builtin(local_invocation_id) lid: vec3<u32>,
               @builtin(workgroup_id) wid: vec3<u32>) {
    let lane = lid.y * MCMM_TILE_WIDTH + lid.x;
    let lx = wid.x * MCMM_TILE_WIDTH + lid.x;
    let ly = wid.y * MCMM_TILE_HEIGHT + lid.y;
    let x = params.tile_x + lx;
    let y = params.tile_y + ly;
    let inside = lx < params.tile_width && ly < params.tile_height && x < params.width
        && y < params.height;
    let index = y * params.width + x;
    let tiles_x = (params.width + MCMM_TILE_WIDTH - 1u) / MCMM_TILE_WIDTH;
    let tile = (y / MCMM_TILE_HEIGHT) * tiles_x + x / MCMM_TILE_WIDTH;
    var tentative = mcmm_empty_state();
    if inside {
        tentative = mcmm_load_previous(index);
    }
    var current = tentative;
    var sum = vec3<f32>(0.0);
    for (var s = 0u; s < params.spp; s++) {
        var rng = path_seed(params.seed, params.frame, index, s);
        if inside {
            var taken = 0u;
            tentative = mcmm_collaborative_discovery(tentative, vec2<i32>(i32(x), i32(y)),
                                                     vec2<f32>(0.0), mcg_mcmm_params, &rng,
                                                     &taken);
        }
        var trng = path_seed(params.seed ^ MCMM_TILE_SALT, params.frame, tile, s);
        let mask = mcmm_select_uniform(MCMM_LANES, mcg_rng_uniform(&trng));
        let source = mcmm_xor_source_lane(lane, mask);
        tile_exchange_chain(lane, source, &tentative, &current);
        // After the exchange's barriers (the last step's mixtures are read) and before the
        // publish's barrier (this step's mixtures read them).
        publish_lobe(lane, tentative, mcg_mcmm_params);
        tile_states[lane] = tentative;
        workgroupBarrier();
        if inside {
            sum += mcmm_shade(x, y, &tentative, &current, &rng);
        }
    }
    if inside {
        mcmm_store_current(index, current);
        image[index] = vec4<f32>(sum / f32(params.spp), 1.0);
    }
}
#endif
