// The GPU MCPG guide's per-frame pass (`GpuMcpgGuide::record_end_frame`): the cache's fold, the
// two eviction passes and the frame advance of `mcg::mcpg`, the guide's group at group 0.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::mcpg::{
    mcpg_advance_frame, mcpg_evict_slot, mcpg_fold_cache_slot, mcpg_maintenance_slots,
    mcpg_trim_slot
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_fold_cache(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    mcpg_fold_cache_slot(mcg_invocation_index(id, groups));
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_evict(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < mcpg_maintenance_slots() {
        mcpg_evict_slot(i);
    }
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn mcpg_trim(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < mcpg_maintenance_slots() {
        mcpg_trim_slot(i);
    }
}

@compute @workgroup_size(1)
fn mcpg_next_frame() {
    mcpg_advance_frame();
}
