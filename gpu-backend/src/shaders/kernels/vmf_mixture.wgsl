// Mixture pdf and sampling, used by the parity tests. One invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::VmfSample
#import mcg::vmf_mixture::{
    VmfMixture, vmf_mixture_pdf, vmf_mixture_sample_with_pdf, vmf_mixture_select
}

// A direction to evaluate and two uniforms to sample with (`VmfQuery` on the host, 32 bytes).
struct VmfQuery {
    direction: vec3<f32>,
    uniforms: vec2<f32>,
}

@group(0) @binding(0) var<storage, read> mixtures: array<VmfMixture>;
@group(0) @binding(1) var<storage, read> queries: array<VmfQuery>;
@group(0) @binding(2) var<storage, read_write> samples: array<VmfSample>;
// Per element: the chosen component, the bits of the rescaled uniform and the bits of the
// mixture's pdf at the query's direction.
@group(0) @binding(3) var<storage, read_write> choices: array<vec4<u32>>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn vmf_mixture_eval(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&choices) {
        return;
    }
    let m = mixtures[i];
    let q = queries[i];
    samples[i] = vmf_mixture_sample_with_pdf(m, q.uniforms);
    let c = vmf_mixture_select(m, q.uniforms.x);
    choices[i] = vec4<u32>(c.index, bitcast<u32>(c.u), bitcast<u32>(vmf_mixture_pdf(m, q.direction)), 0u);
}
