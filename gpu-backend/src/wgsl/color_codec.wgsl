// mcg-color-codec twin: packed colour words (R11G11B10, RGB9E5, gamma-5 R10G10B10A2), the log
// codec of ADGI eq. 21, the 9/9/8 + 6 irradiance and 13/13 + 6 visibility words, and the
// moving-average update (ADGI sec. 4.7) as a compare-and-swap loop. Needs the prelude.
// Mirrors mcg-color-codec's `r11g11b10.rs`, `rgb9e5.rs`, `gamma5_r10g10b10a2.rs`, `math.rs`,
// `quantize.rs`, `log_codec.rs`, `irradiance_word.rs`, `visibility_word.rs` and
// `moving_average.rs`; every operation is exact or correctly rounded f32 arithmetic in the
// same order as on the CPU, so the words are bit-identical.

// `f32_to_ufloat`: the unsigned small float with 5 exponent bits and `n` mantissa bits
// (n = 6 for R11, 5 for B10), rounded to nearest even, negatives and NaN to 0, overflow to
// the largest finite code.
fn codec_f32_to_ufloat(v_in: f32, n: u32) -> u32 {
    let max_code = (30u << n) | ((1u << n) - 1u);
    let v = select(0.0, v_in, v_in > 0.0);
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

fn codec_rgb9e5_clamp(v: f32) -> f32 {
    if v >= 0.0 {
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
