#define_import_path mcg::mcpg
// MCPG (Alber et al. 2025, "Real-Time Markov Chain Path Guiding") as one module a path tracer
// imports: the twin of `mcg_markov_guide::mcpg::Guide` with the same vertex API.
//
//   let v = mcpg_begin(mcpg_surface_vertex(x, n), begin_uniforms);   // Alg. 1
//   let s = mcpg_sample(&v, sample_uniforms);                         // Alg. 2: ω and its exact pdf
//   ... trace ω, weight = f·cos/s.pdf ...
//   mcpg_finish(&v, s, mcpg_observation_hit(y, n_y, emitted, weight), finish_uniforms); // Alg. 3
//
// or, to finish once the path is done (with its own L_r at y in `obs.reflected`), keep
// `let p = mcpg_pending(&v, s);` and call `mcpg_finish_pending(p, obs, finish_uniforms)` then.
//
// A renderer with its own BSDF sets `vertex.scatter = MCPG_SCATTER_CUSTOM` and calls
// `mcpg_choose`, `mcpg_sample_lobe` and `mcpg_pdf_with` itself (see `mcpg_sample`).
//
// Bindings, all in one group chosen by the shader def MCG_MCPG_GROUP (the host object
// `GpuMcpgGuide` builds that group): 0 the parameters (`mcpg_params`), 1 the hash tables' words
// (`mcg_hashgrid_words` of `mcg::hashgrid_table`: set MCG_HASHGRID_GROUP to the same group and
// MCG_HASHGRID_BINDING to 1), 2 the guide's words (`mcpg_words`: the frame counter, the chain
// states with their guard words, the irradiance cache's cells and per-frame sums).
//
// Racing stores (MCPG: last writer wins) never produce a torn state: every state slot has a
// guard word holding MCPG_GUARD_LOCKED while a writer is inside and otherwise a 32-bit stamp of
// the state's eight words (0 for the all-zero, empty state). A writer that finds the slot locked
// or loses the compare-and-swap drops its state (the CPU guide's seqlock does the same); a
// reader that finds the lock or words whose stamp differs from the guard reads the empty state,
// as a hash collision reads in Alg. 1 line 7. WGSL atomics are relaxed, so the stamp, not the
// order of the stores, is what detects a mixture of two writes.

#import mcg::constants::{
    HASHGRID_CLASS_NONE, HASHGRID_NO_SLOT, MCG_F32_MAX, MCPG_DISCARD_PAPER,
    MCPG_ENGINE_DISCARD_BASE, MCPG_ENGINE_DISCARD_SLOPE, MCPG_FRAME_WORD, MCPG_GUARD_FIRST_STAMP,
    MCPG_GUARD_LOCKED, MCPG_HEMISPHERE_COSINE_PRODUCT, MCPG_LUMINANCE_B, MCPG_LUMINANCE_G,
    MCPG_LUMINANCE_R, MCPG_MAX_CANDIDATES, MCPG_NO_LOBE, MCPG_SCATTER_ISOTROPIC,
    MCPG_SCATTER_LAMBERTIAN, MCPG_TRACED_ESCAPED, MCPG_TRACED_HIT, MCPG_TRANSITION_DISCARDED,
    MCPG_TRANSITION_DROPPED, MCPG_TRANSITION_REJECTED, MCPG_TRANSITION_STORED,
    VMF_CLAMPED_COSINE_KAPPA, VMF_KAPPA_MAX, VMF_PRIOR_DECAY_SQUARED_COUNT, VMF_UNIFORM_SPHERE_PDF
}
#import mcg::math::{
    mcg_infinity_bits, mcg_is_finite, mcg_is_finite3, mcg_is_nan, mcg_max_abs3, mcg_rounded
}
#import mcg::sampling::{mcg_cosine_hemisphere_pdf, mcg_cosine_hemisphere_sample, mcg_pcg_hash}
#import mcg::vmf::{
    Vmf, VmfFitParams, VmfMapPrior, vmf_normalization, vmf_posterior_one_minus_mean_cosine,
    vmf_sample, vmf_stats_update, vmf_try_normalize
}
#import mcg::hashgrid::{
    HashgridCellKey, HashgridLevels, HashgridTable, hashgrid_cell_key, hashgrid_checksum,
    hashgrid_geometric_jitter, hashgrid_home_slot, hashgrid_normal_class,
    hashgrid_stochastic_trilinear, hashgrid_target_level
}
#import mcg::hashgrid_table::{
    hashgrid_evict_slot, hashgrid_find, hashgrid_insert_or_get, hashgrid_touch, hashgrid_trim_slot
}
#import mcg::markov::{
    MarkovGridState, markov_grid_state_is_valid, markov_grid_state_lobe,
    markov_grid_state_pack, markov_grid_state_predicted, markov_grid_state_resampling_weight,
    markov_grid_state_sample_count, markov_grid_state_stats
}

// Everything the guide's functions read (`McpgGpuParams` on the host, 1 296 bytes): MCPG's
// constants (`McpgParams`), the grids' geometry, the three tables in `mcg_hashgrid_words`,
// where each array starts in `mcpg_words`, the camera, and every adaptive level's cell width
// (the CPU guide's table of `AdaptiveGrid::width`, so keys match bit for bit).
struct McpgParams {
    candidates: u32,
    adaptive_probability: f32,
    bsdf_probability: f32,
    prior_scale: f32,
    prior_min_weight: f32,
    static_normal_threshold: f32,
    discard_rule: u32,
    discard_ratio: f32,
    fit: VmfFitParams,
    hemisphere: u32,
    environment_distance: f32,
    static_width: f32,
    age_tracking: u32,
    camera: vec3<f32>,
    max_state_age: u32,
    levels: HashgridLevels,
    adaptive_table: HashgridTable,
    static_table: HashgridTable,
    cache_table: HashgridTable,
    cache_enabled: u32,
    cache_accumulation: f32,
    cache_coarser_levels: u32,
    cache_level_bias: u32,
    cache_max_age: u32,
    cache_max_weight: f32,
    adaptive_states: u32,
    static_states: u32,
    adaptive_guards: u32,
    static_guards: u32,
    cache_cells: u32,
    cache_sums: u32,
    confidence_inverse: f32,
    cache_add_scale: f32,
    widths: array<vec4<f32>, 64>,
}

@group(#{MCG_MCPG_GROUP}) @binding(0) var<uniform> mcpg_params: McpgParams;
@group(#{MCG_MCPG_GROUP}) @binding(2) var<storage, read_write> mcpg_words: array<atomic<u32>>;
// The same buffer as `mcpg_words`, viewed as vec4 for the states' plain loads and stores
// (`GpuMcpgGuide::GUIDE_WORDS_VEC4_BINDING`): every state starts at a multiple of 4 words.
@group(#{MCG_MCPG_GROUP}) @binding(3) var<storage, read_write> mcpg_words4: array<vec4<u32>>;

// Where a path vertex is (`Vertex`): the position, the direction whose cube-map class goes into
// the adaptive key (the normal, or the jittered reverse view direction in a volume), the normal
// when `has_normal` is 1, and the scattering the guide falls back to (MCPG_SCATTER_*).
struct McpgVertex {
    position: vec3<f32>,
    scatter: u32,
    key_direction: vec3<f32>,
    has_normal: u32,
    normal: vec3<f32>,
}

// `Vertex::surface`: a Lambertian surface vertex with unit `normal` on the path's side.
fn mcpg_surface_vertex(position: vec3<f32>, normal: vec3<f32>) -> McpgVertex {
    return McpgVertex(position, MCPG_SCATTER_LAMBERTIAN, normal, 1u, normal);
}

// `Vertex::volume`: a vertex in a volume with the isotropic phase function, seen along unit
// `view` (camera towards the vertex); the key direction is −view jittered by a cosine lobe from
// `jitter` (MCPG sec. 4, "Extension to Single Scattering"; `jittered_view_direction`).
fn mcpg_volume_vertex(position: vec3<f32>, view: vec3<f32>, jitter: vec2<f32>) -> McpgVertex {
    let key = mcg_cosine_hemisphere_sample(-view, jitter).direction;
    return McpgVertex(position, MCPG_SCATTER_ISOTROPIC, key, 0u, vec3<f32>(0.0));
}

// `BeginUniforms`: per candidate (grid, level, corner, reservoir); the first N_mc are used.
struct McpgBeginUniforms {
    candidates: array<vec4<f32>, 8>,
}

// `SampleUniforms`: Alg. 2's ξ against p_bsdf and the direction's two.
struct McpgSampleUniforms {
    choice: f32,
    direction: vec2<f32>,
}

// `FinishUniforms`: acceptance, the store vertex's grid, level and corner, the cache corner.
struct McpgFinishUniforms {
    accept: f32,
    store_grid: f32,
    store_level: f32,
    store_corner: f32,
    cache: f32,
}

// `GuidedSample`: ω, the density to divide by, and the candidate whose lobe was sampled
// (MCPG_NO_LOBE for the scatter technique).
struct McpgSample {
    direction: vec3<f32>,
    pdf: f32,
    lobe: u32,
}

// `VertexObservation`: what the ray along ω found. `traced` is MCPG_TRACED_HIT (then
// `position`, `normal`, `emitted` and, when `has_previous` is 1, `previous_position` of moving
// geometry) or MCPG_TRACED_ESCAPED (`emitted` is the environment's radiance). `weight` is f·cos/p;
// `reflected` (when `has_reflected` is 1) is L_r at the hit, otherwise the cache is read.
// `emission_weight` is the MIS weight the renderer gave `emitted` (1 without light sampling):
// the chain learns from weight·(emission_weight·emitted + L_r), the cache gets the whole
// weight·(emitted + L_r) (`VertexObservation::emission_weight`).
struct McpgObservation {
    traced: u32,
    has_previous: u32,
    has_reflected: u32,
    emission_weight: f32,
    position: vec3<f32>,
    normal: vec3<f32>,
    emitted: vec3<f32>,
    previous_position: vec3<f32>,
    weight: vec3<f32>,
    reflected: vec3<f32>,
}

// `VertexObservation::hit`: a hit of static geometry, L_r from the cache.
fn mcpg_observation_hit(position: vec3<f32>, normal: vec3<f32>, emitted: vec3<f32>, weight: vec3<f32>) -> McpgObservation {
    let zero = vec3<f32>(0.0);
    return McpgObservation(MCPG_TRACED_HIT, 0u, 0u, 1.0, position, normal, emitted, position, weight, zero);
}

// `VertexObservation::escaped`: a ray that left the scene, seeing `radiance`.
fn mcpg_observation_escaped(radiance: vec3<f32>, weight: vec3<f32>) -> McpgObservation {
    let zero = vec3<f32>(0.0);
    return McpgObservation(MCPG_TRACED_ESCAPED, 0u, 0u, 1.0, zero, zero, radiance, zero, weight, zero);
}

// One vertex between `mcpg_begin` and `mcpg_finish` (`GuidedVertex`): the candidates' lobes
// (with the cosine product if configured), their normalisations and shares w̄_k/Σw̄, the share
// of candidates without a lobe at x, the chosen candidate, and the slot each was read from.
struct McpgGuidedVertex {
    vertex: McpgVertex,
    normal_class: u32,
    target_level: u32,
    count: u32,
    selected: u32,
    weight_sum: f32,
    scatter_share: f32,
    static_mask: u32,
    chosen: MarkovGridState,
    slots: array<u32, 8>,
    lobes: array<Vmf, 8>,
    normalizations: array<f32, 8>,
    shares: array<f32, 8>,
}

// The current frame, the time T of the states (advanced by the host's per-frame pass).
fn mcpg_frame() -> u32 {
    return atomicLoad(&mcpg_words[MCPG_FRAME_WORD]);
}

// `luminance`: Rec. 709 luminance of linear RGB (MCPG Alg. 3 line 1), products unfused.
fn mcpg_luminance(rgb: vec3<f32>) -> f32 {
    return mcg_rounded(rgb.x * MCPG_LUMINANCE_R) + mcg_rounded(rgb.y * MCPG_LUMINANCE_G) + mcg_rounded(rgb.z * MCPG_LUMINANCE_B);
}

fn mcpg_width(level: u32) -> f32 {
    return mcpg_params.widths[level >> 2u][level & 3u];
}

fn mcpg_table(is_static: bool) -> HashgridTable {
    if is_static {
        return mcpg_params.static_table;
    }
    return mcpg_params.adaptive_table;
}

// The chain state slots: eight words each, and one guard word.
fn mcpg_state_word(is_static: bool, slot: u32) -> u32 {
    return select(mcpg_params.adaptive_states, mcpg_params.static_states, is_static) + 8u * slot;
}

fn mcpg_guard_word(is_static: bool, slot: u32) -> u32 {
    return select(mcpg_params.adaptive_guards, mcpg_params.static_guards, is_static) + slot;
}

// The guard value of a state's words: 0 for all zeros (the empty state a fresh or evicted slot
// holds), else a hash of the eight words moved past MCPG_GUARD_LOCKED.
fn mcpg_stamp(w: array<u32, 8>) -> u32 {
    var any = 0u;
    var h = 0u;
    for (var i = 0u; i < 8u; i += 1u) {
        any |= w[i];
        h = mcg_pcg_hash(h ^ w[i]);
    }
    if any == 0u {
        return 0u;
    }
    return select(h, h + MCPG_GUARD_FIRST_STAMP, h < MCPG_GUARD_FIRST_STAMP);
}

fn mcpg_state_from_words(w: array<u32, 8>) -> MarkovGridState {
    return MarkovGridState(bitcast<f32>(w[0]), bitcast<f32>(w[1]), bitcast<f32>(w[2]), bitcast<f32>(w[3]), bitcast<f32>(w[4]), bitcast<f32>(w[5]), w[6], w[7]);
}

fn mcpg_words_of_state(s: MarkovGridState) -> array<u32, 8> {
    return array<u32, 8>(bitcast<u32>(s.mean_target_x), bitcast<u32>(s.mean_target_y), bitcast<u32>(s.mean_target_z), bitcast<u32>(s.weight_sum), bitcast<u32>(s.one_minus_mean_cosine), bitcast<u32>(s.time), s.velocity_xy, s.velocity_z_count);
}

// The eight words of the state at `slot`, as they are (no guard check): two 16-byte plain
// loads through the vec4 view. A load racing a writer may mix old and new words (or, in WGSL's
// memory model, give indeterminate values); `mcpg_load_state`'s stamp check drops such a read.
// On lavapipe each load with a per-invocation address is a loop over the SIMD group's lanes, so
// two loads instead of eight atomic ones made the bench's guided kernel 6-9 % faster.
fn mcpg_read_words(is_static: bool, slot: u32) -> array<u32, 8> {
    let q = mcpg_state_word(is_static, slot) / 4u;
    let a = mcpg_words4[q];
    let b = mcpg_words4[q + 1u];
    return array<u32, 8>(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w);
}

// The state at `slot`; false (and `out` untouched) while a writer is inside or when the words
// read do not match the guard (a torn read).
fn mcpg_load_state(is_static: bool, slot: u32, out: ptr<function, MarkovGridState>) -> bool {
    let guard = atomicLoad(&mcpg_words[mcpg_guard_word(is_static, slot)]);
    if guard == MCPG_GUARD_LOCKED {
        return false;
    }
    let w = mcpg_read_words(is_static, slot);
    if mcpg_stamp(w) != guard {
        return false;
    }
    *out = mcpg_state_from_words(w);
    return true;
}

// Takes the slot's guard (MCPG_GUARD_LOCKED); false when another writer holds it or takes it
// first.
fn mcpg_lock(guard_word: u32) -> bool {
    var old = atomicLoad(&mcpg_words[guard_word]);
    loop {
        if old == MCPG_GUARD_LOCKED {
            return false;
        }
        let r = atomicCompareExchangeWeak(&mcpg_words[guard_word], old, MCPG_GUARD_LOCKED);
        if r.exchanged {
            return true;
        }
        if r.old_value != old {
            return false;
        }
    }
    return false;
}

// Writes the eight words as two 16-byte plain stores through the vec4 view, then the stamp
// into the guard. WGSL's atomics are relaxed, so eight atomic stores ordered the words no
// better against a reader: what keeps a reader from using a mix of old and new words is the
// stamp, a hash of all eight, which `mcpg_load_state` checks. (On lavapipe each store with a
// per-invocation address is a loop over the SIMD group's lanes: two instead of eight.)
fn mcpg_write_and_unlock(is_static: bool, slot: u32, w: array<u32, 8>) {
    let q = mcpg_state_word(is_static, slot) / 4u;
    mcpg_words4[q] = vec4<u32>(w[0], w[1], w[2], w[3]);
    mcpg_words4[q + 1u] = vec4<u32>(w[4], w[5], w[6], w[7]);
    atomicStore(&mcpg_words[mcpg_guard_word(is_static, slot)], mcpg_stamp(w));
}

// `SharedStates::store`: writes the whole state unless another writer is inside.
fn mcpg_store_state(is_static: bool, slot: u32, s: MarkovGridState) -> bool {
    if !mcpg_lock(mcpg_guard_word(is_static, slot)) {
        return false;
    }
    mcpg_write_and_unlock(is_static, slot, mcpg_words_of_state(s));
    return true;
}

// `SharedStates::clear_weight`: w̄ ← 0 (the discard heuristic's action, MCPG sec. 5).
fn mcpg_clear_weight(is_static: bool, slot: u32) -> bool {
    if !mcpg_lock(mcpg_guard_word(is_static, slot)) {
        return false;
    }
    var w = mcpg_read_words(is_static, slot);
    w[3] = 0u;
    mcpg_write_and_unlock(is_static, slot, w);
    return true;
}

// A grid vertex of `grid.load` / `grid.store` (MCPG sec. 4, step 3).
struct McpgKey {
    is_static: bool,
    key: HashgridCellKey,
}

// `Guide::key`: the adaptive grid with probability p_adaptive at the target level plus the
// geometric jitter, its stochastic trilinear vertex and the class; else the static grid's vertex
// (`StaticGrid::vertex_key`: level 0, no class). One trilinear choice and one key serve both
// grids, so the code exists once (a SIMD CPU driver runs both sides of a branch).
fn mcpg_key(position: vec3<f32>, normal_class: u32, target_level: u32, u_grid: f32, u_level: f32, u_corner: f32) -> McpgKey {
    let is_static = !(u_grid < mcpg_params.adaptive_probability);
    let level = min(target_level + hashgrid_geometric_jitter(u_level), mcpg_params.levels.max_level);
    let width = select(mcpg_width(level), mcpg_params.static_width, is_static);
    let vertex = hashgrid_stochastic_trilinear(position / width, u_corner);
    return McpgKey(is_static, hashgrid_cell_key(vertex, select(level, 0u, is_static), select(normal_class, HASHGRID_CLASS_NONE, is_static)));
}

// The slot holding `key` (touching its age with `frame`), HASHGRID_NO_SLOT when absent.
fn mcpg_find(table: HashgridTable, key: HashgridCellKey, touch: bool, frame: u32) -> u32 {
    let slot = hashgrid_find(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
    if slot != HASHGRID_NO_SLOT && touch {
        hashgrid_touch(table, slot, frame);
    }
    return slot;
}

// Finds or claims the slot of `key` (touching its age with `frame`), HASHGRID_NO_SLOT when full.
fn mcpg_insert(table: HashgridTable, key: HashgridCellKey, touch: bool, frame: u32) -> u32 {
    let slot = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key)).slot;
    if slot != HASHGRID_NO_SLOT && touch {
        hashgrid_touch(table, slot, frame);
    }
    return slot;
}

// `distance_prior`: r_p = 0 with N_p = max(N_p,min, scale/|ȳ − x|²), decaying with N².
fn mcpg_distance_prior(s: MarkovGridState, x: vec3<f32>) -> VmfMapPrior {
    let d = vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z) - x;
    let d2 = dot(d, d);
    var weight = bitcast<f32>(mcg_infinity_bits());
    if d2 > 0.0 {
        let ratio = mcpg_params.prior_scale / d2;
        weight = select(max(ratio, mcpg_params.prior_min_weight), mcpg_params.prior_min_weight, mcg_is_nan(ratio));
    }
    return VmfMapPrior(0.0, weight, VMF_PRIOR_DECAY_SQUARED_COUNT);
}

// `prepare_candidate`: velocity prediction to `now` (eq. 10); w̄ ← 0 after a collision, for an
// invalid state, and in the static grid when the lobe direction at x is not above the surface.
fn mcpg_prepare_candidate(state: MarkovGridState, collided: bool, is_static: bool, x: vec3<f32>, vertex: McpgVertex, now: f32) -> MarkovGridState {
    var s = markov_grid_state_predicted(state, now);
    var rejected = collided || !markov_grid_state_is_valid(s);
    if !rejected && is_static && vertex.has_normal != 0u {
        var mu = vec3<f32>(0.0);
        if !vmf_try_normalize(vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z) - x, &mu) {
            mu = vec3<f32>(0.0);
        }
        rejected = !(dot(mu, vertex.normal) > mcpg_params.static_normal_threshold);
    }
    if rejected {
        s.weight_sum = 0.0;
    }
    return s;
}

// `Vmf::new(m, |m|)`: the unit mean of a non-zero, finite `m` with κ = |m| ≤ VMF_KAPPA_MAX.
fn mcpg_vmf_new(m: vec3<f32>, kappa: f32, out: ptr<function, Vmf>) -> bool {
    let largest = mcg_max_abs3(m);
    if !mcg_is_finite3(m) || !mcg_is_finite(kappa) || kappa > VMF_KAPPA_MAX || largest == 0.0 {
        return false;
    }
    var mu = vec3<f32>(0.0);
    if !vmf_try_normalize(m / largest, &mu) {
        return false;
    }
    *out = Vmf(mu, kappa);
    return true;
}

// `Vmf::product_lobe`: the lobe of the product with the clamped-cosine vMF (its scale is not
// needed): μ' ∝ κμ + κ_c n, κ' = |κμ + κ_c n|, μ kept when the sum vanishes.
fn mcpg_product_lobe(a: Vmf, b: Vmf) -> Vmf {
    let m = a.mu * a.kappa + b.mu * b.kappa;
    let kappa = sqrt(dot(m, m));
    var mu = a.mu;
    if kappa > 0.0 {
        mu = m / kappa;
    }
    var unit: vec3<f32>;
    if !vmf_try_normalize(mu, &unit) {
        unit = a.mu;
    }
    return Vmf(unit, kappa);
}

// MCPG Alg. 1 at `vertex` (`Guide::begin`): N_mc candidates from the grids, predicted (eq. 10),
// collisions and static-grid normal mismatches rejected, one chosen by reservoir sampling on w̄,
// every candidate's lobe built once. A non-finite position loads nothing.
fn mcpg_begin(vertex: McpgVertex, u: McpgBeginUniforms) -> McpgGuidedVertex {
    var v: McpgGuidedVertex;
    mcpg_begin_at(vertex, u, &v);
    return v;
}

// `mcpg_begin` written into `*v`, a vertex the caller keeps (e.g. one per path, reused at each
// of its vertices): no copy of the vertex out, and only what the vertex reads is reset. A
// candidate's lobe and normalisation are read only where its share is > 0, so they are left
// as they were elsewhere.
fn mcpg_begin_at(vertex: McpgVertex, u: McpgBeginUniforms, v: ptr<function, McpgGuidedVertex>) {
    (*v).vertex = vertex;
    (*v).selected = MCPG_NO_LOBE;
    (*v).normal_class = hashgrid_normal_class(vertex.key_direction);
    let x = vertex.position;
    (*v).target_level = hashgrid_target_level(mcpg_params.levels, distance(mcpg_params.camera, x));
    (*v).count = 0u;
    (*v).weight_sum = 0.0;
    (*v).scatter_share = 0.0;
    (*v).static_mask = 0u;
    (*v).chosen = MarkovGridState();
    let count = min(mcpg_params.candidates, MCPG_MAX_CANDIDATES);
    for (var k = 0u; k < MCPG_MAX_CANDIDATES; k += 1u) {
        (*v).slots[k] = HASHGRID_NO_SLOT;
        (*v).shares[k] = 0.0;
    }
    if !mcg_is_finite3(x) {
        return;
    }
    (*v).count = count;
    let frame = mcpg_frame();
    let now = f32(frame);
    let touch = mcpg_params.age_tracking != 0u;
    var cosine = Vmf(vec3<f32>(0.0), 0.0);
    var has_cosine = false;
    if mcpg_params.hemisphere == MCPG_HEMISPHERE_COSINE_PRODUCT && vertex.has_normal != 0u {
        has_cosine = mcpg_vmf_new(vertex.normal, VMF_CLAMPED_COSINE_KAPPA, &cosine);
    }
    // One pass over the N_mc candidates (N_mc, not MCPG_MAX_CANDIDATES, iterations: a SIMD CPU
    // driver such as llvmpipe runs a skipped iteration's body anyway, masked): load, prepare,
    // offer to the reservoir, and build the lobe of every candidate with w̄ > 0 (a w̄ > 0
    // makes Σw̄ > 0, when the CPU builds them all); `shares` holds w̄ until Σw̄ is known,
    // `lobeless` marks the candidates without a lobe at x.
    var lobeless = 0u;
    var young_counts: array<u32, 8>;
    for (var k = 0u; k < count; k += 1u) {
        let c = u.candidates[k];
        let key = mcpg_key(x, (*v).normal_class, (*v).target_level, c.x, c.y, c.z);
        let slot = mcpg_find(mcpg_table(key.is_static), key.key, touch, frame);
        var state: MarkovGridState;
        var collided = true;
        if slot != HASHGRID_NO_SLOT && mcpg_load_state(key.is_static, slot, &state) {
            collided = false;
            (*v).slots[k] = slot;
            (*v).static_mask |= select(0u, 1u << k, key.is_static);
        }
        let candidate = mcpg_prepare_candidate(state, collided, key.is_static, x, vertex, now);
        // `Reservoir::offer`: Σw̄ saturates at f32::MAX; weight 0 is never taken.
        let w = markov_grid_state_resampling_weight(candidate);
        (*v).weight_sum = min((*v).weight_sum + w, MCG_F32_MAX);
        if w > 0.0 && c.w * (*v).weight_sum < w {
            (*v).selected = k;
            (*v).chosen = candidate;
        }
        if !(w > 0.0) {
            continue;
        }
        (*v).shares[k] = w;
        young_counts[k] = markov_grid_state_sample_count(candidate);
        var lobe: Vmf;
        if markov_grid_state_lobe(candidate, x, mcpg_distance_prior(candidate, x), &lobe) {
            if has_cosine {
                lobe = mcpg_product_lobe(lobe, cosine);
            }
            (*v).lobes[k] = lobe;
            (*v).normalizations[k] = vmf_normalization(lobe.kappa);
        } else {
            lobeless |= 1u << k;
        }
    }
    // A fixed trip count here and in `mcpg_pdf_with`: small loops unroll, and the arrays are
    // read at constant indices (a loop over N_mc made the whole guide 1.3x slower on llvmpipe).
    // A young candidate lends the part `mcpg_young_share` of its share to the scatter
    // technique (`confidence_samples`, mcg's extension; 0 without it).
    let total = (*v).weight_sum;
    for (var k = 0u; k < MCPG_MAX_CANDIDATES; k += 1u) {
        let w = (*v).shares[k];
        if !(w > 0.0) {
            continue;
        }
        let share = w / total;
        if (lobeless & (1u << k)) != 0u {
            (*v).scatter_share += share;
            (*v).shares[k] = 0.0;
        } else {
            let young = mcpg_young_share(young_counts[k]);
            (*v).scatter_share += share * young;
            (*v).shares[k] = share * (1.0 - young);
        }
    }
}

// `McpgParams::young_share`: the part of a state's mixture share that goes to the scatter
// technique, max(0, 1 − N·(1/N_c)) for N ≥ 1 samples; 0 without `confidence_samples` or for
// N = 0.
fn mcpg_young_share(sample_count: u32) -> f32 {
    if !(mcpg_params.confidence_inverse > 0.0) || sample_count == 0u {
        return 0.0;
    }
    return max(1.0 - f32(sample_count) * mcpg_params.confidence_inverse, 0.0);
}

// The chosen candidate when it is young and has a lobe (`GuidedVertex::young_chain`): the
// chain a scatter sample continues; MCPG_NO_LOBE otherwise.
fn mcpg_young_chain(v: ptr<function, McpgGuidedVertex>) -> u32 {
    let k = (*v).selected;
    if k == MCPG_NO_LOBE || !((*v).shares[k] > 0.0) {
        return MCPG_NO_LOBE;
    }
    if !(mcpg_young_share(markov_grid_state_sample_count((*v).chosen)) > 0.0) {
        return MCPG_NO_LOBE;
    }
    return k;
}

// Alg. 2's technique (`GuidedVertex::sample`'s choice): the chosen candidate's index, or
// MCPG_NO_LOBE for the scatter technique (no candidate chosen, `choice` < p_bsdf, or no lobe).
fn mcpg_choose(v: ptr<function, McpgGuidedVertex>, choice: f32) -> u32 {
    let k = (*v).selected;
    let p = mcpg_params.bsdf_probability;
    if k == MCPG_NO_LOBE || choice < p || !((*v).shares[k] > 0.0) {
        return MCPG_NO_LOBE;
    }
    // A young chosen state's lobe gets the part 1 − y of the remaining choices.
    let young = mcpg_young_share(markov_grid_state_sample_count((*v).chosen));
    if choice - p < young * (1.0 - p) {
        return MCPG_NO_LOBE;
    }
    return k;
}

// `GuidedVertex::sample_mixture`'s choice: the lobe a direction from the whole mixture of
// `mcpg_pdf_with` takes — MCPG_NO_LOBE (the scatter technique) with probability p_bsdf, else
// candidate k with its share, else MCPG_NO_LOBE — chosen afresh, not the state Alg. 1 chose.
fn mcpg_choose_mixture(v: ptr<function, McpgGuidedVertex>, choice: f32) -> u32 {
    let p = mcpg_params.bsdf_probability;
    if !((*v).weight_sum > 0.0) || choice < p {
        return MCPG_NO_LOBE;
    }
    var rest = (choice - p) / (1.0 - p);
    for (var k = 0u; k < MCPG_MAX_CANDIDATES; k += 1u) {
        let share = (*v).shares[k];
        if rest < share {
            return k;
        }
        rest -= share;
    }
    return MCPG_NO_LOBE;
}

// A direction from candidate `k`'s lobe.
fn mcpg_sample_lobe(v: ptr<function, McpgGuidedVertex>, k: u32, u: vec2<f32>) -> vec3<f32> {
    return vmf_sample((*v).lobes[k], u);
}

// The built-in scattering's direction: the cosine hemisphere about the normal
// (MCPG_SCATTER_LAMBERTIAN) or the uniform sphere (MCPG_SCATTER_ISOTROPIC).
fn mcpg_scatter_sample(v: ptr<function, McpgGuidedVertex>, u: vec2<f32>) -> vec3<f32> {
    if (*v).vertex.scatter == MCPG_SCATTER_LAMBERTIAN {
        return mcg_cosine_hemisphere_sample((*v).vertex.normal, u).direction;
    }
    return vmf_sample(Vmf(vec3<f32>(0.0, 0.0, 1.0), 0.0), u);
}

// The built-in scattering's density at `w`.
fn mcpg_scatter_pdf(v: ptr<function, McpgGuidedVertex>, w: vec3<f32>) -> f32 {
    if (*v).vertex.scatter == MCPG_SCATTER_LAMBERTIAN {
        return mcg_cosine_hemisphere_pdf((*v).vertex.normal, w);
    }
    return VMF_UNIFORM_SPHERE_PDF;
}

// `GuidedVertex::pdf` with the renderer's scattering density `scatter_pdf` at `w` (MCPG eq. 6-7,
// the exact mixture): p_bsdf·p_s + (1 − p_bsdf)·Σ_k (w̄_k/Σw̄)·V_k(ω), the share of a candidate
// without a lobe going to p_s; p_s alone when Σw̄ = 0.
fn mcpg_pdf_with(v: ptr<function, McpgGuidedVertex>, w: vec3<f32>, scatter_pdf: f32) -> f32 {
    if !((*v).weight_sum > 0.0) {
        return scatter_pdf;
    }
    var lobes = (*v).scatter_share * scatter_pdf;
    for (var k = 0u; k < MCPG_MAX_CANDIDATES; k += 1u) {
        let share = (*v).shares[k];
        if share > 0.0 {
            let lobe = (*v).lobes[k];
            let d = w - lobe.mu;
            lobes += share * ((*v).normalizations[k] * exp(-0.5 * lobe.kappa * dot(d, d)));
        }
    }
    let p = mcpg_params.bsdf_probability;
    return p * scatter_pdf + (1.0 - p) * lobes;
}

// `GuidedVertex::pdf` with the built-in scattering.
fn mcpg_pdf(v: ptr<function, McpgGuidedVertex>, w: vec3<f32>) -> f32 {
    return mcpg_pdf_with(v, w, mcpg_scatter_pdf(v, w));
}

// `GuidedVertex::sample` with the built-in scattering (MCPG Alg. 2): ω and the exact density.
// One `vmf_sample` serves the chosen lobe and the isotropic phase function (the uniform sphere is
// the lobe κ = 0), so its code exists once.
fn mcpg_sample(v: ptr<function, McpgGuidedVertex>, u: McpgSampleUniforms) -> McpgSample {
    let k = mcpg_choose(v, u.choice);
    var lobe = Vmf(vec3<f32>(0.0, 0.0, 1.0), 0.0);
    if k != MCPG_NO_LOBE {
        lobe = (*v).lobes[k];
    }
    var w = vmf_sample(lobe, u.direction);
    if k == MCPG_NO_LOBE && (*v).vertex.scatter == MCPG_SCATTER_LAMBERTIAN {
        w = mcg_cosine_hemisphere_sample((*v).vertex.normal, u.direction).direction;
    }
    return McpgSample(w, mcpg_pdf(v, w), k);
}

// The cache's level for a target level plus `extra` coarser (`IrradianceCache::cell_level`).
fn mcpg_cache_level(level: u32, extra: u32) -> u32 {
    let biased = level + min(mcpg_params.cache_level_bias, mcpg_params.levels.max_level);
    return min(biased + extra, mcpg_params.levels.max_level);
}

fn mcpg_cache_key(position: vec3<f32>, normal: vec3<f32>, level: u32, corner: f32) -> HashgridCellKey {
    let vertex = hashgrid_stochastic_trilinear(position / mcpg_width(level), corner);
    return hashgrid_cell_key(vertex, level, hashgrid_normal_class(normal));
}

// `IrradianceCache::add`: one sample of outgoing radiance at a surface point into the frame's
// sums of the cell at `level` (coarser on a full probe neighbourhood). NaN, infinite or
// negative samples are ignored.
fn mcpg_cache_add(position: vec3<f32>, normal: vec3<f32>, level: u32, corner: f32, radiance: vec3<f32>) -> bool {
    return mcpg_cache_add_at(position, normal, level, corner, radiance, mcpg_frame());
}

// `mcpg_cache_add` in `frame`. The level loop only finds the slot and the sums are added after
// it, so the adding code exists once (a SIMD CPU driver runs every iteration's body, masked).
fn mcpg_cache_add_at(position: vec3<f32>, normal: vec3<f32>, level: u32, corner: f32, radiance: vec3<f32>, frame: u32) -> bool {
    if !(mcg_is_finite3(radiance) && min(min(radiance.x, radiance.y), radiance.z) >= 0.0 && mcg_is_finite3(position)) {
        return false;
    }
    var slot = HASHGRID_NO_SLOT;
    for (var extra = 0u; extra <= mcpg_params.cache_coarser_levels; extra += 1u) {
        let key = mcpg_cache_key(position, normal, mcpg_cache_level(level, extra), corner);
        slot = mcpg_insert(mcpg_params.cache_table, key, true, frame);
        if slot != HASHGRID_NO_SLOT {
            break;
        }
    }
    if slot == HASHGRID_NO_SLOT {
        return false;
    }
    let base = mcpg_params.cache_sums + 4u * slot;
    for (var c = 0u; c < 3u; c += 1u) {
        var old = atomicLoad(&mcpg_words[base + c]);
        loop {
            let next = bitcast<u32>(bitcast<f32>(old) + radiance[c]);
            let r = atomicCompareExchangeWeak(&mcpg_words[base + c], old, next);
            if r.exchanged {
                break;
            }
            old = r.old_value;
        }
    }
    atomicAdd(&mcpg_words[base + 3u], 1u);
    return true;
}

// `IrradianceCache::query`: the committed radiance of the first cell found from `level` on
// (MCPG sec. 4, "Irradiance Caching"); 0 when none holds one.
fn mcpg_cache_query(position: vec3<f32>, normal: vec3<f32>, level: u32, corner: f32) -> vec3<f32> {
    return mcpg_cache_query_at(position, normal, level, corner, mcpg_frame());
}

// `mcpg_cache_query` in `frame`; the radiance is read after the level loop, once.
fn mcpg_cache_query_at(position: vec3<f32>, normal: vec3<f32>, level: u32, corner: f32, frame: u32) -> vec3<f32> {
    if !mcg_is_finite3(position) {
        return vec3<f32>(0.0);
    }
    var cell = HASHGRID_NO_SLOT;
    for (var extra = 0u; extra <= mcpg_params.cache_coarser_levels; extra += 1u) {
        let key = mcpg_cache_key(position, normal, mcpg_cache_level(level, extra), corner);
        let slot = mcpg_find(mcpg_params.cache_table, key, true, frame);
        if slot != HASHGRID_NO_SLOT {
            let base = mcpg_params.cache_cells + 4u * slot;
            if bitcast<f32>(atomicLoad(&mcpg_words[base + 3u])) > 0.0 {
                cell = base;
                break;
            }
        }
    }
    if cell == HASHGRID_NO_SLOT {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(bitcast<f32>(atomicLoad(&mcpg_words[cell])), bitcast<f32>(atomicLoad(&mcpg_words[cell + 1u])), bitcast<f32>(atomicLoad(&mcpg_words[cell + 2u])));
}

// `should_discard` (MCPG sec. 5): a rejected lobe sample whose estimate is small, for a state not
// updated now, along a direction close to the state's target.
fn mcpg_should_discard(s: MarkovGridState, x: vec3<f32>, w: vec3<f32>, estimate: f32, now: f32) -> bool {
    if !markov_grid_state_is_valid(s) || s.time == now {
        return false;
    }
    let e = select(0.0, estimate, estimate >= 0.0);
    if !(e <= mcg_rounded(mcpg_params.discard_ratio * s.weight_sum)) {
        return false;
    }
    var mu: vec3<f32>;
    if !vmf_try_normalize(vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z) - x, &mu) {
        return false;
    }
    if mcpg_params.discard_rule == MCPG_DISCARD_PAPER {
        let threshold = 1.0 - vmf_posterior_one_minus_mean_cosine(markov_grid_state_stats(s), mcpg_distance_prior(s, x));
        return dot(mu, w) > threshold;
    }
    let threshold = MCPG_ENGINE_DISCARD_BASE + mcg_rounded(MCPG_ENGINE_DISCARD_SLOPE * (1.0 - s.one_minus_mean_cosine));
    return dot(mu, w) >= threshold;
}

// Radiance that may reach a chain's estimate or the cache: 0 when any component is NaN or
// infinite, else negative components made 0 (`math::finite_radiance`).
fn mcpg_finite_radiance(v: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), max(v, vec3<f32>(0.0)), mcg_is_finite3(v));
}

// MCPG Alg. 3 and the cache update after the renderer traced `sample` (`GuidedVertex::finish`):
// L = L_e + L_r (L_r observed or from the cache), f_mc = lum(weight·(w_e·L_e + L_r)) with w_e the
// observation's emission_weight (1 in MCPG); weight·L into the cache at
// a surface x; acceptance against the mean candidate score (eq. 8); the MLE update of the chosen
// state (or the empty one after a scatter sample), T ← now, v from the hit's previous position
// (eq. 9), stored at a fresh vertex (line 12); a rejected lobe sample may discard its state.
// Returns MCPG_TRANSITION_*. The same as `mcpg_finish_pending(mcpg_pending(v, sample), obs, u)`.
fn mcpg_finish(v: ptr<function, McpgGuidedVertex>, sample: McpgSample, obs: McpgObservation, u: McpgFinishUniforms) -> u32 {
    return mcpg_finish_pending(mcpg_pending(v, sample), obs, u);
}

// What `mcpg_finish` needs of a begun vertex once its sample is drawn (`PendingFinish`): where
// the vertex is, the sampled direction, the chain the transition continues (the
// sampled lobe's state, a young chosen state's after a scatter sample, else the empty state:
// Alg. 2 line 4), the candidates' mean score (eq. 8) and the slot of the sampled lobe's state
// (for the discard). A tracer that finishes its vertices only when the path is done, to train
// on the path's own L_r, keeps one of these per vertex instead of the whole McpgGuidedVertex.
struct McpgPending {
    position: vec3<f32>,
    has_normal: u32,
    normal: vec3<f32>,
    normal_class: u32,
    direction: vec3<f32>,
    target_level: u32,
    chosen: MarkovGridState,
    mean_weight: f32,
    // The slot of the sampled lobe's state; HASHGRID_NO_SLOT after a scatter sample or for a
    // state that was not found.
    lobe_slot: u32,
    lobe_is_static: u32,
}

// `GuidedVertex::pending`.
fn mcpg_pending(v: ptr<function, McpgGuidedVertex>, sample: McpgSample) -> McpgPending {
    var p: McpgPending;
    p.position = (*v).vertex.position;
    p.has_normal = (*v).vertex.has_normal;
    p.normal = (*v).vertex.normal;
    p.normal_class = (*v).normal_class;
    p.direction = sample.direction;
    p.target_level = (*v).target_level;
    if sample.lobe != MCPG_NO_LOBE || mcpg_young_chain(v) != MCPG_NO_LOBE {
        p.chosen = (*v).chosen;
    }
    p.mean_weight = 0.0;
    if (*v).count > 0u {
        p.mean_weight = (*v).weight_sum / f32((*v).count);
    }
    if !(p.mean_weight >= 0.0 && mcg_is_finite(p.mean_weight)) {
        p.mean_weight = 0.0;
    }
    let k = sample.lobe;
    p.lobe_slot = HASHGRID_NO_SLOT;
    p.lobe_is_static = 0u;
    if k != MCPG_NO_LOBE {
        p.lobe_slot = (*v).slots[k];
        p.lobe_is_static = ((*v).static_mask >> k) & 1u;
    }
    return p;
}

// `PendingFinish::finish`: `mcpg_finish` of the vertex `p` was taken from.
fn mcpg_finish_pending(p: McpgPending, obs: McpgObservation, u: McpgFinishUniforms) -> u32 {
    let frame = mcpg_frame();
    let x = p.position;
    let w = p.direction;
    var next: vec3<f32>;
    var next_previous: vec3<f32>;
    var incident: vec3<f32>;
    var learned: vec3<f32>;
    // Clamped to [0, 1]; NaN counts as 1.
    let w_e = select(clamp(obs.emission_weight, 0.0, 1.0), 1.0, mcg_is_nan(obs.emission_weight));
    if obs.traced == MCPG_TRACED_HIT {
        var reflected = obs.reflected;
        if obs.has_reflected == 0u {
            reflected = vec3<f32>(0.0);
            if mcpg_params.cache_enabled != 0u {
                let level = hashgrid_target_level(mcpg_params.levels, distance(mcpg_params.camera, obs.position));
                reflected = mcpg_cache_query_at(obs.position, obs.normal, level, u.cache, frame);
            }
        }
        next = obs.position;
        next_previous = select(obs.position, obs.previous_position, obs.has_previous != 0u);
        incident = obs.emitted + reflected;
        learned = obs.emitted * w_e + reflected;
    } else {
        next = x + w * mcpg_params.environment_distance;
        next_previous = next;
        incident = obs.emitted;
        learned = obs.emitted * w_e;
    }
    let carried = mcpg_finite_radiance(obs.weight * incident);
    // `CacheConfig::add_uniform`: the add's corner u·s, s = 1/add_probability; no add when
    // it reaches 1 (with s = 1, always an add at u).
    let scale = mcpg_params.cache_add_scale;
    let add_corner = u.cache * scale;
    if mcpg_params.cache_enabled != 0u && p.has_normal != 0u
        && (scale <= 1.0 || add_corner < 1.0) {
        mcpg_cache_add_at(x, p.normal, p.target_level, add_corner, carried, frame);
    }
    let estimate = mcpg_luminance(mcpg_finite_radiance(obs.weight * learned));
    let now = f32(frame);
    let chosen = p.chosen;
    let mean_weight = p.mean_weight;
    // `update`: eq. 8's acceptance u < f/(sum/N), then the MLE step, stored at a fresh vertex;
    // or the discard of the chosen state. Both end in one locked write of a slot (`store`, or
    // `clear_weight` on the words read under the lock), so that code exists once.
    var transition = MCPG_TRANSITION_REJECTED;
    var is_static = false;
    var slot = HASHGRID_NO_SLOT;
    var words: array<u32, 8>;
    let acceptable = estimate >= 0.0 && mcg_is_finite(estimate) && mcg_is_finite(now);
    if acceptable && estimate > 0.0 && u.accept * mean_weight < estimate {
        var stats = markov_grid_state_stats(chosen);
        vmf_stats_update(&stats, x, next, estimate, mcpg_params.fit);
        words = mcpg_words_of_state(markov_grid_state_pack(stats, now, next - next_previous));
        let key = mcpg_key(x, p.normal_class, p.target_level, u.store_grid, u.store_level, u.store_corner);
        is_static = key.is_static;
        slot = mcpg_insert(mcpg_table(is_static), key.key, mcpg_params.age_tracking != 0u, frame);
        transition = MCPG_TRANSITION_DROPPED;
    } else if p.lobe_slot != HASHGRID_NO_SLOT && mcpg_should_discard(chosen, x, w, estimate, now) {
        is_static = p.lobe_is_static != 0u;
        slot = p.lobe_slot;
        transition = MCPG_TRANSITION_DISCARDED;
    }
    if slot != HASHGRID_NO_SLOT && mcpg_lock(mcpg_guard_word(is_static, slot)) {
        if transition == MCPG_TRANSITION_DISCARDED {
            words = mcpg_read_words(is_static, slot);
            words[3] = 0u;
        } else {
            transition = MCPG_TRANSITION_STORED;
        }
        mcpg_write_and_unlock(is_static, slot, words);
    }
    return transition;
}

// The per-frame pass (`Guide::end_frame`), one dispatch per function over
// `mcpg_maintenance_slots()` invocations, in this order, with no guide calls in flight:
// `mcpg_fold_cache_slot` (cache slots only), `mcpg_evict_slot`, `mcpg_trim_slot`, then one
// invocation of `mcpg_advance_frame`. `GpuMcpgGuide::record_end_frame` records them.

// Slots of the three tables together: adaptive, static, then the cache's.
fn mcpg_maintenance_slots() -> u32 {
    return mcpg_params.adaptive_table.capacity + mcpg_params.static_table.capacity + select(0u, mcpg_params.cache_table.capacity, mcpg_params.cache_enabled != 0u);
}

// `IrradianceCache::end_frame`'s fold of cache slot `slot`: the frame's mean blended in with
// α = max(1/frames, α_min), frames capped at 1/α_min; the sums cleared.
fn mcpg_fold_cache_slot(slot: u32) {
    if mcpg_params.cache_enabled == 0u || slot >= mcpg_params.cache_table.capacity {
        return;
    }
    let sums = mcpg_params.cache_sums + 4u * slot;
    let count = atomicLoad(&mcpg_words[sums + 3u]);
    if count == 0u {
        return;
    }
    let sum = vec3<f32>(bitcast<f32>(atomicLoad(&mcpg_words[sums])), bitcast<f32>(atomicLoad(&mcpg_words[sums + 1u])), bitcast<f32>(atomicLoad(&mcpg_words[sums + 2u])));
    for (var i = 0u; i < 4u; i += 1u) {
        atomicStore(&mcpg_words[sums + i], 0u);
    }
    let mean = sum / f32(count);
    if !mcg_is_finite3(mean) {
        return;
    }
    let cell = mcpg_params.cache_cells + 4u * slot;
    let weight = min(bitcast<f32>(atomicLoad(&mcpg_words[cell + 3u])) + 1.0, mcpg_params.cache_max_weight);
    let alpha = max(1.0 / weight, mcpg_params.cache_accumulation);
    let keep = 1.0 - alpha;
    for (var c = 0u; c < 3u; c += 1u) {
        let old = bitcast<f32>(atomicLoad(&mcpg_words[cell + c]));
        atomicStore(&mcpg_words[cell + c], bitcast<u32>(mcg_rounded(old * keep) + mcg_rounded(mean[c] * alpha)));
    }
    atomicStore(&mcpg_words[cell + 3u], bitcast<u32>(weight));
}

// Table, local slot, and maximum age of maintenance index `i`; the kind is 0 adaptive, 1 static,
// 2 cache.
fn mcpg_maintenance_target(i: u32) -> vec2<u32> {
    let a = mcpg_params.adaptive_table.capacity;
    let s = mcpg_params.static_table.capacity;
    if i < a {
        return vec2<u32>(0u, i);
    }
    if i < a + s {
        return vec2<u32>(1u, i - a);
    }
    return vec2<u32>(2u, i - a - s);
}

fn mcpg_maintenance_table(kind: u32) -> HashgridTable {
    if kind == 2u {
        return mcpg_params.cache_table;
    }
    return mcpg_table(kind == 1u);
}

// `evict_older_than`'s first pass at maintenance index `i`: a slot idle for more than the
// maximum age (states: `max_state_age`, when tracked; cache: its `max_age`) at the next frame
// becomes a tombstone and its value is emptied. Returns whether it evicted.
fn mcpg_evict_slot(i: u32) -> bool {
    let t = mcpg_maintenance_target(i);
    if t.x < 2u && mcpg_params.age_tracking == 0u {
        return false;
    }
    let max_age = select(mcpg_params.max_state_age, mcpg_params.cache_max_age, t.x == 2u);
    if !hashgrid_evict_slot(mcpg_maintenance_table(t.x), t.y, mcpg_frame() + 1u, max_age) {
        return false;
    }
    if t.x == 2u {
        let cell = mcpg_params.cache_cells + 4u * t.y;
        for (var c = 0u; c < 4u; c += 1u) {
            atomicStore(&mcpg_words[cell + c], 0u);
        }
    } else {
        let is_static = t.x == 1u;
        let base = mcpg_state_word(is_static, t.y);
        for (var c = 0u; c < 8u; c += 1u) {
            atomicStore(&mcpg_words[base + c], 0u);
        }
        atomicStore(&mcpg_words[mcpg_guard_word(is_static, t.y)], 0u);
    }
    return true;
}

// `evict_older_than`'s second pass (`trim_tombstones`) at maintenance index `i`.
fn mcpg_trim_slot(i: u32) -> bool {
    let t = mcpg_maintenance_target(i);
    return hashgrid_trim_slot(mcpg_maintenance_table(t.x), t.y);
}

// Advances the time by one frame (run once, last).
fn mcpg_advance_frame() {
    atomicAdd(&mcpg_words[MCPG_FRAME_WORD], 1u);
}
