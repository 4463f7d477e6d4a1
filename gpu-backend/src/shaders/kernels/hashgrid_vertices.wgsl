// Static-grid keys and jittered vertices, used by the parity tests. One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::hashgrid::{HashgridCellKey, hashgrid_jittered_vertex, hashgrid_static_vertex_key}

// A position with the uniforms of both vertex choices (`HashgridJitterQuery` in the tests).
struct HashgridJitterQuery {
    position: vec3<f32>,
    u_corner: f32,
    u_jitter: vec3<f32>,
    width: f32,
}

@group(0) @binding(0) var<storage, read> queries: array<HashgridJitterQuery>;
// `StaticGrid::new(width).vertex_key(position, u_corner)`.
@group(0) @binding(1) var<storage, read_write> static_keys: array<HashgridCellKey>;
// `jittered_vertex(position, u_jitter)` (w unused).
@group(0) @binding(2) var<storage, read_write> jittered: array<vec4<i32>>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_vertices(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&static_keys) {
        return;
    }
    let q = queries[i];
    static_keys[i] = hashgrid_static_vertex_key(q.width, q.position, q.u_corner);
    jittered[i] = vec4<i32>(hashgrid_jittered_vertex(q.position, q.u_jitter), 0);
}
