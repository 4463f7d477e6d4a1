//! Typed GPU buffers.

use core::marker::PhantomData;

use bytemuck::Pod;

/// A wgpu buffer holding `len` elements of the `Pod` type `T`, laid out exactly as in host
/// memory (so the CPU crates' arrays upload as they are).
///
/// Created by [`GpuContext::storage_buffer`](crate::GpuContext::storage_buffer),
/// [`zeroed_buffer`](crate::GpuContext::zeroed_buffer) and
/// [`uniform_buffer`](crate::GpuContext::uniform_buffer); read back with
/// [`GpuContext::read_back`](crate::GpuContext::read_back).
#[derive(Debug)]
pub struct GpuBuffer<T> {
    buffer: wgpu::Buffer,
    len: usize,
    _element: PhantomData<T>,
}

impl<T: Pod> GpuBuffer<T> {
    pub(crate) fn new(buffer: wgpu::Buffer, len: usize) -> Self {
        Self {
            buffer,
            len,
            _element: PhantomData,
        }
    }

    /// Number of elements.
    #[must_use]
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when the buffer holds no element (it still has one zeroed element on the GPU,
    /// as wgpu forbids empty bindings).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The wgpu buffer, to bind in your own pipelines.
    #[must_use]
    pub fn raw(&self) -> &wgpu::Buffer {
        &self.buffer
    }
}
