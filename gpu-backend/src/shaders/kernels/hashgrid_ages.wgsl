// Age-tracked tables: insert-and-touch (concurrent, and serial for slot-by-slot parity) and the
// two eviction passes. Each entry point binds a prefix of the bindings below.

#import mcg::constants::{HASHGRID_FULL, HASHGRID_INSERTED, MCG_WORKGROUP_SIZE}
#import mcg::dispatch::mcg_invocation_index
#import mcg::hashgrid::{HashgridCellKey, HashgridTable, hashgrid_checksum, hashgrid_home_slot}
#import mcg::hashgrid_table::{
    hashgrid_evict_slot, hashgrid_insert_or_get, hashgrid_touch, hashgrid_trim_slot
}

// The frame and the eviction age (`HashgridAgeParams` in the tests, 16 bytes).
struct HashgridAgeParams {
    frame: u32,
    max_age: u32,
    pad_a: u32,
    pad_b: u32,
}

@group(0) @binding(0) var<uniform> table: HashgridTable;
// Binding 1: `mcg_hashgrid_words` of `mcg::hashgrid_table` (MCG_HASHGRID_GROUP 0, MCG_HASHGRID_BINDING 1).
@group(0) @binding(2) var<uniform> age_params: HashgridAgeParams;
// Evicted slots (`hashgrid_evict`) or `Inserted` outcomes (the insert entry points).
@group(0) @binding(3) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read> keys: array<HashgridCellKey>;

fn insert_touch(i: u32) {
    let key = keys[i];
    let r = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
    if r.outcome != HASHGRID_FULL {
        hashgrid_touch(table, r.slot, age_params.frame);
    }
    if r.outcome == HASHGRID_INSERTED {
        atomicAdd(&counter[0], 1u);
    }
}

// One invocation per key, racing (`ConcurrentTable::insert_or_get`, which touches).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_insert_touch(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i < arrayLength(&keys) {
        insert_touch(i);
    }
}

// Invocation 0 inserts every key in order (`HashTable::insert_or_get`, slot for slot).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_insert_touch_serial(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    if mcg_invocation_index(id, groups) != 0u {
        return;
    }
    for (var i = 0u; i < arrayLength(&keys); i += 1u) {
        insert_touch(i);
    }
}

// Pass 1 of `evict_older_than`: one invocation per slot.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_evict(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = mcg_invocation_index(id, groups);
    if slot < table.capacity && hashgrid_evict_slot(table, slot, age_params.frame, age_params.max_age) {
        atomicAdd(&counter[0], 1u);
    }
}

// Pass 2: trailing tombstones cleared, one invocation per slot.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn hashgrid_trim(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = mcg_invocation_index(id, groups);
    if slot < table.capacity {
        hashgrid_trim_slot(table, slot);
    }
}
