// The steps of `GpuProbeCache`, one entry point per dispatch: the cache's group at group 0
// (`mcg::adgi`), the step's inputs at group 1 (`GpuProbeCache`'s step layout).

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::adgi::{
    AdgiClipVolumes, AdgiRaySample, adgi_blend_texel, adgi_blend_texels_per_probe, adgi_cap_word,
    adgi_in_shell, adgi_irradiance_at, adgi_params, adgi_update_sample, adgi_word_count,
    adgi_word_probe
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
