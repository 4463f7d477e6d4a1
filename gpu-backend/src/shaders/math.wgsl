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

// `f32::is_finite`: neither infinite nor NaN.
fn mcg_is_finite(x: f32) -> bool {
    return abs(x) <= MCG_F32_MAX;
}

// `Vec3::is_finite`: every component finite.
fn mcg_is_finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3<f32>(MCG_F32_MAX));
}
