// Table kernels: concurrent insert-or-get, a serial insert (one invocation, in order, for
// outcome-by-outcome parity with the CPU) and lookup. The checksum words are the table.s,
// uploaded as is.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::hashgrid::{HashgridCellKey, HashgridTable, hashgrid_checksum, hashgrid_home_slot}
#import mcg::hashgrid_table::{hashgrid_find, hashgrid_insert_or_get}

@group(0) @binding(0) var<uniform> table: HashgridTable;
// Binding 1: `mcg_hashgrid_words` of `mcg::hashgrid_table` (MCG_HASHGRID_GROUP 0, MCG_HASHGRID_BINDING 1).
@group(0) @binding(2) var<storage, read> keys: array<HashgridCellKey>;
// Per key: (slot, outcome) of the insert, or (slot, 0) of a lookup.
@group(0) @binding(3) var<storage, read_write> results: array<vec2<u32>>;

fn insert_key(i: u32) {
    let key = keys[i];
    let r = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
    results[i] = vec2<u32>(r.slot, r.outcome);
}

// One invocation per key, all racing on the checksum array.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_insert(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&results) {
        insert_key(i);
    }
}

// Invocation 0 inserts every key in order: the CPU's serial sequence of outcomes.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_insert_serial(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    if mcg_invocation_index(id, groups) != 0u {
        return;
    }
    for (var i = 0u; i < arrayLength(&results); i += 1u) {
        insert_key(i);
    }
}

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_lookup(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&results) {
        let key = keys[i];
        results[i] = vec2<u32>(hashgrid_find(table, hashgrid_home_slot(table, key), hashgrid_checksum(key)), 0u);
    }
}
