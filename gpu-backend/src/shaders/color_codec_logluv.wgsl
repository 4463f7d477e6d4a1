#define_import_path mcg::color_codec_logluv
// mcg-color-codec LogLuv32 twin (`logluv32.rs`): Ward's LogLuv32 (Larson 1998; libtiff's
// `Luv32fromXYZ` without dithering), sign | Le: 15 | ue: 8 | ve: 8 with
// Le = ⌊256 (log₂ Y + 64)⌋, ue = ⌊410 u′⌋, ve = ⌊410 v′⌋. LogLuv's two step
// tables (512 floats from `mcg_gpu_backend::shaders::constants::logluv_tables()`, read off the
// CPU encoder and decoder) live in the storage array `mcg_codec_logluv_tables`, bound where
// the shader defs MCG_CODEC_LOGLUV_GROUP and MCG_CODEC_LOGLUV_BINDING say
// (as WGSL `const` arrays indexed at run time, the tables cost lavapipe seconds of
// compilation per use; a storage array costs nothing).
//
// The CPU encodes in f64, which WGSL lacks. The twin decides the same codes exactly in f32:
// Le from the exponent of Y and its mantissa's place among the log₂ steps T[k], and
// ue, ve from an f32 candidate that an exact sign test of k·S − 410·4X (or 9Y) moves by at
// most one; S = X + 15Y + 3Z. Where 410 u′ lies within ~2⁻⁵⁰ below an integer, the CPU's
// f64 rounding lands on the integer and so does the twin (within 2⁻⁴⁹); only quotients
// within 2⁻⁵²..2⁻⁴⁹ of an integer, where f64 itself may go either way, can differ. Every sum whose rounding matters is wrapped in `mcg_rounded`, so the compiler
// can neither fuse nor reassociate it. The decoder's Y is E[Le mod 256] · 2^{⌊Le/256⌋ − 64}.

#import mcg::constants::{
    CODEC_LOGLUV_INV_UV_SCALE, CODEC_LOGLUV_LE_MAX, CODEC_LOGLUV_NEUTRAL_UE,
    CODEC_LOGLUV_NEUTRAL_VE, CODEC_LOGLUV_SRGB_TO_XYZ_0, CODEC_LOGLUV_SRGB_TO_XYZ_1,
    CODEC_LOGLUV_SRGB_TO_XYZ_2, CODEC_LOGLUV_SRGB_TO_XYZ_3, CODEC_LOGLUV_SRGB_TO_XYZ_4,
    CODEC_LOGLUV_SRGB_TO_XYZ_5, CODEC_LOGLUV_SRGB_TO_XYZ_6, CODEC_LOGLUV_SRGB_TO_XYZ_7,
    CODEC_LOGLUV_SRGB_TO_XYZ_8, CODEC_LOGLUV_UV_SCALE, CODEC_LOGLUV_XYZ_TO_SRGB_0,
    CODEC_LOGLUV_XYZ_TO_SRGB_1, CODEC_LOGLUV_XYZ_TO_SRGB_2, CODEC_LOGLUV_XYZ_TO_SRGB_3,
    CODEC_LOGLUV_XYZ_TO_SRGB_4, CODEC_LOGLUV_XYZ_TO_SRGB_5, CODEC_LOGLUV_XYZ_TO_SRGB_6,
    CODEC_LOGLUV_XYZ_TO_SRGB_7, CODEC_LOGLUV_XYZ_TO_SRGB_8, CODEC_LOGLUV_Y_MAX, CODEC_LOGLUV_Y_MIN,
    MCG_F32_MAX
}
#import mcg::math::{mcg_positive_part3, mcg_rounded, mcg_rounded3}

@group(#{MCG_CODEC_LOGLUV_GROUP}) @binding(#{MCG_CODEC_LOGLUV_BINDING})
var<storage, read> mcg_codec_logluv_tables: array<f32>;

// The twin of a sum's rounding error (Knuth's TwoSum): (a + b, a + b − fl(a + b)), exact.
fn codec_two_sum(a: f32, b: f32) -> vec2<f32> {
    // Each step wrapped, so that no algebraic rewrite ((a + b) − a → b) can see through it.
    let s = mcg_rounded(a + b);
    let bb = mcg_rounded(s - a);
    return vec2<f32>(s, mcg_rounded(a - mcg_rounded(s - bb)) + mcg_rounded(b - bb));
}

// c · v for integer coefficients |c| < 2¹², with the exact sign and to f32 precision: each vᵢ
// is split into 12 + 12 significant bits so every product is exact, and the six products are
// summed into a non-overlapping expansion (Shewchuk's grow-expansion), whose largest nonzero
// term has the sum's sign and approximates it.
fn codec_exact_dot(c: vec3<f32>, v: vec3<f32>) -> f32 {
    var terms: array<f32, 6>;
    for (var i = 0u; i < 3u; i += 1u) {
        let hi = bitcast<f32>(bitcast<u32>(v[i]) & 0xfffff000u);
        terms[2u * i] = c[i] * hi;
        terms[2u * i + 1u] = c[i] * (v[i] - hi);
    }
    var e: array<f32, 6>;
    for (var n = 0u; n < 6u; n += 1u) {
        var q = terms[n];
        for (var i = 0u; i < n; i += 1u) {
            let r = codec_two_sum(q, e[i]);
            e[i] = r.y;
            q = r.x;
        }
        e[n] = q;
    }
    for (var i = 5; i >= 0; i -= 1) {
        if e[i] != 0.0 {
            return e[i];
        }
    }
    return 0.0;
}

// min(⌊scale · w/S⌋, 255) for the scaled components v (max in [1, 2)) where w = v.x (scale =
// 4·410) or v.y (scale = 9·410): an f32 candidate, moved by the exact sign of
// scale · w − k S = (scale·[w is x] − k) X + (scale·[w is y] − 15k) Y − 3k Z.
fn codec_logluv_chroma(v: vec3<f32>, pick: vec3<f32>, scale: f32) -> u32 {
    let s = v.x + mcg_rounded(15.0 * v.y) + mcg_rounded(3.0 * v.z);
    let w = dot(v, pick);
    let q = mcg_rounded(scale * w) / s;
    var k = min(floor(q), 255.0);
    // q is within a few ulps (≤ 5 ulp, 1.5·10⁻⁴ absolute for q ≤ 256; the division counted
    // at WGSL's 2.5 ulp) of the exact quotient: farther than 2⁻¹⁰ from an integer its floor is
    // exact, and only the rest (≈ 0.2 % of colours) takes the exact test.
    if abs(q - round(q)) > 0.0009765625 || q > 256.0 {
        return u32(k);
    }
    // The CPU computes in f64: where the exact quotient lies within ~2⁻⁵⁰ below an integer
    // (S then carries terms f64 drops), its rounding lands on the integer. Within τ the
    // twin rounds up the same way.
    let tau = ldexp(scale * w, -49);
    let up = k + 1.0;
    let here = k;
    if k < 255.0 && codec_exact_dot(pick * scale - vec3<f32>(up, 15.0 * up, 3.0 * up), v) >= -tau {
        k = up;
    } else if k > 0.0 && codec_exact_dot(pick * scale - vec3<f32>(here, 15.0 * here, 3.0 * here), v) < -tau {
        k -= 1.0;
    }
    return u32(k);
}

// `LogLuv32::pack_xyz`: CIE XYZ (negatives and NaN as 0) to the word.
fn codec_logluv32_pack_xyz(xyz: vec3<f32>) -> u32 {
    let c = mcg_positive_part3(xyz);
    let y = c.y;
    var le = 0u;
    if y >= CODEC_LOGLUV_Y_MAX {
        le = CODEC_LOGLUV_LE_MAX;
    } else if y > CODEC_LOGLUV_Y_MIN {
        // Y = 2ᵉ m, m ∈ [1, 2) (Y is normal here): Le = 256 (e + 64) + #{k ≥ 1 : m ≥ T[k]}.
        let bits = bitcast<u32>(y);
        let e = i32(bits >> 23u) - 127;
        let m = bitcast<f32>((bits & 0x007fffffu) | 0x3f800000u);
        // WGSL's log₂ is within 2⁻²¹ on [1, 2), so 256 log₂ m is within 10⁻³ of the truth and
        // the step count off by at most one: two table reads settle it exactly.
        let k0 = u32(clamp(floor(256.0 * log2(m)), 0.0, 255.0));
        var k = k0;
        if k0 < 255u && m >= mcg_codec_logluv_tables[k0 + 1u] {
            k = k0 + 1u;
        } else if k0 > 0u && m < mcg_codec_logluv_tables[k0] {
            k = k0 - 1u;
        }
        le = u32(max(256 * (e + 64) + i32(k), 0));
    }
    if le == 0u || !(c.x + c.y + c.z > 0.0) {
        return (le << 16u) | (CODEC_LOGLUV_NEUTRAL_UE << 8u) | CODEC_LOGLUV_NEUTRAL_VE;
    }
    if any(c > vec3<f32>(MCG_F32_MAX)) {
        // S = ∞: u′ and v′ are 0 (or NaN, which the CPU's cast also turns into 0).
        return le << 16u;
    }
    // Scale so the largest component is in [1, 2): exact, and u′, v′ are ratios.
    let largest = max(max(c.x, c.y), c.z);
    let v = ldexp(c, vec3<i32>(-(i32(bitcast<u32>(largest) >> 23u) - 127)));
    let uv = f32(CODEC_LOGLUV_UV_SCALE);
    let ue = codec_logluv_chroma(v, vec3<f32>(1.0, 0.0, 0.0), 4.0 * uv);
    let ve = codec_logluv_chroma(v, vec3<f32>(0.0, 1.0, 0.0), 9.0 * uv);
    return (le << 16u) | (ue << 8u) | ve;
}

// `LogLuv32::unpack_xyz`: Y = E[Le mod 256] · 2^{⌊Le/256⌋ − 64}, u′ = (ue + ½)/410,
// v′ = (ve + ½)/410; black for Le = 0 and for words with the sign bit.
fn codec_logluv32_unpack_xyz(word: u32) -> vec3<f32> {
    let le = (word >> 16u) & CODEC_LOGLUV_LE_MAX;
    if le == 0u || (word >> 31u) != 0u {
        return vec3<f32>(0.0);
    }
    let y = ldexp(mcg_codec_logluv_tables[256u + (le & 255u)], i32(le >> 8u) - 64);
    let u = mcg_rounded((f32((word >> 8u) & 0xffu) + 0.5) * CODEC_LOGLUV_INV_UV_SCALE);
    let v = mcg_rounded((f32(word & 0xffu) + 0.5) * CODEC_LOGLUV_INV_UV_SCALE);
    // Every step wrapped: besides fusing, compilers reassociate constants ((a − b) + 12 as
    // (a + 12) − b, 9 (a · c) as a (9c) on lavapipe), which WGSL does not forbid either.
    let s = 1.0 / (mcg_rounded(mcg_rounded(6.0 * u) - 16.0 * v) + 12.0);
    let cx = mcg_rounded(mcg_rounded(9.0 * u) * s);
    let cy = mcg_rounded(mcg_rounded(4.0 * v) * s);
    return vec3<f32>(mcg_rounded(cx / cy) * y, y, mcg_rounded(mcg_rounded(mcg_rounded(1.0 - cx) - cy) / cy) * y);
}

// M · v in glam's order ((col₀ vₓ + col₁ v_y) + col₂ v_z), every product rounded.
fn codec_mat3_mul(c0: vec3<f32>, c1: vec3<f32>, c2: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return (mcg_rounded3(c0 * v.x) + mcg_rounded3(c1 * v.y)) + mcg_rounded3(c2 * v.z);
}

// `LogLuv32.encode(rgb)`: linear sRGB (negatives and NaN as 0) through SRGB_TO_XYZ.
fn codec_logluv32_pack(rgb: vec3<f32>) -> u32 {
    let c = mcg_positive_part3(rgb);
    let xyz = codec_mat3_mul(
        vec3<f32>(CODEC_LOGLUV_SRGB_TO_XYZ_0, CODEC_LOGLUV_SRGB_TO_XYZ_1, CODEC_LOGLUV_SRGB_TO_XYZ_2),
        vec3<f32>(CODEC_LOGLUV_SRGB_TO_XYZ_3, CODEC_LOGLUV_SRGB_TO_XYZ_4, CODEC_LOGLUV_SRGB_TO_XYZ_5),
        vec3<f32>(CODEC_LOGLUV_SRGB_TO_XYZ_6, CODEC_LOGLUV_SRGB_TO_XYZ_7, CODEC_LOGLUV_SRGB_TO_XYZ_8),
        c,
    );
    return codec_logluv32_pack_xyz(xyz);
}

// `LogLuv32.decode(word)`: XYZ_TO_SRGB · XYZ, clamped at 0.
fn codec_logluv32_unpack(word: u32) -> vec3<f32> {
    let rgb = codec_mat3_mul(
        vec3<f32>(CODEC_LOGLUV_XYZ_TO_SRGB_0, CODEC_LOGLUV_XYZ_TO_SRGB_1, CODEC_LOGLUV_XYZ_TO_SRGB_2),
        vec3<f32>(CODEC_LOGLUV_XYZ_TO_SRGB_3, CODEC_LOGLUV_XYZ_TO_SRGB_4, CODEC_LOGLUV_XYZ_TO_SRGB_5),
        vec3<f32>(CODEC_LOGLUV_XYZ_TO_SRGB_6, CODEC_LOGLUV_XYZ_TO_SRGB_7, CODEC_LOGLUV_XYZ_TO_SRGB_8),
        codec_logluv32_unpack_xyz(word),
    );
    return select(vec3<f32>(0.0), rgb, rgb > vec3<f32>(0.0));
}
