// MCPG grid states queried on the GPU: validity, resampling weight, velocity prediction
// (MCPG eq. 10) and the lobe at a shading point, used by the parity tests. One invocation per
// element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{Vmf, VmfMapPrior}
#import mcg::markov::{
    MarkovGridState, markov_grid_state_is_valid, markov_grid_state_lobe,
    markov_grid_state_predicted, markov_grid_state_resampling_weight
}

// The time, shading point and MAP prior of the queries (`MarkovGridQuery` on the host).
struct GridQuery {
    x: vec3<f32>,
    now: f32,
    prior_mean_cosine: f32,
    prior_weight: f32,
    prior_decay: u32,
}

@group(0) @binding(0) var<storage, read> states: array<MarkovGridState>;
@group(0) @binding(1) var<uniform> query: GridQuery;
// Per state: (valid as 0/1, resampling weight, κ of the lobe or −1 for none, 0).
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> predicted: array<MarkovGridState>;
@group(0) @binding(4) var<storage, read_write> lobes: array<Vmf>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn markov_grid_queries(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&results) {
        return;
    }
    let s = states[i];
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    let prior = VmfMapPrior(query.prior_mean_cosine, query.prior_weight, query.prior_decay);
    let found = markov_grid_state_lobe(s, query.x, prior, &lobe);
    results[i] = vec4<f32>(select(0.0, 1.0, markov_grid_state_is_valid(s)), markov_grid_state_resampling_weight(s), select(-1.0, lobe.kappa, found), 0.0);
    predicted[i] = markov_grid_state_predicted(s, query.now);
    lobes[i] = lobe;
}
