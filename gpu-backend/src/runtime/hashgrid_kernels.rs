//! The hash-grid key kernels.

use std::sync::OnceLock;

use glam::IVec3;
use mcg_hashgrid::CellKey;

use super::lazy;
use crate::shaders::kernels as src;
use crate::types::{HashgridJitterQuery, HashgridLevelParams, HashgridVertexQuery};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// The hash-grid key kernels: bucket hashes and checksums of keys, adaptive-grid vertex keys
/// (MCPG sec. 4), static-grid vertex keys and jittered vertices. Pipelines are built on
/// first use.
#[derive(Debug, Default)]
pub struct HashgridKernels {
    hashes: OnceLock<ComputeKernel>,
    vertices: OnceLock<ComputeKernel>,
}

impl HashgridKernels {
    /// The kernels, none built yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Runs `hashgrid_hashes` on `keys` and `queries` (each padded to one element when empty)
    /// and reads both outputs back.
    fn run_hashes(
        &self,
        ctx: &GpuContext,
        keys: &[CellKey],
        levels: &HashgridLevelParams,
        queries: &[HashgridVertexQuery],
    ) -> Result<(Vec<[u32; 4]>, Vec<CellKey>), GpuError> {
        let kernel = lazy(&self.hashes, ctx, src::HASHGRID_KEYS, "hashgrid_hashes")?;
        let keys_buffer = ctx.storage_buffer("keys", keys);
        let hashes: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("hashes", keys.len());
        let levels = ctx.uniform_buffer("levels", levels);
        let queries_buffer = ctx.storage_buffer("vertex queries", queries);
        let vertex_keys: GpuBuffer<CellKey> = ctx.zeroed_buffer("vertex keys", queries.len());
        ctx.dispatch(
            kernel,
            &[
                keys_buffer.raw(),
                hashes.raw(),
                levels.raw(),
                queries_buffer.raw(),
                vertex_keys.raw(),
            ],
            keys.len().max(queries.len()) as u32,
        )?;
        Ok((ctx.read_back(&hashes)?, ctx.read_back(&vertex_keys)?))
    }

    /// For each key: `[hash_xor_primes, hash_mix, hash_mix_coherent, checksum]`, on the GPU.
    pub fn hashes(&self, ctx: &GpuContext, keys: &[CellKey]) -> Result<Vec<[u32; 4]>, GpuError> {
        let levels = HashgridLevelParams::default();
        Ok(self.run_hashes(ctx, keys, &levels, &[])?.0)
    }

    /// For each query: the adaptive grid's vertex key, `levels` being the grid
    /// (`HashgridLevelParams::from(&grid)`): level from the camera distance with the query's
    /// jitter, the stochastic trilinear vertex of the position read as grid coordinates,
    /// the normal class (`hashgrid_level`, `hashgrid_stochastic_trilinear`,
    /// `hashgrid_normal_class`; compare with `AdaptiveGrid::level`,
    /// `stochastic_trilinear` and `normal_class`).
    pub fn vertex_keys(
        &self,
        ctx: &GpuContext,
        levels: &HashgridLevelParams,
        queries: &[HashgridVertexQuery],
    ) -> Result<Vec<CellKey>, GpuError> {
        Ok(self.run_hashes(ctx, &[], levels, queries)?.1)
    }

    /// For each query: `StaticGrid::new(width).vertex_key(position, u_corner)` and
    /// `jittered_vertex(position, u_jitter)`, on the GPU.
    pub fn static_vertices(
        &self,
        ctx: &GpuContext,
        queries: &[HashgridJitterQuery],
    ) -> Result<(Vec<CellKey>, Vec<IVec3>), GpuError> {
        let kernel = lazy(
            &self.vertices,
            ctx,
            src::HASHGRID_VERTICES,
            "hashgrid_vertices",
        )?;
        let n = queries.len();
        let queries = ctx.storage_buffer("queries", queries);
        let keys: GpuBuffer<CellKey> = ctx.zeroed_buffer("static keys", n);
        let jittered: GpuBuffer<[i32; 4]> = ctx.zeroed_buffer("jittered", n);
        ctx.dispatch(
            kernel,
            &[queries.raw(), keys.raw(), jittered.raw()],
            n as u32,
        )?;
        let jittered = ctx.read_back(&jittered)?;
        Ok((
            ctx.read_back(&keys)?,
            jittered
                .into_iter()
                .map(|v| IVec3::new(v[0], v[1], v[2]))
                .collect(),
        ))
    }
}
