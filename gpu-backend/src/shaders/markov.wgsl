#define_import_path mcg::markov
// mcg-markov-guide twin: the chain states of MCPG (a hash-grid cell's, MCPG Table 1) and MCMM
// (a pixel's, MCMM Table 1), read and written bit for bit like `mcpg/state.rs` and
// `mcmm/state.rs`.

#import mcg::math::{mcg_is_finite, mcg_is_finite3, mcg_rounded3}
#import mcg::vmf::{Vmf, VmfMapPrior, VmfSufficientStats, vmf_from_sufficient_stats}

// 32 bytes, the layout of `mcg_markov_guide::mcpg::GridState`: the sufficient statistics
// (ȳ, w̄, 1 − r̄), the time of the last update, the velocity as three IEEE half floats and the
// sample count N as a u16, packed little-endian into two words.
struct MarkovGridState {
    mean_target_x: f32,
    mean_target_y: f32,
    mean_target_z: f32,
    weight_sum: f32,
    one_minus_mean_cosine: f32,
    time: f32,
    velocity_xy: u32,
    velocity_z_count: u32,
}

// The IEEE half float in the low 16 bits of `h`, exactly, with bit operations only
// (`unpack2x16float` needs naga's SHADER_FLOAT16_IN_FLOAT32 capability on some backends).
// Infinities and NaN never occur here: the CPU clamps velocities to ±65 504 and maps NaN to 0.
fn markov_f16_to_f32(h: u32) -> f32 {
    let sign = (h & 0x8000u) << 16u;
    let exponent = (h >> 10u) & 0x1fu;
    let mantissa = h & 0x3ffu;
    if exponent == 0u {
        let magnitude = ldexp(f32(mantissa), -24);
        return bitcast<f32>(bitcast<u32>(magnitude) | sign);
    }
    return bitcast<f32>(sign | ((exponent + 112u) << 23u) | (mantissa << 13u));
}

// `GridState::velocity`: the three half floats, exactly.
fn markov_grid_state_velocity(s: MarkovGridState) -> vec3<f32> {
    return vec3<f32>(
        markov_f16_to_f32(s.velocity_xy & 0xffffu),
        markov_f16_to_f32(s.velocity_xy >> 16u),
        markov_f16_to_f32(s.velocity_z_count & 0xffffu),
    );
}

// `GridState::sample_count`.
fn markov_grid_state_sample_count(s: MarkovGridState) -> u32 {
    return s.velocity_z_count >> 16u;
}

// `GridState::stats`: the sufficient statistics, for `vmf_from_sufficient_stats`.
fn markov_grid_state_stats(s: MarkovGridState) -> VmfSufficientStats {
    return VmfSufficientStats(s.mean_target_x, s.mean_target_y, s.mean_target_z, s.weight_sum, s.one_minus_mean_cosine, markov_grid_state_sample_count(s));
}

// The IEEE half float nearest to `x` (ties to even), for |x| ≤ 65 504, as the low 16 bits:
// `half::f16::from_f32` with bit operations only (`pack2x16float` does not promise a rounding
// mode). Normal halves round the f32 mantissa to 10 bits; subnormal ones are |x|·2²⁴ rounded
// to an integer, which `round` does ties-to-even.
fn markov_f32_to_f16(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    let sign = (bits >> 16u) & 0x8000u;
    let magnitude = bits & 0x7fffffffu;
    if magnitude >= 0x38800000u {
        // 2⁻¹⁴ and above: rebias the exponent (127 → 15) and round off 13 mantissa bits.
        let rebiased = magnitude - 0x38000000u;
        return sign | ((rebiased + 0xfffu + ((rebiased >> 13u) & 1u)) >> 13u);
    }
    return sign | u32(round(bitcast<f32>(magnitude) * 16777216.0));
}

// `GridState::set_velocity`: each component clamped to ±65 504 and rounded to a half; a
// velocity with a NaN or infinite component stores 0.
fn markov_pack_velocity(velocity: vec3<f32>, count: u32) -> vec2<u32> {
    var v = vec3<f32>(0.0);
    if mcg_is_finite3(velocity) {
        v = clamp(velocity, vec3<f32>(-65504.0), vec3<f32>(65504.0));
    }
    let x = markov_f32_to_f16(v.x);
    let y = markov_f32_to_f16(v.y);
    let z = markov_f32_to_f16(v.z);
    return vec2<u32>(x | (y << 16u), z | (count << 16u));
}

// `GridState::from_stats(stats, time, velocity)`: the state written after an update (MCPG
// Alg. 3), N clamped to 65 535 and the velocity packed as three halves.
fn markov_grid_state_pack(stats: VmfSufficientStats, time: f32, velocity: vec3<f32>) -> MarkovGridState {
    let words = markov_pack_velocity(velocity, min(stats.sample_count, 65535u));
    return MarkovGridState(stats.mean_target_x, stats.mean_target_y, stats.mean_target_z, stats.weight_sum, stats.one_minus_mean_cosine, time, words.x, words.y);
}

// `GridState::is_valid`: w̄ > 0 and finite, ȳ finite.
fn markov_grid_state_is_valid(s: MarkovGridState) -> bool {
    let t = vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z);
    return s.weight_sum > 0.0 && mcg_is_finite(s.weight_sum) && mcg_is_finite3(t);
}

// `GridState::resampling_weight`: w̄ (MCPG Alg. 1 line 8), 0 for an invalid state.
fn markov_grid_state_resampling_weight(s: MarkovGridState) -> f32 {
    return select(0.0, s.weight_sum, markov_grid_state_is_valid(s));
}

// `GridState::predicted(now)`: velocity prediction on load (MCPG eq. 10), ȳ ← ȳ + (t_now − T)·v
// for the normalised ȳ stored; invalid states and non-finite results come back unchanged.
fn markov_grid_state_predicted(s: MarkovGridState, now: f32) -> MarkovGridState {
    if !markov_grid_state_is_valid(s) {
        return s;
    }
    let mean = vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z);
    let moved = mean + mcg_rounded3((now - s.time) * markov_grid_state_velocity(s));
    if !mcg_is_finite3(moved) {
        return s;
    }
    var p = s;
    p.mean_target_x = moved.x;
    p.mean_target_y = moved.y;
    p.mean_target_z = moved.z;
    return p;
}

// `GridState::lobe(x, prior)`: the lobe at shading point `x` (MCPG Alg. 2 lines 6-8); false
// for an invalid state or when ȳ coincides with `x`.
fn markov_grid_state_lobe(s: MarkovGridState, x: vec3<f32>, prior: VmfMapPrior, out: ptr<function, Vmf>) -> bool {
    if !markov_grid_state_is_valid(s) {
        return false;
    }
    return vmf_from_sufficient_stats(markov_grid_state_stats(s), x, prior, out);
}

// 28 bytes, the layout of `mcg_markov_guide::mcmm::PixelState` (MCMM Table 1): the sufficient
// statistics (ȳ, w̄, 1 − r̄, N) and the score f. All zeros is the empty state.
struct MarkovPixelState {
    stats: VmfSufficientStats,
    score: f32,
}

// `PixelState::is_valid`: w̄ > 0 and finite, ȳ finite, score finite and ≥ 0 (MCMM sec. 4.1).
fn markov_pixel_state_is_valid(s: MarkovPixelState) -> bool {
    let t = vec3<f32>(s.stats.mean_target_x, s.stats.mean_target_y, s.stats.mean_target_z);
    return s.stats.weight_sum > 0.0 && mcg_is_finite(s.stats.weight_sum) && mcg_is_finite3(t) && s.score >= 0.0 && mcg_is_finite(s.score);
}

// `PixelState::resampling_score`: score(S) = S.f of MCMM Alg. 1, 0 for an invalid state.
fn markov_pixel_state_resampling_score(s: MarkovPixelState) -> f32 {
    return select(0.0, s.score, markov_pixel_state_is_valid(s));
}

// `PixelState::lobe`: the lobe at shading point `x` with a fixed prior (MCMM Alg. 2 lines
// 5-8); false for an invalid state or when ȳ coincides with `x`.
fn markov_pixel_state_lobe(s: MarkovPixelState, x: vec3<f32>, prior: VmfMapPrior, out: ptr<function, Vmf>) -> bool {
    if !markov_pixel_state_is_valid(s) {
        return false;
    }
    return vmf_from_sufficient_stats(s.stats, x, prior, out);
}

// `PixelState { stats, score }`: the state MCMM Alg. 3 writes.
fn markov_pixel_state_pack(stats: VmfSufficientStats, score: f32) -> MarkovPixelState {
    return MarkovPixelState(stats, score);
}
