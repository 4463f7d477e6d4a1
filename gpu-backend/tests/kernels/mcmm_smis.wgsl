// MCMM Fig. 16 on the GPU: one frame of MCMM chains per 32-pixel tile (one workgroup, one
// image row) on a toy scene, a sphere light of radiance L above the plane z = 0, estimated with
// TSMIS (n-sample SMIS over a pixel's n (technique, sample) pairs, MCMM eq. 8) or SSMIS (the
// one-sample estimator over the tile's states at each step, eq. 9), with or without the
// decorrelating permutation of sec. 4.2 done through workgroup memory. The guide's bindings
// are in group 1; the window is 0, so Alg. 1 only re-offers the pixel's own previous state
// and tiles (rows) are independent. With the shader def MCG_MCMM_SUBGROUPS the tile is one
// subgroup and the shuffles are subgroup shuffles (the rows stay the independent units).

#import mcg::markov::MarkovPixelState
#import mcg::sampling::{mcg_cosine_hemisphere_pdf, mcg_pcg_hash, mcg_rng_uniform, mcg_rng_uniform2, mcg_uniform_float}
#ifdef MCG_MCMM_SUBGROUPS
#import mcg::mcmm::{mcmm_subgroup_exchange, mcmm_subgroup_mixture_pdf}
#endif
#import mcg::mcmm::{
    mcg_mcmm_params, mcmm_collaborative_discovery, mcmm_cyclic_source_lane, mcmm_load_previous,
    mcmm_ratio, mcmm_sample_cosine, mcmm_select_uniform, mcmm_store_current, mcmm_technique_pdf,
    mcmm_tile_exchange, mcmm_tile_mixture_pdf, mcmm_tile_publish, mcmm_update,
    mcmm_xor_source_lane
}

struct Frame {
    light_centre: vec3<f32>,
    light_radius: f32,
    origin: vec3<f32>,
    spacing: f32,
    radiance: f32,
    seed: u32,
    // 0: TSMIS shuffled, 1: SSMIS shuffled, 2: TSMIS unshuffled, 3: SSMIS unshuffled.
    scheme: u32,
    steps: u32,
}

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read_write> estimates: array<f32>;

const TILE: u32 = 32u;
const MAX_STEPS: u32 = 8u;

// The light's radiance along ω from x, and the point the ray reaches (the sphere or far away).
fn trace(x: vec3<f32>, w: vec3<f32>, hit: ptr<function, vec3<f32>>) -> f32 {
    let oc = x - frame.light_centre;
    let b = dot(oc, w);
    let c = dot(oc, oc) - frame.light_radius * frame.light_radius;
    let disc = b * b - c;
    *hit = x + 100.0 * w;
    if disc < 0.0 {
        return 0.0;
    }
    let t = -b - sqrt(disc);
    if t <= 0.0 {
        return 0.0;
    }
    *hit = x + t * w;
    return frame.radiance;
}

// The tile's shuffle: workgroup memory, or the subgroup.
fn exchange(lane: u32, source: u32, state: MarkovPixelState) -> MarkovPixelState {
#ifdef MCG_MCMM_SUBGROUPS
    return mcmm_subgroup_exchange(source, state);
#else
    return mcmm_tile_exchange(lane, source, state);
#endif
}

@compute @workgroup_size(32)
fn mcmm_smis_frame(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(workgroup_id) workgroup: vec3<u32>,
#ifdef MCG_MCMM_SUBGROUPS
    @builtin(subgroup_invocation_id) lane: u32,
    @builtin(subgroup_size) tile_size: u32,
#else
    @builtin(local_invocation_index) lane: u32,
#endif
) {
#ifndef MCG_MCMM_SUBGROUPS
    let tile_size = TILE;
#endif
    let params = mcg_mcmm_params;
    let i = id.x;
    let pixel = vec2<i32>(i32(i % params.width), i32(i / params.width));
    let x = frame.origin + frame.spacing * vec3<f32>(f32(pixel.x), 0.0, 0.0);
    let normal = vec3<f32>(0.0, 0.0, 1.0);
    var rng = mcg_pcg_hash(i ^ mcg_pcg_hash(frame.seed));
    let start = mcmm_load_previous(i);
    var tentative = start;
    var current = start;
    let temporal = frame.scheme == 0u || frame.scheme == 2u;
    let shuffled = frame.scheme < 2u;
    let steps = min(frame.steps, MAX_STEPS);
    var states: array<MarkovPixelState, MAX_STEPS>;
    var directions: array<vec3<f32>, MAX_STEPS>;
    var values: array<f32, MAX_STEPS>;
    var estimate = 0.0;
    for (var step = 0u; step < steps; step++) {
        if temporal && shuffled {
            // TSMIS: shift the chains (S and S_c) by one lane (Alg. 1 line 1).
            let source = mcmm_cyclic_source_lane(lane, tile_size, 1u);
            tentative = exchange(lane, source, tentative);
            current = exchange(lane, source, current);
        }
        var taken = 0u;
        tentative = mcmm_collaborative_discovery(tentative, pixel, vec2<f32>(0.0), params, &rng, &taken);
        if !temporal && shuffled {
            // SSMIS: a random xor mask, the same for the whole tile.
            // (Per workgroup, so also the same for every lane of a subgroup.)
            let u_mask = mcg_uniform_float(mcg_pcg_hash(workgroup.x ^ mcg_pcg_hash(frame.seed + 0x9e3779b9u * (step + 1u))));
            let source = mcmm_xor_source_lane(lane, mcmm_select_uniform(tile_size, u_mask));
            tentative = exchange(lane, source, tentative);
            current = exchange(lane, source, current);
        }
        let u_select = mcg_rng_uniform(&rng);
        let s = mcmm_sample_cosine(tentative, x, normal, u_select, mcg_rng_uniform2(&rng), params);
        var hit: vec3<f32>;
        let value = trace(x, s.direction, &hit) * max(dot(normal, s.direction), 0.0);
        let p = mcmm_technique_pdf(tentative, x, s.direction, mcg_cosine_hemisphere_pdf(normal, s.direction), params);
        if temporal {
            states[step] = tentative;
            directions[step] = s.direction;
            values[step] = value;
        } else {
#ifdef MCG_MCMM_SUBGROUPS
            let mixture = mcmm_subgroup_mixture_pdf(tentative, tile_size, x, normal, s.direction, params);
#else
            mcmm_tile_publish(lane, tentative);
            let mixture = mcmm_tile_mixture_pdf(0u, TILE, x, normal, s.direction, params);
#endif
            estimate += mcmm_ratio(value, mixture) / f32(steps);
        }
        mcmm_update(&tentative, &current, x, hit, mcmm_ratio(value, p), s.from_hemisphere, mcg_rng_uniform(&rng), params);
    }
    if temporal {
        // Eq. 8 over the pixel's n (technique, sample) pairs of this frame.
        for (var k = 0u; k < steps; k++) {
            let hemisphere = mcg_cosine_hemisphere_pdf(normal, directions[k]);
            var sum = 0.0;
            for (var j = 0u; j < steps; j++) {
                sum += mcmm_technique_pdf(states[j], x, directions[k], hemisphere, params);
            }
            estimate += mcmm_ratio(values[k], sum);
        }
    }
    mcmm_store_current(i, current);
    estimates[i] = estimate;
}
