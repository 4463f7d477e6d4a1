#define_import_path mcg::adgi_chains
// ADGI's guiding function and Metropolis probe chains ("Adaptive Dynamic Global Illumination",
// sec. 3.2-3.3, 4.8-4.9, Alg. 1 and 5) as pure functions: the twins of
// `mcg_probe_cache::{guiding_function, proxies, probe_chains}` and of
// `mcg_markov_guide::{standard_normal_from_uniform, RandomWalk}`.
//
//   let h = adgi_guiding_value(f, g_hat, alpha, cap);               // eq. 2 (capped exponent)
//   let x = adgi_locate(state, grid);                               // cell, octant, direction
//   let y = adgi_propose(state, u, grid);                           // Alg. 5 line 2
//   let u = adgi_pilot_uniforms(seed, pattern, probe, octant, 0u);  // sec. 4.4's pilot rays
//
// A chain's state is (p, cos θ, φ) (`AdgiChainState`); the tables of the guide are indexed
// `cell · 8 + octant`, a cell being a probe (static chains, sec. 4.8) or a block of
// `block³` probes (dynamic chains on ADGI's 3 × 3 × 3 virtual proxies, sec. 4.9).
// Every product that feeds a sum is wrapped in `mcg_rounded`, so that everything but
// `log`/`sqrt`/`sin`/`cos`/`exp` rounds as on the CPU.

#import mcg::constants::{
    MARKOV_QUANTILE_CENTRAL_P0, MARKOV_QUANTILE_CENTRAL_P1, MARKOV_QUANTILE_CENTRAL_P2,
    MARKOV_QUANTILE_CENTRAL_P3, MARKOV_QUANTILE_CENTRAL_P4, MARKOV_QUANTILE_CENTRAL_P5,
    MARKOV_QUANTILE_CENTRAL_P6, MARKOV_QUANTILE_CENTRAL_P7, MARKOV_QUANTILE_CENTRAL_P8,
    MARKOV_QUANTILE_SWITCH, MARKOV_QUANTILE_TAIL_P0, MARKOV_QUANTILE_TAIL_P1,
    MARKOV_QUANTILE_TAIL_P2, MARKOV_QUANTILE_TAIL_P3, MARKOV_QUANTILE_TAIL_P4,
    MARKOV_QUANTILE_TAIL_P5, MARKOV_QUANTILE_TAIL_P6, MARKOV_QUANTILE_TAIL_P7,
    MARKOV_QUANTILE_TAIL_P8, MARKOV_QUANTILE_U_MIN, MCG_F32_MAX, MCG_ONE_MINUS_EPSILON,
    MCG_SQRT_2, MCG_TAU, ADGI_HASH_GAMMA_HI, ADGI_HASH_GAMMA_LO, ADGI_HASH_MUL_A_HI,
    ADGI_HASH_MUL_A_LO, ADGI_HASH_MUL_B_HI, ADGI_HASH_MUL_B_LO, ADGI_PILOT_SEED_SALT_HI,
    ADGI_PILOT_SEED_SALT_LO, MCG_UNIFORM_FLOAT_SCALE
}
#import mcg::math::{mcg_is_finite, mcg_is_nan, mcg_rounded, mcg_rounded3}
#import mcg::sampling::{mcg_pcg_hash, mcg_rng_uniform}

// One chain (`GpuChainState` on the host, 32 bytes): the state x = (p, z = cos θ, φ) of
// `ProbeChainState`, h(x) (`target`), and what the last frame did: bit i of `accepted` set
// when step i (< 32) was accepted, `restarted` 1 when the chain restarted uniformly.
struct AdgiChainState {
    position: vec3<f32>,
    z: f32,
    phi: f32,
    target_value: f32,
    accepted: u32,
    restarted: u32,
}

// One emitted sample (`GpuProbeSample`, 48 bytes): `ProbeSample`'s position, cell, direction,
// h, the probe's linear index and the octant, and which chain emitted it at which step.
struct AdgiProbeSample {
    position: vec3<f32>,
    cell: u32,
    direction: vec3<f32>,
    guiding_value: f32,
    probe: u32,
    octant: u32,
    chain: u32,
    step: u32,
}

// The grid the chains walk on: the probe grid and its cells (`ProxyGrid`), and the box the
// uniform restarts cover (`lo`, `extent`: the probes' Voronoi cells).
struct AdgiChainGrid {
    origin: vec3<f32>,
    spacing: vec3<f32>,
    counts: vec3<u32>,
    block: u32,
    cell_counts: vec3<u32>,
    lo: vec3<f32>,
    extent: vec3<f32>,
}

// Where a state points (`ProbeChains::locate`): its position, whether it lies in the sampling
// domain (`inside`), the nearest probe's coordinates and linear index, its cell, the folded
// direction coordinates (z, φ), the unit direction and its octant.
struct AdgiLocated {
    position: vec3<f32>,
    inside: bool,
    probe_coords: vec3<u32>,
    probe: u32,
    cell: u32,
    folded: vec2<f32>,
    direction: vec3<f32>,
    octant: u32,
}

// The uniforms of one step (`ProbeStepUniforms`): five for the proposal, one for the test.
struct AdgiStepUniforms {
    proposal: array<f32, 5>,
    accept: f32,
}

// `heuristics::unit`: x clamped to [0, 1], NaN → 0.
fn adgi_unit(x: f32) -> f32 {
    if mcg_is_nan(x) || !(x > 0.0) {
        return 0.0;
    }
    return min(x, 1.0);
}

// `GuideParams::guiding_value` (ADGI eq. 2 with a capped exponent): exp(min(α ĝ / f, cap)) · f
// with f clamped to [0, 1]; 0 for f = 0, a NaN or negative ĝ counts as 0, α = 0 ignores ĝ.
fn adgi_guiding_value(f_in: f32, g_hat: f32, alpha: f32, cap: f32) -> f32 {
    let f = adgi_unit(f_in);
    if !(f > 0.0) {
        return 0.0;
    }
    var g = 0.0;
    if !mcg_is_nan(g_hat) && g_hat > 0.0 {
        g = g_hat;
    }
    if !(alpha > 0.0 && g > 0.0) {
        return f;
    }
    let ratio = alpha * g / f;
    // Rust's `min` returns the other operand for NaN; α g / f is never NaN here (g, f > 0).
    let exponent = min(ratio, cap);
    if exponent == 0.0 {
        return f;
    }
    return exp(exponent) * f;
}

// `heuristics::octant`: bit 0, 1, 2 set for a negative x, y, z component.
fn adgi_octant(d: vec3<f32>) -> u32 {
    return select(0u, 1u, d.x < 0.0) | select(0u, 2u, d.y < 0.0) | select(0u, 4u, d.z < 0.0);
}

// `standard_normal_from_uniform`: Φ⁻¹(u) = √2 erf⁻¹(2u − 1) with M. Giles' single-precision
// erf⁻¹ ("Approximating the erfinv function", GPU Computing Gems Jade, 2011); u clamped to
// [2⁻²⁵, 1 − 2⁻²⁴], NaN → 0.
fn adgi_normal_quantile(u_in: f32) -> f32 {
    if mcg_is_nan(u_in) {
        return 0.0;
    }
    let u = clamp(u_in, MARKOV_QUANTILE_U_MIN, MCG_ONE_MINUS_EPSILON);
    let x = 2.0 * u - 1.0;
    let w = -log(mcg_rounded(4.0 * u) * (1.0 - u));
    var p: f32;
    if w < MARKOV_QUANTILE_SWITCH {
        let v = w - 2.5;
        p = MARKOV_QUANTILE_CENTRAL_P0;
        p = MARKOV_QUANTILE_CENTRAL_P1 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P2 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P3 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P4 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P5 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P6 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P7 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_CENTRAL_P8 + mcg_rounded(p * v);
    } else {
        let v = sqrt(w) - 3.0;
        p = MARKOV_QUANTILE_TAIL_P0;
        p = MARKOV_QUANTILE_TAIL_P1 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P2 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P3 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P4 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P5 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P6 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P7 + mcg_rounded(p * v);
        p = MARKOV_QUANTILE_TAIL_P8 + mcg_rounded(p * v);
    }
    return mcg_rounded(MCG_SQRT_2 * p) * x;
}

// x mod 4 in [0, 4) for finite x, exactly (division by 4 and the product are exact).
fn adgi_rem_euclid_4(x: f32) -> f32 {
    let r = x - 4.0 * trunc(ldexp(x, -2));
    return select(r, r + 4.0, r < 0.0);
}

// `probe_chains::fold_direction`: z reflected into [−1, 1] (period 4), φ wrapped into
// [0, 2π); non-finite coordinates give (1, 0).
fn adgi_fold_direction(z: f32, phi: f32) -> vec2<f32> {
    if !(mcg_is_finite(z) && mcg_is_finite(phi)) {
        return vec2<f32>(1.0, 0.0);
    }
    var fz: f32;
    if z >= -1.0 && z <= 1.0 {
        fz = z;
    } else if z >= 1.0 && z <= 3.0 {
        fz = 2.0 - z;
    } else if z >= -3.0 && z < -1.0 {
        fz = -2.0 - z;
    } else {
        var t = adgi_rem_euclid_4(z + 1.0);
        if t > 2.0 {
            t = 4.0 - t;
        }
        fz = t - 1.0;
    }
    var fp: f32;
    if phi >= 0.0 && phi < MCG_TAU {
        fp = phi;
    } else if phi >= -MCG_TAU && phi < 0.0 {
        fp = phi + MCG_TAU;
    } else if phi >= MCG_TAU && phi < 2.0 * MCG_TAU {
        fp = phi - MCG_TAU;
    } else {
        // Unreachable from a walk's proposal (|step| ≤ 5.6 σ < 2π); WGSL's `%` is not the
        // CPU's exact `rem_euclid` here.
        let r = phi - MCG_TAU * trunc(phi / MCG_TAU);
        fp = select(r, r + MCG_TAU, r < 0.0);
    }
    if fp >= MCG_TAU {
        fp = 0.0;
    }
    return vec2<f32>(fz, fp);
}

// `probe_chains::direction_from_chain`: (√(1−z²) cos φ, √(1−z²) sin φ, z), z clamped.
fn adgi_direction_from_chain(z_in: f32, phi: f32) -> vec3<f32> {
    let z = clamp(z_in, -1.0, 1.0);
    let r = sqrt(max(1.0 - mcg_rounded(z * z), 0.0));
    return vec3<f32>(r * cos(phi), r * sin(phi), z);
}

// `ProxyGrid::nearest_probe` and `proxy_of_probe`, then the direction: the state resolved.
fn adgi_locate(position: vec3<f32>, z: f32, phi: f32, grid: AdgiChainGrid) -> AdgiLocated {
    var at: AdgiLocated;
    at.position = position;
    at.folded = adgi_fold_direction(z, phi);
    at.direction = adgi_direction_from_chain(at.folded.x, at.folded.y);
    at.octant = adgi_octant(at.direction);
    let t = mcg_rounded3((position - grid.origin) / grid.spacing) + vec3<f32>(0.5);
    let counts = vec3<f32>(grid.counts);
    // NaN fails both tests (`mcg_is_finite` first: lavapipe may fold NaN compares).
    at.inside = mcg_is_finite(t.x + t.y + t.z) && all(t >= vec3<f32>(0.0)) && all(t < counts);
    if at.inside {
        let c = min(vec3<u32>(t), grid.counts - vec3<u32>(1u));
        at.probe_coords = c;
        at.probe = c.x + grid.counts.x * (c.y + grid.counts.y * c.z);
        let b = c / grid.block;
        at.cell = b.x + grid.cell_counts.x * (b.y + grid.cell_counts.y * b.z);
    }
    return at;
}

// `probe_chains::uniform_state`: the point lo + c(u₀..₂) ⊙ extent, z = 2c(u₃) − 1, φ = 2π c(u₄),
// c clamping to [0, 1] (NaN → 0), folded. Returns (p, z, φ) in a state with h = 0.
fn adgi_uniform_state(u: array<f32, 5>, grid: AdgiChainGrid) -> AdgiChainState {
    var c: array<f32, 5>;
    for (var i = 0; i < 5; i += 1) {
        c[i] = select(0.0, min(u[i], 1.0), !mcg_is_nan(u[i]) && u[i] >= 0.0);
    }
    var s: AdgiChainState;
    s.position = grid.lo + mcg_rounded3(vec3<f32>(c[0], c[1], c[2]) * grid.extent);
    let folded = adgi_fold_direction(2.0 * c[3] - 1.0, MCG_TAU * c[4]);
    s.z = folded.x;
    s.phi = folded.y;
    return s;
}

// `RandomWalk::propose` on a chain state: x + σ ⊙ Φ⁻¹(u) per coordinate, saturating at
// ±f32::MAX (σ = (`position_step`, `direction_step`, `direction_step`)).
fn adgi_propose(s: AdgiChainState, u: array<f32, 5>, position_step: vec3<f32>, direction_step: f32) -> AdgiChainState {
    var y = s;
    let n = vec3<f32>(adgi_normal_quantile(u[0]), adgi_normal_quantile(u[1]), adgi_normal_quantile(u[2]));
    y.position = clamp(s.position + mcg_rounded3(position_step * n), vec3<f32>(-MCG_F32_MAX), vec3<f32>(MCG_F32_MAX));
    y.z = clamp(s.z + mcg_rounded(direction_step * adgi_normal_quantile(u[3])), -MCG_F32_MAX, MCG_F32_MAX);
    y.phi = clamp(s.phi + mcg_rounded(direction_step * adgi_normal_quantile(u[4])), -MCG_F32_MAX, MCG_F32_MAX);
    return y;
}

// The uniforms of draw `draw` of chain `chain` under the frame key `seed`, from the
// counter-based hash of `mcg::sampling` (`chain_step_uniforms` on the host): six uniforms of
// the stream seeded with pcg(pcg(pcg(seed) ^ chain) ^ draw).
fn adgi_chain_uniforms(seed: u32, chain: u32, draw: u32) -> AdgiStepUniforms {
    var state = mcg_pcg_hash(mcg_pcg_hash(mcg_pcg_hash(seed) ^ chain) ^ draw);
    var u: AdgiStepUniforms;
    for (var i = 0; i < 5; i += 1) {
        u.proposal[i] = mcg_rng_uniform(&state);
    }
    u.accept = mcg_rng_uniform(&state);
    return u;
}

// ---------------------------------------------------------------------------------------------
// ADGI's pilot rays (sec. 4.4: "a stratified-random ray-direction such that there is always one
// ray per octant", the same rays on both frames of a pair): the twins of
// `mcg_probe_cache::probe_update::{hash_uniform, ProbeUpdater::pilot_uniforms}` (the directions
// from them: `adgi_pilot_direction` of `mcg::adgi`). WGSL has no 64-bit integers, so the u64
// counters are vec2<u32>(low, high) words with wrapping arithmetic, and the uniforms equal the
// CPU's bit for bit (integer hashing, then 24 bits times 2⁻²⁴, exact).

// a + b mod 2⁶⁴.
fn adgi_u64_add(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    return vec2<u32>(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

// The full 64-bit product of two u32 (16-bit limbs, no partial sum overflows).
fn adgi_u32_mul_wide(a: u32, b: u32) -> vec2<u32> {
    let a0 = a & 0xffffu;
    let a1 = a >> 16u;
    let b0 = b & 0xffffu;
    let b1 = b >> 16u;
    let p00 = a0 * b0;
    let p01 = a0 * b1;
    let p10 = a1 * b0;
    let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
    let lo = (p00 & 0xffffu) | (mid << 16u);
    return vec2<u32>(lo, a1 * b1 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

// a · b mod 2⁶⁴ (`u64::wrapping_mul`).
fn adgi_u64_mul(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let p = adgi_u32_mul_wide(a.x, b.x);
    return vec2<u32>(p.x, p.y + a.x * b.y + a.y * b.x);
}

// z ^ (z >> s) for 0 < s < 32.
fn adgi_u64_xor_shift(z: vec2<u32>, s: u32) -> vec2<u32> {
    return z ^ vec2<u32>((z.x >> s) | (z.y << (32u - s)), z.y >> s);
}

// `hash_uniform`: SplitMix64's finaliser (Steele et al. 2014) of counter + γ, its top 24 bits
// times 2⁻²⁴ — a uniform in [0, 1), exactly the CPU's.
fn adgi_hash_uniform(counter: vec2<u32>) -> f32 {
    var z = adgi_u64_add(counter, vec2<u32>(ADGI_HASH_GAMMA_LO, ADGI_HASH_GAMMA_HI));
    z = adgi_u64_mul(adgi_u64_xor_shift(z, 30u), vec2<u32>(ADGI_HASH_MUL_A_LO, ADGI_HASH_MUL_A_HI));
    z = adgi_u64_mul(adgi_u64_xor_shift(z, 27u), vec2<u32>(ADGI_HASH_MUL_B_LO, ADGI_HASH_MUL_B_HI));
    z = adgi_u64_xor_shift(z, 31u);
    return f32(z.y >> 8u) * MCG_UNIFORM_FLOAT_SCALE;
}

// `ProbeUpdater::pilot_uniforms(seed, pattern, probe, octant, k)`: the two uniforms of the
// counter (seed ^ salt) + pattern · γ + ((8 probe + octant) << 3) + k and of the counter after
// it (k = 0 the direction, k = 2 the light sample at the hit); probe < 2²⁹.
fn adgi_pilot_uniforms(seed: vec2<u32>, pattern: vec2<u32>, probe: u32, octant: u32, k: u32) -> vec2<f32> {
    let salted = seed ^ vec2<u32>(ADGI_PILOT_SEED_SALT_LO, ADGI_PILOT_SEED_SALT_HI);
    let step = adgi_u64_mul(pattern, vec2<u32>(ADGI_HASH_GAMMA_LO, ADGI_HASH_GAMMA_HI));
    let slot = probe * 8u + octant;
    var c = adgi_u64_add(salted, step);
    c = adgi_u64_add(c, vec2<u32>(slot << 3u, slot >> 29u));
    c = adgi_u64_add(c, vec2<u32>(k, 0u));
    return vec2<f32>(adgi_hash_uniform(c), adgi_hash_uniform(adgi_u64_add(c, vec2<u32>(1u, 0u))));
}
