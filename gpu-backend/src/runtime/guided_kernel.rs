//! Bind group layout entries and the setup of a renderer-style kernel: the caller's buffers at
//! group 0, a guide's bind group at group 1.

use crate::GpuContext;

/// A buffer binding visible to compute shaders, without a dynamic offset or a minimum size.
///
/// `ty` is the buffer's kind, e.g. `wgpu::BufferBindingType::Uniform` or
/// `wgpu::BufferBindingType::Storage { read_only: true }`. See also [`storage_entry`] and
/// [`sized_buffer_entry`].
#[must_use]
pub fn buffer_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    sized_buffer_entry(binding, ty, None)
}

/// [`buffer_entry`] for a storage buffer, read-only or read-write.
#[must_use]
pub fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    buffer_entry(binding, wgpu::BufferBindingType::Storage { read_only })
}

/// [`buffer_entry`] with a minimum binding size (`None`: checked at draw time only), so that
/// wgpu rejects a too-small buffer when the bind group is created.
#[must_use]
pub fn sized_buffer_entry(
    binding: u32,
    ty: wgpu::BufferBindingType,
    min_binding_size: Option<wgpu::BufferSize>,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size,
        },
        count: None,
    }
}

/// A compute shader as a renderer binds it: its own buffers in group 0 (layout from the
/// entries given) and a guide's bind group layout (e.g.
/// [`GpuMcpgGuide::bind_group_layout`](crate::guides::mcpg::GpuMcpgGuide::bind_group_layout))
/// in group 1, the index the guides' `shader_defs(1)` place it at.
///
/// Build pipelines for its entry points with [`GuidedKernel::pipeline`], the group-0 bind
/// group with [`GuidedKernel::io_bind_group`].
#[derive(Debug)]
pub struct GuidedKernel {
    module: wgpu::ShaderModule,
    io_layout: wgpu::BindGroupLayout,
    layout: wgpu::PipelineLayout,
}

impl GuidedKernel {
    /// The shader module from `source` and the pipeline layout [group 0: `io`, group 1:
    /// `guide_layout`]. `label` names the module and the layouts in wgpu's messages.
    #[must_use]
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        source: wgpu::ShaderSource<'_>,
        io: &[wgpu::BindGroupLayoutEntry],
        guide_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let device = ctx.device();
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source,
        });
        let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: io,
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&io_layout), Some(guide_layout)],
            immediate_size: 0,
        });
        Self {
            module,
            io_layout,
            layout,
        }
    }

    /// [`GuidedKernel::new`] from WGSL text (e.g. the output of
    /// [`shaders::compose`](crate::shaders::compose)).
    #[must_use]
    pub fn from_wgsl(
        ctx: &GpuContext,
        label: &str,
        wgsl: String,
        io: &[wgpu::BindGroupLayoutEntry],
        guide_layout: &wgpu::BindGroupLayout,
    ) -> Self {
        let source = wgpu::ShaderSource::Wgsl(wgsl.into());
        Self::new(ctx, label, source, io, guide_layout)
    }

    /// The compute pipeline of `entry_point`, default compilation options, no cache.
    #[must_use]
    pub fn pipeline(&self, ctx: &GpuContext, entry_point: &str) -> wgpu::ComputePipeline {
        ctx.device()
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry_point),
                layout: Some(&self.layout),
                module: &self.module,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            })
    }

    /// The group-0 bind group: `buffers[i]`, whole, at binding `i`.
    #[must_use]
    pub fn io_bind_group(&self, ctx: &GpuContext, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        super::bind_group(ctx, None, &self.io_layout, buffers)
    }

    /// The group-0 layout.
    #[must_use]
    pub fn io_layout(&self) -> &wgpu::BindGroupLayout {
        &self.io_layout
    }

    /// The pipeline layout (group 0 and the guide's group 1).
    #[must_use]
    pub fn layout(&self) -> &wgpu::PipelineLayout {
        &self.layout
    }
}
