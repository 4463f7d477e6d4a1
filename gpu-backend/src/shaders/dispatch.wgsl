#define_import_path mcg::dispatch
// mcg-gpu-backend: helpers shared by the kernels.

#import mcg::constants::MCG_WORKGROUP_SIZE

// Flat invocation index of a dispatch made by `GpuContext::dispatch`: workgroups of
// MCG_WORKGROUP_SIZE along x, rows of `num_workgroups.x` workgroups along y.
fn mcg_invocation_index(global_id: vec3<u32>, num_workgroups: vec3<u32>) -> u32 {
    return global_id.x + global_id.y * num_workgroups.x * MCG_WORKGROUP_SIZE;
}
