// The spatial and directional smoothing of the temporal triggers (ADGI sec. 4.1.4, eq. 15 and
// 18; `temporal_gradient::spatial_smoothing`), one pass per axis: the probe cache's group at
// group 0 (the trigger states in `adgi_pilot_state.zw`), the pass at group 1.
//
// The CPU's filter is separable: the octant average (the octant and its three edge-adjacent
// octants, o ^ 1, o ^ 2, o ^ 4), then box means of the in-grid probes within the radius along
// x, y and z, in that order. Pass 0 reads the trigger states and averages the octants of each
// tap as it goes (the same sums in the same order); passes 1 and 2 read the previous pass.
// Every sum and product rounds as on the CPU, and the box's reciprocals 1/n come from the host,
// so the result is the CPU's bit for bit.

#import mcg::constants::{MCG_F32_MAX, MCG_WORKGROUP_SIZE}
#import mcg::dispatch::mcg_invocation_index
#import mcg::math::mcg_is_finite
#import mcg::adgi::{adgi_params, adgi_pilot_state}

// One pass (`GpuSmoothingPass` on the host, 16 bytes): the axis (0 x, 1 y, 2 z), the radius r
// in probes, 1 to average octants (pass 0 only).
struct AdgiSmoothingPass {
    axis: u32,
    radius: u32,
    directional: u32,
    pad_a: u32,
}

@group(1) @binding(0) var<uniform> smoothing_pass: AdgiSmoothingPass;
@group(1) @binding(1) var<storage, read> smoothing_src: array<vec2<f32>>;
@group(1) @binding(2) var<storage, read_write> smoothing_dst: array<vec2<f32>>;
// reciprocals[n] = 1/n as the CPU's f32 division rounds it (n ≤ the longest axis).
@group(1) @binding(3) var<storage, read> smoothing_reciprocals: array<f32>;

// 0 for NaN and ±∞ (the CPU's `finite`).
fn smoothing_finite(x: vec2<f32>) -> vec2<f32> {
    return vec2<f32>(select(0.0, x.x, mcg_is_finite(x.x)), select(0.0, x.y, mcg_is_finite(x.y)));
}

// The input of pass 0 at table index `k` (probe · 8 + octant): the trigger states (f_1, f_3 of
// eq. 14, 17), averaged with the three edge-adjacent octants when directional.
fn smoothing_input(k: u32) -> vec2<f32> {
    if smoothing_pass.directional == 0u {
        return smoothing_finite(adgi_pilot_state[k].zw);
    }
    let base = k & ~7u;
    let o = k & 7u;
    // ¼ of each term as the CPU scales it (exactly: a power of two).
    let quarter = vec2<i32>(-2);
    var s = ldexp(smoothing_finite(adgi_pilot_state[k].zw), quarter);
    s += ldexp(smoothing_finite(adgi_pilot_state[base + (o ^ 1u)].zw), quarter);
    s += ldexp(smoothing_finite(adgi_pilot_state[base + (o ^ 2u)].zw), quarter);
    s += ldexp(smoothing_finite(adgi_pilot_state[base + (o ^ 4u)].zw), quarter);
    return s;
}

// One axis of the box mean of every probe and octant.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_smooth_axis(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let k = mcg_invocation_index(id, groups);
    let counts = adgi_params.counts;
    if k >= adgi_params.probe_count * 8u {
        return;
    }
    let probe = k / 8u;
    let coords = vec3<u32>(probe % counts.x, (probe / counts.x) % counts.y, probe / (counts.x * counts.y));
    let axis = smoothing_pass.axis;
    let strides = vec3<u32>(8u, 8u * counts.x, 8u * counts.x * counts.y);
    let i = coords[axis];
    let len = counts[axis];
    let r = smoothing_pass.radius;
    let lo = select(0u, i - r, i >= r);
    let hi = min(i + min(r, len), len - 1u);
    let first = k - i * strides[axis];
    var s = vec2<f32>(0.0);
    for (var j = lo; j <= hi; j += 1u) {
        let tap = first + j * strides[axis];
        if axis == 0u {
            s += smoothing_input(tap);
        } else {
            s += smoothing_src[tap];
        }
    }
    let mean = s * smoothing_reciprocals[hi - lo + 1u];
    smoothing_dst[k] = clamp(mean, vec2<f32>(-MCG_F32_MAX), vec2<f32>(MCG_F32_MAX));
}
