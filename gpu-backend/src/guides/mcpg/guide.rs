//! `GpuMcpgGuide`: the buffers, bind group and per-frame pass of `mcg::mcpg`.

use std::num::NonZeroU64;
use std::sync::OnceLock;

use glam::Vec3;
use mcg_markov_guide::mcpg::{CacheCell, GridState, GuideConfig};

use super::{McpgBufferWords, McpgGpuParams};
use crate::runtime::build_pipelines;
use crate::shaders::{defs, kernels};
use crate::{GpuBuffer, GpuContext, GpuError, codes, sized_buffer_entry, storage_entry};

/// The per-frame pass's pipelines, in the order they run.
#[derive(Debug)]
struct Maintenance {
    fold: wgpu::ComputePipeline,
    evict: wgpu::ComputePipeline,
    trim: wgpu::ComputePipeline,
    next_frame: wgpu::ComputePipeline,
}

/// What [`GpuMcpgGuide::read_back`] copies out: the states, keys and ages of both grids and the
/// cache's cells, each in slot order (compare with the CPU guide's `grids_mut().snapshot()`
/// and `cache().cells()`).
#[derive(Clone, Debug, PartialEq)]
pub struct McpgReadBack {
    /// The current frame (time T of the states).
    pub frame: u32,
    /// The adaptive grid's states.
    pub adaptive_states: Vec<GridState>,
    /// The static grid's states.
    pub static_states: Vec<GridState>,
    /// The adaptive grid's checksum words (0 empty, 1 tombstone, else a key's checksum).
    pub adaptive_checksums: Vec<u32>,
    /// The static grid's checksum words.
    pub static_checksums: Vec<u32>,
    /// The adaptive grid's age words (the frame each slot was last used; empty without age
    /// tracking).
    pub adaptive_ages: Vec<u32>,
    /// The static grid's age words.
    pub static_ages: Vec<u32>,
    /// The irradiance cache's cells (empty without a cache).
    pub cache_cells: Vec<CacheCell>,
    /// The cache's checksum words.
    pub cache_checksums: Vec<u32>,
}

/// Bytes of GPU memory the guide holds, per slot and in all.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct McpgMemory {
    /// One chain state (MCPG Table 1 in 32 bytes).
    pub state: u64,
    /// One grid slot: the state, its guard word, its checksum and its age.
    pub grid_slot: u64,
    /// One cache slot: the cell, its per-frame sums, its checksum and its age.
    pub cache_slot: u64,
    /// The hash words buffer.
    pub table_buffer: u64,
    /// The guide's words buffer.
    pub guide_buffer: u64,
    /// The parameters.
    pub params: u64,
}

/// MCPG on the GPU: the grids, the irradiance cache and the parameters of `mcg::mcpg` in
/// buffers, the bind group a renderer's pipelines bind at a group index of its choice, and the
/// per-frame pass recorded into the renderer's encoder. Built from the same [`GuideConfig`] as
/// the CPU guide (`mcg_markov_guide::mcpg::Guide`), whose decisions it reproduces for the same
/// uniforms.
///
/// Per frame: [`set_camera`](Self::set_camera) before submitting the frame's work, the
/// renderer's dispatches (which call `mcpg_begin` / `mcpg_sample` / `mcpg_finish`), then
/// [`record_end_frame`](Self::record_end_frame) after them.
#[derive(Debug)]
pub struct GpuMcpgGuide {
    config: GuideConfig,
    params: McpgGpuParams,
    sizes: McpgBufferWords,
    params_buffer: GpuBuffer<McpgGpuParams>,
    table_words: GpuBuffer<u32>,
    guide_words: GpuBuffer<u32>,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    maintenance: OnceLock<Maintenance>,
    frame: u32,
}

impl GpuMcpgGuide {
    /// The binding of the parameters in the guide's group.
    pub const PARAMS_BINDING: u32 = 0;
    /// The binding of the hash words (`mcg_hashgrid_words`) in the guide's group.
    pub const TABLE_WORDS_BINDING: u32 = 1;
    /// The binding of the guide's words (`mcpg_words`) in the guide's group.
    pub const GUIDE_WORDS_BINDING: u32 = 2;
    /// The binding of the same words viewed as `vec4<u32>` (`mcpg_words4`) in the guide's
    /// group: a candidate's state is read, and a locked writer's state written, as two 16-byte
    /// accesses instead of eight atomic word accesses (WGSL has no plain access to an atomic
    /// array). The view aliases [`GUIDE_WORDS_BINDING`](Self::GUIDE_WORDS_BINDING)'s buffer;
    /// a read racing a writer may come back torn, which the state's guard stamp (a hash of its
    /// eight words) detects, and the candidate is dropped, as a torn atomic read was.
    pub const GUIDE_WORDS_VEC4_BINDING: u32 = 3;

    /// The largest buffer, in bytes, the guide may bind on `ctx`'s device: the smaller of
    /// `max_storage_buffer_binding_size` and `max_buffer_size`.
    #[must_use]
    pub fn max_buffer_bytes(ctx: &GpuContext) -> u64 {
        let limits = ctx.device().limits();
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    }

    /// `config` with its adaptive table halved until the guide's two buffers fit one storage
    /// binding of `ctx`'s device (`max_storage_buffer_binding_size` and `max_buffer_size`):
    /// the largest adaptive grid of this configuration the device holds, for
    /// [`new`](Self::new). The table is not halved below 2¹² slots, and a configuration
    /// [`new`](Self::new) rejects for another reason comes back unchanged (`new` says why).
    ///
    /// A `GuideConfig::for_pixels` table at 1920 × 1080 (2²² slots, 176 MiB) fits a desktop
    /// GPU's bindings; WebGPU's default 128 MiB binding (and lavapipe's) holds 2²¹.
    #[must_use]
    pub fn fitted_config(ctx: &GpuContext, config: &GuideConfig) -> GuideConfig {
        let maximum = Self::max_buffer_bytes(ctx);
        let mut fitted = *config;
        while fitted.adaptive_capacity / 2 >= 1 << 12 {
            match McpgGpuParams::new(&fitted) {
                Ok((_, sizes)) if 4 * sizes.table_words.max(sizes.guide_words) <= maximum => break,
                Ok(_) | Err(GpuError::GuideTooLarge { .. }) => fitted.adaptive_capacity /= 2,
                Err(_) => return *config,
            }
        }
        fitted
    }

    /// An empty guide on `ctx`'s device.
    ///
    /// # Errors
    /// [`GpuError::Guide`] for a configuration the CPU guide rejects,
    /// [`GpuError::GuideTooLarge`] when a buffer exceeds the device's binding size.
    pub fn new(ctx: &GpuContext, config: &GuideConfig) -> Result<Self, GpuError> {
        let (params, sizes) = McpgGpuParams::new(config)?;
        let maximum = Self::max_buffer_bytes(ctx);
        for words in [sizes.table_words, sizes.guide_words] {
            let bytes = 4 * words;
            if bytes > maximum {
                return Err(GpuError::GuideTooLarge { bytes, maximum });
            }
        }
        let params_buffer = ctx.uniform_buffer("mcpg params", &params);
        let table_words = ctx.zeroed_buffer("mcpg hash words", sizes.table_words as usize);
        let guide_words = ctx.zeroed_buffer("mcpg words", sizes.guide_words as usize);
        let layout = ctx
            .device()
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("mcg::mcpg"),
                entries: &[
                    sized_buffer_entry(
                        Self::PARAMS_BINDING,
                        wgpu::BufferBindingType::Uniform,
                        NonZeroU64::new(size_of::<McpgGpuParams>() as u64),
                    ),
                    storage_entry(Self::TABLE_WORDS_BINDING, false),
                    storage_entry(Self::GUIDE_WORDS_BINDING, false),
                    storage_entry(Self::GUIDE_WORDS_VEC4_BINDING, false),
                ],
            });
        let bind_group = ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mcg::mcpg"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: Self::PARAMS_BINDING,
                    resource: params_buffer.raw().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: Self::TABLE_WORDS_BINDING,
                    resource: table_words.raw().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: Self::GUIDE_WORDS_BINDING,
                    resource: guide_words.raw().as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: Self::GUIDE_WORDS_VEC4_BINDING,
                    resource: guide_words.raw().as_entire_binding(),
                },
            ],
        });
        Ok(Self {
            config: *config,
            params,
            sizes,
            params_buffer,
            table_words,
            guide_words,
            layout,
            bind_group,
            maintenance: OnceLock::new(),
            frame: 0,
        })
    }

    /// The shader defs that put `mcg::mcpg` (and the hash words it uses) at bind group
    /// `group`: pass them to naga_oil's `shader_defs` or to [`crate::shaders::compose`].
    #[must_use]
    pub const fn shader_defs(group: u32) -> [(&'static str, u32); 3] {
        [
            (defs::MCPG_GROUP, group),
            (defs::HASHGRID_GROUP, group),
            (defs::HASHGRID_BINDING, Self::TABLE_WORDS_BINDING),
        ]
    }

    /// The layout of the guide's group (compute stage), for the renderer's pipeline layout.
    #[must_use]
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The guide's group, to set at the index given to [`shader_defs`](Self::shader_defs).
    #[must_use]
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &GuideConfig {
        &self.config
    }

    /// The parameters as the shaders read them.
    #[must_use]
    pub const fn params(&self) -> &McpgGpuParams {
        &self.params
    }

    /// The current frame (the time T of the states), as the host counts it.
    #[must_use]
    pub const fn frame(&self) -> u32 {
        self.frame
    }

    /// Sets the camera position the adaptive levels follow (`Guide::set_camera`). Written with
    /// `queue.write_buffer`, so it applies to work submitted after this call.
    pub fn set_camera(&mut self, ctx: &GpuContext, camera: Vec3) {
        self.params.camera = camera;
        ctx.queue().write_buffer(
            self.params_buffer.raw(),
            0,
            bytemuck::bytes_of(&self.params),
        );
    }

    fn maintenance(&self, ctx: &GpuContext) -> Result<&Maintenance, GpuError> {
        if let Some(m) = self.maintenance.get() {
            return Ok(m);
        }
        let [fold, evict, trim, next_frame] = build_pipelines(
            ctx,
            &[&self.layout],
            (
                "mcpg maintenance",
                kernels::MCPG_MAINTENANCE,
                kernels::KERNEL_DEFS,
            ),
            [
                "mcpg_fold_cache",
                "mcpg_evict",
                "mcpg_trim",
                "mcpg_next_frame",
            ],
        )?;
        let m = Maintenance {
            fold,
            evict,
            trim,
            next_frame,
        };
        Ok(self.maintenance.get_or_init(|| m))
    }

    /// Records the per-frame pass into `encoder` (`Guide::end_frame`): the cache folds the
    /// frame's samples in and evicts idle cells, idle states are evicted
    /// (`GuideConfig::max_state_age`), and the time advances by one frame. Record it after the
    /// frame's guide calls; the pipelines are built on the first call.
    ///
    /// # Errors
    /// [`GpuError::Shader`] if the pass's pipelines fail to build (a bug of this crate).
    pub fn record_end_frame(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), GpuError> {
        self.record_end_frame_timed(ctx, encoder, None)
    }

    /// [`record_end_frame`](Self::record_end_frame) with timestamps written at the beginning
    /// and end of its compute pass (a device with `TIMESTAMP_QUERY`), so that a renderer can
    /// time the guide's per-frame work on the GPU's clock beside its own passes.
    ///
    /// # Errors
    /// As [`record_end_frame`](Self::record_end_frame).
    pub fn record_end_frame_timed(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<(), GpuError> {
        let m = self.maintenance(ctx)?;
        let grid = |invocations: u32| ctx.workgroup_grid(invocations, crate::WORKGROUP_SIZE);
        let p = &self.params;
        let slots = p.adaptive_table.capacity
            + p.static_table.capacity
            + if p.cache_enabled != 0 {
                p.cache_table.capacity
            } else {
                0
            };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("mcpg end of frame"),
            timestamp_writes,
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        if p.cache_enabled != 0 {
            let (x, y) = grid(p.cache_table.capacity);
            pass.set_pipeline(&m.fold);
            pass.dispatch_workgroups(x, y, 1);
        }
        let (x, y) = grid(slots);
        pass.set_pipeline(&m.evict);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&m.trim);
        pass.dispatch_workgroups(x, y, 1);
        pass.set_pipeline(&m.next_frame);
        pass.dispatch_workgroups(1, 1, 1);
        drop(pass);
        self.frame = self.frame.wrapping_add(1);
        Ok(())
    }

    /// [`record_end_frame`](Self::record_end_frame) in an encoder of its own, submitted.
    ///
    /// # Errors
    /// As [`record_end_frame`](Self::record_end_frame).
    pub fn end_frame(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        self.record_end_frame(ctx, &mut encoder)?;
        ctx.queue().submit([encoder.finish()]);
        Ok(())
    }

    /// Empties the grids and the cache and sets the time back to frame 0, keeping the buffers,
    /// the bind group and the pipelines (a fresh guide without rebuilding the renderer's
    /// pipelines). Recorded with `clear_buffer` into an encoder of its own and submitted.
    pub fn reset(&mut self, ctx: &GpuContext) {
        let mut encoder = ctx
            .device()
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.clear_buffer(self.table_words.raw(), 0, None);
        encoder.clear_buffer(self.guide_words.raw(), 0, None);
        ctx.queue().submit([encoder.finish()]);
        self.frame = 0;
    }

    /// The hash words buffer (checksums and ages of the three tables).
    #[must_use]
    pub fn table_words(&self) -> &GpuBuffer<u32> {
        &self.table_words
    }

    /// The guide's words buffer (frame, states, guards, cache).
    #[must_use]
    pub fn guide_words(&self) -> &GpuBuffer<u32> {
        &self.guide_words
    }

    /// Copies the states, keys, ages and cache cells back (waits for the queue).
    ///
    /// # Errors
    /// [`GpuError::Map`] when the read-back fails.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<McpgReadBack, GpuError> {
        let table = ctx.read_back(&self.table_words)?;
        let words = ctx.read_back(&self.guide_words)?;
        let p = &self.params;
        let range = |start: u32, len: u32| start as usize..(start + len) as usize;
        let states = |start: u32, slots: u32| -> Vec<GridState> {
            bytemuck::pod_collect_to_vec(&words[range(start, 8 * slots)])
        };
        let (ca, cs) = (p.adaptive_table.capacity, p.static_table.capacity);
        let cc = if p.cache_enabled != 0 {
            p.cache_table.capacity
        } else {
            0
        };
        let aged = if p.age_tracking != 0 { 1 } else { 0 };
        Ok(McpgReadBack {
            frame: words[codes::MCPG_FRAME_WORD as usize],
            adaptive_states: states(p.adaptive_states, ca),
            static_states: states(p.static_states, cs),
            adaptive_checksums: table[range(p.adaptive_table.checksum_offset, ca)].to_vec(),
            static_checksums: table[range(p.static_table.checksum_offset, cs)].to_vec(),
            adaptive_ages: table[range(p.adaptive_table.age_offset, aged * ca)].to_vec(),
            static_ages: table[range(p.static_table.age_offset, aged * cs)].to_vec(),
            cache_cells: bytemuck::pod_collect_to_vec(&words[range(p.cache_cells, 4 * cc)]),
            cache_checksums: table[range(p.cache_table.checksum_offset, cc)].to_vec(),
        })
    }

    /// The guide's GPU memory: 44 bytes per grid slot (the 32-byte state, its guard word, its
    /// checksum and its age), 40 per cache slot (16-byte cell, 16 bytes of per-frame sums,
    /// checksum, age), and the two buffers in all.
    #[must_use]
    pub fn memory(&self) -> McpgMemory {
        McpgMemory {
            state: size_of::<GridState>() as u64,
            grid_slot: size_of::<GridState>() as u64 + 3 * 4,
            cache_slot: size_of::<CacheCell>() as u64 + 16 + 2 * 4,
            table_buffer: 4 * self.sizes.table_words,
            guide_buffer: 4 * self.sizes.guide_words,
            params: size_of::<McpgGpuParams>() as u64,
        }
    }
}
