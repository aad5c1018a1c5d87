//! Initialisation of new device-local buffers, deferred to the next submission.
//!
//! A new buffer is zeroed, or filled from its staging buffer, by a copy command. As one
//! submission and one wait each, opening a scene and allocating its path state made some
//! thirty round trips to the GPU before the first iteration. Recorded instead at the start
//! of the next submission, they cost none: the queue runs them before everything that
//! submission and later ones do, and the submission's leading full barrier makes their
//! writes visible.

use std::sync::Arc;

use ash::vk;

use super::Buffer;

/// Above this much staging memory waiting for its copy, `create_buffer` submits at once,
/// so that uploading a large scene never holds all of its staging memory.
const MAX_STAGED_BYTES: u64 = 256 << 20;

/// Fills and copies not yet recorded. Dropped only once the submission that recorded them
/// is done (the staging buffers and destinations live until then).
#[derive(Default)]
pub(super) struct Pending {
    /// Buffers to zero.
    fills: Vec<Arc<Buffer>>,
    /// (staging, destination, bytes).
    copies: Vec<(Buffer, Arc<Buffer>, u64)>,
    staged_bytes: u64,
}

impl Pending {
    pub(super) fn zero(&mut self, buffer: Arc<Buffer>) {
        self.fills.push(buffer);
    }

    /// Queues the copy of `bytes` from `staging` into `dst`; true when so much staging
    /// memory waits that the caller should submit now.
    pub(super) fn copy(&mut self, staging: Buffer, dst: Arc<Buffer>, bytes: u64) -> bool {
        self.staged_bytes += bytes;
        self.copies.push((staging, dst, bytes));
        self.staged_bytes > MAX_STAGED_BYTES
    }

    pub(super) fn is_empty(&self) -> bool {
        self.fills.is_empty() && self.copies.is_empty()
    }

    /// Records every fill and copy into `cb`. `self` must outlive the submission of `cb`.
    ///
    /// # Safety
    /// `cb` is recording, and belongs to `device`.
    pub(super) unsafe fn record(&self, device: &ash::Device, cb: vk::CommandBuffer) {
        for b in &self.fills {
            unsafe { device.cmd_fill_buffer(cb, b.raw, 0, vk::WHOLE_SIZE, 0) };
        }
        for (staging, dst, bytes) in &self.copies {
            let region = vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: *bytes,
            };
            unsafe { device.cmd_copy_buffer(cb, staging.raw, dst.raw, &[region]) };
        }
    }
}
