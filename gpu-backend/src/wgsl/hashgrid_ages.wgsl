// mcg-hashgrid age-counter twin: the frame each slot was last inserted or touched in, and the
// eviction of stale cells (`HashTable::touch`, `evict_older_than`; `ConcurrentTable` alike).
// Needs the prelude, `hashgrid.wgsl` and `hashgrid_table.wgsl`, and an age array the including
// shader declares beside `hashgrid_checksums`:
//
//     @group(0) @binding(2) var<storage, read_write> hashgrid_ages: array<atomic<u32>>;
//
// Upload `HashTable::ages()` / `ConcurrentTable::ages()` into it as is. Eviction runs as two
// dispatches with no inserts in flight (the CPU's `evict_older_than` takes `&mut self`):
// `hashgrid_evict_slot` on every slot, then `hashgrid_trim_slot` on every slot.

// `touch`: slot used in `frame` (a relaxed store, like `ConcurrentTable::touch`).
fn hashgrid_touch(slot: u32, frame: u32) {
    atomicStore(&hashgrid_ages[slot], frame);
}

// Stale when frame − age > max_age, with wrapping u32 arithmetic (frames wrap too).
fn hashgrid_is_stale(age: u32, frame: u32, max_age: u32) -> bool {
    return frame - age > max_age;
}

// First pass of `evict_older_than`: a stale occupied slot becomes a tombstone. Returns
// whether it evicted (count with an atomic add; reset the slot's value yourself).
fn hashgrid_evict_slot(slot: u32, frame: u32, max_age: u32) -> bool {
    let w = atomicLoad(&hashgrid_checksums[slot]);
    if w > HASHGRID_TOMBSTONE && hashgrid_is_stale(atomicLoad(&hashgrid_ages[slot]), frame, max_age) {
        atomicStore(&hashgrid_checksums[slot], HASHGRID_TOMBSTONE);
        return true;
    }
    return false;
}

// Second pass (`trim_tombstones`): a tombstone followed in probe order by tombstones and then
// an empty slot becomes empty (no key can sit behind it). Tombstones only ever turn empty in
// this pass, so racing invocations reach the CPU's result in any order; with no empty slot
// anywhere nothing changes, as on the CPU. Returns whether it cleared the slot.
fn hashgrid_trim_slot(table: HashgridTable, slot: u32) -> bool {
    if atomicLoad(&hashgrid_checksums[slot]) != HASHGRID_TOMBSTONE {
        return false;
    }
    var s = hashgrid_next_slot(table, slot);
    for (var i = 1u; i < table.capacity; i += 1u) {
        let v = atomicLoad(&hashgrid_checksums[s]);
        if v == HASHGRID_EMPTY {
            atomicStore(&hashgrid_checksums[slot], HASHGRID_EMPTY);
            return true;
        }
        if v != HASHGRID_TOMBSTONE {
            return false;
        }
        s = hashgrid_next_slot(table, s);
    }
    return false;
}
