// The baselines of the ADGI benches, composed with `GpuProbeCache::shader_defs(0)` and
// MCG_ADGI_FLOAT_TEXELS: DDGI's float texels (RGBA32F irradiance, RG32F moments) at bindings 4
// and 5 of the cache's group, the bench's inputs at group 1.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::adgi::{
    AdgiRaySample, adgi_float_irradiance, adgi_float_visibility, adgi_irradiance_at,
    adgi_map_texel, adgi_normalise_distance, adgi_params
}

struct BenchStep {
    count: u32,
    max_count: u32,
    cap: u32,
    pad_a: u32,
}

struct BenchQuery {
    position: vec4<f32>,
    normal: vec4<f32>,
    to_viewer: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> samples: array<AdgiRaySample>;
@group(1) @binding(2) var<uniform> step: BenchStep;
@group(1) @binding(3) var<storage, read> queries: array<BenchQuery>;
@group(1) @binding(4) var<storage, read_write> results: array<vec4<f32>>;

// One ray stored as DDGI's float texels would take it: the radiance and a count into the
// RGBA32F texel of its direction, (t, t²) into the RG32F texel (plain stores, no average).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn store_rgba32f(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= step.count {
        return;
    }
    let s = samples[i];
    let si = adgi_params.irradiance_side;
    let sv = adgi_params.visibility_side;
    let ti = adgi_map_texel(s.direction, si, adgi_params.irradiance_interior);
    adgi_float_irradiance[s.probe * si * si + ti] = vec4<f32>(s.radiance, 1.0);
    let t = adgi_normalise_distance(s.distance);
    if t >= 0.0 {
        let tv = adgi_map_texel(s.direction, sv, adgi_params.visibility_interior);
        adgi_float_visibility[s.probe * sv * sv + tv] = vec2<f32>(t, t * t);
    }
}

// The irradiance query on the float texels.
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn query_rgba32f(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= step.count {
        return;
    }
    let q = queries[i];
    results[i] = vec4<f32>(adgi_irradiance_at(q.position.xyz, q.normal.xyz, q.to_viewer.xyz), 0.0);
}
