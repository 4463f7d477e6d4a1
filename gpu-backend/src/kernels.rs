//! Host-side pipelines for the kernels of [`crate::shaders::kernels`], with typed inputs and
//! outputs. Each method uploads its inputs, dispatches one invocation per element and reads
//! the results back; renderers that keep data on the GPU bind the same modules in their own
//! pipelines instead.

use bytemuck::Pod;
use mcg_hashgrid::{CellKey, HashTable, Insert};
use mcg_vmf::{SufficientStats, Vmf};

use crate::shaders::kernels as src;
use crate::types::{
    HashgridAgeParams, HashgridTableParams, TexelParams, TexelUpdate, VmfQuery, VmfSample,
    VmfStatsQuery, VmfStatsResult,
};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// The vMF kernels: pdf, sampling, reconstruction and products on arrays of lobes.
#[derive(Debug)]
pub struct VmfKernels {
    pdf_and_sample: ComputeKernel,
    stats: ComputeKernel,
}

impl VmfKernels {
    /// Builds the pipelines.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            pdf_and_sample: ctx.compute_kernel(src::VMF, "vmf_pdf_and_sample")?,
            stats: ctx.compute_kernel(src::VMF_STATS, "vmf_stats")?,
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
}

/// A hash table on the GPU: the checksum array and the value array of a
/// [`HashTable`] uploaded as they are, with the pipelines that insert and look up keys.
#[derive(Debug)]
pub struct GpuHashTable<T: Pod> {
    params: HashgridTableParams,
    params_buffer: GpuBuffer<HashgridTableParams>,
    checksums: GpuBuffer<u32>,
    values: GpuBuffer<T>,
    insert: ComputeKernel,
    insert_serial: ComputeKernel,
    lookup: ComputeKernel,
    evict: ComputeKernel,
    trim: ComputeKernel,
}

impl<T: Pod> GpuHashTable<T> {
    /// Uploads `table`'s checksums and values as they are (its slots, tombstones included).
    pub fn upload(ctx: &GpuContext, table: &HashTable<T>) -> Result<Self, GpuError> {
        let params =
            HashgridTableParams::new(table.capacity(), table.max_probes(), table.bucket_hash())
                .expect("a HashTable has a non-zero capacity");
        Ok(Self {
            params,
            params_buffer: ctx.uniform_buffer("table", &params),
            checksums: ctx.storage_buffer("checksums", table.checksums()),
            values: ctx.storage_buffer("values", table.values()),
            insert: ctx.compute_kernel(src::HASHGRID_TABLE, "hashgrid_insert")?,
            insert_serial: ctx.compute_kernel(src::HASHGRID_TABLE, "hashgrid_insert_serial")?,
            lookup: ctx.compute_kernel(src::HASHGRID_TABLE, "hashgrid_lookup")?,
            evict: ctx.compute_kernel(src::HASHGRID_AGES, "hashgrid_evict")?,
            trim: ctx.compute_kernel(src::HASHGRID_AGES, "hashgrid_trim")?,
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
        kernel: &ComputeKernel,
        keys: &[CellKey],
        invocations: u32,
    ) -> Result<Vec<[u32; 2]>, GpuError> {
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
            &self.insert,
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
            &self.insert_serial,
            keys,
            1,
        )?))
    }

    /// Looks every key up (`hashgrid_find`): its slot, or `None`.
    pub fn find(&self, ctx: &GpuContext, keys: &[CellKey]) -> Result<Vec<Option<u32>>, GpuError> {
        Ok(self
            .run(ctx, &self.lookup, keys, keys.len() as u32)?
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
        ctx.dispatch(
            &self.evict,
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
            &self.trim,
            &[self.params_buffer.raw(), self.checksums.raw()],
            capacity,
        )?;
        Ok(ctx.read_back(&evicted)?[0])
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
