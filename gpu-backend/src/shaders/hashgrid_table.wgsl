#define_import_path mcg::hashgrid_table
// mcg-hashgrid table twin: lock-free lookup and insert-or-get (`probe.rs`, `concurrent.rs`),
// the age counter and the eviction of stale cells (`HashTable::touch`, `evict_older_than`).
//
// Storage: the words of every table a shader uses live in one storage array,
// `mcg_hashgrid_words`, bound where the shader defs MCG_HASHGRID_GROUP and
// MCG_HASHGRID_BINDING say. A `HashgridTable` descriptor names a table's checksum words
// (`checksum_offset`, `capacity` of them) and, for an age-tracked table, its age words
// (`age_offset`), so an adaptive grid, a static grid and an irradiance cache sit side by side
// in one buffer (WGSL without `unrestricted_pointer_parameters` cannot pass a storage array to
// a function; one binding works on every backend). Upload `HashTable::checksums()` /
// `ConcurrentTable::checksums()` (and `ages()`) into it as is at those offsets; the values
// stay in arrays of your own, indexed by the slot these functions return.

#import mcg::constants::{
    HASHGRID_EMPTY, HASHGRID_FOUND, HASHGRID_FULL, HASHGRID_INSERTED, HASHGRID_NO_SLOT,
    HASHGRID_TOMBSTONE
}
#import mcg::hashgrid::{HashgridInsert, HashgridTable, hashgrid_next_slot}

@group(#{MCG_HASHGRID_GROUP}) @binding(#{MCG_HASHGRID_BINDING})
var<storage, read_write> mcg_hashgrid_words: array<atomic<u32>>;

// `find`: the slot holding `checksum` within `max_probes` slots from `home` (wrapping),
// stopping at the first empty slot; HASHGRID_NO_SLOT when absent.
fn hashgrid_find(table: HashgridTable, home: u32, checksum: u32) -> u32 {
    var slot = home;
    for (var i = 0u; i < table.max_probes; i += 1u) {
        let v = atomicLoad(&mcg_hashgrid_words[table.checksum_offset + slot]);
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
        let v = atomicLoad(&mcg_hashgrid_words[table.checksum_offset + slot]);
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
        var v = atomicLoad(&mcg_hashgrid_words[table.checksum_offset + slot]);
        loop {
            if v == checksum {
                return HashgridInsert(slot, HASHGRID_FOUND);
            }
            if v != HASHGRID_EMPTY && v != HASHGRID_TOMBSTONE {
                break;
            }
            let r = atomicCompareExchangeWeak(&mcg_hashgrid_words[table.checksum_offset + slot], v, checksum);
            if r.exchanged {
                return HashgridInsert(slot, HASHGRID_INSERTED);
            }
            v = r.old_value;
        }
        slot = hashgrid_next_slot(table, slot);
    }
    return HashgridInsert(HASHGRID_NO_SLOT, HASHGRID_FULL);
}

// Age-tracked tables: the frame each slot was last inserted or touched in, at
// `table.age_offset + slot`. Eviction runs as two dispatches with no inserts in flight (the
// CPU's `evict_older_than` takes `&mut self`): `hashgrid_evict_slot` on every slot, then
// `hashgrid_trim_slot` on every slot.

// `touch`: slot used in `frame` (a relaxed store, like `ConcurrentTable::touch`), written only
// when the age changes: the invocations that read a hot slot in one frame then load it
// instead of all storing to the same word (the CPU twin keeps cache lines unshared so).
fn hashgrid_touch(table: HashgridTable, slot: u32, frame: u32) {
    let age = table.age_offset + slot;
    if atomicLoad(&mcg_hashgrid_words[age]) != frame {
        atomicStore(&mcg_hashgrid_words[age], frame);
    }
}

// Stale when frame − age > max_age, with wrapping u32 arithmetic (frames wrap too).
fn hashgrid_is_stale(age: u32, frame: u32, max_age: u32) -> bool {
    return frame - age > max_age;
}

// First pass of `evict_older_than`: a stale occupied slot becomes a tombstone. Returns
// whether it evicted (count with an atomic add; reset the slot's value yourself).
fn hashgrid_evict_slot(table: HashgridTable, slot: u32, frame: u32, max_age: u32) -> bool {
    let w = atomicLoad(&mcg_hashgrid_words[table.checksum_offset + slot]);
    if w > HASHGRID_TOMBSTONE && hashgrid_is_stale(atomicLoad(&mcg_hashgrid_words[table.age_offset + slot]), frame, max_age) {
        atomicStore(&mcg_hashgrid_words[table.checksum_offset + slot], HASHGRID_TOMBSTONE);
        return true;
    }
    return false;
}

// Second pass (`trim_tombstones`): a tombstone followed in probe order by tombstones and then
// an empty slot becomes empty (no key can sit behind it). Tombstones only ever turn empty in
// this pass, so racing invocations reach the CPU's result in any order; with no empty slot
// anywhere nothing changes, as on the CPU. Returns whether it cleared the slot.
fn hashgrid_trim_slot(table: HashgridTable, slot: u32) -> bool {
    if atomicLoad(&mcg_hashgrid_words[table.checksum_offset + slot]) != HASHGRID_TOMBSTONE {
        return false;
    }
    var s = hashgrid_next_slot(table, slot);
    for (var i = 1u; i < table.capacity; i += 1u) {
        let v = atomicLoad(&mcg_hashgrid_words[table.checksum_offset + s]);
        if v == HASHGRID_EMPTY {
            atomicStore(&mcg_hashgrid_words[table.checksum_offset + slot], HASHGRID_EMPTY);
            return true;
        }
        if v != HASHGRID_TOMBSTONE {
            return false;
        }
        s = hashgrid_next_slot(table, s);
    }
    return false;
}
