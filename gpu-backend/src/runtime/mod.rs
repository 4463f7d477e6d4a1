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
