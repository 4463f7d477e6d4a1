//! The headless wgpu context: instance, adapter, device and queue, plus the small helpers that
//! build compute pipelines, upload buffers, dispatch and read back.

use std::sync::OnceLock;

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use crate::{GpuBuffer, GpuError, WORKGROUP_SIZE};

/// Limits the kernels of this crate rely on, all at or below the WebGPU defaults
/// (`wgpu::Limits::default()`), checked against the adapter in [`GpuContext::new`].
/// A limit's name, how to read it, and the least value the kernels need.
type NeededLimit = (&'static str, fn(&wgpu::Limits) -> u64, u64);

const NEEDED_LIMITS: [NeededLimit; 4] = [
    (
        "max_storage_buffers_per_shader_stage",
        |l| u64::from(l.max_storage_buffers_per_shader_stage),
        4,
    ),
    (
        "max_compute_invocations_per_workgroup",
        |l| u64::from(l.max_compute_invocations_per_workgroup),
        WORKGROUP_SIZE as u64,
    ),
    (
        "max_compute_workgroup_size_x",
        |l| u64::from(l.max_compute_workgroup_size_x),
        WORKGROUP_SIZE as u64,
    ),
    (
        "max_compute_workgroups_per_dimension",
        |l| u64::from(l.max_compute_workgroups_per_dimension),
        65_535,
    ),
];

/// A headless wgpu device for compute work: no window, no surface.
///
/// Created by [`GpuContext::new`], which picks the adapter wgpu prefers (honouring the
/// `WGPU_BACKEND`, `WGPU_ADAPTER_NAME` and `WGPU_POWER_PREF` environment variables), checks
/// the limits the kernels need and requests a device with **no features** beyond WebGPU's
/// defaults and WebGPU's default limits, so everything here also runs in a browser.
#[derive(Debug)]
pub struct GpuContext {
    adapter: Option<wgpu::Adapter>,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

/// A compute pipeline for one entry point, with the bind group layout of its group 0.
///
/// Built by [`GpuContext::compute_kernel`]; run with [`GpuContext::dispatch`].
#[derive(Debug)]
pub struct ComputeKernel {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    entry_point: String,
}

impl ComputeKernel {
    /// The wgpu pipeline, to record into your own compute passes.
    #[must_use]
    pub fn pipeline(&self) -> &wgpu::ComputePipeline {
        &self.pipeline
    }

    /// Layout of bind group 0 (derived from the shader).
    #[must_use]
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The entry point's name.
    #[must_use]
    pub fn entry_point(&self) -> &str {
        &self.entry_point
    }
}

/// `Ok` when `available` meets every limit of [`NEEDED_LIMITS`], else the first one it misses.
fn check_limits(available: &wgpu::Limits) -> Result<(), GpuError> {
    for (limit, get, required) in NEEDED_LIMITS {
        let have = get(available);
        if have < required {
            return Err(GpuError::LimitTooLow {
                limit,
                required,
                available: have,
            });
        }
    }
    Ok(())
}

impl GpuContext {
    /// Creates a headless instance, adapter, device and queue.
    ///
    /// Errors: [`GpuError::NoAdapter`] when wgpu finds no adapter at all (the message says
    /// how to install lavapipe), [`GpuError::LimitTooLow`] when the adapter cannot run the
    /// kernels (below WebGPU's defaults), [`GpuError::RequestDevice`] when the adapter
    /// refuses the device.
    pub fn new() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::from_env()
                .unwrap_or(wgpu::PowerPreference::HighPerformance),
            force_fallback_adapter: false,
            compatible_surface: None,
            apply_limit_buckets: false,
        };
        let adapter = pollster::block_on(instance.request_adapter(&options)).map_err(|e| {
            GpuError::NoAdapter {
                reason: e.to_string(),
            }
        })?;
        let available = adapter.limits();
        check_limits(&available)?;
        // WebGPU's default limits, lowered only where the adapter offers less (a software
        // or downlevel adapter), never raised: the kernels fit in what is checked above.
        let limits = wgpu::Limits::default().using_resolution(available.clone());
        let limits = limits.using_alignment(available);
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("mcg-gpu-backend"),
            required_features: wgpu::Features::empty(),
            required_limits: limits,
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| {
                GpuError::RequestDevice {
                    reason: e.to_string(),
                }
            })?;
        Ok(Self {
            adapter: Some(adapter),
            device,
            queue,
        })
    }

    /// A context on your renderer's own device and queue, so the host types of this crate
    /// (tables, texels, kernels) run beside your pipelines and share their buffers. wgpu
    /// handles are reference-counted: pass clones. The kernels need no feature and no limit
    /// beyond WebGPU's defaults.
    ///
    /// Use the `wgpu` this crate re-exports ([`crate::wgpu`]), or the same version, so the
    /// types match.
    ///
    /// # Errors
    /// [`GpuError::LimitTooLow`] when the device's limits are below what the kernels need.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue) -> Result<Self, GpuError> {
        check_limits(&device.limits())?;
        Ok(Self {
            adapter: None,
            device,
            queue,
        })
    }

    /// One context per process, created on first use and shared afterwards (creating a
    /// device costs tens of milliseconds on a software adapter). Returns the creation error
    /// on every call when there is no adapter.
    pub fn shared() -> Result<&'static GpuContext, GpuError> {
        static SHARED: OnceLock<Result<GpuContext, GpuError>> = OnceLock::new();
        SHARED
            .get_or_init(GpuContext::new)
            .as_ref()
            .map_err(Clone::clone)
    }

    /// Name, backend and device type of the adapter in use (e.g. "llvmpipe", Vulkan, Cpu).
    #[must_use]
    pub fn adapter_info(&self) -> wgpu::AdapterInfo {
        self.device.adapter_info()
    }

    /// The adapter, `None` for a context made [`from_device`](Self::from_device).
    #[must_use]
    pub fn adapter(&self) -> Option<&wgpu::Adapter> {
        self.adapter.as_ref()
    }

    /// The device.
    #[must_use]
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue.
    #[must_use]
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// Compiles `source` (WGSL, e.g. one of the composed modules in [`crate::shaders`]) and
    /// builds a compute pipeline for `entry_point` with an automatic layout.
    ///
    /// Validation errors (naga's or the driver's) come back as [`GpuError::Shader`] instead
    /// of wgpu's default panic.
    pub fn compute_kernel(
        &self,
        source: &str,
        entry_point: &str,
    ) -> Result<ComputeKernel, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(entry_point),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry_point),
                layout: None,
                module: &module,
                entry_point: Some(entry_point),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                cache: None,
            });
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader {
                entry_point: entry_point.to_owned(),
                message: error.to_string(),
            });
        }
        let layout = pipeline.get_bind_group_layout(0);
        Ok(ComputeKernel {
            pipeline,
            layout,
            entry_point: entry_point.to_owned(),
        })
    }

    /// A storage buffer holding `data` as is (its bytes), readable and writable by shaders
    /// and copyable for read-back. Empty slices get one zeroed element (wgpu forbids
    /// zero-sized bindings).
    pub fn storage_buffer<T: Pod>(&self, label: &str, data: &[T]) -> GpuBuffer<T> {
        let zero = [T::zeroed()];
        let contents: &[T] = if data.is_empty() { &zero } else { data };
        let buffer = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::cast_slice(contents),
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
            });
        GpuBuffer::new(buffer, data.len())
    }

    /// A storage buffer of `len` zeroed elements.
    pub fn zeroed_buffer<T: Pod>(&self, label: &str, len: usize) -> GpuBuffer<T> {
        self.storage_buffer(label, &vec![T::zeroed(); len])
    }

    /// A uniform buffer holding `value` as is. Its WGSL twin must follow the uniform
    /// address space's layout rules (the structs in [`crate::shaders`] do).
    pub fn uniform_buffer<T: Pod>(&self, label: &str, value: &T) -> GpuBuffer<T> {
        let buffer = self
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        GpuBuffer::new(buffer, 1)
    }

    /// The workgroup grid `(x, y)` of a 2D dispatch of `invocations` (at least one workgroup)
    /// in workgroups of `group_size` invocations: `x` up to the device's
    /// `max_compute_workgroups_per_dimension`, `y` the rows of `x` workgroups needed for the
    /// rest. A kernel dispatched over it recovers its flat index as
    /// `id.x + id.y · x · group_size` (`mcg_invocation_index` of the prelude for
    /// [`WORKGROUP_SIZE`]) and skips indices ≥ its element count. `y` can exceed the limit
    /// only beyond `max² · group_size` invocations ([`dispatch`](Self::dispatch) reports that
    /// as [`GpuError::TooManyInvocations`]).
    #[must_use]
    pub fn workgroup_grid(&self, invocations: u32, group_size: u32) -> (u32, u32) {
        let max = self.device.limits().max_compute_workgroups_per_dimension;
        let groups = invocations.div_ceil(group_size.max(1)).max(1);
        let x = groups.min(max);
        (x, groups.div_ceil(x))
    }

    /// Runs `kernel` for `invocations` invocations with `buffers[i]` bound at
    /// `@group(0) @binding(i)`, and waits for it to finish.
    ///
    /// The grid is `(x, y, 1)` workgroups of [`WORKGROUP_SIZE`] invocations with
    /// `x ≤ 65 535`; kernels recover their flat index with `mcg_invocation_index` of the
    /// prelude and must skip indices ≥ their element count (the last workgroup is partial).
    pub fn dispatch(
        &self,
        kernel: &ComputeKernel,
        buffers: &[&wgpu::Buffer],
        invocations: u32,
    ) -> Result<(), GpuError> {
        let max = self.device.limits().max_compute_workgroups_per_dimension;
        let (x, y) = self.workgroup_grid(invocations, WORKGROUP_SIZE);
        if y > max {
            return Err(GpuError::TooManyInvocations {
                requested: u64::from(invocations),
                maximum: u64::from(max) * u64::from(max) * u64::from(WORKGROUP_SIZE),
            });
        }
        let entries: Vec<wgpu::BindGroupEntry<'_>> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&kernel.entry_point),
            layout: &kernel.layout,
            entries: &entries,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(&kernel.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            if invocations > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        }
        self.queue.submit([encoder.finish()]);
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader {
                entry_point: kernel.entry_point.clone(),
                message: error.to_string(),
            });
        }
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Map {
                reason: e.to_string(),
            })?;
        Ok(())
    }

    /// Copies `buffer` back to the host.
    pub fn read_back<T: Pod>(&self, buffer: &GpuBuffer<T>) -> Result<Vec<T>, GpuError> {
        let bytes = (buffer.len().max(1) * size_of::<T>()) as u64;
        let size = bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mcg read-back"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        encoder.copy_buffer_to_buffer(buffer.raw(), 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Map {
                reason: e.to_string(),
            })?;
        receiver
            .recv()
            .map_err(|e| GpuError::Map {
                reason: e.to_string(),
            })?
            .map_err(|e| GpuError::Map {
                reason: e.to_string(),
            })?;
        let view = slice.get_mapped_range().map_err(|e| GpuError::Map {
            reason: e.to_string(),
        })?;
        let out = bytemuck::pod_collect_to_vec::<u8, T>(&view[..bytes as usize]);
        drop(view);
        staging.unmap();
        Ok(out[..buffer.len()].to_vec())
    }

    /// Overwrites `buffer` with `data`.
    ///
    /// # Errors
    /// [`GpuError::LengthMismatch`] unless `data` has the buffer's length.
    pub fn write<T: Pod>(&self, buffer: &GpuBuffer<T>, data: &[T]) -> Result<(), GpuError> {
        GpuError::check_len(buffer.len(), data.len())?;
        self.queue
            .write_buffer(buffer.raw(), 0, bytemuck::cast_slice(data));
        Ok(())
    }
}
