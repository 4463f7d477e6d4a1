#define_import_path mcg::vmf_mixture
// mcg-vmf mixture twin: `VmfMixture<K>` (MCMM eq. 5) with the component chosen by the first
// uniform, which is then rescaled and reused (`mixture.rs`). K, the number of lobes, is the
// shader def MCG_VMF_MIXTURE_K (default 4; `VmfMixture<K>` on the host).
//
// Upload mixtures with `mcg_gpu_backend::types::pack_mixtures` (lobes, then the normalised
// weights, each mixture padded to 16 bytes).

#import mcg::constants::MCG_ONE_MINUS_EPSILON
#import mcg::vmf::{Vmf, VmfSample, vmf_pdf, vmf_sample}

#ifdef MCG_VMF_MIXTURE_K
const VMF_MIXTURE_K: u32 = #{MCG_VMF_MIXTURE_K}u;
#else
const VMF_MIXTURE_K: u32 = 4u;
#endif

struct VmfMixture {
    lobes: array<Vmf, VMF_MIXTURE_K>,
    weights: array<f32, VMF_MIXTURE_K>,
}

// The component a uniform picks and the uniform rescaled into it (`VmfMixture::select`).
struct VmfMixtureChoice {
    index: u32,
    u: f32,
}

// Σ wᵢ Vᵢ(ω), in component order (`VmfMixture::pdf`).
fn vmf_mixture_pdf(m: VmfMixture, w: vec3<f32>) -> f32 {
    var mixture = m;
    var pdf = 0.0;
    for (var i = 0u; i < VMF_MIXTURE_K; i += 1u) {
        pdf += mixture.weights[i] * vmf_pdf(mixture.lobes[i], w);
    }
    return pdf;
}

// `VmfMixture::select`: walks the CDF of the weights, skipping zero weights; the uniform is
// rescaled to [0, 1 − ε/2] inside the chosen component (the last positive one when u ≥ 1).
fn vmf_mixture_select(m: VmfMixture, u: f32) -> VmfMixtureChoice {
    var mixture = m;
    var start = 0.0;
    var last = 0u;
    for (var i = 0u; i < VMF_MIXTURE_K; i += 1u) {
        let weight = mixture.weights[i];
        if weight > 0.0 {
            let end = start + weight;
            if u < end {
                return VmfMixtureChoice(i, clamp((u - start) / weight, 0.0, MCG_ONE_MINUS_EPSILON));
            }
            start = end;
            last = i;
        }
    }
    return VmfMixtureChoice(last, MCG_ONE_MINUS_EPSILON);
}

// `VmfMixture::sample`: the component from u.x, then its lobe sampled with (rescaled u.x, u.y).
fn vmf_mixture_sample(m: VmfMixture, u: vec2<f32>) -> vec3<f32> {
    var mixture = m;
    let choice = vmf_mixture_select(m, u.x);
    return vmf_sample(mixture.lobes[choice.index], vec2<f32>(choice.u, u.y));
}

// `VmfMixture::sample_with_pdf`: the sample and the mixture's density there.
fn vmf_mixture_sample_with_pdf(m: VmfMixture, u: vec2<f32>) -> VmfSample {
    let w = vmf_mixture_sample(m, u);
    return VmfSample(w, vmf_mixture_pdf(m, w));
}
