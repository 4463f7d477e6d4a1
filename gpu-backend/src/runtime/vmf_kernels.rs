//! The vMF kernels on arrays of lobes.

use std::sync::OnceLock;

use mcg_vmf::{FitParams, SufficientStats, Vmf};

use super::lazy;
use crate::shaders::kernels as src;
use crate::types::{
    VmfFitParamsGpu, VmfQuery, VmfSample, VmfStatsQuery, VmfStatsResult, VmfUpdate,
};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// The vMF kernels: pdf, sampling, reconstruction and products on arrays of lobes.
#[derive(Debug, Default)]
pub struct VmfKernels {
    pdf_and_sample: OnceLock<ComputeKernel>,
    stats: OnceLock<ComputeKernel>,
    convolve: OnceLock<ComputeKernel>,
    update: OnceLock<ComputeKernel>,
}

impl VmfKernels {
    /// The kernels, none built yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// For each `i`: `lobes[i].pdf(queries[i].direction)` and
    /// `lobes[i].sample_with_pdf(queries[i].uniforms)`, on the GPU.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] if the slices differ in length.
    pub fn pdf_and_sample(
        &self,
        ctx: &GpuContext,
        lobes: &[Vmf],
        queries: &[VmfQuery],
    ) -> Result<(Vec<f32>, Vec<VmfSample>), GpuError> {
        GpuError::check_len(lobes.len(), queries.len())?;
        let n = lobes.len();
        let lobes = ctx.storage_buffer("lobes", lobes);
        let queries = ctx.storage_buffer("queries", queries);
        let pdfs: GpuBuffer<f32> = ctx.zeroed_buffer("pdfs", n);
        let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
        let kernel = lazy(&self.pdf_and_sample, ctx, src::VMF, "vmf_pdf_and_sample")?;
        ctx.dispatch(
            kernel,
            &[lobes.raw(), queries.raw(), pdfs.raw(), samples.raw()],
            n as u32,
        )?;
        Ok((ctx.read_back(&pdfs)?, ctx.read_back(&samples)?))
    }

    /// For each `i`: `stats[i].to_vmf(x, prior)`, its product with `other`, and the
    /// mean-cosine round trip of `kappa` (see [`VmfStatsResult`]).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] if the slices differ in length.
    pub fn stats(
        &self,
        ctx: &GpuContext,
        stats: &[SufficientStats],
        queries: &[VmfStatsQuery],
    ) -> Result<Vec<VmfStatsResult>, GpuError> {
        GpuError::check_len(stats.len(), queries.len())?;
        let n = stats.len();
        let stats = ctx.storage_buffer("stats", stats);
        let queries = ctx.storage_buffer("queries", queries);
        let results: GpuBuffer<VmfStatsResult> = ctx.zeroed_buffer("results", n);
        let kernel = lazy(&self.stats, ctx, src::VMF_STATS, "vmf_stats")?;
        ctx.dispatch(
            kernel,
            &[stats.raw(), queries.raw(), results.raw()],
            n as u32,
        )?;
        ctx.read_back(&results)
    }

    /// For each `i`: `stats[i]` after `update(x, y, weight, fit)` with `updates[i]`'s sample
    /// (`vmf_stats_update`, MCMM Alg. 3 / MCPG Alg. 3; the pipeline is built on the first
    /// call). Returns the updated statistics.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] if the slices differ in length.
    pub fn update_stats(
        &self,
        ctx: &GpuContext,
        stats: &[SufficientStats],
        updates: &[VmfUpdate],
        fit: &FitParams,
    ) -> Result<Vec<SufficientStats>, GpuError> {
        GpuError::check_len(stats.len(), updates.len())?;
        let kernel = lazy(&self.update, ctx, src::VMF_UPDATE, "vmf_update")?;
        let stats = ctx.storage_buffer("stats", stats);
        let updates_buffer = ctx.storage_buffer("updates", updates);
        let fit = ctx.uniform_buffer("fit", &VmfFitParamsGpu::from(fit));
        ctx.dispatch(
            kernel,
            &[stats.raw(), updates_buffer.raw(), fit.raw()],
            updates.len() as u32,
        )?;
        ctx.read_back(&stats)
    }

    /// For each `i`: `lobes[i].convolve(kernel_kappas[i])` (a negative κ is a delta
    /// kernel, like the CPU's) and `kappa_from_mean_cosine_exact(mean_cosines[i])`, on the
    /// GPU (`vmf_convolve`, `vmf_kappa_from_mean_cosine_exact`; the pipeline is built on the
    /// first call).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] if the slices differ in length.
    pub fn convolve(
        &self,
        ctx: &GpuContext,
        lobes: &[Vmf],
        kernel_kappas: &[f32],
        mean_cosines: &[f32],
    ) -> Result<(Vec<Vmf>, Vec<f32>), GpuError> {
        let n = lobes.len();
        GpuError::check_len(n, kernel_kappas.len())?;
        GpuError::check_len(n, mean_cosines.len())?;
        let kernel = lazy(&self.convolve, ctx, src::VMF_CONVOLVE, "vmf_convolve_lobes")?;
        let params: Vec<[f32; 2]> = kernel_kappas
            .iter()
            .zip(mean_cosines)
            .map(|(&k, &r)| [k, r])
            .collect();
        let lobes = ctx.storage_buffer("lobes", lobes);
        let params = ctx.storage_buffer("params", &params);
        let convolved: GpuBuffer<Vmf> = ctx.zeroed_buffer("convolved", n);
        let kappas: GpuBuffer<f32> = ctx.zeroed_buffer("kappas", n);
        ctx.dispatch(
            kernel,
            &[lobes.raw(), params.raw(), convolved.raw(), kappas.raw()],
            n as u32,
        )?;
        Ok((ctx.read_back(&convolved)?, ctx.read_back(&kappas)?))
    }
}
