#define_import_path mcg::math
// Float helpers the bit-exact twins share.

#import mcg::constants::MCG_F32_MAX

// `x` itself, for every finite x and +∞. Wrapping a product in it keeps it rounded on its
// own: WGSL has no `precise`, and compilers (lavapipe's among them) fuse `a * b + c` into an
// FMA, which rounds once where the CPU rounds twice. Results that must match the CPU bit for
// bit wrap every product that feeds a sum.
fn mcg_rounded(x: f32) -> f32 {
    return max(x, -MCG_F32_MAX);
}

// `mcg_rounded` per component.
fn mcg_rounded3(x: vec3<f32>) -> vec3<f32> {
    return max(x, vec3<f32>(-MCG_F32_MAX));
}

// The bits of +∞: those of f32::MAX plus one. For tests on the bits: WGSL lets an
// implementation assume that no value is infinite or NaN, under which comparisons such as
// `abs(x) <= MCG_F32_MAX` may be folded to true and `x != x` to false (lavapipe does the latter).
fn mcg_infinity_bits() -> u32 {
    return bitcast<u32>(MCG_F32_MAX) + 1u;
}

// `f32::is_finite`: neither infinite nor NaN, from the bits: without the sign, below +∞'s.
fn mcg_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) << 1u) < (mcg_infinity_bits() << 1u);
}

// `Vec3::is_finite`: every component finite (`mcg_is_finite`).
fn mcg_is_finite3(v: vec3<f32>) -> bool {
    return mcg_is_finite(v.x) && mcg_is_finite(v.y) && mcg_is_finite(v.z);
}

// `f32::is_nan` from the bits: the exponent all ones and a non-zero mantissa, i.e. the bits
// without the sign above those of +∞.
fn mcg_is_nan(x: f32) -> bool {
    return (bitcast<u32>(x) << 1u) > (mcg_infinity_bits() << 1u);
}

// `x > 0.0` from the bits (+0 < x ≤ +∞; false for NaN), for guards on data that may be NaN.
// Under WGSL's no-NaN assumption a compiler may rewrite `!(x > 0.0)` as `x <= 0.0` or
// `select(0.0, x, x > 0.0)` as `select(x, 0.0, x <= 0.0)`, which let a NaN through.
fn mcg_is_positive(x: f32) -> bool {
    return bitcast<u32>(x) - 1u < mcg_infinity_bits();
}

// The components of `v` that are > 0 (`mcg_is_positive`), the others 0: negatives, zeros and
// NaN become 0.
fn mcg_positive_part3(v: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), v, bitcast<vec3<u32>>(v) - vec3<u32>(1u) < vec3<u32>(mcg_infinity_bits()));
}

// `v.abs().max_element()`: the largest component magnitude (for rescaling before a length).
fn mcg_max_abs3(v: vec3<f32>) -> f32 {
    return max(max(abs(v.x), abs(v.y)), abs(v.z));
}

// Whether any component is NaN (`mcg_is_nan`).
fn mcg_any_nan2(v: vec2<f32>) -> bool {
    return mcg_is_nan(v.x) || mcg_is_nan(v.y);
}

// Whether any component is NaN (`mcg_is_nan`).
fn mcg_any_nan3(v: vec3<f32>) -> bool {
    return mcg_is_nan(v.x) || mcg_is_nan(v.y) || mcg_is_nan(v.z);
}
