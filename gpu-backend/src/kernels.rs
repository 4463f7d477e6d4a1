//! Host-side pipelines for the kernels of [`crate::shaders::kernels`], with typed inputs and
//! outputs. Each method uploads its inputs, dispatches one invocation per element and reads
//! the results back; renderers that keep data on the GPU bind the same modules in their own
//! pipelines instead.

use std::sync::OnceLock;

use bytemuck::Pod;
use glam::{IVec3, Vec3};
use mcg_hashgrid::{CellKey, HashTable, Insert};
use mcg_markov_guide::mcmm::PixelState;
use mcg_markov_guide::mcpg::GridState;
use mcg_vmf::{FitParams, MapPrior, SufficientStats, Vmf, VmfMixture};

use crate::shaders::kernels as src;
use crate::types::{
    HashgridAgeParams, HashgridJitterQuery, HashgridLevelParams, HashgridTableParams,
    HashgridVertexQuery, MarkovPixelQuery, TexelParams, TexelUpdate, VmfFitParamsGpu, VmfQuery,
    VmfSample, VmfStatsQuery, VmfStatsResult, VmfUpdate, pack_mixtures,
};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// The pipeline in `cell`, built from `source` and `entry` on first use: a wrapper compiles
/// only the kernels it runs (compiling is slow on software adapters).
fn lazy<'a>(
    cell: &'a OnceLock<ComputeKernel>,
    ctx: &GpuContext,
    source: &str,
    entry: &str,
) -> Result<&'a ComputeKernel, GpuError> {
    if let Some(kernel) = cell.get() {
        return Ok(kernel);
    }
    let kernel = ctx.compute_kernel(source, entry)?;
    Ok(cell.get_or_init(|| kernel))
}

/// The vMF kernels: pdf, sampling, reconstruction and products on arrays of lobes.
#[derive(Debug)]
pub struct VmfKernels {
    pdf_and_sample: ComputeKernel,
    stats: ComputeKernel,
    convolve: OnceLock<ComputeKernel>,
    update: OnceLock<ComputeKernel>,
}

impl VmfKernels {
    /// Builds the pipelines.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            pdf_and_sample: ctx.compute_kernel(src::VMF, "vmf_pdf_and_sample")?,
            stats: ctx.compute_kernel(src::VMF_STATS, "vmf_stats")?,
            convolve: OnceLock::new(),
            update: OnceLock::new(),
        })
    }

    /// For each `i`: `lobes[i].pdf(queries[i].direction)` and
    /// `lobes[i].sample_with_pdf(queries[i].uniforms)`, on the GPU.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn pdf_and_sample(
        &self,
        ctx: &GpuContext,
        lobes: &[Vmf],
        queries: &[VmfQuery],
    ) -> Result<(Vec<f32>, Vec<VmfSample>), GpuError> {
        assert_eq!(lobes.len(), queries.len(), "one query per lobe");
        let n = lobes.len();
        let lobes = ctx.storage_buffer("lobes", lobes);
        let queries = ctx.storage_buffer("queries", queries);
        let pdfs: GpuBuffer<f32> = ctx.zeroed_buffer("pdfs", n);
        let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
        ctx.dispatch(
            &self.pdf_and_sample,
            &[lobes.raw(), queries.raw(), pdfs.raw(), samples.raw()],
            n as u32,
        )?;
        Ok((ctx.read_back(&pdfs)?, ctx.read_back(&samples)?))
    }

    /// For each `i`: `stats[i].to_vmf(x, prior)`, its product with `other`, and the
    /// mean-cosine round trip of `kappa` (see [`VmfStatsResult`]).
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn stats(
        &self,
        ctx: &GpuContext,
        stats: &[SufficientStats],
        queries: &[VmfStatsQuery],
    ) -> Result<Vec<VmfStatsResult>, GpuError> {
        assert_eq!(stats.len(), queries.len(), "one query per statistics");
        let n = stats.len();
        let stats = ctx.storage_buffer("stats", stats);
        let queries = ctx.storage_buffer("queries", queries);
        let results: GpuBuffer<VmfStatsResult> = ctx.zeroed_buffer("results", n);
        ctx.dispatch(
            &self.stats,
            &[stats.raw(), queries.raw(), results.raw()],
            n as u32,
        )?;
        ctx.read_back(&results)
    }

    /// For each `i`: `stats[i]` after `update(x, y, weight, fit)` with `updates[i]`'s sample
    /// (`vmf_stats_update`, MCMM Alg. 3 / MCPG Alg. 3; the pipeline is built on the first
    /// call). Returns the updated statistics.
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn update_stats(
        &self,
        ctx: &GpuContext,
        stats: &[SufficientStats],
        updates: &[VmfUpdate],
        fit: &FitParams,
    ) -> Result<Vec<SufficientStats>, GpuError> {
        assert_eq!(stats.len(), updates.len(), "one update per statistics");
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
    /// # Panics
    /// If the slices differ in length.
    pub fn convolve(
        &self,
        ctx: &GpuContext,
        lobes: &[Vmf],
        kernel_kappas: &[f32],
        mean_cosines: &[f32],
    ) -> Result<(Vec<Vmf>, Vec<f32>), GpuError> {
        let n = lobes.len();
        assert!(
            kernel_kappas.len() == n && mean_cosines.len() == n,
            "one kernel κ and one mean cosine per lobe"
        );
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
    eval: ComputeKernel,
}

impl<const K: usize> VmfMixtureKernel<K> {
    /// Builds the pipeline for K lobes (the kernel module with its `VMF_MIXTURE_K` set to
    /// K). K = 0 fails to compile ([`GpuError::Shader`]).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let source = src::VMF_MIXTURE.replace(
            "const VMF_MIXTURE_K: u32 = 4u;",
            &format!("const VMF_MIXTURE_K: u32 = {K}u;"),
        );
        Ok(Self {
            eval: ctx.compute_kernel(&source, "vmf_mixture_eval")?,
        })
    }

    /// For each `i`: `mixtures[i].sample_with_pdf(queries[i].uniforms)`,
    /// `mixtures[i].select(queries[i].uniforms.x)` and `mixtures[i].pdf(queries[i].direction)`,
    /// on the GPU (uploaded with [`pack_mixtures`]).
    ///
    /// # Panics
    /// If the slices differ in length.
    pub fn eval(
        &self,
        ctx: &GpuContext,
        mixtures: &[VmfMixture<K>],
        queries: &[VmfQuery],
    ) -> Result<Vec<VmfMixtureEval>, GpuError> {
        assert_eq!(mixtures.len(), queries.len(), "one query per mixture");
        let n = mixtures.len();
        let mixtures = ctx.storage_buffer("mixtures", &pack_mixtures(mixtures));
        let queries = ctx.storage_buffer("queries", queries);
        let samples: GpuBuffer<VmfSample> = ctx.zeroed_buffer("samples", n);
        let choices: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("choices", n);
        ctx.dispatch(
            &self.eval,
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

/// The colour-codec kernels: every packed layout and LogLuv32 encoded and decoded on the GPU
/// (the WGSL twins of mcg-color-codec), for checking a device against the CPU crate or
/// converting arrays of colours. Pipelines are built on first use.
#[derive(Debug, Default)]
pub struct CodecKernels {
    pack_unpack: OnceLock<ComputeKernel>,
    logluv: OnceLock<ComputeKernel>,
}

/// What [`CodecKernels::pack_unpack`] computes for one input `[r, g, b, u]` (colour and the
/// uniform of stochastic rounding), with the sample count `i mod 64` of element `i`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CodecPackRead {
    /// R11G11B10, RGB9E5 and gamma-5 R10G10B10A2 words of the colour, and its ADGI irradiance
    /// word rounded down.
    pub formats: [u32; 4],
    /// The irradiance word rounded to nearest and stochastically with `u`; the visibility word
    /// of the moments `(r, g)` rounded to nearest and stochastically.
    pub rounded: [u32; 4],
    /// The heuristics word of `min(colour, 1)` rounded to nearest and stochastically (then 0, 0).
    pub heuristics: [u32; 4],
    /// The words decoded again: R11G11B10, RGB9E5, gamma-5, irradiance (down), irradiance
    /// (nearest) as RGB; the visibility moments (nearest) in `.xy`; the heuristics (nearest).
    pub decoded: [[f32; 4]; 7],
}

/// What [`CodecKernels::logluv`] computes for one colour and one word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogLuvRead {
    /// `LogLuv32::pack_xyz(colour)` and `LogLuv32.encode(colour)` (the colour as CIE XYZ and as
    /// linear sRGB).
    pub packed: [u32; 2],
    /// `LogLuv32::unpack_xyz(word)`.
    pub xyz: Vec3,
    /// `LogLuv32.decode(word)` (linear sRGB).
    pub rgb: Vec3,
}

impl CodecKernels {
    /// The kernels, none built yet.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Encodes and decodes each `[r, g, b, u]` of `values` in every packed layout on the GPU
    /// (`codec_pack_unpack`); see [`CodecPackRead`].
    pub fn pack_unpack(
        &self,
        ctx: &GpuContext,
        values: &[[f32; 4]],
    ) -> Result<Vec<CodecPackRead>, GpuError> {
        let kernel = lazy(
            &self.pack_unpack,
            ctx,
            src::COLOR_CODEC,
            "codec_pack_unpack",
        )?;
        let n = values.len();
        let values = ctx.storage_buffer("values", values);
        let words: GpuBuffer<[u32; 4]> = ctx.zeroed_buffer("words", 3 * n);
        let decoded: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("decoded", 7 * n);
        ctx.dispatch(
            kernel,
            &[values.raw(), words.raw(), decoded.raw()],
            n as u32,
        )?;
        let words = ctx.read_back(&words)?;
        let decoded = ctx.read_back(&decoded)?;
        Ok(words
            .chunks_exact(3)
            .zip(decoded.chunks_exact(7))
            .map(|(w, d)| CodecPackRead {
                formats: w[0],
                rounded: w[1],
                heuristics: w[2],
                decoded: d.try_into().expect("seven entries"),
            })
            .collect())
    }

    /// LogLuv32 on the GPU (`codec_logluv`, with the step tables of
    /// [`prelude::logluv_tables`](crate::prelude::logluv_tables)): each `colours[i]` packed,
    /// each `words[i]` unpacked.
    ///
    /// # Panics
    /// If `colours` and `words` differ in length.
    pub fn logluv(
        &self,
        ctx: &GpuContext,
        colours: &[Vec3],
        words: &[u32],
    ) -> Result<Vec<LogLuvRead>, GpuError> {
        assert_eq!(colours.len(), words.len(), "one word per colour");
        let kernel = lazy(&self.logluv, ctx, src::COLOR_CODEC_LOGLUV, "codec_logluv")?;
        let n = colours.len();
        let inputs: Vec<[u32; 4]> = colours
            .iter()
            .zip(words)
            .map(|(c, &w)| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits(), w])
            .collect();
        let inputs = ctx.storage_buffer("values", &inputs);
        let tables = ctx.storage_buffer("tables", &crate::prelude::logluv_tables());
        let packed: GpuBuffer<[u32; 2]> = ctx.zeroed_buffer("packed", n);
        let unpacked: GpuBuffer<[f32; 4]> = ctx.zeroed_buffer("unpacked", 2 * n);
        ctx.dispatch(
            kernel,
            &[inputs.raw(), packed.raw(), unpacked.raw(), tables.raw()],
            n as u32,
        )?;
        let packed = ctx.read_back(&packed)?;
        let unpacked = ctx.read_back(&unpacked)?;
        Ok(packed
            .into_iter()
            .zip(unpacked.chunks_exact(2))
            .map(|(packed, u)| LogLuvRead {
                packed,
                xyz: Vec3::new(u[0][0], u[0][1], u[0][2]),
                rgb: Vec3::new(u[1][0], u[1][1], u[1][2]),
            })
            .collect())
    }
}

/// The mcg-markov-guide state kernels: MCPG grid states (MCPG Table 1) and MCMM pixel states
/// (MCMM Table 1, Alg. 1-2), uploaded as they are and read on the GPU. Pipelines are built
/// on first use.
#[derive(Debug, Default)]
pub struct MarkovKernels {
    grid: OnceLock<ComputeKernel>,
    pixel: OnceLock<ComputeKernel>,
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
}

/// A hash table on the GPU: the checksum array and the value array of a
/// [`HashTable`] uploaded as they are, with the pipelines that insert and look up keys.
#[derive(Debug)]
pub struct GpuHashTable<T: Pod> {
    params: HashgridTableParams,
    params_buffer: GpuBuffer<HashgridTableParams>,
    checksums: GpuBuffer<u32>,
    values: GpuBuffer<T>,
    insert: OnceLock<ComputeKernel>,
    insert_serial: OnceLock<ComputeKernel>,
    lookup: OnceLock<ComputeKernel>,
    insert_touch: OnceLock<ComputeKernel>,
    insert_touch_serial: OnceLock<ComputeKernel>,
    evict: OnceLock<ComputeKernel>,
    trim: OnceLock<ComputeKernel>,
}

impl<T: Pod> GpuHashTable<T> {
    /// Uploads `table`'s checksums and values as they are (its slots, tombstones included).
    /// Each pipeline is built on its first use.
    pub fn upload(ctx: &GpuContext, table: &HashTable<T>) -> Result<Self, GpuError> {
        let params =
            HashgridTableParams::new(table.capacity(), table.max_probes(), table.bucket_hash())
                .expect("a HashTable has a non-zero capacity");
        Ok(Self {
            params,
            params_buffer: ctx.uniform_buffer("table", &params),
            checksums: ctx.storage_buffer("checksums", table.checksums()),
            values: ctx.storage_buffer("values", table.values()),
            insert: OnceLock::new(),
            insert_serial: OnceLock::new(),
            lookup: OnceLock::new(),
            insert_touch: OnceLock::new(),
            insert_touch_serial: OnceLock::new(),
            evict: OnceLock::new(),
            trim: OnceLock::new(),
        })
    }

    /// The table's shape as the shaders see it.
    #[must_use]
    pub fn params(&self) -> HashgridTableParams {
        self.params
    }

    /// The checksum buffer (`array<atomic<u32>>` in WGSL), to bind in your own pipelines.
    #[must_use]
    pub fn checksums(&self) -> &GpuBuffer<u32> {
        &self.checksums
    }

    /// The value buffer, indexed by slot.
    #[must_use]
    pub fn values(&self) -> &GpuBuffer<T> {
        &self.values
    }

    fn run(
        &self,
        ctx: &GpuContext,
        kernel: (&OnceLock<ComputeKernel>, &str),
        keys: &[CellKey],
        invocations: u32,
    ) -> Result<Vec<[u32; 2]>, GpuError> {
        if keys.is_empty() {
            // The padded one-element buffers would make the serial kernel insert a zero key.
            return Ok(Vec::new());
        }
        let kernel = lazy(kernel.0, ctx, src::HASHGRID_TABLE, kernel.1)?;
        let keys_buffer = ctx.storage_buffer("keys", keys);
        let results: GpuBuffer<[u32; 2]> = ctx.zeroed_buffer("results", keys.len());
        ctx.dispatch(
            kernel,
            &[
                self.params_buffer.raw(),
                self.checksums.raw(),
                keys_buffer.raw(),
                results.raw(),
            ],
            invocations,
        )?;
        ctx.read_back(&results)
    }

    fn outcomes(raw: Vec<[u32; 2]>) -> Vec<Insert> {
        raw.into_iter()
            .map(|[slot, outcome]| match outcome {
                0 => Insert::Found(slot),
                1 => Insert::Inserted(slot),
                _ => Insert::Full,
            })
            .collect()
    }

    /// Inserts (or finds) every key with one invocation per key, all racing on the checksum
    /// array (`hashgrid_insert_or_get`). New slots' values are not touched (they keep
    /// whatever the slot held; the CPU table zeroes them).
    pub fn insert_or_get(
        &self,
        ctx: &GpuContext,
        keys: &[CellKey],
    ) -> Result<Vec<Insert>, GpuError> {
        Ok(Self::outcomes(self.run(
            ctx,
            (&self.insert, "hashgrid_insert"),
            keys,
            keys.len() as u32,
        )?))
    }

    /// Inserts the keys one after another in one invocation: the outcomes are those of the
    /// same sequence of `HashTable::insert_or_get` calls on the CPU.
    pub fn insert_or_get_serial(
        &self,
        ctx: &GpuContext,
        keys: &[CellKey],
    ) -> Result<Vec<Insert>, GpuError> {
        Ok(Self::outcomes(self.run(
            ctx,
            (&self.insert_serial, "hashgrid_insert_serial"),
            keys,
            1,
        )?))
    }

    /// Looks every key up (`hashgrid_find`): its slot, or `None`.
    pub fn find(&self, ctx: &GpuContext, keys: &[CellKey]) -> Result<Vec<Option<u32>>, GpuError> {
        Ok(self
            .run(
                ctx,
                (&self.lookup, "hashgrid_lookup"),
                keys,
                keys.len() as u32,
            )?
            .into_iter()
            .map(|[slot, _]| (slot != u32::MAX).then_some(slot))
            .collect())
    }

    /// Evicts every key whose age in `ages` (an upload of `HashTable::ages()`, one word per
    /// slot, kept up to date by your kernels with `hashgrid_touch`) is stale at `frame`
    /// (frame − age > `max_age`, wrapping), in two passes like `HashTable::evict_older_than`:
    /// stale slots become tombstones, then tombstones that end a probe run become empty.
    /// Returns how many keys were evicted. No inserts may run meanwhile.
    ///
    /// # Panics
    /// If `ages` does not have one word per slot.
    pub fn evict_older_than(
        &self,
        ctx: &GpuContext,
        ages: &GpuBuffer<u32>,
        frame: u32,
        max_age: u32,
    ) -> Result<u32, GpuError> {
        assert_eq!(ages.len(), self.checksums.len(), "one age per slot");
        let params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(frame, max_age));
        let evicted: GpuBuffer<u32> = ctx.zeroed_buffer("evicted", 1);
        let capacity = self.params.capacity;
        let evict = lazy(&self.evict, ctx, src::HASHGRID_AGES, "hashgrid_evict")?;
        let trim = lazy(&self.trim, ctx, src::HASHGRID_AGES, "hashgrid_trim")?;
        ctx.dispatch(
            evict,
            &[
                self.params_buffer.raw(),
                self.checksums.raw(),
                ages.raw(),
                params.raw(),
                evicted.raw(),
            ],
            capacity,
        )?;
        ctx.dispatch(
            trim,
            &[self.params_buffer.raw(), self.checksums.raw()],
            capacity,
        )?;
        Ok(ctx.read_back(&evicted)?[0])
    }

    /// Inserts (or finds) every key and touches its slot in `frame`
    /// (`hashgrid_insert_or_get` then `hashgrid_touch`, like an age-tracked
    /// `HashTable::insert_or_get` / `ConcurrentTable::insert_or_get`), one invocation per key,
    /// all racing; `ages` is an upload of `HashTable::ages()` (one word per slot). Keys
    /// that find the table full touch nothing. Returns how many keys were `Inserted`.
    ///
    /// # Panics
    /// If `ages` does not have one word per slot.
    pub fn insert_or_get_touch(
        &self,
        ctx: &GpuContext,
        ages: &GpuBuffer<u32>,
        keys: &[CellKey],
        frame: u32,
    ) -> Result<u32, GpuError> {
        let kernel = (&self.insert_touch, "hashgrid_insert_touch");
        self.run_touch(ctx, kernel, ages, keys, frame, keys.len() as u32)
    }

    /// [`insert_or_get_touch`](Self::insert_or_get_touch) with the keys inserted one after
    /// another in one invocation: checksums and ages end as after the same sequence of
    /// `HashTable::insert_or_get` calls at `frame` on the CPU.
    ///
    /// # Panics
    /// If `ages` does not have one word per slot.
    pub fn insert_or_get_touch_serial(
        &self,
        ctx: &GpuContext,
        ages: &GpuBuffer<u32>,
        keys: &[CellKey],
        frame: u32,
    ) -> Result<u32, GpuError> {
        let kernel = (&self.insert_touch_serial, "hashgrid_insert_touch_serial");
        self.run_touch(ctx, kernel, ages, keys, frame, 1)
    }

    fn run_touch(
        &self,
        ctx: &GpuContext,
        kernel: (&OnceLock<ComputeKernel>, &str),
        ages: &GpuBuffer<u32>,
        keys: &[CellKey],
        frame: u32,
        invocations: u32,
    ) -> Result<u32, GpuError> {
        assert_eq!(ages.len(), self.checksums.len(), "one age per slot");
        if keys.is_empty() {
            // The padded one-element key buffer would insert a zero key.
            return Ok(0);
        }
        let kernel = lazy(kernel.0, ctx, src::HASHGRID_AGES, kernel.1)?;
        let params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(frame, 0));
        let inserted: GpuBuffer<u32> = ctx.zeroed_buffer("inserted", 1);
        let keys = ctx.storage_buffer("keys", keys);
        ctx.dispatch(
            kernel,
            &[
                self.params_buffer.raw(),
                self.checksums.raw(),
                ages.raw(),
                params.raw(),
                inserted.raw(),
                keys.raw(),
            ],
            invocations,
        )?;
        Ok(ctx.read_back(&inserted)?[0])
    }

    /// Reads the checksum array back (compare with `HashTable::checksums`).
    pub fn read_checksums(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        ctx.read_back(&self.checksums)
    }
}

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
            update: ctx.compute_kernel(src::COLOR_CODEC_TEXELS, "codec_texel_updates")?,
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
