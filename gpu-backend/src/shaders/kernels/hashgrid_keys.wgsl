// Hashes, checksums and vertex keys, used by the parity tests (no
// table functions). One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::hashgrid::{
    HashgridCellKey, HashgridLevels, hashgrid_cell_key, hashgrid_checksum, hashgrid_hash_mix,
    hashgrid_hash_mix_coherent, hashgrid_hash_xor_primes, hashgrid_level, hashgrid_normal_class,
    hashgrid_stochastic_trilinear
}

// A shading point query (`HashgridVertexQuery` on the host, 48 bytes).
struct HashgridVertexQuery {
    position: vec3<f32>,
    xi_level: f32,
    normal: vec3<f32>,
    u_corner: f32,
    camera: vec3<f32>,
}

@group(0) @binding(0) var<storage, read> keys: array<HashgridCellKey>;
// Per key: (xor-primes, mix, mix-coherent, checksum).
@group(0) @binding(1) var<storage, read_write> hashes: array<vec4<u32>>;
@group(0) @binding(2) var<uniform> levels: HashgridLevels;
@group(0) @binding(3) var<storage, read> vertex_queries: array<HashgridVertexQuery>;
@group(0) @binding(4) var<storage, read_write> vertex_keys: array<HashgridCellKey>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_hashes(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&hashes) {
        let k = keys[i];
        hashes[i] = vec4<u32>(hashgrid_hash_xor_primes(k), hashgrid_hash_mix(k), hashgrid_hash_mix_coherent(k), hashgrid_checksum(k));
    }
    if i < arrayLength(&vertex_keys) {
        // The parts of `hashgrid_vertex_key` one at a time, so each can be compared: the
        // stochastic trilinear vertex of `position` read as grid coordinates, the level for
        // the camera distance, the normal class.
        let q = vertex_queries[i];
        let level = hashgrid_level(levels, distance(q.camera, q.position), q.xi_level);
        let vertex = hashgrid_stochastic_trilinear(q.position, q.u_corner);
        vertex_keys[i] = hashgrid_cell_key(vertex, level, hashgrid_normal_class(q.normal));
    }
}
