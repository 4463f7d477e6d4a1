// The steps of `GpuProbeCache`, one entry point per dispatch: the cache's group at group 0
// (`mcg::adgi`), the step's inputs at group 1 (`GpuProbeCache`'s step layout).

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::adgi::{
    AdgiClipVolumes, AdgiRaySample, adgi_blend_texel, adgi_blend_texels_per_probe, adgi_cap_word,
    adgi_in_shell, adgi_irradiance_at, adgi_params, adgi_pilot_direction, adgi_pilot_update,
    adgi_traces_pilots, adgi_update_sample, adgi_word_count, adgi_word_probe
}

// The step's sizes (`GpuStepParams` on the host, 16 bytes).
struct AdgiStep {
    count: u32,
    max_count: u32,
    cap: u32,
    pad_a: u32,
}

// One irradiance query: point, normal, direction to the viewer (`GpuIrradianceQuery`, 48 bytes).
struct AdgiQuery {
    position: vec4<f32>,
    normal: vec4<f32>,
    to_viewer: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> step_samples: array<AdgiRaySample>;
@group(1) @binding(1) var<storage, read> step_uniforms: array<f32>;
@group(1) @binding(2) var<uniform> step: AdgiStep;
@group(1) @binding(3) var<storage, read> step_queries: array<AdgiQuery>;
@group(1) @binding(4) var<storage, read_write> step_results: array<vec4<f32>>;
@group(1) @binding(5) var<uniform> step_clip: AdgiClipVolumes;
@group(1) @binding(6) var<uniform> step_pilot: AdgiPilotStep;

// The pilot step's constants (`GpuPilotStep` on the host, 16 bytes): eq. 11's voxel diagonal,
// eq. 12's range β, the trigger's decay θ, and 1 on a detection frame (0: reference frame).
struct AdgiPilotStep {
    voxel_diagonal: f32,
    radiance_range: f32,
    decay: f32,
    detect: u32,
}

// ADGI's per-sample update of `step.count` samples, N_max = `step.max_count`.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_update_samples(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= step.count {
        return;
    }
    let s = step_samples[i];
    if s.probe < adgi_params.probe_count {
        adgi_update_sample(s.probe, s.direction, s.radiance, s.distance, step_uniforms[i], step.max_count);
    }
}

// DDGI's blend of every probe's rays into all its interior texels, the probe's uniform from
// `step_uniforms`.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_blend(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    let per_probe = adgi_blend_texels_per_probe();
    if i >= adgi_params.probe_count * per_probe {
        return;
    }
    let probe = i / per_probe;
    adgi_blend_texel(probe, i % per_probe, step_uniforms[probe]);
}

// The irradiance query at `step.count` points.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_query(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= step.count {
        return;
    }
    let q = step_queries[i];
    step_results[i] = vec4<f32>(adgi_irradiance_at(q.position.xyz, q.normal.xyz, q.to_viewer.xyz), 0.0);
}

// The clip-volume reset (ADGI sec. 4.8): every word of a probe in V_out − V_in gets N ≤ `step.cap`.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_clip_reset(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= adgi_word_count() {
        return;
    }
    if adgi_in_shell(step_clip, adgi_word_probe(i)) {
        adgi_cap_word(i, step.cap);
    }
}

// The pilot rays (ADGI sec. 4.4) of every probe and octant, `probe · 8 + octant`: the direction
// from uniforms `step_uniforms[2i]`, `[2i + 1]` in `xyz`, and in `w` 1 when the probe lies in
// V_out (trace it) and 0 otherwise.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_pilot_rays(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= adgi_params.probe_count * 8u {
        return;
    }
    let d = adgi_pilot_direction(i % 8u, vec2<f32>(step_uniforms[2u * i], step_uniforms[2u * i + 1u]));
    let traced = adgi_traces_pilots(step_clip, i / 8u);
    step_results[i] = vec4<f32>(d, select(0.0, 1.0, traced));
}

// The pilot hits (`step_samples`, `probe · 8 + octant`: distance and radiance of each pilot
// ray) folded into the pilot state of every probe in V_out.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn adgi_pilot_hits(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= adgi_params.probe_count * 8u {
        return;
    }
    let probe = i / 8u;
    if !adgi_traces_pilots(step_clip, probe) {
        return;
    }
    let o = i % 8u;
    let p = step_pilot;
    adgi_pilot_update(probe, o, step_samples[i], step_samples[probe * 8u + (o ^ 7u)], p.voxel_diagonal, p.radiance_range, p.decay, p.detect != 0u);
}
