#define_import_path mcg::vmf
// mcg-vmf twin: von Mises-Fisher lobes on S² (pdf, sampling, mean cosine, reconstruction from
// sufficient statistics, product). Mirrors mcg-vmf's `vmf.rs`, `math.rs`,
// `frame.rs`, `mean_cosine.rs`, `sufficient_stats.rs` and `product.rs` operation by operation;
// see those files for the derivations (MCMM eq. 4, MCPG eq. 4, Jakob 2012).

#import mcg::constants::{
    MCG_F32_EPSILON, MCG_F32_MIN_POSITIVE, MCG_FRAC_1_PI, MCG_FRAC_PI_2, VMF_COS_POLY_0, VMF_COS_POLY_1, VMF_COS_POLY_2,
    VMF_EXP_M1_KAHAN_LIMIT, VMF_EXP_M1_SERIES_0, VMF_EXP_M1_SERIES_1, VMF_EXP_M1_SERIES_2,
    VMF_EXP_M1_SERIES_3, VMF_EXP_M1_SERIES_4, VMF_EXP_M1_SERIES_5, VMF_EXP_M1_SERIES_6,
    VMF_EXP_M1_SERIES_7, VMF_KAPPA_DIRECT_EXPM1, VMF_KAPPA_MAX, VMF_KAPPA_SAMPLE_SATURATED,
    VMF_KAPPA_SATURATED, VMF_KAPPA_TINY, VMF_LN_1P_SERIES_0, VMF_LN_1P_SERIES_1,
    VMF_LN_1P_SERIES_2, VMF_LN_1P_SERIES_3, VMF_LN_1P_SERIES_4, VMF_LN_1P_SERIES_5,
    VMF_LN_1P_SERIES_6, VMF_MEAN_COSINE_DERIVATIVE_SERIES_0,
    VMF_MEAN_COSINE_DERIVATIVE_SERIES_1, VMF_MEAN_COSINE_DERIVATIVE_SERIES_2,
    VMF_MEAN_COSINE_DERIVATIVE_SERIES_3, VMF_MEAN_COSINE_PROJECTED, VMF_MEAN_COSINE_SERIES_0,
    VMF_MEAN_COSINE_SERIES_1, VMF_MEAN_COSINE_SERIES_2, VMF_MEAN_COSINE_SERIES_3,
    VMF_MEAN_COSINE_SERIES_4, VMF_NEWTON_COMPLEMENT_FROM, VMF_NEWTON_MAX_ITERATIONS,
    VMF_NEWTON_RELATIVE_STEP, VMF_PRIOR_DECAY_COUNT, VMF_SERIES_LIMIT, VMF_SIN_POLY_0,
    VMF_SIN_POLY_1, VMF_SIN_POLY_2, VMF_UNIFORM_SPHERE_PDF
}
#import mcg::math::{
    mcg_infinity_bits, mcg_is_finite, mcg_is_finite3, mcg_is_positive, mcg_max_abs3
}
#import mcg::sampling::mcg_frame_to_world

// 16 bytes, the layout of `mcg_vmf::Vmf`: mean direction μ (unit) and concentration κ ≥ 0.
struct Vmf {
    mu: vec3<f32>,
    kappa: f32,
}

// 24 bytes, the layout of `mcg_vmf::SufficientStats` (MCMM/MCPG Table 1). The mean target is
// three scalars: a `vec3<f32>` member would give the struct WGSL's 16-byte alignment and a
// 32-byte size, and arrays of it would not match the host's 24-byte stride.
struct VmfSufficientStats {
    mean_target_x: f32,
    mean_target_y: f32,
    mean_target_z: f32,
    weight_sum: f32,
    one_minus_mean_cosine: f32,
    sample_count: u32,
}

// `mcg_vmf::MapPrior`: r_p, N_p and the decay (VMF_PRIOR_DECAY_*).
struct VmfMapPrior {
    mean_cosine: f32,
    weight: f32,
    decay: u32,
}

// A direction and its density (`Vmf::sample_with_pdf`).
struct VmfSample {
    direction: vec3<f32>,
    pdf: f32,
}

// expm1 (`math::exp_m1`): for |x| ≤ ½ its Taylor series (`EXP_M1_SERIES`), else exp(x) − 1.
// The CPU's Kahan form (u − 1)·x/ln u, u = eˣ, needs a log accurate relative to ln u near 1,
// which WGSL does not promise (`log` within 2⁻²¹ absolute on [½, 2]): on an NVIDIA H200 it
// made C(κ) and the sampled angles of lobes with κ ≈ 10⁻⁷ wrong by tens of per cent.
fn vmf_exp_m1(x: f32) -> f32 {
    if !(abs(x) <= VMF_EXP_M1_KAHAN_LIMIT) {
        return exp(x) - 1.0;
    }
    return x * (VMF_EXP_M1_SERIES_0 + x * (VMF_EXP_M1_SERIES_1 + x * (VMF_EXP_M1_SERIES_2 + x * (VMF_EXP_M1_SERIES_3 + x * (VMF_EXP_M1_SERIES_4 + x * (VMF_EXP_M1_SERIES_5 + x * (VMF_EXP_M1_SERIES_6 + x * VMF_EXP_M1_SERIES_7)))))));
}

// ln(1 + x) for x in [−½, 0] as 2 atanh(s), s = x/(2 + x) in [−⅓, 0], by its odd series
// (`LN_1P_SERIES`): `log` near 1 carries WGSL's 2⁻²¹ absolute error, which is most of
// ln(1 + x) for small x (see `vmf_exp_m1`).
fn vmf_ln_1p_near(x: f32) -> f32 {
    let s = x / (2.0 + x);
    let s2 = s * s;
    return 2.0 * s * (VMF_LN_1P_SERIES_0 + s2 * (VMF_LN_1P_SERIES_1 + s2 * (VMF_LN_1P_SERIES_2 + s2 * (VMF_LN_1P_SERIES_3 + s2 * (VMF_LN_1P_SERIES_4 + s2 * (VMF_LN_1P_SERIES_5 + s2 * VMF_LN_1P_SERIES_6))))));
}

// (sin 2πt, cos 2πt) by quadrant reduction and minimax polynomials (`math::sin_cos_turns`);
// the same arithmetic as the CPU, so it does not depend on the GPU's sin/cos precision.
// Exact for |4t| < 2²², where the CPU's rounding trick is exact too.
fn vmf_sin_cos_turns(t: f32) -> vec2<f32> {
    let quarter_turns = 4.0 * t;
    // The CPU rounds with (4t + 1.5·2²³) − 1.5·2²³, ties to even, and reads the quadrant's
    // low bits off the sum's mantissa. A shader compiler may fold (a + c) − c to a (WGSL
    // has no `precise`), so the twin uses round(), also ties to even, and the integer's low
    // bits, which are the same two bits.
    let quadrant = round(quarter_turns);
    let q = bitcast<u32>(i32(quadrant));
    let x = (quarter_turns - quadrant) * MCG_FRAC_PI_2;
    let x2 = x * x;
    let s = x + x * x2 * (VMF_SIN_POLY_0 + x2 * (VMF_SIN_POLY_1 + x2 * VMF_SIN_POLY_2));
    let c = 1.0 - 0.5 * x2 + x2 * x2 * (VMF_COS_POLY_0 + x2 * (VMF_COS_POLY_1 + x2 * VMF_COS_POLY_2));
    let swap = 0u - (q & 1u);
    let sin_bits = bitcast<u32>(s);
    let cos_bits = bitcast<u32>(c);
    let first = (sin_bits & ~swap) | (cos_bits & swap);
    let second = (cos_bits & ~swap) | (sin_bits & swap);
    return vec2<f32>(
        bitcast<f32>(first ^ ((q & 2u) << 30u)),
        bitcast<f32>(second ^ (((q + 1u) & 2u) << 30u)),
    );
}

// C(κ) = g(−2κ)/(4π), g(x) = x/expm1(x); κ/(2π) above VMF_KAPPA_SATURATED. g = 1 for
// |x| < ε, where x/expm1(x) = 1 − x/2 + … rounds to 1 within an ULP: a subnormal x would
// otherwise divide by an expm1 that hardware flushing subnormals to zero makes 0.
fn vmf_normalization(kappa: f32) -> f32 {
    if kappa > VMF_KAPPA_SATURATED {
        return kappa * (0.5 * MCG_FRAC_1_PI);
    }
    let x = -2.0 * kappa;
    var g = 1.0;
    if abs(x) >= MCG_F32_EPSILON {
        g = x / vmf_exp_m1(x);
    }
    return g * VMF_UNIFORM_SPHERE_PDF;
}

// Density of unit direction `w`: C(κ) e^{−κ|ω − μ|²/2} (the stable form of MCMM eq. 4).
fn vmf_pdf(lobe: Vmf, w: vec3<f32>) -> f32 {
    let d = w - lobe.mu;
    let distance_squared = d.x * d.x + d.y * d.y + d.z * d.z;
    return vmf_normalization(lobe.kappa) * exp(-0.5 * lobe.kappa * distance_squared);
}

// Inverse CDF of cos θ − 1: ln(1 + ξ(e^{−2κ} − 1))/κ in [−2, 0] (Jakob 2012 eq. 8, in the
// cancellation-free forms of `vmf::cos_theta_minus_one`).
fn vmf_cos_theta_minus_one(kappa: f32, xi: f32) -> f32 {
    if kappa < VMF_KAPPA_TINY {
        return clamp(-2.0 * xi, -2.0, 0.0);
    }
    var decay = 0.0;
    var scale = -1.0;
    if !(kappa > VMF_KAPPA_SAMPLE_SATURATED) {
        decay = exp(-2.0 * kappa);
        if kappa > VMF_KAPPA_DIRECT_EXPM1 {
            scale = decay - 1.0;
        } else {
            scale = vmf_exp_m1(-2.0 * kappa);
        }
    }
    // ln(1 + x)/κ: near the peak (x ≥ −½) by `vmf_ln_1p_near` where the CPU takes
    // ln(u)·x/((u − 1)κ), u = 1 + x (the same value up to rounding); in the tail the log of
    // u = (1 − ξ) + ξe^{−2κ} < ½, which WGSL's `log` gives to a few ULP.
    let x = xi * scale;
    var r: f32;
    if x < -0.5 {
        r = log((1.0 - xi) + xi * decay) / kappa;
    } else {
        r = vmf_ln_1p_near(x) / kappa;
    }
    return clamp(r, -2.0, 0.0);
}

fn vmf_direction_from(lobe: Vmf, r: f32, u_phi: f32) -> vec3<f32> {
    let cos_theta = 1.0 + r;
    let sin_theta = sqrt(max(-r * (2.0 + r), 0.0));
    let sc = vmf_sin_cos_turns(u_phi);
    return mcg_frame_to_world(lobe.mu, vec3<f32>(sc.y * sin_theta, sc.x * sin_theta, cos_theta));
}

// Direction from two uniforms in [0, 1)²: azimuth 2π u.x, polar angle by the inverse CDF of u.y.
fn vmf_sample(lobe: Vmf, u: vec2<f32>) -> vec3<f32> {
    return vmf_direction_from(lobe, vmf_cos_theta_minus_one(lobe.kappa, u.y), u.x);
}

// `Vmf::sample_with_pdf`: the density comes from the sampled angle, C(κ) e^{κ r}.
fn vmf_sample_with_pdf(lobe: Vmf, u: vec2<f32>) -> VmfSample {
    let r = vmf_cos_theta_minus_one(lobe.kappa, u.y);
    let w = vmf_direction_from(lobe, r, u.x);
    return VmfSample(w, vmf_normalization(lobe.kappa) * exp(lobe.kappa * r));
}

// Mean cosine A₃(κ) = coth κ − 1/κ (Banerjee et al. 2005 eq. 4.1), series below 0.5; 0 for
// κ ≤ 0 or NaN (tested on the bits: a convolution kernel's κ is the caller's).
fn vmf_mean_cosine_from_kappa(kappa: f32) -> f32 {
    if !mcg_is_positive(kappa) {
        return 0.0;
    }
    if kappa < VMF_SERIES_LIMIT {
        let k2 = kappa * kappa;
        return kappa * (VMF_MEAN_COSINE_SERIES_0 + k2 * (VMF_MEAN_COSINE_SERIES_1 + k2 * (VMF_MEAN_COSINE_SERIES_2 + k2 * (VMF_MEAN_COSINE_SERIES_3 + k2 * VMF_MEAN_COSINE_SERIES_4))));
    }
    return min(1.0 + 2.0 / vmf_exp_m1(2.0 * kappa) - 1.0 / kappa, 1.0);
}

// Banerjee's κ from e = 1 − r: r(3 − r²)/(e(2 − e)), clamped to [0, VMF_KAPPA_MAX]
// (MCMM Alg. 2 line 7, MCPG Alg. 2 line 8).
fn vmf_kappa_from_one_minus_mean_cosine(e: f32) -> f32 {
    if !(e < 1.0) {
        return 0.0;
    }
    if !(e > 0.0) {
        return VMF_KAPPA_MAX;
    }
    let r = 1.0 - e;
    return min(r * (3.0 - r * r) / (e * (2.0 - e)), VMF_KAPPA_MAX);
}

// Banerjee's κ from the mean cosine r (`kappa_from_mean_cosine`); 0 for r ≤ 0 or NaN.
fn vmf_kappa_from_mean_cosine(r: f32) -> f32 {
    if !mcg_is_positive(r) {
        return 0.0;
    }
    return vmf_kappa_from_one_minus_mean_cosine(1.0 - r);
}

// `normalize_robust`: v/|v| where |v|² is a normal f32; else (|v|² overflows, or underflows
// into the subnormals where it loses precision) v scaled by its largest component magnitude
// first. False for a zero, infinite or NaN v (the tests on the bits: WGSL lets a compiler
// assume no NaN or infinity reaches a comparison).
fn vmf_try_normalize(v: vec3<f32>, out: ptr<function, vec3<f32>>) -> bool {
    let length_squared = v.x * v.x + v.y * v.y + v.z * v.z;
    var w = v;
    if !(mcg_is_finite(length_squared) && length_squared >= MCG_F32_MIN_POSITIVE) {
        let largest = mcg_max_abs3(v);
        if !(mcg_is_positive(largest) && mcg_is_finite(largest)) {
            return false;
        }
        w = v / largest;
    }
    let rcp = 1.0 / sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
    if mcg_is_positive(rcp) && mcg_is_finite(rcp) {
        *out = w * rcp;
        return true;
    }
    return false;
}

// 1 − r of the MAP mean cosine r = (N² r̄ + N_p r_p)/(N² + N_p) (MCMM Alg. 2 line 6, MCPG
// Alg. 2 line 7), N instead of N² for VMF_PRIOR_DECAY_COUNT.
fn vmf_posterior_one_minus_mean_cosine(stats: VmfSufficientStats, prior: VmfMapPrior) -> f32 {
    let n = f32(stats.sample_count);
    let n_eff = select(n * n, n, prior.decay == VMF_PRIOR_DECAY_COUNT);
    let prior_weight = max(prior.weight, 0.0);
    // r_p clamped to [0, 1], NaN as 0 (the CPU's `max(0.0).min(1.0)`), tested on the bits.
    let prior_complement = 1.0 - select(0.0, min(prior.mean_cosine, 1.0), mcg_is_positive(prior.mean_cosine));
    if bitcast<u32>(prior_weight) == mcg_infinity_bits() {
        return prior_complement;
    }
    let total = n_eff + prior_weight;
    if !(total > 0.0) {
        return 1.0;
    }
    let sample_complement = clamp(stats.one_minus_mean_cosine, 0.0, 1.0);
    return (n_eff * sample_complement + prior_weight * prior_complement) / total;
}

// The lobe at shading point `x` (MCMM Alg. 2 lines 5-7, MCPG Alg. 2 lines 6-8): false, and
// `out` untouched, for empty statistics or when ȳ coincides with `x` (`to_vmf` → None).
fn vmf_from_sufficient_stats(stats: VmfSufficientStats, x: vec3<f32>, prior: VmfMapPrior, out: ptr<function, Vmf>) -> bool {
    if stats.sample_count == 0u || !mcg_is_positive(stats.weight_sum) {
        return false;
    }
    let mean_target = vec3<f32>(stats.mean_target_x, stats.mean_target_y, stats.mean_target_z);
    var mu: vec3<f32>;
    if !vmf_try_normalize(mean_target - x, &mu) {
        return false;
    }
    let kappa = vmf_kappa_from_one_minus_mean_cosine(vmf_posterior_one_minus_mean_cosine(stats, prior));
    *out = Vmf(mu, kappa);
    return true;
}

// Product of two lobes (`Vmf::product`): a.pdf · b.pdf = scale · product.pdf, with
// m = κ_a μ_a + κ_b μ_b, μ' = m/|m|, κ' = |m| and
// scale = C(κ_a) C(κ_b)/C(κ') · e^{κ' − κ_a − κ_b}. Returns the lobe in `out`, the scale.
fn vmf_product(a: Vmf, b: Vmf, out: ptr<function, Vmf>) -> f32 {
    let m = a.mu * a.kappa + b.mu * b.kappa;
    let kappa = sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
    var mu = a.mu;
    if kappa > 0.0 {
        mu = m / kappa;
    }
    var unit: vec3<f32>;
    if !vmf_try_normalize(mu, &unit) {
        unit = a.mu;
    }
    let exponent = kappa - a.kappa - b.kappa;
    let scale = (vmf_normalization(a.kappa) / vmf_normalization(kappa)) * vmf_normalization(b.kappa) * exp(min(exponent, 0.0));
    *out = Vmf(unit, kappa);
    return scale;
}

// `mcg_vmf::FitParams`: N_max, α_min and the mean-cosine update (VMF_MEAN_COSINE_*); 16 bytes,
// `types::VmfFitParamsGpu` on the host.
struct VmfFitParams {
    max_count: u32,
    alpha_min: f32,
    mean_cosine_update: u32,
    pad_a: u32,
}

// `SufficientStats::update` (MCMM Alg. 3 lines 11-17, MCPG Alg. 3 lines 4-9): absorbs target
// point `y` seen from `x` with weight `weight`; N ← min(N + 1, N_max), α = max(1/N, α_min),
// w̄' = mix(w̄, f, α), β = αf/w̄', ȳ' = (1 − β)ȳ + βy, and 1 − r̄ in the CPU's
// cancellation-free complement forms. Returns false (and leaves `stats` alone) for a
// negative or non-finite weight or point.
fn vmf_stats_update(stats: ptr<function, VmfSufficientStats>, x: vec3<f32>, y: vec3<f32>, weight: f32, params: VmfFitParams) -> bool {
    if !(weight >= 0.0 && mcg_is_finite(weight) && mcg_is_finite3(x) && mcg_is_finite3(y)) {
        return false;
    }
    let s = *stats;
    let max_count = max(params.max_count, 1u);
    let count = min(select(s.sample_count + 1u, s.sample_count, s.sample_count == 0xffffffffu), max_count);
    let alpha = min(max(1.0 / f32(count), clamp(params.alpha_min, 0.0, 1.0)), 1.0);
    let weight_sum = min((1.0 - alpha) * s.weight_sum + alpha * weight, max(s.weight_sum, weight));
    (*stats).sample_count = count;
    if !(weight_sum > 0.0) {
        (*stats).weight_sum = 0.0;
        return true;
    }
    let beta = min(alpha * weight / weight_sum, 1.0);
    var direction = vec3<f32>(0.0);
    if !vmf_try_normalize(y - x, &direction) {
        direction = vec3<f32>(0.0);
    }
    let mean_target = vec3<f32>(s.mean_target_x, s.mean_target_y, s.mean_target_z);
    var mean_direction = direction;
    if s.weight_sum > 0.0 {
        if !vmf_try_normalize(mean_target - x, &mean_direction) {
            mean_direction = direction;
        }
    }
    let e = s.one_minus_mean_cosine;
    if all(direction == vec3<f32>(0.0)) {
        (*stats).one_minus_mean_cosine = beta + (1.0 - beta) * e;
    } else {
        let dd = direction - mean_direction;
        let t = 0.5 * (dd.x * dd.x + dd.y * dd.y + dd.z * dd.z);
        if params.mean_cosine_update == VMF_MEAN_COSINE_PROJECTED {
            (*stats).one_minus_mean_cosine = clamp((1.0 - beta) * e + beta * t, 0.0, 2.0);
        } else {
            let ec = clamp(e, 0.0, 1.0);
            let keep = 1.0 - beta;
            let d = clamp(keep * keep * ec * (2.0 - ec) + 2.0 * beta * keep * (ec + t - ec * t), 0.0, 1.0);
            (*stats).one_minus_mean_cosine = d / (1.0 + sqrt(1.0 - d));
        }
    }
    let new_target = mean_target * (1.0 - beta) + y * beta;
    if mcg_is_finite3(new_target) {
        (*stats).mean_target_x = new_target.x;
        (*stats).mean_target_y = new_target.y;
        (*stats).mean_target_z = new_target.z;
    }
    (*stats).weight_sum = weight_sum;
    return true;
}

// dA₃/dκ = 1/κ² − 1/sinh²κ (`mean_cosine::mean_cosine_derivative`), series below
// VMF_SERIES_LIMIT; 1/sinh²κ as 4e^{−2κ}/expm1(−2κ)², which underflows instead of overflowing.
fn vmf_mean_cosine_derivative(kappa: f32) -> f32 {
    if kappa < VMF_SERIES_LIMIT {
        let k2 = kappa * kappa;
        return VMF_MEAN_COSINE_DERIVATIVE_SERIES_0 + k2 * (VMF_MEAN_COSINE_DERIVATIVE_SERIES_1 + k2 * (VMF_MEAN_COSINE_DERIVATIVE_SERIES_2 + k2 * VMF_MEAN_COSINE_DERIVATIVE_SERIES_3));
    }
    let e = exp(-2.0 * kappa);
    let d = vmf_exp_m1(-2.0 * kappa);
    return 1.0 / (kappa * kappa) - 4.0 * e / (d * d);
}

// 1 − A₃(κ) without cancellation near 1 (`mean_cosine::one_minus_mean_cosine`).
fn vmf_one_minus_mean_cosine(kappa: f32) -> f32 {
    if kappa < VMF_SERIES_LIMIT {
        return 1.0 - vmf_mean_cosine_from_kappa(kappa);
    }
    return 1.0 / kappa - 2.0 / vmf_exp_m1(2.0 * kappa);
}

// κ with A₃(κ) = r to f32 precision (`kappa_from_mean_cosine_exact`): Newton's method from
// Banerjee's κ on A₃(κ) = r, or on 1 − A₃(κ) = 1 − r from r = VMF_NEWTON_COMPLEMENT_FROM on;
// at most VMF_NEWTON_MAX_ITERATIONS steps, stopping at a relative step of
// VMF_NEWTON_RELATIVE_STEP; clamped to [0, VMF_KAPPA_MAX]; 0 for r ≤ 0 or NaN.
fn vmf_kappa_from_mean_cosine_exact(r: f32) -> f32 {
    if !mcg_is_positive(r) {
        return 0.0;
    }
    if r >= 1.0 {
        return VMF_KAPPA_MAX;
    }
    let epsilon = 1.0 - r;
    if epsilon <= 1.0 / VMF_KAPPA_MAX {
        return VMF_KAPPA_MAX;
    }
    var kappa = vmf_kappa_from_mean_cosine(r);
    for (var i = 0u; i < VMF_NEWTON_MAX_ITERATIONS; i += 1u) {
        var residual: f32;
        if r < VMF_NEWTON_COMPLEMENT_FROM {
            residual = vmf_mean_cosine_from_kappa(kappa) - r;
        } else {
            residual = epsilon - vmf_one_minus_mean_cosine(kappa);
        }
        let slope = vmf_mean_cosine_derivative(kappa);
        if !(slope > 0.0) {
            break;
        }
        var next = kappa - residual / slope;
        if !(next > 0.0) {
            next = 0.5 * kappa;
        }
        let converged = abs(next - kappa) <= VMF_NEWTON_RELATIVE_STEP * kappa;
        kappa = min(next, VMF_KAPPA_MAX);
        if converged {
            break;
        }
    }
    return kappa;
}

// Approximate convolution with a rotationally symmetric vMF kernel of concentration
// `kernel_kappa` (`Vmf::convolve`): mean cosines multiply (Funk-Hecke), μ is kept and
// κ' = A₃⁻¹(A₃(κ) A₃(κ_kernel)). A negative or NaN kernel κ blurs to uniform.
fn vmf_convolve(lobe: Vmf, kernel_kappa: f32) -> Vmf {
    let r = vmf_mean_cosine_from_kappa(lobe.kappa) * vmf_mean_cosine_from_kappa(kernel_kappa);
    return Vmf(lobe.mu, vmf_kappa_from_mean_cosine_exact(r));
}
