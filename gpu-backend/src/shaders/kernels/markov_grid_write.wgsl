// MCPG grid states and MCMM pixel states written on the GPU from statistics, used by the
// parity tests. One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::VmfSufficientStats
#import mcg::markov::{
    MarkovGridState, MarkovPixelState, markov_grid_state_pack, markov_pixel_state_pack
}

// What `GridState::from_stats` takes (`MarkovGridWrite` on the host, 40 bytes).
struct MarkovGridWrite {
    stats: VmfSufficientStats,
    time: f32,
    velocity_x: f32,
    velocity_y: f32,
    velocity_z: f32,
}

@group(0) @binding(0) var<storage, read> writes: array<MarkovGridWrite>;
@group(0) @binding(1) var<storage, read_write> grid_states: array<MarkovGridState>;
// The same statistics as a pixel state with the time as its score.
@group(0) @binding(2) var<storage, read_write> pixel_states: array<MarkovPixelState>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn markov_grid_write(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&writes) {
        return;
    }
    let w = writes[i];
    grid_states[i] = markov_grid_state_pack(w.stats, w.time, vec3<f32>(w.velocity_x, w.velocity_y, w.velocity_z));
    pixel_states[i] = markov_pixel_state_pack(w.stats, w.time);
}
