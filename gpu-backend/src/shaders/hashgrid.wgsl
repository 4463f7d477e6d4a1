#define_import_path mcg::hashgrid
// mcg-hashgrid twin: cell keys, bucket hashes and checksums, slot indexing, stochastic
// trilinear vertex choice and adaptive level choice. Mirrors mcg-hashgrid's
// `key.rs`, `hash.rs`, `capacity.rs`, `trilinear.rs` and `level.rs` (MCPG sec. 4 "Hash Grid").
//
// The table functions (`hashgrid_find`, `hashgrid_insert_or_get`) are in `hashgrid_table.wgsl`.

#import mcg::constants::{
    HASHGRID_CLASS_BITS, HASHGRID_CLASS_NONE, HASHGRID_CLASS_SHIFT, HASHGRID_COHERENT_RUN_BITS,
    HASHGRID_FIRST_CHECKSUM, HASHGRID_FOLD_FINISH, HASHGRID_FOLD_META_ROTATE, HASHGRID_FOLD_X,
    HASHGRID_FOLD_Y, HASHGRID_FOLD_Z, HASHGRID_HASH_FOLD, HASHGRID_HASH_MIX_COHERENT,
    HASHGRID_HASH_XOR_PRIMES, HASHGRID_LEVEL_BITS, HASHGRID_LEVEL_SHIFT, HASHGRID_MIX_WORD,
    HASHGRID_ONE_MINUS_EPSILON, HASHGRID_PCG_INC, HASHGRID_PCG_MUL, HASHGRID_PRIME_META,
    HASHGRID_PRIME_X, HASHGRID_PRIME_Y, HASHGRID_PRIME_Z
}
#import mcg::math::mcg_rounded

// 16 bytes, the layout of `mcg_hashgrid::CellKey`: the vertex and the meta word
// (level | class << 8 | extra << 16, the little-endian bytes of the CPU's u8, u8, u16).
struct HashgridCellKey {
    cell: vec3<i32>,
    meta_word: u32,
}

// A table's shape and place, `HashgridTableParams` on the host: the slot indexer (modulo
// `capacity`, or `& mask` when `is_mask` is 1), the probe bound, the bucket hash
// (HASHGRID_HASH_*), and where its checksum and age words start in `mcg_hashgrid_words`
// (`mcg::hashgrid_table`).
struct HashgridTable {
    capacity: u32,
    mask: u32,
    is_mask: u32,
    max_probes: u32,
    bucket_hash: u32,
    checksum_offset: u32,
    age_offset: u32,
    reserved: u32,
}

// Outcome of `hashgrid_insert_or_get` (`mcg_hashgrid::Insert`): the slot (HASHGRID_NO_SLOT when
// full) and HASHGRID_FOUND, HASHGRID_INSERTED or HASHGRID_FULL.
struct HashgridInsert {
    slot: u32,
    outcome: u32,
}

// The low `bits` bits set (bits < 32).
fn hashgrid_field_mask(bits: u32) -> u32 {
    return (1u << bits) - 1u;
}

// `CellKey::new(cell, level, class)` with extra = 0.
fn hashgrid_cell_key(cell: vec3<i32>, level: u32, normal_class: u32) -> HashgridCellKey {
    return HashgridCellKey(cell, ((normal_class & hashgrid_field_mask(HASHGRID_CLASS_BITS)) << HASHGRID_CLASS_SHIFT) | ((level & hashgrid_field_mask(HASHGRID_LEVEL_BITS)) << HASHGRID_LEVEL_SHIFT));
}

// The four words [x, y, z, meta] every hash reads.
fn hashgrid_key_words(key: HashgridCellKey) -> vec4<u32> {
    return vec4<u32>(bitcast<vec3<u32>>(key.cell), key.meta_word);
}

// `normal_class`: 2·axis + (component < 0) of the dominant axis of n.
fn hashgrid_normal_class(n: vec3<f32>) -> u32 {
    let a = abs(n);
    var axis = 2u;
    var component = n.z;
    if a.x >= a.y && a.x >= a.z {
        axis = 0u;
        component = n.x;
    } else if a.y >= a.z {
        axis = 1u;
        component = n.y;
    }
    return 2u * axis + select(0u, 1u, component < 0.0);
}

// x·π₁ ⊕ y·π₂ ⊕ z·π₃ ⊕ meta·π_meta (MCPG sec. 4, Müller et al. 2022 eq. 4).
fn hashgrid_hash_xor_primes(key: HashgridCellKey) -> u32 {
    let w = hashgrid_key_words(key);
    return (w.x * HASHGRID_PRIME_X) ^ (w.y * HASHGRID_PRIME_Y) ^ (w.z * HASHGRID_PRIME_Z) ^ (w.w * HASHGRID_PRIME_META);
}

// pcg4d (Jarzynski and Olano 2020, JCGT 9(3)): a permutation of four words; `hash.rs::pcg4d`.
fn hashgrid_pcg4d(words: vec4<u32>) -> vec4<u32> {
    var v = words * HASHGRID_PCG_MUL + HASHGRID_PCG_INC;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v ^= v >> vec4<u32>(16u);
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// Raw values 0 and 1 (HASHGRID_EMPTY, HASHGRID_TOMBSTONE) move to 2 and 3.
fn hashgrid_reserve(h: u32) -> u32 {
    return select(h, h | HASHGRID_FIRST_CHECKSUM, h < HASHGRID_FIRST_CHECKSUM);
}

// The mixing bucket hash: word HASHGRID_MIX_WORD of pcg4d([x, y, z, meta]).
fn hashgrid_hash_mix(key: HashgridCellKey) -> u32 {
    return hashgrid_pcg4d(hashgrid_key_words(key))[HASHGRID_MIX_WORD];
}

// The coherent mixing hash: hash_mix of [x >> 2, y, z, meta] ⊕ (x & 3).
fn hashgrid_hash_mix_coherent(key: HashgridCellKey) -> u32 {
    let w = hashgrid_key_words(key);
    let run = bitcast<u32>(key.cell.x >> HASHGRID_COHERENT_RUN_BITS);
    let low = w.x & ((1u << HASHGRID_COHERENT_RUN_BITS) - 1u);
    return hashgrid_pcg4d(vec4<u32>(run, w.y, w.z, w.w))[HASHGRID_MIX_WORD] ^ low;
}

// The two folds of the fold hash: (x·FOLD_X + y·FOLD_Y, z·FOLD_Z + rotl(meta, 16)); `hash.rs::folds`.
fn hashgrid_folds(key: HashgridCellKey) -> vec2<u32> {
    let w = hashgrid_key_words(key);
    let rotated = (w.w << HASHGRID_FOLD_META_ROTATE) | (w.w >> (32u - HASHGRID_FOLD_META_ROTATE));
    return vec2<u32>(w.x * HASHGRID_FOLD_X + w.y * HASHGRID_FOLD_Y, w.z * HASHGRID_FOLD_Z + rotated);
}

// The fold bucket hash (the default): t = a ^ b; t ^= t >> 16; t *= FOLD_FINISH; t ^ (t >> 15).
fn hashgrid_hash_fold(key: HashgridCellKey) -> u32 {
    let f = hashgrid_folds(key);
    var t = f.x ^ f.y;
    t = (t ^ (t >> 16u)) * HASHGRID_FOLD_FINISH;
    return t ^ (t >> 15u);
}

// The 32-bit checksum stored in a slot (every bucket hash): the second fold plus the fold
// hash, never HASHGRID_EMPTY or HASHGRID_TOMBSTONE.
fn hashgrid_checksum(key: HashgridCellKey) -> u32 {
    return hashgrid_reserve(hashgrid_folds(key).y + hashgrid_hash_fold(key));
}

// `BucketHash::hash` for HASHGRID_HASH_*.
fn hashgrid_bucket_hash(bucket_hash: u32, key: HashgridCellKey) -> u32 {
    switch bucket_hash {
        case HASHGRID_HASH_XOR_PRIMES: {
            return hashgrid_hash_xor_primes(key);
        }
        case HASHGRID_HASH_MIX_COHERENT: {
            return hashgrid_hash_mix_coherent(key);
        }
        case HASHGRID_HASH_FOLD: {
            return hashgrid_hash_fold(key);
        }
        default: {
            return hashgrid_hash_mix(key);
        }
    }
}

// `SlotIndexer::index`: h mod capacity, or h & mask for a power-of-two capacity. (The CPU's
// multiply-high form of the modulo, Lemire et al. 2019, equals h % capacity exactly.)
fn hashgrid_slot_index(table: HashgridTable, h: u32) -> u32 {
    if table.is_mask != 0u {
        return h & table.mask;
    }
    return h % table.capacity;
}

// `SlotIndexer::next`: the following slot, wrapping to 0.
fn hashgrid_next_slot(table: HashgridTable, slot: u32) -> u32 {
    let n = slot + 1u;
    return select(n, 0u, n == table.capacity);
}

// `HashTable::home_slot`.
fn hashgrid_home_slot(table: HashgridTable, key: HashgridCellKey) -> u32 {
    return hashgrid_slot_index(table, hashgrid_bucket_hash(table.bucket_hash, key));
}

// floor(x) as i32, saturating like the CPU's `floor_i32` (WGSL's i32(f32) saturates too).
fn hashgrid_floor_i32(x: f32) -> i32 {
    let t = i32(x);
    return select(t, t - 1, f32(t) > x && t != -2147483647 - 1);
}

fn hashgrid_sanitize_uniform(u: f32) -> f32 {
    if u >= 0.0 {
        return min(u, HASHGRID_ONE_MINUS_EPSILON);
    }
    return 0.0;
}

// One axis of the stochastic trilinear choice: (corner, rescaled uniform).
fn hashgrid_split(u: f32, f: f32) -> vec2<f32> {
    let lower = 1.0 - f;
    if u < lower {
        return vec2<f32>(0.0, min(u / lower, HASHGRID_ONE_MINUS_EPSILON));
    }
    return vec2<f32>(1.0, min((u - lower) / f, HASHGRID_ONE_MINUS_EPSILON));
}

// `stochastic_trilinear`: a grid vertex around q (grid units) with probability equal to its
// trilinear weight, from one uniform (MCPG sec. 4; z, then y, then x, reusing the uniform).
fn hashgrid_stochastic_trilinear(q: vec3<f32>, u_in: f32) -> vec3<i32> {
    let base = vec3<i32>(hashgrid_floor_i32(q.x), hashgrid_floor_i32(q.y), hashgrid_floor_i32(q.z));
    let f = min(max(q - vec3<f32>(base), vec3<f32>(0.0)), vec3<f32>(1.0));
    let u = hashgrid_sanitize_uniform(u_in);
    let sz = hashgrid_split(u, f.z);
    let sy = hashgrid_split(sz.y, f.y);
    let sx = hashgrid_split(sy.y, f.x);
    return base + vec3<i32>(i32(sx.x), i32(sy.x), i32(sz.x));
}

// `geometric_jitter`: k ≥ 0 with probability 2^{−(k+1)}, read off the exponent of 1 − ξ.
fn hashgrid_geometric_jitter(xi: f32) -> u32 {
    let y = 1.0 - hashgrid_sanitize_uniform(xi);
    let bits = bitcast<u32>(y);
    let exponent = 127u - ((bits >> 23u) & 0xffu);
    return exponent - select(0u, 1u, (bits & 0x007fffffu) != 0u);
}

// `AdaptiveGrid` parameters as the host precomputes them (`HashgridLevelParams` on the host).
struct HashgridLevels {
    tan_half_angle: f32,
    min_width: f32,
    levels_per_ln: f32,
    ln_per_level: f32,
    max_level: u32,
    pad_a: u32,
    pad_b: u32,
    pad_c: u32,
}

// `AdaptiveGrid::target_level`: round(ln(w/w_min) · steps/ln p), w = max(2 tan(θ/2) d, w_min).
fn hashgrid_target_level(levels: HashgridLevels, distance: f32) -> u32 {
    let w = max(2.0 * levels.tan_half_angle * distance, levels.min_width);
    let x = mcg_rounded(log(w / levels.min_width) * levels.levels_per_ln);
    return min(u32(x + 0.5), levels.max_level);
}

// `AdaptiveGrid::level`: the target level plus a geometric jitter (MCPG sec. 4).
fn hashgrid_level(levels: HashgridLevels, distance: f32, xi: f32) -> u32 {
    return min(hashgrid_target_level(levels, distance) + hashgrid_geometric_jitter(xi), levels.max_level);
}

// `AdaptiveGrid::width`: w_min · e^{level · ln p / steps}.
fn hashgrid_level_width(levels: HashgridLevels, level: u32) -> f32 {
    return levels.min_width * exp(f32(level) * levels.ln_per_level);
}

// `AdaptiveGrid::vertex_key`: level from the camera distance, vertex by stochastic trilinear
// choice, class from the normal.
fn hashgrid_vertex_key(levels: HashgridLevels, position: vec3<f32>, normal: vec3<f32>, camera: vec3<f32>, xi_level: f32, u_corner: f32) -> HashgridCellKey {
    let level = hashgrid_level(levels, distance(camera, position), xi_level);
    let vertex = hashgrid_stochastic_trilinear(position / hashgrid_level_width(levels, level), u_corner);
    return hashgrid_cell_key(vertex, level, hashgrid_normal_class(normal));
}

// `HashgridCellKey::unclassed(cell)`: level 0 and class HASHGRID_CLASS_NONE (the static grid's keys).
fn hashgrid_cell_key_unclassed(cell: vec3<i32>) -> HashgridCellKey {
    return hashgrid_cell_key(cell, 0u, HASHGRID_CLASS_NONE);
}

// `StaticGrid::vertex_key`: the stochastic trilinear vertex of position / width (MCPG sec. 4,
// the static grid: one cell width everywhere, no level and no normal in the key).
fn hashgrid_static_vertex_key(width: f32, position: vec3<f32>, u_corner: f32) -> HashgridCellKey {
    return hashgrid_cell_key_unclassed(hashgrid_stochastic_trilinear(position / width, u_corner));
}

// `jittered_vertex`: ⌊q + u⌋ for three uniforms, as ⌊q⌋ + [u ≥ 1 − f] per axis (exact where
// q + u would round): the upper vertex with probability f, independently per axis.
fn hashgrid_jittered_vertex(q: vec3<f32>, u_in: vec3<f32>) -> vec3<i32> {
    let base = vec3<i32>(hashgrid_floor_i32(q.x), hashgrid_floor_i32(q.y), hashgrid_floor_i32(q.z));
    let f = min(max(q - vec3<f32>(base), vec3<f32>(0.0)), vec3<f32>(1.0));
    let u = vec3<f32>(hashgrid_sanitize_uniform(u_in.x), hashgrid_sanitize_uniform(u_in.y), hashgrid_sanitize_uniform(u_in.z));
    return base + select(vec3<i32>(0), vec3<i32>(1), u >= vec3<f32>(1.0) - f);
}
