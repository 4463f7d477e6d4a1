//! The vMF mixture kernel.

use std::sync::OnceLock;

use mcg_vmf::VmfMixture;

use crate::shaders::kernels as src;
use crate::types::{VmfQuery, VmfSample, pack_mixtures};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// One mixture evaluated by [`VmfMixtureKernel::eval`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmfMixtureEval {
    /// `sample_with_pdf(uniforms)`: the direction and the mixture's pdf there.
    pub sample: VmfSample,
    /// The component `select(uniforms.x)` chose.
    pub component: usize,
    /// The rescaled uniform `select` hands to that component.
    pub u: f32,
    /// The mixture's pdf at the query's direction.
    pub pdf: f32,
}

/// The `VmfMixture<K>` kernel (`shaders::VMF_MIXTURE` with `VMF_MIXTURE_K = K`): pdf,
/// component choice and sampling on arrays of mixtures (MCMM eq. 4-5).
#[derive(Debug)]
pub struct VmfMixtureKernel<const K: usize> {
    eval: OnceLock<ComputeKernel>,
}

impl<const K: usize> Default for VmfMixtureKernel<K> {
    fn default() -> Self {
        Self {
            eval: OnceLock::new(),
        }
    }
}

impl<const K: usize> VmfMixtureKernel<K> {
    /// The kernel for K lobes (shader def `MCG_VMF_MIXTURE_K` = K), not built yet. With
    /// K = 0 the first [`eval`](Self::eval) fails ([`GpuError::Shader`]).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    fn kernel(&self, ctx: &GpuContext) -> Result<&ComputeKernel, GpuError> {
        if let Some(kernel) = self.eval.get() {
            return Ok(kernel);
        }
        let mut defs = src::KERNEL_DEFS.to_vec();
        let k = u32::try_from(K).unwrap_or(u32::MAX);
        defs.push((crate::shaders::defs::VMF_MIXTURE_K, k));
        let source =
            crate::shaders::compose(src::VMF_MIXTURE, &defs).map_err(|e| GpuError::Shader {
                entry_point: "vmf_mixture_eval".into(),
                message: e.to_string(),
            })?;
        let kernel = ctx.compute_kernel(&source, "vmf_mixture_eval")?;
        Ok(self.eval.get_or_init(|| kernel))
    }

    /// For each `i`: `mixtures[i].sample_with_pdf(queries[i].uniforms)`,
    /// `mixtures[i].select(queries[i].uniforms.x)` and `mixtures[i].pdf(queries[i].direction)`,
    /// on the GPU (uploaded with [`pack_mixtures`]).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] if the slices differ in length.
    pub fn eval(
        &self,
        ctx: &GpuContext,
        mixtures: &[VmfMixture<K>],
        queries: &[VmfQuery],
    ) -> Result<Vec<VmfMixtureEval>, GpuError> {
        GpuError::check_len(mixtures.len(), queries.len())?;
        let n = mixtures.len();
        let mixtures = ctx.storage_buffer("mixtures", &pack_mixtures(mixtures));
        let queries = ctx.storage_buffer("queries", queries);
        let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
        let choices: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("choices", n);
        ctx.dispatch(
            self.kernel(ctx)?,
            &[mixtures.raw(), queries.raw(), samples.raw(), choices.raw()],
            n as u32,
        )?;
        let samples = ctx.read_back(&samples)?;
        let choices = ctx.read_back(&choices)?;
        Ok(samples
            .into_iter()
            .zip(choices)
            .map(|(sample, [index, u, pdf, _])| VmfMixtureEval {
                sample,
                component: index as usize,
                u: f32::from_bits(u),
                pdf: f32::from_bits(pdf),
            })
            .collect())
    }
}
