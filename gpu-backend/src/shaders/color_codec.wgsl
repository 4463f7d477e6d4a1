#define_import_path mcg::color_codec
// mcg-color-codec twin: packed colour words (R11G11B10, RGB9E5, gamma-5 R10G10B10A2), the log
// codec of ADGI eq. 21, the 9/9/8 + 6 irradiance and 13/13 + 6 visibility words, and the
// moving-average update (ADGI sec. 4.7).
// Mirrors mcg-color-codec's `r11g11b10.rs`, `rgb9e5.rs`, `gamma5_r10g10b10a2.rs`, `math.rs`,
// `quantize.rs`, `log_codec.rs`, `irradiance_word.rs`, `visibility_word.rs` and
// `moving_average.rs`; every operation is exact or correctly rounded f32 arithmetic in the
// same order as on the CPU, so the words are bit-identical.

#import mcg::constants::{
    CODEC_FAST_EXP2_P1, CODEC_FAST_EXP2_P2, CODEC_FAST_EXP2_P3, CODEC_FAST_EXP2_P4,
    CODEC_FAST_EXP2_P5, CODEC_FAST_EXP2_P6, CODEC_FAST_LN_LN2_HI, CODEC_FAST_LN_LN2_LO,
    CODEC_FAST_LN_P0, CODEC_FAST_LN_P1, CODEC_FAST_LN_P2, CODEC_FAST_LN_P3, CODEC_FAST_LN_P4,
    CODEC_FAST_LN_P5, CODEC_FAST_LN_P6, CODEC_FAST_LN_P7, CODEC_FAST_LN_P8,
    CODEC_FAST_LN_SQRT_HALF_BITS, CODEC_GAMMA5_MAX_CODE, CODEC_GAMMA5_MIN_INPUT,
    CODEC_HEURISTICS_FD_BITS, CODEC_HEURISTICS_FD_SHIFT, CODEC_HEURISTICS_FLAG_BITS,
    CODEC_HEURISTICS_FLAG_SHIFT, CODEC_HEURISTICS_FS_BITS, CODEC_HEURISTICS_FS_SHIFT,
    CODEC_HEURISTICS_FV_BITS, CODEC_HEURISTICS_FV_SHIFT, CODEC_IRRADIANCE_B_BITS,
    CODEC_IRRADIANCE_B_DECODE_SCALE, CODEC_IRRADIANCE_B_DOWN_TOLERANCE,
    CODEC_IRRADIANCE_B_ENCODE_SCALE, CODEC_IRRADIANCE_B_EXPONENT_SCALE, CODEC_IRRADIANCE_B_GAMMA,
    CODEC_IRRADIANCE_B_INV_GAMMA, CODEC_IRRADIANCE_B_MAX_CODE, CODEC_IRRADIANCE_B_SHIFT,
    CODEC_IRRADIANCE_COUNT_BITS, CODEC_IRRADIANCE_COUNT_SHIFT, CODEC_IRRADIANCE_G_BITS,
    CODEC_IRRADIANCE_G_DECODE_SCALE, CODEC_IRRADIANCE_G_DOWN_TOLERANCE,
    CODEC_IRRADIANCE_G_ENCODE_SCALE, CODEC_IRRADIANCE_G_EXPONENT_SCALE, CODEC_IRRADIANCE_G_GAMMA,
    CODEC_IRRADIANCE_G_INV_GAMMA, CODEC_IRRADIANCE_G_MAX_CODE, CODEC_IRRADIANCE_G_SHIFT,
    CODEC_IRRADIANCE_R_BITS, CODEC_IRRADIANCE_R_DECODE_SCALE, CODEC_IRRADIANCE_R_DOWN_TOLERANCE,
    CODEC_IRRADIANCE_R_ENCODE_SCALE, CODEC_IRRADIANCE_R_EXPONENT_SCALE, CODEC_IRRADIANCE_R_GAMMA,
    CODEC_IRRADIANCE_R_INV_GAMMA, CODEC_IRRADIANCE_R_MAX_CODE, CODEC_IRRADIANCE_R_SHIFT,
    CODEC_RGB9E5_MAX, CODEC_ROUND_NEAREST, CODEC_ROUND_STOCHASTIC, CODEC_RTXGI_IRRADIANCE_GAMMA,
    CODEC_STOCHASTIC_CHANNEL_STEP, CODEC_VISIBILITY_COUNT_BITS, CODEC_VISIBILITY_COUNT_SHIFT,
    CODEC_VISIBILITY_MEAN_BITS, CODEC_VISIBILITY_MEAN_DECODE_SCALE,
    CODEC_VISIBILITY_MEAN_DOWN_TOLERANCE, CODEC_VISIBILITY_MEAN_ENCODE_SCALE,
    CODEC_VISIBILITY_MEAN_EXPONENT_SCALE, CODEC_VISIBILITY_MEAN_GAMMA,
    CODEC_VISIBILITY_MEAN_INV_GAMMA, CODEC_VISIBILITY_MEAN_MAX_CODE, CODEC_VISIBILITY_MEAN_SHIFT,
    CODEC_VISIBILITY_MEAN_SQ_BITS, CODEC_VISIBILITY_MEAN_SQ_DECODE_SCALE,
    CODEC_VISIBILITY_MEAN_SQ_DOWN_TOLERANCE, CODEC_VISIBILITY_MEAN_SQ_ENCODE_SCALE,
    CODEC_VISIBILITY_MEAN_SQ_EXPONENT_SCALE, CODEC_VISIBILITY_MEAN_SQ_GAMMA,
    CODEC_VISIBILITY_MEAN_SQ_INV_GAMMA, CODEC_VISIBILITY_MEAN_SQ_MAX_CODE,
    CODEC_VISIBILITY_MEAN_SQ_SHIFT, MCG_LOG2_E
}
#import mcg::math::{mcg_any_nan2, mcg_any_nan3, mcg_is_nan, mcg_is_positive, mcg_rounded, mcg_rounded3}

// `f32_to_ufloat`: the unsigned small float with 5 exponent bits and `n` mantissa bits
// (n = 6 for R11, 5 for B10), rounded to nearest even, negatives and NaN to 0, overflow to
// the largest finite code. The colour is the caller's: NaN is tested on the bits.
fn codec_f32_to_ufloat(v_in: f32, n: u32) -> u32 {
    let max_code = (30u << n) | ((1u << n) - 1u);
    let v = select(0.0, v_in, mcg_is_positive(v_in));
    let bits = bitcast<u32>(v);
    let exp32 = bits >> 23u;
    let sig = (bits & 0x7fffffu) | (select(0u, 1u, exp32 != 0u) << 23u);
    let e = i32(exp32) - 112;
    let shift = u32(min(23 - i32(n) + max(1 - e, 0), 31));
    var q = sig >> shift;
    let rem = sig & ((1u << shift) - 1u);
    let half = 1u << (shift - 1u);
    q += select(0u, 1u, rem > half || (rem == half && (q & 1u) == 1u));
    let code = (u32(max(e, 1) - 1) << n) + q;
    return min(code, max_code);
}

// `ufloat_to_f32`, exactly: (2ⁿ + m)·2^{E−15−n}, or m·2^{−14−n} for E = 0. `ldexp` keeps the
// small codes exact where the CPU's bit trick goes through an f32 subnormal, which a GPU may
// flush to zero.
fn codec_ufloat_to_f32(code_in: u32, n: u32) -> f32 {
    let max_code = (30u << n) | ((1u << n) - 1u);
    let code = min(code_in & ((1u << (n + 5u)) - 1u), max_code);
    let exponent = code >> n;
    let mantissa = code & ((1u << n) - 1u);
    if exponent == 0u {
        return ldexp(f32(mantissa), -14 - i32(n));
    }
    return ldexp(f32(mantissa | (1u << n)), i32(exponent) - 15 - i32(n));
}

// `R11G11B10::pack`: R and G in bits 0-10 and 11-21 (6-bit mantissa), B in 22-31 (5-bit).
fn codec_r11g11b10_pack(rgb: vec3<f32>) -> u32 {
    return codec_f32_to_ufloat(rgb.x, 6u) | (codec_f32_to_ufloat(rgb.y, 6u) << 11u) | (codec_f32_to_ufloat(rgb.z, 5u) << 22u);
}

// `R11G11B10::unpack`.
fn codec_r11g11b10_unpack(word: u32) -> vec3<f32> {
    return vec3<f32>(
        codec_ufloat_to_f32(word & 0x7ffu, 6u),
        codec_ufloat_to_f32((word >> 11u) & 0x7ffu, 6u),
        codec_ufloat_to_f32(word >> 22u, 5u),
    );
}

// 2^k for k in the normal range, built from its bits (`rgb9e5::pow2`).
fn codec_pow2(k: i32) -> f32 {
    return bitcast<f32>(u32(k + 127) << 23u);
}

// A channel clamped to [0, CODEC_RGB9E5_MAX], NaN to 0 (tested on the bits).
fn codec_rgb9e5_clamp(v: f32) -> f32 {
    if v >= 0.0 && !mcg_is_nan(v) {
        return min(v, CODEC_RGB9E5_MAX);
    }
    return 0.0;
}

// `Rgb9E5::pack`: three 9-bit mantissas sharing a 5-bit exponent (bias 15), rounded to
// nearest, the shared exponent raised when the largest channel rounds up to 512.
fn codec_rgb9e5_pack(rgb: vec3<f32>) -> u32 {
    let r = codec_rgb9e5_clamp(rgb.x);
    let g = codec_rgb9e5_clamp(rgb.y);
    let b = codec_rgb9e5_clamp(rgb.z);
    let max_c = max(max(r, g), b);
    let floor_log2 = i32(bitcast<u32>(max_c) >> 23u) - 127;
    let exp_p = max(floor_log2, -16) + 16;
    let max_m = u32(max_c * codec_pow2(24 - exp_p) + 0.5);
    let exp = exp_p + select(0, 1, max_m == 512u);
    let scale = codec_pow2(24 - exp);
    let mr = min(u32(r * scale + 0.5), 511u);
    let mg = min(u32(g * scale + 0.5), 511u);
    let mb = min(u32(b * scale + 0.5), 511u);
    return mr | (mg << 9u) | (mb << 18u) | (u32(exp) << 27u);
}

// `Rgb9E5::unpack`.
fn codec_rgb9e5_unpack(word: u32) -> vec3<f32> {
    let scale = codec_pow2(i32(word >> 27u) - 24);
    return vec3<f32>(f32(word & 0x1ffu), f32((word >> 9u) & 0x1ffu), f32((word >> 18u) & 0x1ffu)) * scale;
}

// ---------------------------------------------------------------------------------------
// Gamma-5 R10G10B10A2 (the RTXGI / DDGI irradiance format): c = v^{1/5} in 10 bits per
// channel, alpha bits set.

// `Gamma5R10G10B10A2::encode_channel`: v in [0, 1] (clamped), c = 2^{log2(v)/5} by the
// codec's own ln and exp2, rounded to nearest (ties to even) in 10 bits.
fn codec_gamma5_encode_channel(v_in: f32) -> u32 {
    let v = select(0.0, min(v_in, 1.0), v_in > CODEC_GAMMA5_MIN_INPUT && !mcg_is_nan(v_in));
    let c0 = codec_fast_exp2(codec_fast_ln_ge1(max(v, CODEC_GAMMA5_MIN_INPUT)) * (MCG_LOG2_E / CODEC_RTXGI_IRRADIANCE_GAMMA));
    let c = select(0.0, min(c0, 1.0), v > 0.0);
    return min(u32(round(c * f32(CODEC_GAMMA5_MAX_CODE))), CODEC_GAMMA5_MAX_CODE);
}

// `Gamma5R10G10B10A2::decode_channel`: c⁵ of the 10-bit code.
fn codec_gamma5_decode_channel(code: u32) -> f32 {
    let c = f32(code & CODEC_GAMMA5_MAX_CODE) * (1.0 / f32(CODEC_GAMMA5_MAX_CODE));
    let c2 = c * c;
    return c2 * c2 * c;
}

// `Gamma5R10G10B10A2::encode`.
fn codec_gamma5_pack(rgb: vec3<f32>) -> u32 {
    return codec_gamma5_encode_channel(rgb.x) | (codec_gamma5_encode_channel(rgb.y) << 10u) | (codec_gamma5_encode_channel(rgb.z) << 20u) | (3u << 30u);
}

// `Gamma5R10G10B10A2::decode`.
fn codec_gamma5_unpack(word: u32) -> vec3<f32> {
    return vec3<f32>(codec_gamma5_decode_channel(word), codec_gamma5_decode_channel(word >> 10u), codec_gamma5_decode_channel(word >> 20u));
}

// ---------------------------------------------------------------------------------------
// Log codec (ADGI eq. 21 and App. B): u = ln(1 + γv)/β, quantised to the field's codes.

// One log-coded field: the codec's γ and the field's derived scales, emitted per layout
// channel in `mcg::constants` (CODEC_<LAYOUT>_<CHANNEL>_*), so the divisions are the CPU's.
struct CodecLogField {
    gamma: f32,
    inv_gamma: f32,
    encode_scale: f32,
    exponent_scale: f32,
    decode_scale: f32,
    max_code: u32,
    down_tolerance: f32,
}

// How a value is rounded to a code (`mcg_color_codec::Rounding`): CODEC_ROUND_* and, for
// stochastic rounding, the caller's uniform in [0, 1).
struct CodecRounding {
    mode: u32,
    u: f32,
}

// `Rounding::for_channel`: channel k > 0 of a stochastic rounding uses the uniform shifted
// by k times the golden ratio's fraction, wrapped to [0, 1).
fn codec_rounding_for_channel(rounding: CodecRounding, k: u32) -> CodecRounding {
    if rounding.mode != CODEC_ROUND_STOCHASTIC || k == 0u {
        return rounding;
    }
    let v = rounding.u + mcg_rounded(f32(k) * CODEC_STOCHASTIC_CHANNEL_STEP);
    return CodecRounding(rounding.mode, v - f32(u32(v)));
}

// The reduction and polynomial shared by the two `ln`s (`math::ln_reduce`): x = 2ᵉ m with
// m ∈ [√½, √2) from the bits (musl), t = m − 1 and Cephes' logf polynomial p(t) by Estrin's
// scheme, in the CPU's order. Returns (e, t, t², p).
fn codec_ln_reduce(x: f32) -> vec4<f32> {
    let bits = bitcast<u32>(x);
    let shifted = bits - CODEC_FAST_LN_SQRT_HALF_BITS;
    let e = f32(bitcast<i32>(shifted) >> 23u);
    let m = bitcast<f32>(bits - (shifted & 0xff800000u));
    let t = m - 1.0;
    let t2 = t * t;
    let t4 = t2 * t2;
    let p01 = CODEC_FAST_LN_P0 + mcg_rounded(CODEC_FAST_LN_P1 * t);
    let p23 = CODEC_FAST_LN_P2 + mcg_rounded(CODEC_FAST_LN_P3 * t);
    let p45 = CODEC_FAST_LN_P4 + mcg_rounded(CODEC_FAST_LN_P5 * t);
    let p67 = CODEC_FAST_LN_P6 + mcg_rounded(CODEC_FAST_LN_P7 * t);
    let p03 = p01 + mcg_rounded(p23 * t2);
    let p47 = p45 + mcg_rounded(p67 * t2);
    return vec4<f32>(e, t, t2, p03 + mcg_rounded(p47 * t4) + mcg_rounded(CODEC_FAST_LN_P8 * (t4 * t4)));
}

// ln x for x ≥ 1 (`math::fast_ln_ge1`): ln 2 split into CODEC_FAST_LN_LN2_HI + CODEC_FAST_LN_LN2_LO.
fn codec_fast_ln_ge1(x: f32) -> f32 {
    let r = codec_ln_reduce(x);
    let e = r.x;
    let t = r.y;
    let t2 = r.z;
    let y = mcg_rounded(t * t2 * r.w) + mcg_rounded(e * CODEC_FAST_LN_LN2_LO) - mcg_rounded(0.5 * t2);
    return t + y + mcg_rounded(e * CODEC_FAST_LN_LN2_HI);
}

// ln x for x ≥ 1 in two parts (`math::fast_ln_parts`): (e, ln m) with ln x = e ln 2 + ln m,
// so the log codec can scale e by a pre-rounded (m/β) ln 2.
fn codec_fast_ln_parts(x: f32) -> vec2<f32> {
    let r = codec_ln_reduce(x);
    let t = r.y;
    let t2 = r.z;
    return vec2<f32>(r.x, t + (mcg_rounded(t * t2 * r.w) - mcg_rounded(0.5 * t2)));
}

// 2^x (`math::fast_exp2`): x = i + f with i = round(x) (ties to even, like the CPU's
// 1.5·2²³ trick, which a shader compiler could fold away), Cephes' exp2f polynomial.
fn codec_fast_exp2(x: f32) -> f32 {
    let i = round(x);
    let f = x - i;
    let f2 = f * f;
    let inner = CODEC_FAST_EXP2_P4 + mcg_rounded(CODEC_FAST_EXP2_P5 * f) + mcg_rounded(CODEC_FAST_EXP2_P6 * f2);
    let mid = CODEC_FAST_EXP2_P2 + mcg_rounded(CODEC_FAST_EXP2_P3 * f) + mcg_rounded(f2 * inner);
    let p = 1.0 + mcg_rounded(CODEC_FAST_EXP2_P1 * f) + mcg_rounded(f2 * mid);
    return p * bitcast<f32>(u32(i32(i) + 127) << 23u);
}

// `LogField::decode`: (2^{q·β/(m ln 2)} − 1)/γ, ≥ 0.
fn codec_log_decode(field: CodecLogField, code: u32) -> f32 {
    let q = f32(min(code, field.max_code));
    return max((codec_fast_exp2(q * field.decode_scale) - 1.0) * field.inv_gamma, 0.0);
}

// `LogField::encode`: the code of v ≥ 0 (negatives and NaN as 0) with `rounding`. Round
// down is exact: where x = ln(1 + γv)·m/β lies within the polynomial's error of an integer,
// the code is settled by decoding the candidate, as on the CPU.
fn codec_log_encode(field: CodecLogField, v_in: f32, rounding: CodecRounding) -> u32 {
    let v = max(v_in, 0.0);
    let max_code = f32(field.max_code);
    let parts = codec_fast_ln_parts(mcg_rounded(field.gamma * v) + 1.0);
    let x = min(mcg_rounded(parts.x * field.exponent_scale) + mcg_rounded(parts.y * field.encode_scale), max_code + 0.5);
    let r = round(x);
    let d = x - r;
    var code: f32;
    switch rounding.mode {
        case 0u: {
            if abs(d) <= field.down_tolerance {
                let q0 = floor(max(x - 0.5, 0.0));
                let next = min(q0 + 1.0, max_code);
                code = q0 + select(0.0, 1.0, codec_log_decode(field, u32(next)) <= v);
            } else {
                code = r - select(0.0, 1.0, d < 0.0);
            }
        }
        case 1u: {
            code = r + select(0.0, 1.0, d >= 0.5);
        }
        default: {
            let threshold = select(0.0, rounding.u, rounding.u >= 0.0);
            let q = floor(x);
            code = q + select(0.0, 1.0, x - q > threshold);
        }
    }
    return u32(min(code, max_code));
}

// The ADGI irradiance word (sec. 4.3): R, G, B log codes of 9, 9, 8 bits and a 6-bit count.
fn codec_irradiance_field(channel: u32) -> CodecLogField {
    switch channel {
        case 0u: {
            return CodecLogField(CODEC_IRRADIANCE_R_GAMMA, CODEC_IRRADIANCE_R_INV_GAMMA, CODEC_IRRADIANCE_R_ENCODE_SCALE, CODEC_IRRADIANCE_R_EXPONENT_SCALE, CODEC_IRRADIANCE_R_DECODE_SCALE, CODEC_IRRADIANCE_R_MAX_CODE, CODEC_IRRADIANCE_R_DOWN_TOLERANCE);
        }
        case 1u: {
            return CodecLogField(CODEC_IRRADIANCE_G_GAMMA, CODEC_IRRADIANCE_G_INV_GAMMA, CODEC_IRRADIANCE_G_ENCODE_SCALE, CODEC_IRRADIANCE_G_EXPONENT_SCALE, CODEC_IRRADIANCE_G_DECODE_SCALE, CODEC_IRRADIANCE_G_MAX_CODE, CODEC_IRRADIANCE_G_DOWN_TOLERANCE);
        }
        default: {
            return CodecLogField(CODEC_IRRADIANCE_B_GAMMA, CODEC_IRRADIANCE_B_INV_GAMMA, CODEC_IRRADIANCE_B_ENCODE_SCALE, CODEC_IRRADIANCE_B_EXPONENT_SCALE, CODEC_IRRADIANCE_B_DECODE_SCALE, CODEC_IRRADIANCE_B_MAX_CODE, CODEC_IRRADIANCE_B_DOWN_TOLERANCE);
        }
    }
}

fn codec_bit_mask(bits: u32) -> u32 {
    return select((1u << bits) - 1u, 0xffffffffu, bits >= 32u);
}

fn codec_irradiance_max_count() -> u32 {
    return codec_bit_mask(CODEC_IRRADIANCE_COUNT_BITS);
}

// `IrradianceLayout::ADGI.encode(rgb, count, rounding)`.
fn codec_irradiance_encode(rgb: vec3<f32>, count: u32, rounding: CodecRounding) -> u32 {
    let r = codec_log_encode(codec_irradiance_field(0u), rgb.x, codec_rounding_for_channel(rounding, 0u));
    let g = codec_log_encode(codec_irradiance_field(1u), rgb.y, codec_rounding_for_channel(rounding, 1u));
    let b = codec_log_encode(codec_irradiance_field(2u), rgb.z, codec_rounding_for_channel(rounding, 2u));
    return ((min(count, codec_irradiance_max_count()) & codec_bit_mask(CODEC_IRRADIANCE_COUNT_BITS)) << CODEC_IRRADIANCE_COUNT_SHIFT)
        | ((r & codec_bit_mask(CODEC_IRRADIANCE_R_BITS)) << CODEC_IRRADIANCE_R_SHIFT)
        | ((g & codec_bit_mask(CODEC_IRRADIANCE_G_BITS)) << CODEC_IRRADIANCE_G_SHIFT)
        | ((b & codec_bit_mask(CODEC_IRRADIANCE_B_BITS)) << CODEC_IRRADIANCE_B_SHIFT);
}

// `IrradianceLayout::ADGI.decode(word)`.
fn codec_irradiance_decode(word: u32) -> vec3<f32> {
    return vec3<f32>(
        codec_log_decode(codec_irradiance_field(0u), (word >> CODEC_IRRADIANCE_R_SHIFT) & codec_bit_mask(CODEC_IRRADIANCE_R_BITS)),
        codec_log_decode(codec_irradiance_field(1u), (word >> CODEC_IRRADIANCE_G_SHIFT) & codec_bit_mask(CODEC_IRRADIANCE_G_BITS)),
        codec_log_decode(codec_irradiance_field(2u), (word >> CODEC_IRRADIANCE_B_SHIFT) & codec_bit_mask(CODEC_IRRADIANCE_B_BITS)),
    );
}

// `IrradianceLayout::ADGI.count(word)`.
fn codec_irradiance_count(word: u32) -> u32 {
    return (word >> CODEC_IRRADIANCE_COUNT_SHIFT) & codec_bit_mask(CODEC_IRRADIANCE_COUNT_BITS);
}

// The ADGI visibility word (sec. 4.6): mean distance and mean squared distance as 13-bit
// log codes (β 5, γ 15 and β 8, γ 20) and a 6-bit count (Chebyshev visibility moments).
fn codec_visibility_field(channel: u32) -> CodecLogField {
    if channel == 0u {
        return CodecLogField(CODEC_VISIBILITY_MEAN_GAMMA, CODEC_VISIBILITY_MEAN_INV_GAMMA, CODEC_VISIBILITY_MEAN_ENCODE_SCALE, CODEC_VISIBILITY_MEAN_EXPONENT_SCALE, CODEC_VISIBILITY_MEAN_DECODE_SCALE, CODEC_VISIBILITY_MEAN_MAX_CODE, CODEC_VISIBILITY_MEAN_DOWN_TOLERANCE);
    }
    return CodecLogField(CODEC_VISIBILITY_MEAN_SQ_GAMMA, CODEC_VISIBILITY_MEAN_SQ_INV_GAMMA, CODEC_VISIBILITY_MEAN_SQ_ENCODE_SCALE, CODEC_VISIBILITY_MEAN_SQ_EXPONENT_SCALE, CODEC_VISIBILITY_MEAN_SQ_DECODE_SCALE, CODEC_VISIBILITY_MEAN_SQ_MAX_CODE, CODEC_VISIBILITY_MEAN_SQ_DOWN_TOLERANCE);
}

// `VisibilityLayout::ADGI.encode(moments, count, rounding)`: (mean, mean²).
fn codec_visibility_encode(moments: vec2<f32>, count: u32, rounding: CodecRounding) -> u32 {
    let a = codec_log_encode(codec_visibility_field(0u), moments.x, rounding);
    let b = codec_log_encode(codec_visibility_field(1u), moments.y, codec_rounding_for_channel(rounding, 1u));
    return ((a & codec_bit_mask(CODEC_VISIBILITY_MEAN_BITS)) << CODEC_VISIBILITY_MEAN_SHIFT)
        | ((b & codec_bit_mask(CODEC_VISIBILITY_MEAN_SQ_BITS)) << CODEC_VISIBILITY_MEAN_SQ_SHIFT)
        | ((min(count, codec_bit_mask(CODEC_VISIBILITY_COUNT_BITS)) & codec_bit_mask(CODEC_VISIBILITY_COUNT_BITS)) << CODEC_VISIBILITY_COUNT_SHIFT);
}

// `VisibilityLayout::ADGI.decode(word)`.
fn codec_visibility_decode(word: u32) -> vec2<f32> {
    return vec2<f32>(
        codec_log_decode(codec_visibility_field(0u), (word >> CODEC_VISIBILITY_MEAN_SHIFT) & codec_bit_mask(CODEC_VISIBILITY_MEAN_BITS)),
        codec_log_decode(codec_visibility_field(1u), (word >> CODEC_VISIBILITY_MEAN_SQ_SHIFT) & codec_bit_mask(CODEC_VISIBILITY_MEAN_SQ_BITS)),
    );
}

// `VisibilityLayout::ADGI.count(word)`.
fn codec_visibility_count(word: u32) -> u32 {
    return (word >> CODEC_VISIBILITY_COUNT_SHIFT) & codec_bit_mask(CODEC_VISIBILITY_COUNT_BITS);
}

// `quantize(x, max_code, rounding)`: x clamped to [0, max_code] (NaN to 0), truncated, and
// rounded up by `rounding` (frac ≥ ½ for nearest, frac > u for stochastic).
fn codec_quantize(x_in: f32, max_code: u32, rounding: CodecRounding) -> u32 {
    let x = min(max(x_in, 0.0), f32(max_code));
    let q = i32(x);
    let frac = x - f32(q);
    var up = false;
    if rounding.mode == CODEC_ROUND_NEAREST {
        up = frac >= 0.5;
    } else if rounding.mode == CODEC_ROUND_STOCHASTIC {
        up = frac > max(rounding.u, 0.0);
    }
    return u32(q + select(0, 1, up));
}

// The ADGI heuristics word (sec. 4.6): f_v, f_s, f_d in [0, 1] as 6-, 10- and 10-bit unorm
// fields and 6 flag bits (`HeuristicsLayout::ADGI.encode_with`).
fn codec_heuristics_encode(f: vec3<f32>, flags: u32, rounding: CodecRounding) -> u32 {
    let bits = vec3<u32>(CODEC_HEURISTICS_FV_BITS, CODEC_HEURISTICS_FS_BITS, CODEC_HEURISTICS_FD_BITS);
    let shifts = vec3<u32>(CODEC_HEURISTICS_FV_SHIFT, CODEC_HEURISTICS_FS_SHIFT, CODEC_HEURISTICS_FD_SHIFT);
    var word = (flags & codec_bit_mask(CODEC_HEURISTICS_FLAG_BITS)) << CODEC_HEURISTICS_FLAG_SHIFT;
    for (var i = 0u; i < 3u; i += 1u) {
        let max_code = codec_bit_mask(bits[i]);
        let code = codec_quantize(f[i] * f32(max_code), max_code, codec_rounding_for_channel(rounding, i));
        word |= (code & max_code) << shifts[i];
    }
    return word;
}

// `HeuristicsLayout::ADGI.decode`: (f_v, f_s, f_d) as code / max_code, and the flags (w,
// as a float).
fn codec_heuristics_decode(word: u32) -> vec4<f32> {
    let fv = codec_bit_mask(CODEC_HEURISTICS_FV_BITS);
    let fs = codec_bit_mask(CODEC_HEURISTICS_FS_BITS);
    let fd = codec_bit_mask(CODEC_HEURISTICS_FD_BITS);
    return vec4<f32>(
        f32((word >> CODEC_HEURISTICS_FV_SHIFT) & fv) / f32(fv),
        f32((word >> CODEC_HEURISTICS_FS_SHIFT) & fs) / f32(fs),
        f32((word >> CODEC_HEURISTICS_FD_SHIFT) & fd) / f32(fd),
        f32((word >> CODEC_HEURISTICS_FLAG_SHIFT) & codec_bit_mask(CODEC_HEURISTICS_FLAG_BITS)),
    );
}

// `MovingAverage::update` on an irradiance word (ADGI sec. 4.7): N ← min(N + 1, N_max),
// value ← old + (x − old)/N (x itself when N was 0), negatives clamped to 0; a NaN sample
// leaves the word unchanged (NaN tested from the bits, `mcg_is_nan`).
fn codec_irradiance_update(word: u32, sample: vec3<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    if mcg_any_nan3(sample) {
        return word;
    }
    let x = max(sample, vec3<f32>(0.0));
    let cap = min(max_count, codec_irradiance_max_count());
    let n = codec_irradiance_count(word);
    let next = min(n + 1u, cap);
    var value = x;
    if n != 0u {
        let old = codec_irradiance_decode(word);
        value = old + mcg_rounded3((x - old) * (1.0 / f32(next)));
    }
    return codec_irradiance_encode(value, next, rounding);
}

// `MovingAverage::update` on a visibility word: the same running mean of the moments
// (mean, mean²) as `codec_irradiance_update`.
fn codec_visibility_update(word: u32, sample: vec2<f32>, max_count: u32, rounding: CodecRounding) -> u32 {
    if mcg_any_nan2(sample) {
        return word;
    }
    let x = max(sample, vec2<f32>(0.0));
    let cap = min(max_count, codec_bit_mask(CODEC_VISIBILITY_COUNT_BITS));
    let n = codec_visibility_count(word);
    let next = min(n + 1u, cap);
    var value = x;
    if n != 0u {
        let old = codec_visibility_decode(word);
        let step = (x - old) * (1.0 / f32(next));
        value = old + vec2<f32>(mcg_rounded(step.x), mcg_rounded(step.y));
    }
    return codec_visibility_encode(value, next, rounding);
}
