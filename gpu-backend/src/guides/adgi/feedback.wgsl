// The feedback ĝ of ADGI eq. 2 from the probe cache's irradiance words (sec. 4.8: the target
// "from a higher mip-level"; `guiding_function::octant_feedback` of every probe): the probe
// cache's group at group 0 (`mcg::adgi`), the chains' feedback table at group 1
// (`GpuProbeChains::record_feedback`).
//
// Per probe and octant (`probe · 8 + octant`): the mean Rec. 709 luminance of the probe's
// interior irradiance texels whose centre direction (`adgi_texel_table`, the CPU's `TexelMap`
// directions) lies in the octant; a non-finite or non-positive luminance counts as 0, an octant
// without texels gets 0. The texels are summed in the CPU's order (stored order) with the
// CPU's roundings, so the sum is the CPU's bit for bit; the mean's division is WGSL's (within
// 2.5 ULP, WGSL spec "Floating Point Accuracy").

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::math::mcg_is_finite
#import mcg::adgi::{adgi_interior_index, adgi_load_irradiance, adgi_luminance, adgi_params, adgi_texel_table}
#import mcg::adgi_chains::adgi_octant

// ĝ per `probe · 8 + octant` (the chains' feedback buffer, one cell per probe).
@group(1) @binding(0) var<storage, read_write> feedback_out: array<f32>;

// ĝ of every probe and octant.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_octant_feedback(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= adgi_params.probe_count * 8u {
        return;
    }
    let probe = i / 8u;
    let octant = i % 8u;
    let interior = adgi_params.irradiance_interior;
    let side = adgi_params.irradiance_side;
    var sum = 0.0;
    var n = 0u;
    for (var k = 0u; k < interior * interior; k += 1u) {
        if adgi_octant(adgi_texel_table[k].xyz) != octant {
            continue;
        }
        let y = adgi_luminance(adgi_load_irradiance(probe, adgi_interior_index(k, side, interior)));
        if y > 0.0 && mcg_is_finite(y) {
            sum += y;
        }
        n += 1u;
    }
    feedback_out[i] = select(0.0, sum / f32(n), n > 0u);
}
