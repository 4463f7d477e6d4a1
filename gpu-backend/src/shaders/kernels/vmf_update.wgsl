// One `vmf_stats_update` per element, used by the parity tests.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{VmfFitParams, VmfSufficientStats, vmf_stats_update}

// A sample: target point y seen from shading point x with weight f (`VmfUpdate`, 32 bytes).
struct VmfUpdate {
    x: vec3<f32>,
    weight: f32,
    y: vec3<f32>,
}

@group(0) @binding(0) var<storage, read_write> stats: array<VmfSufficientStats>;
@group(0) @binding(1) var<storage, read> updates: array<VmfUpdate>;
@group(0) @binding(2) var<uniform> fit: VmfFitParams;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn vmf_update(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&updates) {
        return;
    }
    var s = stats[i];
    let u = updates[i];
    vmf_stats_update(&s, u.x, u.y, u.weight, fit);
    stats[i] = s;
}
