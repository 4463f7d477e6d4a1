// mcg-markov-guide twin: the MCPG world-space chain state of a hash-grid cell (MCPG Table 1).
// Needs the prelude and `vmf.wgsl`. Mirrors `mcpg/state.rs`.

// 32 bytes, the layout of `mcg_markov_guide::mcpg::GridState`: the sufficient statistics
// (ȳ, w̄, 1 − r̄), the time of the last update, the velocity as three IEEE half floats and the
// sample count N as a u16, packed little-endian into two words.
struct GridState {
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
fn markov_grid_state_velocity(s: GridState) -> vec3<f32> {
    return vec3<f32>(
        markov_f16_to_f32(s.velocity_xy & 0xffffu),
        markov_f16_to_f32(s.velocity_xy >> 16u),
        markov_f16_to_f32(s.velocity_z_count & 0xffffu),
    );
}

// `GridState::sample_count`.
fn markov_grid_state_sample_count(s: GridState) -> u32 {
    return s.velocity_z_count >> 16u;
}

// `GridState::stats`: the sufficient statistics, for `vmf_from_sufficient_stats`.
fn markov_grid_state_stats(s: GridState) -> SufficientStats {
    return SufficientStats(s.mean_target_x, s.mean_target_y, s.mean_target_z, s.weight_sum, s.one_minus_mean_cosine, markov_grid_state_sample_count(s));
}

// 28 bytes, the layout of `mcg_markov_guide::mcmm::PixelState` (MCMM Table 1): the sufficient
// statistics (ȳ, w̄, 1 − r̄, N) and the score f. All zeros is the empty state.
struct PixelState {
    stats: SufficientStats,
    score: f32,
}

fn markov_is_finite(x: f32) -> bool {
    return abs(x) <= MCG_F32_MAX;
}

// `PixelState::is_valid`: w̄ > 0 and finite, ȳ finite, score finite and ≥ 0 (MCMM sec. 4.1).
fn markov_pixel_state_is_valid(s: PixelState) -> bool {
    let t = vec3<f32>(s.stats.mean_target_x, s.stats.mean_target_y, s.stats.mean_target_z);
    return s.stats.weight_sum > 0.0 && markov_is_finite(s.stats.weight_sum) && vmf_is_finite3(t) && s.score >= 0.0 && markov_is_finite(s.score);
}

// `PixelState::resampling_score`: score(S) = S.f of MCMM Alg. 1, 0 for an invalid state.
fn markov_pixel_state_resampling_score(s: PixelState) -> f32 {
    return select(0.0, s.score, markov_pixel_state_is_valid(s));
}

// `PixelState::lobe`: the lobe at shading point `x` with a fixed prior (MCMM Alg. 2 lines
// 5-8); false for an invalid state or when ȳ coincides with `x`.
fn markov_pixel_state_lobe(s: PixelState, x: vec3<f32>, prior: VmfMapPrior, out: ptr<function, Vmf>) -> bool {
    if !markov_pixel_state_is_valid(s) {
        return false;
    }
    return vmf_from_sufficient_stats(s.stats, x, prior, out);
}
