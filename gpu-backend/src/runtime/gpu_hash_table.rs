//! A hash table on the GPU.

use std::sync::OnceLock;

use bytemuck::Pod;
use mcg_hashgrid::{CellKey, HashTable, Insert};

use super::lazy;
use crate::codes;
use crate::shaders::kernels as src;
use crate::types::{HashgridAgeParams, HashgridTableParams};
use crate::{ComputeKernel, GpuBuffer, GpuContext, GpuError};

/// A hash table on the GPU: the checksum words and ages of a [`HashTable`] uploaded as they
/// are into one words buffer (`mcg_hashgrid_words` of `mcg::hashgrid_table`: `capacity`
/// checksums, then `capacity` ages), the value array beside it, and the pipelines that insert,
/// look up and evict keys. Bind [`words`](Self::words) with [`params`](Self::params) in your
/// own pipelines; several tables can share one words buffer at other offsets (see
/// [`HashgridTableParams::at_offsets`]).
#[derive(Debug)]
pub struct GpuHashTable<T: Pod> {
    params: HashgridTableParams,
    params_buffer: GpuBuffer<HashgridTableParams>,
    words: GpuBuffer<u32>,
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
    /// Uploads `table`'s checksums, ages (zeros for a table without age tracking) and values
    /// as they are (its slots, tombstones included). Each pipeline is built on its first use.
    pub fn upload(ctx: &GpuContext, table: &HashTable<T>) -> Result<Self, GpuError> {
        let capacity = table.capacity();
        let params = HashgridTableParams::new(capacity, table.max_probes(), table.bucket_hash())
            .expect("a HashTable has a non-zero capacity")
            .at_offsets(0, capacity);
        let mut words = table.checksums().to_vec();
        if table.ages().is_empty() {
            words.resize(2 * capacity as usize, 0);
        } else {
            words.extend_from_slice(table.ages());
        }
        Ok(Self {
            params,
            params_buffer: ctx.uniform_buffer("table", &params),
            words: ctx.storage_buffer("hashgrid words", &words),
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

    /// The table's shape and offsets as the shaders see it.
    #[must_use]
    pub fn params(&self) -> HashgridTableParams {
        self.params
    }

    /// The words buffer (`mcg_hashgrid_words`, `array<atomic<u32>>` in WGSL): checksums, then
    /// ages.
    #[must_use]
    pub fn words(&self) -> &GpuBuffer<u32> {
        &self.words
    }

    /// The value buffer, indexed by slot.
    #[must_use]
    pub fn values(&self) -> &GpuBuffer<T> {
        &self.values
    }

    /// Dispatches `kernel`, one of the `hashgrid_table` or `hashgrid_ages` kernels, with the
    /// bindings they all start with (0: the table's params, 1: its words buffer), then `rest`
    /// from binding 2 on.
    fn dispatch(
        &self,
        ctx: &GpuContext,
        kernel: &ComputeKernel,
        rest: &[&wgpu::Buffer],
        invocations: u32,
    ) -> Result<(), GpuError> {
        let mut buffers = vec![self.params_buffer.raw(), self.words.raw()];
        buffers.extend_from_slice(rest);
        ctx.dispatch(kernel, &buffers, invocations)
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
        self.dispatch(
            ctx,
            kernel,
            &[keys_buffer.raw(), results.raw()],
            invocations,
        )?;
        ctx.read_back(&results)
    }

    fn outcomes(raw: Vec<[u32; 2]>) -> Vec<Insert> {
        raw.into_iter()
            .map(|[slot, code]| codes::insert(slot, code).unwrap_or(Insert::Full))
            .collect()
    }

    /// Inserts (or finds) every key with one invocation per key, all racing on the checksum
    /// words (`hashgrid_insert_or_get`). New slots' values are not touched (they keep
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
            .map(|[slot, _]| (slot != codes::NO_SLOT).then_some(slot))
            .collect())
    }

    /// Evicts every key whose age (kept up to date by your kernels with `hashgrid_touch`, or
    /// by [`insert_or_get_touch`](Self::insert_or_get_touch)) is stale at `frame`
    /// (frame − age > `max_age`, wrapping), in two passes like `HashTable::evict_older_than`:
    /// stale slots become tombstones, then tombstones that end a probe run become empty.
    /// Returns how many keys were evicted. No inserts may run meanwhile.
    pub fn evict_older_than(
        &self,
        ctx: &GpuContext,
        frame: u32,
        max_age: u32,
    ) -> Result<u32, GpuError> {
        let params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(frame, max_age));
        let evicted: GpuBuffer<u32> = ctx.zeroed_buffer("evicted", 1);
        let capacity = self.params.capacity;
        let evict = lazy(&self.evict, ctx, src::HASHGRID_AGES, "hashgrid_evict")?;
        let trim = lazy(&self.trim, ctx, src::HASHGRID_AGES, "hashgrid_trim")?;
        self.dispatch(ctx, evict, &[params.raw(), evicted.raw()], capacity)?;
        self.dispatch(ctx, trim, &[], capacity)?;
        Ok(ctx.read_back(&evicted)?[0])
    }

    /// Inserts (or finds) every key and touches its slot in `frame`
    /// (`hashgrid_insert_or_get` then `hashgrid_touch`, like an age-tracked
    /// `HashTable::insert_or_get` / `ConcurrentTable::insert_or_get`), one invocation per key,
    /// all racing. Keys that find the table full touch nothing. Returns how many keys were
    /// `Inserted`.
    pub fn insert_or_get_touch(
        &self,
        ctx: &GpuContext,
        keys: &[CellKey],
        frame: u32,
    ) -> Result<u32, GpuError> {
        let kernel = (&self.insert_touch, "hashgrid_insert_touch");
        self.run_touch(ctx, kernel, keys, frame, keys.len() as u32)
    }

    /// [`insert_or_get_touch`](Self::insert_or_get_touch) with the keys inserted one after
    /// another in one invocation: checksums and ages end as after the same sequence of
    /// `HashTable::insert_or_get` calls at `frame` on the CPU.
    pub fn insert_or_get_touch_serial(
        &self,
        ctx: &GpuContext,
        keys: &[CellKey],
        frame: u32,
    ) -> Result<u32, GpuError> {
        let kernel = (&self.insert_touch_serial, "hashgrid_insert_touch_serial");
        self.run_touch(ctx, kernel, keys, frame, 1)
    }

    fn run_touch(
        &self,
        ctx: &GpuContext,
        kernel: (&OnceLock<ComputeKernel>, &str),
        keys: &[CellKey],
        frame: u32,
        invocations: u32,
    ) -> Result<u32, GpuError> {
        if keys.is_empty() {
            // The padded one-element key buffer would insert a zero key.
            return Ok(0);
        }
        let kernel = lazy(kernel.0, ctx, src::HASHGRID_AGES, kernel.1)?;
        let params = ctx.uniform_buffer("age params", &HashgridAgeParams::new(frame, 0));
        let inserted: GpuBuffer<u32> = ctx.zeroed_buffer("inserted", 1);
        let keys = ctx.storage_buffer("keys", keys);
        self.dispatch(
            ctx,
            kernel,
            &[params.raw(), inserted.raw(), keys.raw()],
            invocations,
        )?;
        Ok(ctx.read_back(&inserted)?[0])
    }

    /// Reads the checksum words back (compare with `HashTable::checksums`).
    pub fn read_checksums(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let mut words = ctx.read_back(&self.words)?;
        words.truncate(self.params.capacity as usize);
        Ok(words)
    }

    /// Reads the age words back (compare with `HashTable::ages`).
    pub fn read_ages(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let words = ctx.read_back(&self.words)?;
        Ok(words[self.params.capacity as usize..].to_vec())
    }

    /// Overwrites the age words (one per slot).
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless `ages` has one word per slot.
    pub fn write_ages(&self, ctx: &GpuContext, ages: &[u32]) -> Result<(), GpuError> {
        GpuError::check_len(self.params.capacity as usize, ages.len())?;
        let offset = u64::from(self.params.age_offset) * size_of::<u32>() as u64;
        ctx.queue()
            .write_buffer(self.words.raw(), offset, bytemuck::cast_slice(ages));
        Ok(())
    }
}
