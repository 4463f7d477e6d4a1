// Reads grid states as the GPU sees them, used by the parity tests. One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::VmfSufficientStats
#import mcg::markov::{
    MarkovGridState, markov_grid_state_sample_count, markov_grid_state_stats,
    markov_grid_state_velocity
}

@group(0) @binding(0) var<storage, read> states: array<MarkovGridState>;
// Per state: (velocity, sample count as f32).
@group(0) @binding(1) var<storage, read_write> velocities: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> stats: array<VmfSufficientStats>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn markov_grid_states(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&velocities) {
        return;
    }
    let s = states[i];
    velocities[i] = vec4<f32>(markov_grid_state_velocity(s), f32(markov_grid_state_sample_count(s)));
    stats[i] = markov_grid_state_stats(s);
}
