// Reconstruction, products and mean cosines, used by the parity tests. One invocation per
// element.

#import mcg::constants::MCG_WORKGROUP_SIZE
#import mcg::dispatch::mcg_invocation_index
#import mcg::vmf::{
    Vmf, VmfMapPrior, VmfSufficientStats, vmf_from_sufficient_stats, vmf_kappa_from_mean_cosine,
    vmf_mean_cosine_from_kappa, vmf_product
}

// A shading point, a prior, a second lobe and a κ (`VmfStatsQuery` on the host, 48 bytes).
struct VmfStatsQuery {
    shading_point: vec3<f32>,
    kappa: f32,
    other: Vmf,
    prior_mean_cosine: f32,
    prior_weight: f32,
    prior_decay: u32,
}

// Per element: the reconstructed lobe (κ = −1 when `to_vmf` gives None), the product with
// `other` and its scale, A₃(κ) and Banerjee's κ of A₃(κ) (`VmfStatsResult`, 48 bytes).
struct VmfStatsResult {
    reconstructed: Vmf,
    product: Vmf,
    product_scale: f32,
    mean_cosine: f32,
    kappa_back: f32,
}

@group(0) @binding(0) var<storage, read> stats: array<VmfSufficientStats>;
@group(0) @binding(1) var<storage, read> queries: array<VmfStatsQuery>;
@group(0) @binding(2) var<storage, read_write> results: array<VmfStatsResult>;

@compute @workgroup_size(MCG_WORKGROUP_SIZE)
fn vmf_stats(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = mcg_invocation_index(id, groups);
    if i >= arrayLength(&results) {
        return;
    }
    let q = queries[i];
    var r: VmfStatsResult;
    var lobe = Vmf(vec3<f32>(0.0), -1.0);
    let prior = VmfMapPrior(q.prior_mean_cosine, q.prior_weight, q.prior_decay);
    if vmf_from_sufficient_stats(stats[i], q.shading_point, prior, &lobe) {
        var product: Vmf;
        r.product_scale = vmf_product(lobe, q.other, &product);
        r.product = product;
    }
    r.reconstructed = lobe;
    r.mean_cosine = vmf_mean_cosine_from_kappa(q.kappa);
    r.kappa_back = vmf_kappa_from_mean_cosine(r.mean_cosine);
    results[i] = r;
}
