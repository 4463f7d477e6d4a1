#define_import_path mcg::sampling
// Random numbers and the defensive sampler: a counter-based u32 hash and the uniform-float
// convention of the CPU (`mcg_gpu_backend::sampling`), Duff et al.'s orthonormal frame
// (`mcg_vmf::Frame`) and the cosine-weighted hemisphere of MCMM Alg. 2 / MCPG Alg. 2
// (`mcg_markov_guide::cosine_hemisphere`).

#import mcg::constants::{
    MCG_FRAC_1_PI, MCG_PCG_HASH_INC, MCG_PCG_HASH_MUL, MCG_PCG_HASH_OUTPUT_MUL, MCG_PI,
    MCG_UNIFORM_FLOAT_SCALE
}

// The PCG hash of Jarzynski and Olano 2020 ("Hash Functions for GPU Rendering", JCGT 9(3)):
// one LCG step of PCG32 followed by its RXS-M-XS output permutation. `sampling::pcg_hash`.
fn mcg_pcg_hash(v: u32) -> u32 {
    let state = v * MCG_PCG_HASH_MUL + MCG_PCG_HASH_INC;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * MCG_PCG_HASH_OUTPUT_MUL;
    return (word >> 22u) ^ word;
}

// A uniform in [0, 1) from 32 random bits: the top 24 bits times 2⁻²⁴, the convention of
// `rand`'s `StandardUniform` for f32 (every value exact, never 1). `sampling::uniform_float`.
fn mcg_uniform_float(bits: u32) -> f32 {
    return f32(bits >> 8u) * MCG_UNIFORM_FLOAT_SCALE;
}

// The next 32 bits of a hash-chained stream: advances `state` to its PCG hash and returns it
// (seed `state` with e.g. `mcg_pcg_hash(pixel_index ^ mcg_pcg_hash(frame))`). `sampling::next_u32`.
fn mcg_rng_next(state: ptr<function, u32>) -> u32 {
    *state = mcg_pcg_hash(*state);
    return *state;
}

// The next uniform in [0, 1) of the stream (`mcg_uniform_float` of `mcg_rng_next`).
fn mcg_rng_uniform(state: ptr<function, u32>) -> f32 {
    return mcg_uniform_float(mcg_rng_next(state));
}

// The next two uniforms, x first.
fn mcg_rng_uniform2(state: ptr<function, u32>) -> vec2<f32> {
    let x = mcg_rng_uniform(state);
    return vec2<f32>(x, mcg_rng_uniform(state));
}

// `Frame::from_normal(n).to_world(local)`: Duff et al. 2017's branchless orthonormal basis
// about the unit `n`, with the sign of n.z copied bit for bit (−0 counts as negative, as on the
// CPU). `local.z` is the component along `n`.
fn mcg_frame_to_world(n: vec3<f32>, local: vec3<f32>) -> vec3<f32> {
    let sign = bitcast<f32>(bitcast<u32>(1.0) | (bitcast<u32>(n.z) & 0x80000000u));
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let tangent = vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bitangent = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return tangent * local.x + bitangent * local.y + n * local.z;
}

// A direction and its density.
struct McgDirectionSample {
    direction: vec3<f32>,
    pdf: f32,
}

// `cosine_hemisphere(normal, u)`: a direction with density cos θ / π about the unit `normal`
// (Malley's method: a uniform disk point lifted to the hemisphere) and its pdf. `u` in [0, 1)².
fn mcg_cosine_hemisphere_sample(normal: vec3<f32>, u: vec2<f32>) -> McgDirectionSample {
    let r = sqrt(u.x);
    let phi = 2.0 * MCG_PI * u.y;
    let z = sqrt(max(1.0 - u.x, 0.0));
    let local = vec3<f32>(r * cos(phi), r * sin(phi), z);
    return McgDirectionSample(mcg_frame_to_world(normal, local), z * MCG_FRAC_1_PI);
}

// `cosine_hemisphere_pdf(normal, w)`: max(0, n·ω)/π.
fn mcg_cosine_hemisphere_pdf(normal: vec3<f32>, w: vec3<f32>) -> f32 {
    return max(dot(normal, w), 0.0) * MCG_FRAC_1_PI;
}
