//! How many ray slots a render keeps in flight. One slot per pixel starves a GPU at small
//! image sizes (16,384 slots at 128x128, where an H100 wants on the order of a million
//! paths at once), so the wavefront holds whole copies of the image: `copies` slots per
//! pixel, each tracing every `copies`-th path of its pixel (`Frame::copies`). Each slot
//! accumulates its own paths; the image sums a pixel's slots in copy order, so the result
//! does not depend on scheduling, and the n-th path of a pixel draws from (seed, pixel, n)
//! whatever the number of copies.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::layout::Frame;

use crate::RenderOptions;

/// The most slots (and pixels) a renderer takes: slot indices and buffer sizes stay
/// within what every backend binds.
pub const MAX_SLOTS: u64 = 1 << 26;

/// Slots that fill `device`: a GPU runs about a million paths at once before its time per
/// iteration grows with the count (BENCHMARKS.md, "Every image size fills the GPU"); the
/// CPU backend and software drivers run a few workgroups per core, and more slots there
/// only cost memory.
pub fn auto_slots(device: &Device) -> u64 {
    let info = device.info();
    if info.backend == BackendKind::Cpu || info.software_driver {
        1 << 14
    } else {
        1 << 20
    }
}

/// Copies of the image the wavefront holds for `opts` on `device`: enough slots for the
/// device (or `opts.wavefront`), never more copies than paths per pixel in the budget (a
/// copy without a path would idle) nor more slots than [`MAX_SLOTS`].
pub fn copies(device: &Device, opts: &RenderOptions, pixels: u64) -> u32 {
    let pixels = pixels.max(1);
    let target = opts.wavefront.map_or_else(|| auto_slots(device), u64::from);
    let mut k = target.div_ceil(pixels).max(1);
    let (_, paths) = opts.path_range();
    if paths > 0 {
        k = k.min(u64::from(paths));
    }
    k.min(MAX_SLOTS / pixels).max(1) as u32
}

/// Slots that start done: copies beyond the paths per pixel of the budget, where the
/// budget changed after the wavefront was sized (`Renderer::set_budget`).
pub fn idle_slots(frame: &Frame) -> u32 {
    let pixels = frame.slots / frame.copies;
    match frame.paths_per_pixel {
        0 => 0,
        p => frame.copies.saturating_sub(p) * pixels,
    }
}
