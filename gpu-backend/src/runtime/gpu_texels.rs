//! Packed texel words on the GPU.

use crate::shaders::kernels as src;
use crate::types::{TexelParams, TexelUpdate};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// Packed texel words on the GPU (ADGI irradiance or visibility words, `mcg_color_codec`'s
/// `IrradianceWord` / `VisibilityWord` arrays uploaded as they are), folded into by the
/// moving average's compare-and-swap loop (`codec_irradiance_update_atomic`,
/// `codec_visibility_update_atomic`; ADGI sec. 4.7).
#[derive(Debug)]
pub struct GpuTexels {
    words: GpuBuffer<u32>,
    update: ComputeKernel,
}

impl GpuTexels {
    /// Uploads `words` as they are.
    pub fn upload(ctx: &GpuContext, words: &[u32]) -> Result<Self, GpuError> {
        Ok(Self {
            words: ctx.storage_buffer("texels", words),
            update: ctx
                .compute_kernel(&src::plain(src::COLOR_CODEC_TEXELS), "codec_texel_updates")?,
        })
    }

    /// The word buffer (`array<atomic<u32>>` in WGSL), to bind in your own pipelines.
    #[must_use]
    pub fn words(&self) -> &GpuBuffer<u32> {
        &self.words
    }

    /// Folds every update into its texel, one invocation per update, racing on shared texels:
    /// the result is one that some serial order of `MovingAverage::update` calls gives.
    ///
    /// # Panics
    /// If an update's texel index is out of range.
    pub fn update(
        &self,
        ctx: &GpuContext,
        updates: &[TexelUpdate],
        params: &TexelParams,
    ) -> Result<(), GpuError> {
        assert!(
            updates
                .iter()
                .all(|u| (u.texel as usize) < self.words.len()),
            "texel index out of range"
        );
        let updates_buffer = ctx.storage_buffer("updates", updates);
        let params = ctx.uniform_buffer("params", params);
        ctx.dispatch(
            &self.update,
            &[self.words.raw(), updates_buffer.raw(), params.raw()],
            updates.len() as u32,
        )
    }

    /// Reads the words back.
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        ctx.read_back(&self.words)
    }
}
