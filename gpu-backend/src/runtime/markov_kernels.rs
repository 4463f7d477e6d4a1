//! The chain-state kernels (MCPG grid and MCMM pixel states).

use std::sync::OnceLock;

use glam::Vec3;
use mcg_markov_guide::mcmm::PixelState;
use mcg_markov_guide::mcpg::GridState;
use mcg_vmf::{MapPrior, SufficientStats};

use super::lazy;
use crate::shaders::kernels as src;
use crate::types::{MarkovGridQuery, MarkovGridWrite, MarkovPixelQuery};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// An MCPG `GridState` as the GPU reads it ([`MarkovKernels::grid_states`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridStateRead {
    /// `GridState::velocity` (three f16).
    pub velocity: Vec3,
    /// `GridState::sample_count`.
    pub sample_count: u32,
    /// `GridState::stats`.
    pub stats: SufficientStats,
}

/// An MCMM `PixelState` as the GPU reads it ([`MarkovKernels::pixel_states`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelStateRead {
    /// `PixelState::resampling_score`.
    pub resampling_score: f32,
    /// `PixelState::is_valid`.
    pub is_valid: bool,
    /// `PixelState::lobe(x, prior)` as (μ, κ), not re-validated on the host.
    pub lobe: Option<(Vec3, f32)>,
    /// `stats.sample_count` as the GPU read it.
    pub sample_count: f32,
}

/// An MCPG `GridState` queried on the GPU ([`MarkovKernels::grid_state_queries`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridStateQueryRead {
    /// `GridState::is_valid`.
    pub is_valid: bool,
    /// `GridState::resampling_weight`.
    pub resampling_weight: f32,
    /// `GridState::predicted(now)` (MCPG eq. 10).
    pub predicted: GridState,
    /// `GridState::lobe(x, prior)` as (μ, κ), not re-validated on the host.
    pub lobe: Option<(Vec3, f32)>,
}

/// The mcg-markov-guide state kernels: MCPG grid states (MCPG Table 1) and MCMM pixel states
/// (MCMM Table 1, Alg. 1-2), written, read and queried on the GPU. Pipelines are built on
/// first use.
#[derive(Debug, Default)]
pub struct MarkovKernels {
    grid: OnceLock<ComputeKernel>,
    pixel: OnceLock<ComputeKernel>,
    write: OnceLock<ComputeKernel>,
    query: OnceLock<ComputeKernel>,
}

impl MarkovKernels {
    /// The kernels, none built yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Each state's velocity, sample count and sufficient statistics, read on the GPU
    /// (`markov_grid_state_velocity`, `_sample_count`, `_stats`).
    pub fn grid_states(
        &self,
        ctx: &GpuContext,
        states: &[GridState],
    ) -> Result<Vec<GridStateRead>, GpuError> {
        let kernel = lazy(&self.grid, ctx, src::MARKOV_GUIDE, "markov_grid_states")?;
        let n = states.len();
        let states = ctx.storage_buffer("states", states);
        let velocities: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("velocities", n);
        let stats: GpuBuffer<SufficientStats> = ctx.zeroed_buffer("stats", n);
        ctx.dispatch(
            kernel,
            &[states.raw(), velocities.raw(), stats.raw()],
            n as u32,
        )?;
        let velocities = ctx.read_back(&velocities)?;
        Ok(velocities
            .into_iter()
            .zip(ctx.read_back(&stats)?)
            .map(|(v, stats)| GridStateRead {
                velocity: Vec3::new(v[0], v[1], v[2]),
                sample_count: v[3] as u32,
                stats,
            })
            .collect())
    }

    /// Each state's validity, resampling score and lobe at shading point `x` with the MAP
    /// `prior`, read on the GPU (`markov_pixel_state_is_valid`, `_resampling_score`,
    /// `_lobe`).
    pub fn pixel_states(
        &self,
        ctx: &GpuContext,
        states: &[PixelState],
        x: Vec3,
        prior: MapPrior,
    ) -> Result<Vec<PixelStateRead>, GpuError> {
        let kernel = lazy(&self.pixel, ctx, src::MARKOV_PIXEL, "markov_pixel_states")?;
        let n = states.len();
        let states = ctx.storage_buffer("pixel states", states);
        let query = ctx.uniform_buffer("query", &MarkovPixelQuery::new(x, prior));
        let results: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("results", n);
        let lobes: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("lobes", n);
        ctx.dispatch(
            kernel,
            &[states.raw(), query.raw(), results.raw(), lobes.raw()],
            n as u32,
        )?;
        let results = ctx.read_back(&results)?;
        Ok(results
            .into_iter()
            .zip(ctx.read_back(&lobes)?)
            .map(|(r, l)| PixelStateRead {
                resampling_score: r[0],
                is_valid: r[1] != 0.0,
                lobe: (r[2] != -1.0).then(|| (Vec3::new(l[0], l[1], l[2]), l[3])),
                sample_count: r[3],
            })
            .collect())
    }

    /// Grid states packed on the GPU from statistics, time and velocity
    /// (`markov_grid_state_pack`, `GridState::from_stats`), and pixel states from the same
    /// statistics with the time as score (`markov_pixel_state_pack`).
    pub fn write_states(
        &self,
        ctx: &GpuContext,
        writes: &[MarkovGridWrite],
    ) -> Result<(Vec<GridState>, Vec<PixelState>), GpuError> {
        let kernel = lazy(
            &self.write,
            ctx,
            src::MARKOV_GRID_WRITE,
            "markov_grid_write",
        )?;
        let n = writes.len();
        let writes = ctx.storage_buffer("writes", writes);
        let grid: GpuBuffer<GridState> = ctx.zeroed_buffer("grid states", n);
        let pixel: GpuBuffer<PixelState> = ctx.zeroed_buffer("pixel states", n);
        ctx.dispatch(kernel, &[writes.raw(), grid.raw(), pixel.raw()], n as u32)?;
        Ok((ctx.read_back(&grid)?, ctx.read_back(&pixel)?))
    }

    /// Each grid state's validity, resampling weight, prediction at `query.now` and lobe at
    /// `query.x`, computed on the GPU (`markov_grid_state_is_valid`, `_resampling_weight`,
    /// `_predicted`, `_lobe`).
    pub fn grid_state_queries(
        &self,
        ctx: &GpuContext,
        states: &[GridState],
        query: &MarkovGridQuery,
    ) -> Result<Vec<GridStateQueryRead>, GpuError> {
        let kernel = lazy(
            &self.query,
            ctx,
            src::MARKOV_GRID_QUERY,
            "markov_grid_queries",
        )?;
        let n = states.len();
        let states = ctx.storage_buffer("states", states);
        let query = ctx.uniform_buffer("query", query);
        let results: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("results", n);
        let predicted: GpuBuffer<GridState> = ctx.zeroed_buffer("predicted", n);
        let lobes: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("lobes", n);
        ctx.dispatch(
            kernel,
            &[
                states.raw(),
                query.raw(),
                results.raw(),
                predicted.raw(),
                lobes.raw(),
            ],
            n as u32,
        )?;
        let results = ctx.read_back(&results)?;
        let predicted = ctx.read_back(&predicted)?;
        let lobes = ctx.read_back(&lobes)?;
        Ok(results
            .into_iter()
            .zip(predicted)
            .zip(lobes)
            .map(|((r, predicted), l)| GridStateQueryRead {
                is_valid: r[0] != 0.0,
                resampling_weight: r[1],
                predicted,
                lobe: (r[2] != -1.0).then(|| (Vec3::new(l[0], l[1], l[2]), l[3])),
            })
            .collect())
    }
}
