//! Typed device buffers as the user sees them, and the type-erased `BufferArg` that kernel
//! calls pass to `Device::dispatch`. A `GpuBuffer<T>` wraps a backend buffer (`RawBuffer`,
//! type-erased: `backend.rs`);
//! the backends read the raw handle back out of a `BufferArg` when they bind it.
//!
//! There is one buffer type for every use (storage, uniform, indirect, copies), so the size
//! rules for all of them are applied once here: `alloc_size` for the allocation,
//! `storage_binding_size` / `uniform_binding_size` for what a descriptor covers.

use std::marker::PhantomData;

pub(crate) use crate::backend::RawBuffer;

/// The smallest allocation: zero-length buffers still need a real handle to bind, and 16 is
/// the uniform-buffer granule, so every allocation can be bound as either kind.
pub(crate) const MIN_ALLOC: u64 = 16;

pub(crate) fn round_up(x: u64, to: u64) -> u64 {
    x.div_ceil(to) * to
}

/// Bytes allocated for a buffer of `bytes` logical bytes.
pub(crate) fn alloc_size(bytes: u64) -> u64 {
    round_up(bytes.max(MIN_ALLOC), 16)
}

/// Bytes covered by a storage binding. Exact where possible so that WGSL `arrayLength`
/// reports the logical length; an empty buffer binds the minimum allocation.
pub(crate) fn storage_binding_size(bytes: u64) -> u64 {
    if bytes == 0 {
        MIN_ALLOC
    } else {
        round_up(bytes, 4)
    }
}

/// Bytes covered by a uniform binding: uniform blocks are sized in 16-byte granules.
pub(crate) fn uniform_binding_size(bytes: u64) -> u64 {
    alloc_size(bytes)
}

/// A typed buffer in device memory, `len` elements of `T`. Dropping it frees the memory
/// (once no recorded batch still refers to it).
pub struct GpuBuffer<T> {
    pub(crate) raw: RawBuffer,
    len: usize,
    _elem: PhantomData<fn() -> T>,
}

impl<T: bytemuck::Pod> GpuBuffer<T> {
    pub(crate) fn new(raw: RawBuffer, len: usize) -> Self {
        GpuBuffer {
            raw,
            len,
            _elem: PhantomData,
        }
    }
}

impl<T> GpuBuffer<T> {
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Logical size (`len * size_of::<T>()`), not the padded allocation.
    pub fn size_bytes(&self) -> u64 {
        (self.len * std::mem::size_of::<T>()) as u64
    }

    pub fn arg(&self) -> BufferArg<'_> {
        BufferArg {
            raw: &self.raw,
            size_bytes: self.size_bytes(),
        }
    }
}

impl<T> std::fmt::Debug for GpuBuffer<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuBuffer")
            .field("elem", &std::any::type_name::<T>())
            .field("len", &self.len)
            .finish()
    }
}

/// A type-erased reference to a buffer, as bound to one kernel parameter.
#[derive(Clone, Copy)]
pub struct BufferArg<'a> {
    pub(crate) raw: &'a RawBuffer,
    pub(crate) size_bytes: u64,
}

impl BufferArg<'_> {
    pub fn size_bytes(&self) -> u64 {
        self.size_bytes
    }
}
