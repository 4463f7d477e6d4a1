// MCMM pixel states as the GPU reads them, used by the parity tests. One invocation per
// element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{Vmf, VmfMapPrior}
#import mcg::markov::{
    MarkovPixelState, markov_pixel_state_is_valid, markov_pixel_state_lobe,
    markov_pixel_state_resampling_score
}

// The shading point and the fixed MAP prior of `PixelState::lobe` (16-byte aligned uniform).
struct PixelQuery {
    x: vec3<f32>,
    prior_mean_cosine: f32,
    prior_weight: f32,
    prior_decay: u32,
}

@group(0) @binding(0) var<storage, read> pixel_states: array<MarkovPixelState>;
@group(0) @binding(1) var<uniform> query: PixelQuery;
// Per state: (resampling score, valid as 0/1, κ of the lobe or −1 for none, N).
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> lobes: array<Vmf>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn markov_pixel_states(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&results) {
        return;
    }
    let s = pixel_states[i];
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    let found = markov_pixel_state_lobe(s, query.x, VmfMapPrior(query.prior_mean_cosine, query.prior_weight, query.prior_decay), &lobe);
    results[i] = vec4<f32>(markov_pixel_state_resampling_score(s), select(0.0, 1.0, markov_pixel_state_is_valid(s)), select(-1.0, lobe.kappa, found), f32(s.stats.sample_count));
    lobes[i] = lobe;
}
