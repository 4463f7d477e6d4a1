//! Flushing a table or a hashbrown-layout map from every cache level (`clflush`), for the
//! cold-cache passes of `benches/peers.rs` and `examples/instructions.rs`.
// `clflush` over raw addresses (SAFETY notes at each block); the crate lints deny unsafe code
// elsewhere.
#![allow(unsafe_code, dead_code)]

use mcg_hashgrid::HashTable;

use super::lookups::State;

/// Flushes every cache line of `bytes` from all cache levels.
pub fn flush(bytes: &[u8]) {
    for line in bytes.chunks(64) {
        // SAFETY: `clflush` of an address inside a live allocation (the slice); SSE2 is part
        // of the x86-64 baseline.
        #[cfg(target_arch = "x86_64")]
        unsafe {
            std::arch::x86_64::_mm_clflush(line.as_ptr());
        }
        #[cfg(not(target_arch = "x86_64"))]
        std::hint::black_box(line);
    }
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a fence has no memory-safety preconditions.
    unsafe {
        std::arch::x86_64::_mm_mfence();
    }
}

/// Flushes the table's checksum and value arrays.
pub fn flush_table(t: &HashTable<State>) {
    flush(bytemuck::cast_slice(t.checksums()));
    flush(bytemuck::cast_slice(t.values()));
}

/// Flushes a hashbrown-layout map (std's `HashMap` is hashbrown): every entry, and the
/// control bytes, which follow the entry of bucket 0, the highest entry address: from the
/// end of the highest occupied entry on, one byte per bucket (buckets: the power of two
/// above 8/7 of the capacity).
pub fn flush_entries<'a>(entries: impl Iterator<Item = (&'a u64, &'a State)>, capacity: usize) {
    let mut top = 0_usize;
    for (k, _) in entries {
        let p = std::ptr::from_ref(k).cast::<u8>();
        // SAFETY: one entry (`(u64, State)`, 40 bytes) of the live map starts at `p`.
        flush(unsafe { std::slice::from_raw_parts(p, 40) });
        top = top.max(p as usize);
    }
    let buckets = (capacity * 8 / 7).next_power_of_two();
    let ctrl = (top + 40) as *const u8;
    // SAFETY: the control bytes start at or after the end of the highest entry and span
    // `buckets + 16` bytes, so these `buckets` bytes lie inside the map's allocation.
    flush(unsafe { std::slice::from_raw_parts(ctrl, buckets) });
}
