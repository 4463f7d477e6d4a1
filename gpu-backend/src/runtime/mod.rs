//! The host side on wgpu (feature `runtime`): a context on your device or a headless one,
//! typed buffers, and one host type per file for the kernels and the GPU-resident tables.

mod buffer;
mod codec_kernels;
mod context;
mod gpu_hash_table;
mod gpu_texels;
mod guided_kernel;
mod hashgrid_kernels;
mod markov_kernels;
pub mod testing;
mod vmf_kernels;
mod vmf_mixture_kernel;

use std::sync::OnceLock;

pub use crate::error::GpuError;
pub use buffer::GpuBuffer;
pub use codec_kernels::{CodecKernels, CodecPackRead, LogLuvRead};
pub use context::{ComputeKernel, GpuContext};
pub use gpu_hash_table::GpuHashTable;
pub use gpu_texels::GpuTexels;
pub use guided_kernel::{GuidedKernel, buffer_entry, sized_buffer_entry, storage_entry};
pub use hashgrid_kernels::HashgridKernels;
pub use markov_kernels::{GridStateQueryRead, GridStateRead, MarkovKernels, PixelStateRead};
pub use vmf_kernels::VmfKernels;
pub use vmf_mixture_kernel::{VmfMixtureEval, VmfMixtureKernel};

use crate::shaders::kernels as src;

/// The pipeline in `cell`, built from the kernel `source` (composed into plain WGSL) and
/// `entry` on first use: a wrapper compiles only the kernels it runs (compiling is slow on
/// software adapters).
pub(crate) fn lazy<'a>(
    cell: &'a OnceLock<ComputeKernel>,
    ctx: &GpuContext,
    source: &str,
    entry: &str,
) -> Result<&'a ComputeKernel, GpuError> {
    if let Some(kernel) = cell.get() {
        return Ok(kernel);
    }
    let kernel = ctx.compute_kernel(&src::plain(source), entry)?;
    Ok(cell.get_or_init(|| kernel))
}

/// The pipelines of `entries` in one kernel file, composed with `defs`, with the bind group
/// `layouts` (group i at i): one shader module and one pipeline layout, both labelled `label`,
/// and a pipeline per entry point labelled with its name. Composition and validation errors
/// come back as [`GpuError::Shader`] with `label` as the entry point.
pub(crate) fn build_pipelines<const N: usize>(
    ctx: &GpuContext,
    layouts: &[&wgpu::BindGroupLayout],
    (label, source, defs): (&str, &str, &[(&str, u32)]),
    entries: [&str; N],
) -> Result<[wgpu::ComputePipeline; N], GpuError> {
    let shader_error = |message: String| GpuError::Shader {
        entry_point: label.to_owned(),
        message,
    };
    let device = ctx.device();
    let source = crate::shaders::compose(source, defs).map_err(|e| shader_error(e.to_string()))?;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts.iter().map(|l| Some(*l)).collect::<Vec<_>>(),
        immediate_size: 0,
    });
    let pipelines = entries.map(|entry| {
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            cache: None,
        })
    });
    if let Some(error) = pollster::block_on(scope.pop()) {
        return Err(shader_error(error.to_string()));
    }
    Ok(pipelines)
}

/// Records one compute pass named `label` into `encoder`: `pipeline` with `groups[i]` at
/// group i, dispatched over [`GpuContext::workgroup_grid`]`(invocations, WORKGROUP_SIZE)`.
pub(crate) fn record_dispatch(
    ctx: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    groups: &[&wgpu::BindGroup],
    invocations: u32,
) {
    let (x, y) = ctx.workgroup_grid(invocations, crate::WORKGROUP_SIZE);
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    pass.set_pipeline(pipeline);
    for (i, g) in (0..).zip(groups) {
        pass.set_bind_group(i, *g, &[]);
    }
    pass.dispatch_workgroups(x, y, 1);
}

/// A bind group of `layout` with `buffers[i]`, whole, at binding `i`, named `label` in wgpu's
/// messages.
pub(crate) fn bind_group(
    ctx: &GpuContext,
    label: Option<&str>,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
        .iter()
        .zip(0..)
        .map(|(b, binding)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
        label,
        layout,
        entries: &entries,
    })
}
