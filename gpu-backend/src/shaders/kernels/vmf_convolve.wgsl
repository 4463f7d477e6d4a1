// Convolutions and the exact mean-cosine inverse, used by the parity tests. One invocation per
// element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{Vmf, vmf_convolve, vmf_kappa_from_mean_cosine_exact}

@group(0) @binding(0) var<storage, read> lobes: array<Vmf>;
// Per element: the kernel's κ (x) and a mean cosine to invert (y).
@group(0) @binding(1) var<storage, read> params: array<vec2<f32>>;
@group(0) @binding(2) var<storage, read_write> convolved: array<Vmf>;
// Per element: κ of `kappa_from_mean_cosine_exact(params.y)`.
@group(0) @binding(3) var<storage, read_write> kappas: array<f32>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn vmf_convolve_lobes(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&kappas) {
        return;
    }
    convolved[i] = vmf_convolve(lobes[i], params[i].x);
    kappas[i] = vmf_kappa_from_mean_cosine_exact(params[i].y);
}
