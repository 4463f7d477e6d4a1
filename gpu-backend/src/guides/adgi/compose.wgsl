// The heuristics words of the whole grid (ADGI sec. 4.1-4.3; `heuristics::compose_grid`): the
// probe cache's group at group 0 (`mcg::adgi`: the grid and, in `adgi_pilot_state.x`, the pilot
// rays' f_v of eq. 11), the composition's inputs at group 1
// (`GpuTriggerSmoothing::record_compose`).
//
// Per probe and octant (`probe · 8 + octant`): f_c of the probe's distance to the camera
// (eq. 10), f_s = f_c f_v (eq. 19), f_d = f_c f_v (f_Δv + μ f_Δr)/(1 + μ) (eq. 20 over its
// bound) from the smoothed triggers f_Δv, f_Δr (eq. 15, 18), packed with the word's old flags
// into the 6-10-10 word (sec. 4.3, `HeuristicsLayout::ADGI`, rounded to nearest). Every input
// is clamped as on the CPU (`heuristics::unit`: NaN → 0); sums and products round as on the
// CPU. WGSL's `sqrt`, `exp` and division are within a few ULP of the CPU's (WGSL spec,
// "Floating Point Accuracy"), so a field's code can differ by one where the CPU's value lies
// within those ULP of a rounding tie; with f_c = 1 (a probe within the threshold) f_v and f_s
// are exact.

#import mcg::constants::{
    CODEC_HEURISTICS_FLAG_BITS, CODEC_HEURISTICS_FLAG_SHIFT, CODEC_ROUND_NEAREST,
    MCG_WORKGROUP_SIZE
}
#import mcg::dispatch::mcg_invocation_index
#import mcg::math::{mcg_is_finite, mcg_is_nan, mcg_rounded}
#import mcg::color_codec::{CodecRounding, codec_bit_mask, codec_heuristics_encode}
#import mcg::adgi::{adgi_dot, adgi_params, adgi_pilot_state, adgi_probe_position}

// The composition's constants (`GpuComposeParams` on the host, 32 bytes): the camera c and
// threshold k of eq. 10, the lighting weight μ of eq. 20.
struct AdgiCompose {
    camera: vec3<f32>,
    camera_threshold: f32,
    lighting_weight: f32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

@group(1) @binding(0) var<uniform> compose_params: AdgiCompose;
// [f_Δv, f_Δr] per `probe · 8 + octant` (`GpuTriggerSmoothing::delta`).
@group(1) @binding(1) var<storage, read> compose_delta: array<vec2<f32>>;
// The heuristics words, one per `probe · 8 + octant`; their flags are kept.
@group(1) @binding(2) var<storage, read_write> compose_words: array<u32>;

// `heuristics::unit`: x clamped to [0, 1], NaN → 0 (tested on the bits: see `mcg_is_nan`).
fn adgi_unit(x: f32) -> f32 {
    return select(0.0, min(x, 1.0), x > 0.0 && !mcg_is_nan(x));
}

// `heuristics::camera_distance` (eq. 10): 1 within k of the camera, e^{−(d − k)} beyond, 0 for
// a non-finite distance.
fn adgi_camera_distance(probe: vec3<f32>, camera: vec3<f32>, k_in: f32) -> f32 {
    let v = probe - camera;
    let d = sqrt(adgi_dot(v, v));
    if !mcg_is_finite(d) {
        return 0.0;
    }
    let k = select(0.0, k_in, k_in >= 0.0);
    if d < k {
        return 1.0;
    }
    return exp(-(d - k));
}

// The word of every probe and octant.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_compose_heuristics(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= adgi_params.probe_count * 8u {
        return;
    }
    let f_c = adgi_unit(adgi_camera_distance(adgi_probe_position(i / 8u), compose_params.camera, compose_params.camera_threshold));
    let f_v = adgi_unit(adgi_pilot_state[i].x);
    let delta = compose_delta[i];
    let mu = select(0.0, compose_params.lighting_weight, compose_params.lighting_weight >= 0.0 && mcg_is_finite(compose_params.lighting_weight));
    // `static_heuristic` and `dynamic_heuristic` (eq. 19, 20 over 1 + μ).
    let f_s = f_c * f_v;
    let f_d = f_s * (adgi_unit(delta.x) + mcg_rounded(mu * adgi_unit(delta.y))) / (1.0 + mu);
    let flags = (compose_words[i] >> CODEC_HEURISTICS_FLAG_SHIFT) & codec_bit_mask(CODEC_HEURISTICS_FLAG_BITS);
    compose_words[i] = codec_heuristics_encode(vec3<f32>(f_v, f_s, f_d), flags, CodecRounding(CODEC_ROUND_NEAREST, 0.0));
}
