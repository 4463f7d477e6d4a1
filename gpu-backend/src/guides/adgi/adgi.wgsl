#define_import_path mcg::adgi
// ADGI's probe cache ("Adaptive Dynamic Global Illumination", ADGI) and DDGI's uniform
// update (Majercik et al. 2019) as one module a renderer imports: the twin of
// `mcg_probe_cache::ProbeTexels` (texel words, per-sample update, DDGI blend, irradiance query,
// clip-volume count reset).
//
//   adgi_update_sample(probe, direction, radiance, distance, u, max_count); // ADGI Alg. 2-4
//   adgi_blend_texel(probe, k, u);   // DDGI sec. 4, the probe's rays in adgi_rays
//   let e = adgi_irradiance_at(x, n, to_viewer);                             // DDGI sec. 4-5
//
// Bindings, all in one group chosen by the shader def MCG_ADGI_GROUP (the host object
// `GpuProbeCache` builds that group; 6 holds the pilot rays' state): 0 the parameters
// (`adgi_params`), 1 the texel words (`mcg_codec_texels` of `mcg::color_codec_texels`: set
// MCG_CODEC_TEXELS_GROUP to the same group and MCG_CODEC_TEXELS_BINDING to 1; the irradiance words
// first, probe-major, then the visibility words from `adgi_params.visibility_offset`), 2 the
// interior texels' centre directions and solid angles (`adgi_texel_table`, computed on the host by
// the CPU crate's `TexelMap`, irradiance texels first), 3 the rays of DDGI's blend (`adgi_rays`,
// probe-major, written by the renderer). Maps are octahedral with the ADGI word layouts of
// `mcg::color_codec`. With the shader def MCG_ADGI_FLOAT_TEXELS the query reads float texels at
// bindings 4 and 5 instead (the benches' RGBA32F + RG32F baseline).

#import mcg::constants::{
    ADGI_BLEND_WEIGHT_EPSILON, ADGI_TEXEL_UNIFORM_PERIOD, ADGI_TEXEL_UNIFORM_STEP,
    ADGI_WRAP_SHADING_OFFSET, CODEC_IRRADIANCE_COUNT_BITS, CODEC_IRRADIANCE_COUNT_SHIFT,
    CODEC_VISIBILITY_COUNT_BITS, CODEC_VISIBILITY_COUNT_SHIFT, MCG_F32_EPSILON, MCG_F32_MAX,
    MCG_FRAC_PI_2, MCG_ONE_MINUS_EPSILON, MCG_PI, MCPG_LUMINANCE_B, MCPG_LUMINANCE_G,
    MCPG_LUMINANCE_R
}
#import mcg::math::{
    mcg_any_nan3, mcg_is_finite, mcg_is_finite3, mcg_is_nan, mcg_rounded, mcg_rounded3
}
#import mcg::color_codec::{
    CodecRounding, codec_bit_mask, codec_irradiance_decode, codec_visibility_decode
}
#import mcg::color_codec_texels::{
    codec_irradiance_update_atomic, codec_visibility_update_atomic, mcg_codec_texels
}

// Everything the module reads (`AdgiGpuParams` on the host, 144 bytes): the grid, the two maps,
// where the visibility words start, the moving average and rounding, the codec's range, DDGI's
// blend exponents and the query's constants (`QueryConfig`).
struct AdgiParams {
    origin: vec3<f32>,
    cell_diagonal: f32,
    spacing: vec3<f32>,
    min_spacing: f32,
    counts: vec3<u32>,
    probe_count: u32,
    irradiance_side: u32,
    irradiance_interior: u32,
    visibility_side: u32,
    visibility_interior: u32,
    visibility_offset: u32,
    max_count: u32,
    rounding: u32,
    rays_per_probe: u32,
    max_distance: f32,
    irradiance_max_value: f32,
    irradiance_power: f32,
    distance_power: f32,
    radiance_content: u32,
    normal_bias: f32,
    view_bias: f32,
    wrap_shading: u32,
    visibility: u32,
    chebyshev_floor: f32,
    crush_threshold: f32,
    min_weight: f32,
    min_trilinear: f32,
    sqrt_blend: u32,
    shell_count: u32,
    pad_a: u32,
}

// One ray a renderer traced from a probe (`RaySample` plus the probe's index; `GpuRaySample`
// on the host, 32 bytes): direction (any length), hit distance in world units (+∞ or any value
// past the codec's range for a miss, NaN ignored), radiance (NaN: a failed ray, ignored).
struct AdgiRaySample {
    direction: vec3<f32>,
    distance: f32,
    radiance: vec3<f32>,
    probe: u32,
}

@group(#{MCG_ADGI_GROUP}) @binding(0) var<uniform> adgi_params: AdgiParams;
@group(#{MCG_ADGI_GROUP}) @binding(2) var<storage, read> adgi_texel_table: array<vec4<f32>>;
@group(#{MCG_ADGI_GROUP}) @binding(3) var<storage, read> adgi_rays: array<AdgiRaySample>;
// Per probe and octant (`probe · 8 + octant`): the pilot rays' reference f_v, f_r and the
// temporal trigger's states for f_v and f_r (`adgi_pilot_update`).
@group(#{MCG_ADGI_GROUP}) @binding(6) var<storage, read_write> adgi_pilot_state: array<vec4<f32>>;


// ±1 with the sign of each component, +1 for ±0 (RTXGI's `DDGISignNotZero`).
fn adgi_sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2<f32>(-1.0), vec2<f32>(1.0), v >= vec2<f32>(0.0));
}

// `octahedral_encode`: square coordinates in [−1, 1]² of a direction (any length; zero or NaN
// reads the +z pole).
fn adgi_octahedral_encode(d: vec3<f32>) -> vec2<f32> {
    let l1 = abs(d.x) + abs(d.y) + abs(d.z);
    if !(l1 > 0.0) || !mcg_is_finite(l1) {
        return vec2<f32>(0.0);
    }
    let uv = d.xy / l1;
    var folded = uv;
    if d.z < 0.0 {
        folded = (vec2<f32>(1.0) - vec2<f32>(abs(uv.y), abs(uv.x))) * adgi_sign_not_zero(uv);
    }
    return clamp(folded, vec2<f32>(-1.0), vec2<f32>(1.0));
}

// `Vec3::dot` in the CPU's order, each product rounded on its own.
fn adgi_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return mcg_rounded(a.x * b.x) + mcg_rounded(a.y * b.y) + mcg_rounded(a.z * b.z);
}

// `Vec3::try_normalize`; the zero vector when it would fail.
fn adgi_try_normalize(v: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / sqrt(adgi_dot(v, v));
    if mcg_is_finite(rcp) && rcp > 0.0 {
        return v * rcp;
    }
    return vec3<f32>(0.0);
}

// `TexelMap::texel` then `TexelMap::index`: the stored texel (always interior) that `d` lands
// in, of a map with `side` stored and `interior` covering texels.
fn adgi_map_texel(d: vec3<f32>, side: u32, interior: u32) -> u32 {
    let border = (side - interior) / 2u;
    let half_n = 0.5 * f32(interior);
    let c = (adgi_octahedral_encode(d) + vec2<f32>(1.0)) * half_n;
    let shifted = vec2<f32>(mcg_rounded(c.x), mcg_rounded(c.y)) + vec2<f32>(f32(border));
    let t = clamp(vec2<u32>(max(shifted, vec2<f32>(0.0))), vec2<u32>(border), vec2<u32>(border + interior - 1u));
    return t.y * side + t.x;
}

// The stored index of interior texel `k` (row-major over the interior) of a map.
fn adgi_interior_index(k: u32, side: u32, interior: u32) -> u32 {
    let border = (side - interior) / 2u;
    return (k / interior + border) * side + k % interior + border;
}

// `rotate_uniform`: the k-th rotation u + (k mod P)·step mod 1 of a uniform.
fn adgi_rotate_uniform(u: f32, k: u32) -> f32 {
    let v = u + mcg_rounded(f32(k % ADGI_TEXEL_UNIFORM_PERIOD) * ADGI_TEXEL_UNIFORM_STEP);
    let f = v - floor(v);
    return select(0.0, f, f < 1.0);
}

// `ProbeTexels::normalise_distance`: world distance → cell diagonals in [0, max_distance];
// −1 for NaN (no update).
fn adgi_normalise_distance(distance: f32) -> f32 {
    if mcg_is_nan(distance) {
        return -1.0;
    }
    return clamp(distance / adgi_params.cell_diagonal, 0.0, adgi_params.max_distance);
}

// Word index of probe `probe`'s irradiance texel `texel` in `mcg_codec_texels`.
fn adgi_irradiance_word_index(probe: u32, texel: u32) -> u32 {
    return probe * adgi_params.irradiance_side * adgi_params.irradiance_side + texel;
}

// Word index of probe `probe`'s visibility texel `texel`.
fn adgi_visibility_word_index(probe: u32, texel: u32) -> u32 {
    let side = adgi_params.visibility_side;
    return adgi_params.visibility_offset + probe * side * side + texel;
}

fn adgi_rounding(u: f32) -> CodecRounding {
    return CodecRounding(adgi_params.rounding, u);
}

// ADGI's per-sample update (`ProbeTexels::update_sample_with`, ADGI Alg. 2 line 3, Alg. 3-4):
// one moving-average step, N_max = `max_count`, of the irradiance texel the direction lands in
// toward `radiance` and of the visibility texel toward (t, t²), t the hit distance in cell
// diagonals; stochastic rounding from `u` (the visibility word takes its first rotation).
fn adgi_update_sample(probe: u32, direction: vec3<f32>, radiance: vec3<f32>, distance: f32, u: f32, max_count: u32) {
    // A NaN component leaves the word unchanged (`MovingAverage::update`).
    if !mcg_any_nan3(radiance) {
        let ti = adgi_map_texel(direction, adgi_params.irradiance_side, adgi_params.irradiance_interior);
        codec_irradiance_update_atomic(adgi_irradiance_word_index(probe, ti), radiance, max_count, adgi_rounding(u));
    }
    let t = adgi_normalise_distance(distance);
    if t >= 0.0 {
        let tv = adgi_map_texel(direction, adgi_params.visibility_side, adgi_params.visibility_interior);
        let moments = vec2<f32>(t, t * t);
        codec_visibility_update_atomic(adgi_visibility_word_index(probe, tv), moments, max_count, adgi_rounding(adgi_rotate_uniform(u, 1u)));
    }
}

// `pow_weight`: c^p with the CPU's exact products for p = 1 and p = 50.
fn adgi_pow_weight(c: f32, p: f32) -> f32 {
    if p == 1.0 {
        return c;
    }
    if p == 50.0 {
        let c2 = c * c;
        let c5 = c2 * c2 * c;
        let c10 = c5 * c5;
        let c20 = c10 * c10;
        return c20 * c20 * c10;
    }
    return pow(c, p);
}

// Invocations of one DDGI blend pass per probe: every interior texel of both maps.
fn adgi_blend_texels_per_probe() -> u32 {
    let ni = adgi_params.irradiance_interior;
    let nv = adgi_params.visibility_interior;
    return ni * ni + nv * nv;
}

// DDGI's blend (`ProbeTexels::blend_rays`) for one texel: interior texel `k` of probe `probe`
// (irradiance texels first, then visibility texels), from the probe's `adgi_params.rays_per_probe`
// rays in `adgi_rays`, rounding with rotation k of the probe's uniform `u`. Returns the word
// written (or the old word when no ray reached the texel).
fn adgi_blend_texel(probe: u32, k: u32, u: f32) -> u32 {
    let ni = adgi_params.irradiance_interior * adgi_params.irradiance_interior;
    let first = probe * adgi_params.rays_per_probe;
    let last = first + adgi_params.rays_per_probe;
    let is_irradiance = k < ni;
    // The table holds the irradiance texels, then the visibility texels: entry k either way.
    let n = adgi_texel_table[k].xyz;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var r = first; r < last; r += 1u) {
        let ray = adgi_rays[r];
        let d = adgi_try_normalize(ray.direction);
        if all(d == vec3<f32>(0.0)) {
            continue;
        }
        var x: vec3<f32>;
        var power: f32;
        if is_irradiance {
            if mcg_any_nan3(ray.radiance) {
                continue;
            }
            x = clamp(ray.radiance, vec3<f32>(0.0), vec3<f32>(adgi_params.irradiance_max_value));
            power = adgi_params.irradiance_power;
        } else {
            let t = adgi_normalise_distance(ray.distance);
            if t < 0.0 {
                continue;
            }
            x = vec3<f32>(t, t * t, 0.0);
            power = adgi_params.distance_power;
        }
        let c = adgi_dot(n, d);
        if c > 0.0 {
            let w = adgi_pow_weight(c, power);
            sum += mcg_rounded3(w * x);
            wsum += w;
        }
    }
    if is_irradiance {
        let index = adgi_irradiance_word_index(probe, adgi_interior_index(k, adgi_params.irradiance_side, adgi_params.irradiance_interior));
        if wsum > ADGI_BLEND_WEIGHT_EPSILON {
            return codec_irradiance_update_atomic(index, sum / wsum, adgi_params.max_count, adgi_rounding(adgi_rotate_uniform(u, k)));
        }
        return atomicLoad(&mcg_codec_texels[index]);
    }
    let kv = k - ni;
    let index = adgi_visibility_word_index(probe, adgi_interior_index(kv, adgi_params.visibility_side, adgi_params.visibility_interior));
    if wsum > ADGI_BLEND_WEIGHT_EPSILON {
        return codec_visibility_update_atomic(index, sum.xy / wsum, adgi_params.max_count, adgi_rounding(adgi_rotate_uniform(u, k)));
    }
    return atomicLoad(&mcg_codec_texels[index]);
}

// `TexelMap::fold`: interior coordinates in [−1, n]² folded back by the border rule.
fn adgi_fold(xy: vec2<i32>, interior: u32) -> vec2<u32> {
    let n = i32(interior);
    var x = xy.x;
    var y = xy.y;
    if x < 0 || x >= n {
        x = clamp(x, 0, n - 1);
        y = n - 1 - y;
    }
    if y < 0 || y >= n {
        y = clamp(y, 0, n - 1);
        x = n - 1 - x;
    }
    return vec2<u32>(vec2<i32>(clamp(x, 0, n - 1), clamp(y, 0, n - 1)));
}

#ifdef MCG_ADGI_FLOAT_TEXELS
// DDGI's float texels instead of the packed words (shader def MCG_ADGI_FLOAT_TEXELS): RGBA32F
// irradiance texels (RGB, count in A) and RG32F visibility moments, at bindings 4 and 5 of the
// group, same probe-major layout. The baseline of the benches; `GpuProbeCache` binds words.
@group(#{MCG_ADGI_GROUP}) @binding(4) var<storage, read_write> adgi_float_irradiance: array<vec4<f32>>;
@group(#{MCG_ADGI_GROUP}) @binding(5) var<storage, read_write> adgi_float_visibility: array<vec2<f32>>;

// The value of probe `probe`'s irradiance texel `texel`.
fn adgi_load_irradiance(probe: u32, texel: u32) -> vec3<f32> {
    return adgi_float_irradiance[adgi_irradiance_word_index(probe, texel)].xyz;
}

// The moments (t̄, t̄²) of probe `probe`'s visibility texel `texel`.
fn adgi_load_moments(probe: u32, texel: u32) -> vec2<f32> {
    let side = adgi_params.visibility_side;
    return adgi_float_visibility[probe * side * side + texel];
}
#else
// The value of probe `probe`'s irradiance texel `texel` (`IrradianceLayout::decode`).
fn adgi_load_irradiance(probe: u32, texel: u32) -> vec3<f32> {
    return codec_irradiance_decode(atomicLoad(&mcg_codec_texels[adgi_irradiance_word_index(probe, texel)]));
}

// The moments (t̄, t̄²) of probe `probe`'s visibility texel `texel` (`VisibilityLayout::decode`).
fn adgi_load_moments(probe: u32, texel: u32) -> vec2<f32> {
    return codec_visibility_decode(atomicLoad(&mcg_codec_texels[adgi_visibility_word_index(probe, texel)]));
}
#endif

// The four bilinear taps of a map (`TexelMap::bilinear`): stored indices and weights.
struct AdgiTaps {
    index: vec4<u32>,
    weight: vec4<f32>,
}

fn adgi_bilinear(d: vec3<f32>, side: u32, interior: u32) -> AdgiTaps {
    let n = f32(interior);
    let border = vec2<u32>((side - interior) / 2u);
    let scaled = (adgi_octahedral_encode(d) + vec2<f32>(1.0)) * (0.5 * n);
    let c0 = vec2<f32>(mcg_rounded(scaled.x), mcg_rounded(scaled.y)) - vec2<f32>(0.5);
    let c = clamp(c0, vec2<f32>(-0.5), vec2<f32>(n - 0.5));
    let x0 = i32(c.x + 1.0) - 1;
    let y0 = i32(c.y + 1.0) - 1;
    let w = clamp(c - vec2<f32>(f32(x0), f32(y0)), vec2<f32>(0.0), vec2<f32>(1.0));
    var taps: AdgiTaps;
    for (var i = 0; i < 4; i += 1) {
        let t = adgi_fold(vec2<i32>(x0 + (i & 1), y0 + (i >> 1u)), interior) + border;
        let clamped = min(t, vec2<u32>(side - 1u));
        taps.index[i] = clamped.y * side + clamped.x;
    }
    taps.weight = vec4<f32>((1.0 - w.x) * (1.0 - w.y), w.x * (1.0 - w.y), (1.0 - w.x) * w.y, w.x * w.y);
    return taps;
}

// `ProbeTexels::probe_irradiance`: E(n) of one probe for unit `n` — π × the bilinear lookup
// for irradiance texels (DDGI's blend), the normalised cosine convolution over the interior
// texels for radiance texels (ADGI's per-sample update).
fn adgi_probe_irradiance(probe: u32, n: vec3<f32>, taps: AdgiTaps) -> vec3<f32> {
    if adgi_params.radiance_content == 0u {
        var e = vec3<f32>(0.0);
        for (var i = 0; i < 4; i += 1) {
            e += taps.weight[i] * adgi_load_irradiance(probe, taps.index[i]);
        }
        return MCG_PI * e;
    }
    let side = adgi_params.irradiance_side;
    let interior = adgi_params.irradiance_interior;
    var e = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var k = 0u; k < interior * interior; k += 1u) {
        let t = adgi_texel_table[k];
        let c = dot(n, t.xyz);
        if c > 0.0 {
            let w = c * t.w;
            e += w * adgi_load_irradiance(probe, adgi_interior_index(k, side, interior));
            wsum += w;
        }
    }
    if wsum > 0.0 {
        return e * (MCG_PI / wsum);
    }
    return vec3<f32>(0.0);
}

// `ProbeTexels::probe_moments`: bilinear (t̄, t̄²) of one probe in direction `d`.
fn adgi_probe_moments(probe: u32, d: vec3<f32>) -> vec2<f32> {
    let taps = adgi_bilinear(d, adgi_params.visibility_side, adgi_params.visibility_interior);
    var m = vec2<f32>(0.0);
    for (var i = 0; i < 4; i += 1) {
        if taps.weight[i] > 0.0 {
            m += taps.weight[i] * adgi_load_moments(probe, taps.index[i]);
        }
    }
    return m;
}

// `ProbeTexels::irradiance_at`: irradiance at shading point `x` with normal `n`, seen from
// `to_viewer` (zero for no view bias), from the eight probes around it (DDGI sec. 4-5; RTXGI's
// `DDGIGetVolumeIrradiance`): trilinear weights, wrap shading, Chebyshev visibility
// (σ²/(σ² + (r − t̄)²))³ with its floor, the crush of small weights, and the blend in
// square-root space. Always finite and non-negative; black for a non-finite point.
fn adgi_irradiance_at(x: vec3<f32>, n_in: vec3<f32>, to_viewer: vec3<f32>) -> vec3<f32> {
    if !mcg_is_finite3(x) {
        return vec3<f32>(0.0);
    }
    let p = adgi_params;
    let n = adgi_try_normalize(n_in);
    let has_normal = any(n != vec3<f32>(0.0));
    let v = adgi_try_normalize(to_viewer);
    let bias = (n * p.normal_bias + v * p.view_bias) * p.min_spacing;
    var biased = x;
    if mcg_is_finite3(bias) {
        biased = x + bias;
    }
    // `ProbeGrid::cell`.
    let last_cell = vec3<f32>(max(p.counts, vec3<u32>(2u)) - vec3<u32>(2u));
    let t = max((biased - p.origin) / p.spacing, vec3<f32>(0.0));
    let base = min(floor(t), last_cell);
    let alpha = select(min(t - base, vec3<f32>(1.0)), vec3<f32>(0.0), p.counts == vec3<u32>(1u));
    let inv_diag = 1.0 / p.cell_diagonal;
    let lookup_n = select(vec3<f32>(0.0, 0.0, 1.0), n, has_normal);
    let taps = adgi_bilinear(lookup_n, p.irradiance_side, p.irradiance_interior);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let step = vec3<u32>(corner & 1u, (corner >> 1u) & 1u, (corner >> 2u) & 1u);
        let coords = min(vec3<u32>(base) + step, p.counts - vec3<u32>(1u));
        let tri = max(select(vec3<f32>(1.0) - alpha, alpha, step == vec3<u32>(1u)), vec3<f32>(p.min_trilinear));
        let probe = coords.x + p.counts.x * (coords.y + p.counts.y * coords.z);
        let position = p.origin + vec3<f32>(coords) * p.spacing;
        var w = 1.0;
        if p.wrap_shading != 0u {
            let d = adgi_try_normalize(position - x);
            let s = (dot(n, d) + 1.0) * 0.5;
            w *= s * s + ADGI_WRAP_SHADING_OFFSET;
        }
        if p.visibility != 0u {
            let to_probe = position - biased;
            let r = length(to_probe);
            if r > 0.0 {
                let m = adgi_probe_moments(probe, -to_probe / r);
                let rn = r * inv_diag;
                if rn > m.x {
                    let variance = abs(m.y - m.x * m.x);
                    let delta = rn - m.x;
                    let c = variance / (variance + delta * delta);
                    var cheb = 0.0;
                    if mcg_is_finite(c) {
                        cheb = c * c * c;
                    }
                    w *= max(cheb, p.chebyshev_floor);
                }
            }
        }
        w = max(w, p.min_weight);
        if w < p.crush_threshold {
            w *= w * w / (p.crush_threshold * p.crush_threshold);
        }
        w *= tri.x * tri.y * tri.z;
        let e = adgi_probe_irradiance(probe, lookup_n, taps);
        if p.sqrt_blend != 0u {
            sum += w * sqrt(max(e, vec3<f32>(0.0)));
        } else {
            sum += w * e;
        }
        wsum += w;
    }
    if !(wsum > 0.0) {
        return vec3<f32>(0.0);
    }
    var e = sum / wsum;
    if p.sqrt_blend != 0u {
        e = e * e;
    }
    if mcg_is_finite3(e) {
        return max(e, vec3<f32>(0.0));
    }
    return vec3<f32>(0.0);
}

// Lowers the count of word `index` to at most `cap`, keeping the value (`cap_counts`,
// `clamp_irradiance_counts` / `clamp_visibility_counts`): irradiance words below
// `adgi_params.visibility_offset`, visibility words from it. Returns whether it changed.
fn adgi_cap_word(index: u32, cap: u32) -> bool {
    var shift = CODEC_IRRADIANCE_COUNT_SHIFT;
    var mask = codec_bit_mask(CODEC_IRRADIANCE_COUNT_BITS);
    if index >= adgi_params.visibility_offset {
        shift = CODEC_VISIBILITY_COUNT_SHIFT;
        mask = codec_bit_mask(CODEC_VISIBILITY_COUNT_BITS);
    }
    var current = atomicLoad(&mcg_codec_texels[index]);
    loop {
        if ((current >> shift) & mask) <= cap {
            return false;
        }
        let next = (current & ~(mask << shift)) | (cap << shift);
        let r = atomicCompareExchangeWeak(&mcg_codec_texels[index], current, next);
        if r.exchanged {
            return true;
        }
        current = r.old_value;
    }
    return false;
}

// The probe a texel word belongs to.
fn adgi_word_probe(index: u32) -> u32 {
    if index >= adgi_params.visibility_offset {
        let side = adgi_params.visibility_side;
        return (index - adgi_params.visibility_offset) / (side * side);
    }
    let side = adgi_params.irradiance_side;
    return index / (side * side);
}

// Words of both maps of every probe: the invocations of a pass over every word.
fn adgi_word_count() -> u32 {
    let vs = adgi_params.visibility_side;
    return adgi_params.visibility_offset + adgi_params.probe_count * vs * vs;
}

// `ProbeGrid::probe_position` of the probe with linear index `probe`.
fn adgi_probe_position(probe: u32) -> vec3<f32> {
    let c = adgi_params.counts;
    let coords = vec3<u32>(probe % c.x, (probe / c.x) % c.y, probe / (c.x * c.y));
    return adgi_params.origin + mcg_rounded3(vec3<f32>(coords) * adgi_params.spacing);
}

// ADGI's clip volumes (Fig. 6b): a frustum (six planes n·p + d ≥ 0 inside) intersected with a
// box (`ClipVolume`). `AdgiClipVolumes` holds V_in and V_out (`GpuClipVolumes` on the host).
struct AdgiClipVolume {
    planes: array<vec4<f32>, 6>,
    min_corner: vec4<f32>,
    max_corner: vec4<f32>,
}

struct AdgiClipVolumes {
    inner: AdgiClipVolume,
    outer: AdgiClipVolume,
}

// `ClipVolume::contains`.
fn adgi_clip_contains(v: AdgiClipVolume, p: vec3<f32>) -> bool {
    if !(all(p >= v.min_corner.xyz) && all(p <= v.max_corner.xyz)) {
        return false;
    }
    for (var i = 0; i < 6; i += 1) {
        let pl = v.planes[i];
        if !(adgi_dot(pl.xyz, p) + pl.w >= 0.0) {
            return false;
        }
    }
    return true;
}

// Whether probe `probe` lies in the shell V_out − V_in (`ClipVolumes::classify` is `Shell`).
fn adgi_in_shell(volumes: AdgiClipVolumes, probe: u32) -> bool {
    let p = adgi_probe_position(probe);
    return !adgi_clip_contains(volumes.inner, p) && adgi_clip_contains(volumes.outer, p);
}

// Whether probe `probe` traces pilot rays: it lies in V_out (`ClipVolumes::traces_pilots`).
fn adgi_traces_pilots(volumes: AdgiClipVolumes, probe: u32) -> bool {
    let p = adgi_probe_position(probe);
    return adgi_clip_contains(volumes.inner, p) || adgi_clip_contains(volumes.outer, p);
}

// `pilot_direction` (ADGI sec. 4.4): the stratified pilot direction of octant `octant` from
// uniforms `u` — (z, φ) uniform on the first octant's patch of the sphere (z ∈ (0, 1),
// φ ∈ (0, π/2)), mirrored into the octant; inputs clamped to [2⁻²⁴, 1 − 2⁻²⁴] (NaN → ½).
fn adgi_pilot_direction(octant: u32, u: vec2<f32>) -> vec3<f32> {
    let lo = 0.5 * MCG_F32_EPSILON;
    var open = clamp(u, vec2<f32>(lo), vec2<f32>(MCG_ONE_MINUS_EPSILON));
    if mcg_is_nan(u.x) {
        open.x = 0.5;
    }
    if mcg_is_nan(u.y) {
        open.y = 0.5;
    }
    let z = open.x;
    let phi = open.y * MCG_FRAC_PI_2;
    // `mcg_rounded` keeps z² from fusing into an FMA with the subtraction, as on the CPU.
    let r = sqrt(max(1.0 - mcg_rounded(z * z), 0.0));
    let signs = select(vec3<f32>(1.0), vec3<f32>(-1.0), (vec3<u32>(octant) >> vec3<u32>(0u, 1u, 2u) & vec3<u32>(1u)) == vec3<u32>(1u));
    return vec3<f32>(r * cos(phi), r * sin(phi), z) * signs;
}

// `heuristics::probe_visibility` (ADGI eq. 11): f_v = exp(−2t/s) for a hit at distance t
// along −ω, s the voxel diagonal; 1 for t ≤ 0, 0 for a miss.
fn adgi_probe_visibility(t: f32, s: f32) -> f32 {
    if mcg_is_nan(t) {
        return 0.0;
    }
    if t <= 0.0 {
        return 1.0;
    }
    if !(s > 0.0) {
        return 0.0;
    }
    let ratio = 2.0 * t / s;
    if mcg_is_nan(ratio) {
        return 0.0;
    }
    return exp(-ratio);
}

// `heuristics::incoming_radiance` (ADGI eq. 12): f_r = min(r, β)/β.
fn adgi_incoming_radiance(r: f32, beta: f32) -> f32 {
    if !(beta > 0.0) || !mcg_is_finite(beta) || !(r > 0.0) {
        return 0.0;
    }
    return min(r, beta) / beta;
}

// `TemporalTrigger::apply` (ADGI eq. 14, 17): max(|pulse|, θ · state).
fn adgi_trigger(pulse: f32, state: f32, decay: f32) -> f32 {
    var x = 0.0;
    if !mcg_is_nan(pulse) {
        x = min(abs(pulse), MCG_F32_MAX);
    }
    var y = 0.0;
    if state > 0.0 {
        y = min(state, MCG_F32_MAX);
    }
    return max(x, decay * y);
}

// `temporal_gradient` of one entry: current − previous, 0 when not finite.
fn adgi_gradient(current: f32, previous: f32) -> f32 {
    let d = current - previous;
    return select(0.0, d, mcg_is_finite(d));
}

// Rec. 709 luminance (`guiding_function::LUMINANCE`).
fn adgi_luminance(rgb: vec3<f32>) -> f32 {
    return adgi_dot(rgb, vec3<f32>(MCPG_LUMINANCE_R, MCPG_LUMINANCE_G, MCPG_LUMINANCE_B));
}

// One pilot update of probe `probe`, octant `octant` from the probe's 8 hits (`hit_r` traced
// in the octant, `hit_v` in the opposite one, eq. 11 uses −ω): f_v, f_r (`octant_heuristics`);
// on a detection frame the temporal gradient against the reference and the trigger
// (`ChangeDetector::detect` before its smoothing); then the finite values become the
// reference. Returns (f_v, f_r, trigger_v, trigger_r) as stored.
fn adgi_pilot_update(probe: u32, octant: u32, hit_r: AdgiRaySample, hit_v: AdgiRaySample, voxel_diagonal: f32, radiance_range: f32, decay: f32, detect: bool) -> vec4<f32> {
    let f_v = adgi_probe_visibility(hit_v.distance, voxel_diagonal);
    let f_r = adgi_incoming_radiance(adgi_luminance(hit_r.radiance), radiance_range);
    let i = probe * 8u + octant;
    var s = adgi_pilot_state[i];
    if detect {
        s.z = adgi_trigger(adgi_gradient(f_v, s.x), s.z, decay);
        s.w = adgi_trigger(adgi_gradient(f_r, s.y), s.w, decay);
    }
    if mcg_is_finite(f_v) {
        s.x = f_v;
    }
    if mcg_is_finite(f_r) {
        s.y = f_r;
    }
    adgi_pilot_state[i] = s;
    return s;
}
