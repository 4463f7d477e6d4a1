// Kernels over arrays of lobes, used by the parity tests and `mcg_gpu_backend::kernels`. One
// invocation per element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{Vmf, VmfSample, vmf_pdf, vmf_sample_with_pdf}

// A direction to evaluate and two uniforms to sample with (`VmfQuery` on the host, 32 bytes).
struct VmfQuery {
    direction: vec3<f32>,
    uniforms: vec2<f32>,
}

@group(0) @binding(0) var<storage, read> lobes: array<Vmf>;
@group(0) @binding(1) var<storage, read> queries: array<VmfQuery>;
@group(0) @binding(2) var<storage, read_write> pdfs: array<f32>;
@group(0) @binding(3) var<storage, read_write> samples: array<VmfSample>;

// pdfs[i] = lobes[i].pdf(queries[i].direction); samples[i] = lobes[i].sample_with_pdf(u).
@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn vmf_pdf_and_sample(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&pdfs) {
        return;
    }
    let lobe = lobes[i];
    let q = queries[i];
    pdfs[i] = vmf_pdf(lobe, q.direction);
    samples[i] = vmf_sample_with_pdf(lobe, q.uniforms);
}
