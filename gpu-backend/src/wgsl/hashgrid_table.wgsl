// mcg-hashgrid table twin: lock-free lookup and insert-or-get on a checksum array
// (`probe.rs`, `concurrent.rs`). Needs the prelude and `hashgrid.wgsl`, and a checksum array
// the including shader declares under this name:
//
//     @group(0) @binding(1) var<storage, read_write> hashgrid_checksums: array<atomic<u32>>;
//
// (WGSL without the `unrestricted_pointer_parameters` extension cannot pass a storage array
// to a function). Upload `HashTable::checksums()` / `ConcurrentTable::checksums()` into it as
// is; the values array stays the caller's, indexed by the slot these functions return.

// `find`: the slot holding `checksum` within `max_probes` slots from `home` (wrapping),
// stopping at the first empty slot; HASHGRID_NO_SLOT when absent.
fn hashgrid_find(table: HashgridTable, home: u32, checksum: u32) -> u32 {
    var slot = home;
    for (var i = 0u; i < table.max_probes; i += 1u) {
        let v = atomicLoad(&hashgrid_checksums[slot]);
        if v == checksum {
            return slot;
        }
        if v == HASHGRID_EMPTY {
            return HASHGRID_NO_SLOT;
        }
        slot = hashgrid_next_slot(table, slot);
    }
    return HASHGRID_NO_SLOT;
}

// `insert_or_get`: the slot of `checksum` if present, else claims the first empty or
// tombstone slot with a compare-and-swap (which may fail spuriously and is retried; a slot
// taken by another key moves on), else HASHGRID_FULL after `max_probes` slots.
fn hashgrid_insert_or_get(table: HashgridTable, home: u32, checksum: u32) -> HashgridInsert {
    var slot = home;
    var first_free = table.max_probes;
    var first_free_slot = 0u;
    for (var i = 0u; i < table.max_probes; i += 1u) {
        let v = atomicLoad(&hashgrid_checksums[slot]);
        if v == checksum {
            return HashgridInsert(slot, HASHGRID_FOUND);
        }
        if v == HASHGRID_EMPTY || v == HASHGRID_TOMBSTONE {
            if first_free == table.max_probes {
                first_free = i;
                first_free_slot = slot;
            }
            if v == HASHGRID_EMPTY {
                break;
            }
        }
        slot = hashgrid_next_slot(table, slot);
    }
    if first_free == table.max_probes {
        return HashgridInsert(HASHGRID_NO_SLOT, HASHGRID_FULL);
    }
    slot = first_free_slot;
    for (var i = first_free; i < table.max_probes; i += 1u) {
        var v = atomicLoad(&hashgrid_checksums[slot]);
        loop {
            if v == checksum {
                return HashgridInsert(slot, HASHGRID_FOUND);
            }
            if v != HASHGRID_EMPTY && v != HASHGRID_TOMBSTONE {
                break;
            }
            let r = atomicCompareExchangeWeak(&hashgrid_checksums[slot], v, checksum);
            if r.exchanged {
                return HashgridInsert(slot, HASHGRID_INSERTED);
            }
            v = r.old_value;
        }
        slot = hashgrid_next_slot(table, slot);
    }
    return HashgridInsert(HASHGRID_NO_SLOT, HASHGRID_FULL);
}
