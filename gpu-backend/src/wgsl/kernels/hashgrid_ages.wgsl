// Age-tracked tables: insert-and-touch (concurrent, and serial for slot-by-slot parity) and
// the two eviction passes. Composed after the prelude, `common.wgsl`, `hashgrid.wgsl`,
// `hashgrid_table.wgsl` and `hashgrid_ages.wgsl`. Each entry point binds a prefix of the
// bindings below.

// The frame and the eviction age (`HashgridAgeParams` in the tests, 16 bytes).
struct HashgridAgeParams {
    frame: u32,
    max_age: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> table: HashgridTable;
@group(0) @binding(1) var<storage, read_write> hashgrid_checksums: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> hashgrid_ages: array<atomic<u32>>;
@group(0) @binding(3) var<uniform> age_params: HashgridAgeParams;
// Evicted slots (`hashgrid_evict`) or `Inserted` outcomes (the insert entry points).
@group(0) @binding(4) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> keys: array<CellKey>;

fn insert_touch(i: u32) {
    let key = keys[i];
    let r = hashgrid_insert_or_get(table, hashgrid_home_slot(table, key), hashgrid_checksum(key));
    if r.outcome != HASHGRID_FULL {
        hashgrid_touch(r.slot, age_params.frame);
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
    if slot < table.capacity && hashgrid_evict_slot(slot, age_params.frame, age_params.max_age) {
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
