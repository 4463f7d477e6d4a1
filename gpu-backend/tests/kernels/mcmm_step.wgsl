// One MCMM iteration per pixel (Alg. 1-3) with a renderer-supplied hit, for the parity tests;
// the guide's bindings in group 1 (shader def MCG_MCMM_GROUP = 1), the test's in group 0.
// Pixels are row-major; a tile is 32 consecutive pixels = one workgroup (the test's width is
// a multiple of 32).

#import mcg::markov::MarkovPixelState
#import mcg::sampling::{mcg_cosine_hemisphere_pdf, mcg_rng_uniform, mcg_rng_uniform2}
#import mcg::mcmm::{
    mcg_mcmm_params, mcmm_collaborative_discovery, mcmm_cyclic_source_lane,
    mcmm_load_previous, mcmm_ratio, mcmm_sample_cosine, mcmm_select_uniform, mcmm_store_current,
    mcmm_technique_pdf, mcmm_tile_exchange, mcmm_tile_mixture_pdf, mcmm_tile_publish,
    mcmm_update, mcmm_xor_source_lane
}
#import mcg::constants::MCMM_SCORE_TILE_MIXTURE

struct StepInput {
    x: vec3<f32>,
    seed: u32,
    normal: vec3<f32>,
    value: f32,
    hit: vec3<f32>,
    pad_a: f32,
    motion: vec2<f32>,
    pad_b: vec2<f32>,
}

struct StepOutput {
    discovered: MarkovPixelState,
    pdf: f32,
    direction: vec3<f32>,
    score: f32,
    flags: u32,
    taken: u32,
    pad_a: u32,
    pad_b: u32,
}

@group(0) @binding(0) var<storage, read> inputs: array<StepInput>;
@group(0) @binding(1) var<storage, read_write> outputs: array<StepOutput>;

const TILE: u32 = 32u;

@compute @workgroup_size(32)
fn mcmm_step(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let params = mcg_mcmm_params;
    let n = params.width * params.height;
    let i = id.x;
    let in_image = i < n;
    let input = inputs[min(i, n - 1u)];
    var rng = input.seed;
    let pixel = vec2<i32>(i32(i % params.width), i32(i / params.width));
    let start = mcmm_load_previous(i);
    var taken = 0u;
    var tentative = mcmm_collaborative_discovery(start, pixel, input.motion, params, &rng, &taken);
    let u_select = mcg_rng_uniform(&rng);
    let u = mcg_rng_uniform2(&rng);
    let s = mcmm_sample_cosine(tentative, input.x, input.normal, u_select, u, params);
    let value = input.value * max(dot(input.normal, s.direction), 0.0);
    var pdf = 0.0;
    // Every lane reaches the barriers of the tile helpers (uniform control flow).
    if params.score_density == MCMM_SCORE_TILE_MIXTURE {
        mcmm_tile_publish(lane, tentative);
        pdf = mcmm_tile_mixture_pdf(0u, TILE, input.x, input.normal, s.direction, params);
    } else {
        pdf = mcmm_technique_pdf(tentative, input.x, s.direction, mcg_cosine_hemisphere_pdf(input.normal, s.direction), params);
    }
    let f = mcmm_ratio(value, pdf);
    let discovered = tentative;
    var current = start;
    let accepted = mcmm_update(&tentative, &current, input.x, input.hit, f, s.from_hemisphere, mcg_rng_uniform(&rng), params);
    if in_image {
        mcmm_store_current(i, current);
        let flags = select(1u, 0u, s.from_hemisphere) | select(0u, 2u, accepted);
        outputs[i] = StepOutput(discovered, pdf, s.direction, f, flags, taken, 0u, 0u);
    }
}

// The portable tile shuffles: lane l of each 32-lane tile publishes `mcg_mcmm_previous[l]`
// and receives the state of lane `mcmm_cyclic_source_lane(l, size, shift)` (inputs[0].seed =
// 0, shift = inputs[0].value as u32) or of lane `l ^ mask` with mask =
// `mcmm_select_uniform(size, inputs[0].value)` (seed = 1), for tiles of `size` =
// inputs[0].pad_a lanes (the first `size` lanes of the workgroup; the others keep theirs).
@compute @workgroup_size(32)
fn mcmm_shuffle(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let q = inputs[0];
    let size = u32(q.pad_a);
    let state = mcmm_load_previous(id.x);
    var source = lane;
    if lane < size {
        if q.seed == 0u {
            source = mcmm_cyclic_source_lane(lane, size, u32(q.value));
        } else {
            source = mcmm_xor_source_lane(lane, mcmm_select_uniform(size, q.value));
        }
    }
    let received = mcmm_tile_exchange(lane, source, state);
    mcmm_store_current(id.x, received);
}
