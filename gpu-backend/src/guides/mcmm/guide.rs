//! [`GpuMcmmGuide`]: the host side of `mcg::mcmm`.

use mcg_markov_guide::GuideError;
use mcg_markov_guide::mcmm::{McmmParams, PixelState};

use super::GpuMcmmParams;
use crate::shaders::defs;
use crate::{GpuBuffer, GpuContext, GpuError, sized_buffer_entry};

/// The MCMM guide's GPU resources for a `width × height` image: the parameters as a uniform
/// and two buffers of [`PixelState`]s (MCMM sec. 4.1: a pixel resamples the states its
/// neighbours wrote in the previous frame and writes its own for the next), a bind group
/// layout with the bindings of `mcg::mcmm` (0: parameters, 1: previous states, read;
/// 2: current states, written; compute stage) and one bind group per frame parity.
///
/// The renderer composes its shader with [`GpuMcmmGuide::shader_defs`]`(group)` for the group
/// index it chooses, puts [`bind_group_layout`](Self::bind_group_layout) at that index of its
/// pipeline layout, sets [`bind_group`](Self::bind_group) there each frame and calls
/// [`swap`](Self::swap) after the frame's passes: the states just written become the previous
/// frame's. New buffers hold empty chains (all zeros).
///
/// # Example
/// ```no_run
/// use mcg_gpu_backend::guides::mcmm::GpuMcmmGuide;
/// use mcg_gpu_backend::{GpuContext, shaders, wgpu};
/// use mcg_markov_guide::mcmm::McmmParams;
///
/// let ctx = GpuContext::new()?;
/// let mut guide = GpuMcmmGuide::new(&ctx, 1920, 1080, &McmmParams::PAPER)?;
/// // The renderer's shader imports mcg::mcmm; the guide's bindings go to group 1.
/// let my_shader = "\
/// #import mcg::mcmm::{mcg_mcmm_params, mcmm_load_previous, mcmm_store_current}
/// @compute @workgroup_size(32)
/// fn main(@builtin(global_invocation_id) id: vec3<u32>) {
///     mcmm_store_current(id.x, mcmm_load_previous(id.x));
/// }
/// ";
/// let wgsl = shaders::compose(my_shader, &GpuMcmmGuide::shader_defs(1))?;
/// let device = ctx.device();
/// let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
///     label: None,
///     source: wgpu::ShaderSource::Wgsl(wgsl.into()),
/// });
/// let own = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
///     label: None,
///     entries: &[],
/// });
/// let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
///     label: None,
///     bind_group_layouts: &[Some(&own), Some(guide.bind_group_layout())],
///     immediate_size: 0,
/// });
/// # let _ = (module, layout);
/// // Each frame: `pass.set_bind_group(1, guide.bind_group(), &[])`, dispatch, then:
/// guide.swap();
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug)]
pub struct GpuMcmmGuide {
    params: GpuMcmmParams,
    params_buffer: GpuBuffer<GpuMcmmParams>,
    states: [GpuBuffer<PixelState>; 2],
    layout: wgpu::BindGroupLayout,
    bind_groups: [wgpu::BindGroup; 2],
    /// Index into `states` of the previous frame's buffer.
    previous: usize,
}

impl GpuMcmmGuide {
    /// Buffers of empty chains for a `width × height` image and the uniform of `params`.
    ///
    /// # Errors
    /// [`GpuError::Guide`] (with [`GuideError::Params`]) when `params` do not validate;
    /// [`GpuError::GuideTooLarge`] when a state buffer would not fit one storage binding of
    /// the device.
    pub fn new(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        params: &McmmParams,
    ) -> Result<Self, GpuError> {
        params
            .validate()
            .map_err(|e| GpuError::Guide(GuideError::Params(e)))?;
        let pixels = u64::from(width) * u64::from(height);
        let state_size = size_of::<PixelState>() as u64;
        let limits = ctx.device().limits();
        let max_bytes = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let bytes = pixels.saturating_mul(state_size);
        if bytes > max_bytes {
            return Err(GpuError::GuideTooLarge {
                bytes,
                maximum: max_bytes,
            });
        }
        let gpu_params = GpuMcmmParams::new(params, width, height);
        let params_buffer = ctx.uniform_buffer("mcmm params", &gpu_params);
        let n = pixels as usize;
        let states = [
            ctx.zeroed_buffer::<PixelState>("mcmm states a", n),
            ctx.zeroed_buffer::<PixelState>("mcmm states b", n),
        ];
        let storage = |binding, read_only| {
            let ty = wgpu::BufferBindingType::Storage { read_only };
            sized_buffer_entry(binding, ty, wgpu::BufferSize::new(state_size))
        };
        let layout = ctx
            .device()
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("mcmm guide"),
                entries: &[
                    sized_buffer_entry(
                        0,
                        wgpu::BufferBindingType::Uniform,
                        wgpu::BufferSize::new(size_of::<GpuMcmmParams>() as u64),
                    ),
                    storage(1, true),
                    storage(2, false),
                ],
            });
        let bind_group = |previous: &GpuBuffer<PixelState>, current: &GpuBuffer<PixelState>| {
            ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("mcmm guide"),
                layout: &layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: params_buffer.raw().as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: previous.raw().as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: current.raw().as_entire_binding(),
                    },
                ],
            })
        };
        let bind_groups = [
            bind_group(&states[0], &states[1]),
            bind_group(&states[1], &states[0]),
        ];
        Ok(Self {
            params: gpu_params,
            params_buffer,
            states,
            layout,
            bind_groups,
            previous: 0,
        })
    }

    /// The shader defs that place `mcg::mcmm`'s bindings in bind group `group`: pass them to
    /// [`shaders::compose`](crate::shaders::compose) or naga_oil's `shader_defs`.
    #[must_use]
    pub const fn shader_defs(group: u32) -> [(&'static str, u32); 1] {
        [(defs::MCMM_GROUP, group)]
    }

    /// The layout of the guide's bind group (bindings 0-2 of `mcg::mcmm`).
    #[must_use]
    pub const fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// This frame's bind group: the previous frame's states at binding 1, this frame's at 2.
    #[must_use]
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_groups[self.previous]
    }

    /// Ends the frame: the states written this frame become the previous frame's.
    pub fn swap(&mut self) {
        self.previous ^= 1;
    }

    /// The uniform as uploaded.
    #[must_use]
    pub const fn params(&self) -> &GpuMcmmParams {
        &self.params
    }

    /// Image width in pixels.
    #[must_use]
    pub const fn width(&self) -> u32 {
        self.params.width
    }

    /// Image height in pixels.
    #[must_use]
    pub const fn height(&self) -> u32 {
        self.params.height
    }

    /// Replaces the parameters (same image size).
    ///
    /// # Errors
    /// [`GpuError::Guide`] (with [`GuideError::Params`]) when `params` do not validate.
    pub fn set_params(&mut self, ctx: &GpuContext, params: &McmmParams) -> Result<(), GpuError> {
        params
            .validate()
            .map_err(|e| GpuError::Guide(GuideError::Params(e)))?;
        self.params = GpuMcmmParams::new(params, self.params.width, self.params.height);
        ctx.write(&self.params_buffer, &[self.params])?;
        Ok(())
    }

    /// The buffer bound at binding 1 this frame (the previous frame's states).
    #[must_use]
    pub fn previous_buffer(&self) -> &GpuBuffer<PixelState> {
        &self.states[self.previous]
    }

    /// The buffer bound at binding 2 this frame (this frame's states).
    #[must_use]
    pub fn current_buffer(&self) -> &GpuBuffer<PixelState> {
        &self.states[self.previous ^ 1]
    }

    /// Reads the previous frame's states back, row-major.
    ///
    /// # Errors
    /// [`GpuError`] when the read-back fails.
    pub fn read_previous(&self, ctx: &GpuContext) -> Result<Vec<PixelState>, GpuError> {
        ctx.read_back(self.previous_buffer())
    }

    /// Reads this frame's states back, row-major.
    ///
    /// # Errors
    /// [`GpuError`] when the read-back fails.
    pub fn read_current(&self, ctx: &GpuContext) -> Result<Vec<PixelState>, GpuError> {
        ctx.read_back(self.current_buffer())
    }

    /// Overwrites the previous frame's states (row-major, one per pixel), e.g. to restore or
    /// to start from CPU states.
    ///
    /// # Errors
    /// [`GpuError`] unless `states` has one state per pixel.
    pub fn write_previous(&self, ctx: &GpuContext, states: &[PixelState]) -> Result<(), GpuError> {
        ctx.write(self.previous_buffer(), states)
    }

    /// Empties every chain of both buffers (a camera cut).
    ///
    /// # Errors
    /// [`GpuError`] never for a guide built by [`new`](Self::new); kept for the
    /// write's length check.
    pub fn clear(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let empty = vec![PixelState::EMPTY; self.states[0].len()];
        for buffer in &self.states {
            ctx.write(buffer, &empty)?;
        }
        Ok(())
    }
}
