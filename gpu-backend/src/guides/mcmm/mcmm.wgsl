#define_import_path mcg::mcmm
// mcg-markov-guide twin: MCMM's screen-space chains (Dittebrandt et al. 2023) on the GPU, one
// chain state per pixel, operation by operation like `mcmm/{resampling,sampling,update}.rs`:
// collaborative discovery from the previous frame's states (Alg. 1) with B-spline offsets and
// a renderer-supplied motion vector, technique choice and the defensive pdf (Alg. 2), the
// acceptance and MLE update (Alg. 3), and the tile helpers of TSMIS/SSMIS (sec. 4.2): the
// cyclic shift and xor permutation of states through workgroup memory and the tile-mixture
// density of `ScoreDensity::TileMixture`.
//
// Bindings (all in the group the shader def MCG_MCMM_GROUP names; `GpuMcmmGuide` on the host
// creates the layout, the buffers and one bind group per frame parity):
//   0: `mcg_mcmm_params` (uniform `McmmParams`),
//   1: `mcg_mcmm_previous` (the states written last frame, read),
//   2: `mcg_mcmm_current` (this frame's states, written).

#import mcg::constants::{
    MCG_F32_MAX, MCMM_MAX_TILE_SIZE, MCMM_PRIOR_LIGHT_SIZE, VMF_PRIOR_DECAY_SQUARED_COUNT
}
#import mcg::math::{mcg_is_finite, mcg_max_abs3}
#import mcg::sampling::{mcg_cosine_hemisphere_pdf, mcg_cosine_hemisphere_sample, mcg_rng_uniform}
#import mcg::vmf::{
    Vmf, VmfFitParams, VmfMapPrior, VmfSufficientStats, vmf_from_sufficient_stats, vmf_pdf,
    vmf_sample, vmf_stats_update
}
#import mcg::markov::{MarkovPixelState, markov_pixel_state_is_valid, markov_pixel_state_resampling_score}

// 64 bytes, `GpuMcmmParams` on the host (`mcg_markov_guide::mcmm::McmmParams` and the image
// size): the fit of Alg. 3, p_h of Alg. 2, the prior (MCMM_PRIOR_FIXED with r_p, N_p and its
// decay, or MCMM_PRIOR_LIGHT_SIZE with the emitter radius and N_p), the candidates and window
// of Alg. 1, the score density (MCMM_SCORE_*) and the image size.
struct McmmParams {
    fit: VmfFitParams,
    hemisphere_probability: f32,
    prior_mean_cosine: f32,
    prior_weight: f32,
    prior_decay: u32,
    prior_kind: u32,
    prior_radius: f32,
    neighbour_candidates: u32,
    window_half_width: f32,
    score_density: u32,
    width: u32,
    height: u32,
    pad_a: u32,
}

@group(#{MCG_MCMM_GROUP}) @binding(0)
var<uniform> mcg_mcmm_params: McmmParams;
@group(#{MCG_MCMM_GROUP}) @binding(1)
var<storage, read> mcg_mcmm_previous: array<MarkovPixelState>;
@group(#{MCG_MCMM_GROUP}) @binding(2)
var<storage, read_write> mcg_mcmm_current: array<MarkovPixelState>;

// The states of one tile (at most MCMM_MAX_TILE_SIZE lanes, one workgroup or a part of one)
// while they are shuffled or summed over (sec. 4.2, the portable path of the subgroup shuffle).
var<workgroup> mcmm_tile: array<MarkovPixelState, MCMM_MAX_TILE_SIZE>;

// The empty state ({0} of Alg. 3 line 6).
fn mcmm_empty_state() -> MarkovPixelState {
    return MarkovPixelState(VmfSufficientStats(0.0, 0.0, 0.0, 0.0, 0.0, 0u), 0.0);
}

// `bspline_offset(u, half_width)`: per axis half_width/3 · (Σ₆ uᵢ − 3), the degree-5 B-spline
// (Irwin-Hall of order 6) with support ±half_width (MCMM sec. 4.1, Alg. 1 line 4). u[0..6]
// drive x, u[6..12] y; summed in the CPU's order.
fn mcmm_bspline_offset(u: array<f32, 12>, half_width: f32) -> vec2<f32> {
    var sx = 0.0;
    var sy = 0.0;
    for (var k = 0u; k < 6u; k++) {
        sx += u[k];
        sy += u[k + 6u];
    }
    return vec2<f32>(sx - 3.0, sy - 3.0) * (half_width / 3.0);
}

// `f32::round` per component: halves away from zero (WGSL's `round` ties to even).
// q − trunc(q) is exact for every f32.
fn mcmm_round_half_away(q: vec2<f32>) -> vec2<f32> {
    let t = trunc(q);
    return select(t, t + sign(q), abs(q - t) >= vec2<f32>(0.5));
}

// `PixelStateBuffers::neighbour` as an index: the pixel `pixel + offset + motion`, rounded to
// the nearest pixel, of a `width × height` row-major image, where `motion` maps this frame's
// pixel to its position in the previous frame (Alg. 1 line 4); −1 off screen or for a
// non-finite position.
fn mcmm_neighbour_index(pixel: vec2<i32>, offset: vec2<f32>, motion: vec2<f32>, width: u32, height: u32) -> i32 {
    let q = vec2<f32>(pixel) + offset + motion;
    if !(mcg_is_finite(q.x) && mcg_is_finite(q.y)) {
        return -1;
    }
    let r = mcmm_round_half_away(q);
    if abs(r.x) > 1.0e9 || abs(r.y) > 1.0e9 {
        return -1;
    }
    let p = vec2<i32>(r);
    if p.x < 0 || p.y < 0 || p.x >= i32(width) || p.y >= i32(height) {
        return -1;
    }
    return p.y * i32(width) + p.x;
}

// `resample_neighbour`: offers `candidate` to the reservoir (`state`, running score sum `sum`)
// of Alg. 1 lines 4-10; it replaces the state when the state is invalid or u < s_q/(s_q + sum).
// Invalid candidates are skipped. Returns whether it replaced the state.
fn mcmm_resample_neighbour(state: ptr<function, MarkovPixelState>, sum: ptr<function, f32>, candidate: MarkovPixelState, u: f32) -> bool {
    if !markov_pixel_state_is_valid(candidate) {
        return false;
    }
    let score = markov_pixel_state_resampling_score(candidate);
    let total = *sum + score;
    let take = !markov_pixel_state_is_valid(*state) || u * total < score;
    if take {
        *state = candidate;
    }
    *sum = total;
    return take;
}

// Alg. 1 for the pixel `pixel` of the guide's image: the reservoir starts at `state` (the
// pixel's own, shuffled state) with sum = score(S) and is offered `params.neighbour_candidates`
// states of `mcg_mcmm_previous`, each at a B-spline offset plus `motion`. Per candidate it
// draws 12 uniforms for the offset, then one for the selection, from `rng` (the order of the
// CPU reference loop). Off-screen candidates are not offered. Returns the resampled state;
// `taken` counts the replacements.
fn mcmm_collaborative_discovery(state: MarkovPixelState, pixel: vec2<i32>, motion: vec2<f32>, params: McmmParams, rng: ptr<function, u32>, taken: ptr<function, u32>) -> MarkovPixelState {
    var s = state;
    var sum = markov_pixel_state_resampling_score(state);
    *taken = 0u;
    for (var c = 0u; c < params.neighbour_candidates; c++) {
        var u: array<f32, 12>;
        for (var k = 0u; k < 12u; k++) {
            u[k] = mcg_rng_uniform(rng);
        }
        let offset = mcmm_bspline_offset(u, params.window_half_width);
        let u_select = mcg_rng_uniform(rng);
        let q = mcmm_neighbour_index(pixel, offset, motion, params.width, params.height);
        if q >= 0 && mcmm_resample_neighbour(&s, &sum, mcg_mcmm_previous[q], u_select) {
            *taken += 1u;
        }
    }
    return s;
}

// `length_robust`: |v| without overflow for large finite components.
fn mcmm_length_robust(v: vec3<f32>) -> f32 {
    let length_squared = dot(v, v);
    if mcg_is_finite(length_squared) {
        return sqrt(length_squared);
    }
    let largest = mcg_max_abs3(v);
    if !mcg_is_finite(largest) {
        return MCG_F32_MAX;
    }
    return min(largest * length(v / largest), MCG_F32_MAX);
}

// `McmmPrior::at_distance`: the fixed prior, or for MCMM_PRIOR_LIGHT_SIZE the mean cosine of a
// cone that a sphere of `prior_radius` subtends at `distance`, 1 − r_p = (1 − cos θ)/2 with
// sin θ = radius/d (MCMM sec. 5, informed priors), decaying with N².
fn mcmm_prior_at_distance(params: McmmParams, distance: f32) -> VmfMapPrior {
    if params.prior_kind != MCMM_PRIOR_LIGHT_SIZE {
        return VmfMapPrior(params.prior_mean_cosine, params.prior_weight, params.prior_decay);
    }
    var s = 1.0;
    if distance > params.prior_radius {
        s = params.prior_radius / distance;
    }
    let c = sqrt(max(1.0 - s * s, 0.0));
    let one_minus_cos = s * s / (1.0 + c);
    return VmfMapPrior(1.0 - 0.5 * one_minus_cos, params.prior_weight, VMF_PRIOR_DECAY_SQUARED_COUNT);
}

// `PixelState::lobe_with`: the lobe at shading point `x` with the guide's prior (Alg. 2 lines
// 5-8); false for an invalid state or when ȳ coincides with `x`.
fn mcmm_lobe(s: MarkovPixelState, x: vec3<f32>, params: McmmParams, out: ptr<function, Vmf>) -> bool {
    if !markov_pixel_state_is_valid(s) {
        return false;
    }
    var prior = VmfMapPrior(params.prior_mean_cosine, params.prior_weight, params.prior_decay);
    if params.prior_kind == MCMM_PRIOR_LIGHT_SIZE {
        let target_point = vec3<f32>(s.stats.mean_target_x, s.stats.mean_target_y, s.stats.mean_target_z);
        prior = mcmm_prior_at_distance(params, mcmm_length_robust(target_point - x));
    }
    return vmf_from_sufficient_stats(s.stats, x, prior, out);
}

// `choose_technique`: Alg. 2 lines 1-9. True with the state's lobe in `out`; false for the
// hemisphere (u < p_h, an invalid state, or no lobe at `x`).
fn mcmm_choose_technique(s: MarkovPixelState, x: vec3<f32>, u: f32, params: McmmParams, out: ptr<function, Vmf>) -> bool {
    if u < params.hemisphere_probability {
        return false;
    }
    return mcmm_lobe(s, x, params, out);
}

// `technique_pdf`: p(ω | S) = p_h p_hemi(ω) + (1 − p_h) V(ω | μ, κ) for a state with a lobe at
// `x`, p_hemi(ω) otherwise (Alg. 2, appendix A). `hemisphere_pdf` is the renderer's cosine or
// BSDF density at ω.
fn mcmm_technique_pdf(s: MarkovPixelState, x: vec3<f32>, w: vec3<f32>, hemisphere_pdf: f32, params: McmmParams) -> f32 {
    var lobe: Vmf;
    if !mcmm_lobe(s, x, params, &lobe) {
        return hemisphere_pdf;
    }
    let p = params.hemisphere_probability;
    return p * hemisphere_pdf + (1.0 - p) * vmf_pdf(lobe, w);
}

// A direction drawn by a chain's technique and whether the hemisphere branch drew it.
struct McmmSample {
    direction: vec3<f32>,
    from_hemisphere: bool,
}

// `CosineChainTechnique::sample_with_branch`: the lobe of `s` at `x` unless u_select < p_h or
// there is none, else the cosine hemisphere about `normal`; `u` in [0, 1)².
fn mcmm_sample_cosine(s: MarkovPixelState, x: vec3<f32>, normal: vec3<f32>, u_select: f32, u: vec2<f32>, params: McmmParams) -> McmmSample {
    var lobe: Vmf;
    if mcmm_choose_technique(s, x, u_select, params, &lobe) {
        return McmmSample(vmf_sample(lobe, u), false);
    }
    return McmmSample(mcg_cosine_hemisphere_sample(normal, u).direction, true);
}

// `value / density`, or 0 when the density is not > 0 or the quotient is not finite (the
// SMIS crate's `ratio`): the score f of Alg. 3 line 1 and the one-sample estimates.
fn mcmm_ratio(value: f32, density: f32) -> f32 {
    let r = value / density;
    if density > 0.0 && mcg_is_finite(r) {
        return r;
    }
    return 0.0;
}

// `update` (Alg. 3): acceptance of the tentative state S against the current S_c with
// a = min(1, f/S_c.f) (u·S_c.f < f; any f > 0 against an invalid S_c), reset of S after an
// accepted hemisphere sample, S.f ← f, the MLE update of S with (x2, f), and S_c ← S on
// acceptance. A NaN, infinite or negative f counts as 0. Returns whether S was accepted.
fn mcmm_update(tentative: ptr<function, MarkovPixelState>, current: ptr<function, MarkovPixelState>, x1: vec3<f32>, x2: vec3<f32>, f_in: f32, from_hemisphere: bool, u: f32, params: McmmParams) -> bool {
    var f = 0.0;
    if f_in >= 0.0 && mcg_is_finite(f_in) {
        f = f_in;
    }
    let accepted = f > 0.0 && (!markov_pixel_state_is_valid(*current) || u * (*current).score < f);
    if accepted {
        if from_hemisphere {
            *tentative = mcmm_empty_state();
        }
        (*tentative).score = f;
    }
    var stats = (*tentative).stats;
    vmf_stats_update(&stats, x1, x2, f, params.fit);
    (*tentative).stats = stats;
    if accepted {
        *current = *tentative;
    }
    return accepted;
}

// The state pixel `index` wrote last frame (the empty state past the end).
fn mcmm_load_previous(index: u32) -> MarkovPixelState {
    if index >= arrayLength(&mcg_mcmm_previous) {
        return mcmm_empty_state();
    }
    return mcg_mcmm_previous[index];
}

// Writes this frame's state S_c of pixel `index` (ignored past the end).
fn mcmm_store_current(index: u32, state: MarkovPixelState) {
    if index < arrayLength(&mcg_mcmm_current) {
        mcg_mcmm_current[index] = state;
    }
}

// `cyclic_source_lane`: the lane whose state lane `lane` receives under a cyclic shift by
// `shift` in a tile of `size` lanes (TSMIS, sec. 4.2, "shuffle up"); `size` ≥ 1.
fn mcmm_cyclic_source_lane(lane: u32, size: u32, shift: u32) -> u32 {
    return (lane % size + size - shift % size) % size;
}

// `xor_source_lane`: the lane whose state `lane` takes under the xor permutation with `mask`
// (SSMIS, sec. 4.2); a permutation of a power-of-two tile for mask < size.
fn mcmm_xor_source_lane(lane: u32, mask: u32) -> u32 {
    return lane ^ mask;
}

// `select_uniform(n, u)`: ⌊u·n⌋ clamped to n − 1 (NaN and negatives select 0); n ≥ 1.
fn mcmm_select_uniform(n: u32, u: f32) -> u32 {
    let t = u * f32(n);
    if !(t >= 0.0) {
        return 0u;
    }
    return min(u32(min(t, f32(n))), n - 1u);
}

// Publishes `state` as lane `lane`'s entry of the tile (`mcmm_tile`). Every invocation of the
// workgroup must call it (it holds two barriers): uniform control flow.
fn mcmm_tile_publish(lane: u32, state: MarkovPixelState) {
    workgroupBarrier();
    mcmm_tile[lane] = state;
    workgroupBarrier();
}

// The portable shuffle: publishes `state` at `lane` and returns the state lane `source`
// published (`CyclicShift`/`XorPermutation::apply` on the tile). Uniform control flow.
fn mcmm_tile_exchange(lane: u32, source: u32, state: MarkovPixelState) -> MarkovPixelState {
    mcmm_tile_publish(lane, state);
    return mcmm_tile[source];
}

// The tile-mixture density (1/n) Σⱼ p(ω | tⱼ) over the n published states of lanes
// `first..first + n`, each reconstructed at the caller's shading point `x` with the cosine
// hemisphere about `normal` as its defensive branch: the denominator of the one-sample SSMIS
// estimator (MCMM eq. 9, `smis_one_sample`) and the density of `ScoreDensity::TileMixture`.
// A sum that overflows saturates at f32::MAX; 0 for n = 0.
fn mcmm_tile_mixture_pdf(first: u32, n: u32, x: vec3<f32>, normal: vec3<f32>, w: vec3<f32>, params: McmmParams) -> f32 {
    if n == 0u {
        return 0.0;
    }
    let hemisphere = mcg_cosine_hemisphere_pdf(normal, w);
    var sum = 0.0;
    for (var j = 0u; j < n; j++) {
        sum += mcmm_technique_pdf(mcmm_tile[first + j], x, w, hemisphere, params);
    }
    return min(sum, MCG_F32_MAX) / f32(n);
}

#ifdef MCG_MCMM_SUBGROUPS
// The subgroup path of the tile shuffles (MCMM sec. 4.2: the tile is one subgroup), compiled
// only with the shader def MCG_MCMM_SUBGROUPS (the device needs wgpu's SUBGROUP feature).
// Same permutations, same estimators: results identical in distribution to the workgroup
// path. Every invocation of the subgroup must call these (subgroup-uniform control flow).

// The state subgroup lane `source` holds (`mcmm_tile_exchange` without workgroup memory).
fn mcmm_subgroup_exchange(source: u32, state: MarkovPixelState) -> MarkovPixelState {
    let s = state.stats;
    let a = subgroupShuffle(vec4<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z, s.weight_sum), source);
    let b = subgroupShuffle(vec2<f32>(s.one_minus_mean_cosine, state.score), source);
    let count = subgroupShuffle(s.sample_count, source);
    return MarkovPixelState(VmfSufficientStats(a.x, a.y, a.z, a.w, b.x, count), b.y);
}

// `mcmm_tile_mixture_pdf` over the `size` lanes of the subgroup, each lane passing its own
// `state`: (1/n) Σⱼ p(ω | tⱼ) at the caller's `x` (MCMM eq. 9).
fn mcmm_subgroup_mixture_pdf(state: MarkovPixelState, size: u32, x: vec3<f32>, normal: vec3<f32>, w: vec3<f32>, params: McmmParams) -> f32 {
    let hemisphere = mcg_cosine_hemisphere_pdf(normal, w);
    var sum = 0.0;
    for (var j = 0u; j < size; j++) {
        sum += mcmm_technique_pdf(mcmm_subgroup_exchange(j, state), x, w, hemisphere, params);
    }
    return min(sum, MCG_F32_MAX) / f32(max(size, 1u));
}
#endif
