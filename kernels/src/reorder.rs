//! Ray reordering before traversal (traversal work, item 4; Meister et al. 2020 sort secondary
//! rays to make them coherent): a counting sort of the live rays' slots by a 12-bit key,
//! the direction octant and then the Morton code of the origin's cell in an 8x8x8 grid over
//! the scene's bounds. Four dispatches ([`DISPATCHES`]): [`bin_clear`], [`bin_count`] (key
//! and histogram by atomics), [`bin_offsets`] (one workgroup's exclusive scan),
//! [`bin_scatter`], recorded in order by [`record`]. The result is a permutation of `idrays[..count]` that only the
//! traversal reads: every other kernel keeps the slot order, so the path state stays
//! coalesced, and the image is the same bit for bit (a ray's hit does not depend on the
//! invocation that traces it). Slots whose path is done go to an extra last bin, so that
//! whole warps of them finish at once.
//!
//! The order inside a bin is that of the atomics (not deterministic); nothing depends on it.

use crate::layout::DONE;
use cohort::prelude::*;

/// Bins of live rays: 3 octant bits and a 9-bit origin cell.
pub const BINS: u32 = 4096;
/// Length of the histogram buffer: the live bins and one bin of done slots.
pub const HISTOGRAM_LEN: usize = BINS as usize + 1;
/// Dispatches one sort records.
pub const DISPATCHES: usize = 4;

/// The bin of a ray from `o` along `d`: direction octant, then the Morton code of its
/// origin's cell in an 8x8x8 grid over `cells` = (lower corner, 8 / extent).
#[kernel_fn]
pub fn bin_key(o: Vec3, d: Vec3, cells: &[Vec4]) -> u32 {
    let c = ((o - cells[0].truncate()) * cells[1].truncate())
        .max(Vec3::ZERO)
        .min(Vec3::splat(7.0));
    let x = c.x as u32;
    let y = c.y as u32;
    let z = c.z as u32;
    let mut cell = 0u32;
    for b in 0..3u32 {
        cell |= (((x >> b) & 1) << (3 * b))
            | (((y >> b) & 1) << (3 * b + 1))
            | (((z >> b) & 1) << (3 * b + 2));
    }
    let oct = (d.x < 0.0) as u32 | ((d.y < 0.0) as u32) << 1 | ((d.z < 0.0) as u32) << 2;
    (oct << 9) | cell
}

/// Zeroes the histogram.
#[kernel(workgroup = 256)]
pub fn bin_clear(#[builtin(global_index)] gi: u32, bins: &mut [u32]) {
    let i = gi as usize;
    if i < bins.len() {
        bins[i] = 0;
    }
}

/// The key of every listed ray (`keys[gi]` for `idrays[gi]`, gi < `count[0]`) and the
/// histogram of keys; a done slot's key is [`BINS`].
#[kernel(workgroup = 256, loops = finite)]
pub fn bin_count(
    #[builtin(global_index)] gi: u32,
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    cells: &[Vec4],
    keys: &mut [u32],
    bins: &[AtomicU32],
) {
    if gi < count[0] {
        let s = idrays[gi as usize] as usize;
        let mut k = BINS;
        if state[s].w & DONE == 0 {
            k = bin_key(ray_o[s].truncate(), ray_d[s].truncate(), cells);
        }
        keys[gi as usize] = k;
        bins[k as usize].fetch_add(1, Ordering::Relaxed);
    }
}

/// One workgroup of 256: the histogram's exclusive prefix sums, in place (16 bins per
/// invocation, then a scan of the 256 partial sums in workgroup memory; the done bin
/// starts after all live bins).
#[kernel(workgroup = 256, loops = finite)]
pub fn bin_offsets(
    #[builtin(local_index)] li: u32,
    #[workgroup] part: &mut [u32; 256],
    bins: &mut [u32],
) {
    let per = BINS / 256;
    let mut sum = 0u32;
    for j in 0..per {
        sum += bins[(li * per + j) as usize];
    }
    part[li as usize] = sum;
    workgroup_barrier();
    let mut step = 1u32;
    while step < 256 {
        let mut v = part[li as usize];
        if li >= step {
            v += part[(li - step) as usize];
        }
        workgroup_barrier();
        part[li as usize] = v;
        workgroup_barrier();
        step *= 2;
    }
    let mut run = part[li as usize] - sum;
    for j in 0..per {
        let k = (li * per + j) as usize;
        let c = bins[k];
        bins[k] = run;
        run += c;
    }
    if li == 255 {
        bins[BINS as usize] = run;
    }
}

/// Each listed ray's slot at the next free place of its bin: `sorted[..count]` is a
/// permutation of `idrays[..count]`.
#[kernel(workgroup = 256)]
pub fn bin_scatter(
    #[builtin(global_index)] gi: u32,
    count: &[u32],
    idrays: &[u32],
    keys: &[u32],
    offsets: &[AtomicU32],
    sorted: &mut [u32],
) {
    if gi < count[0] {
        let at = offsets[keys[gi as usize] as usize].fetch_add(1, Ordering::Relaxed);
        sorted[at as usize] = idrays[gi as usize];
    }
}

/// The grid `bin_key` reads, (lower corner, 8 / extent), over the box `lo`..`hi`.
pub fn cells(lo: Vec3, hi: Vec3) -> [Vec4; 2] {
    // An empty scene's box is inverted (+inf..-inf): one cell for every ray.
    if !(lo.is_finite() && hi.is_finite()) {
        return [Vec4::ZERO, Vec4::ZERO];
    }
    [
        lo.extend(0.0),
        (8.0 / (hi - lo).max(Vec3::splat(1e-20))).extend(0.0),
    ]
}

/// The four kernels' specialisations for a device.
pub struct Specs {
    pub clear: cohort::Spec,
    pub count: cohort::Spec,
    pub offsets: cohort::Spec,
    pub scatter: cohort::Spec,
}

pub fn specs(device: &cohort::runtime::Device) -> Specs {
    Specs {
        clear: bin_clear::spec(device, None),
        count: bin_count::spec(device, None),
        offsets: bin_offsets::spec(device, None),
        scatter: bin_scatter::spec(device, None),
    }
}

/// The four kernels' compiled artifacts (to prepare their pipelines ahead of use).
pub fn artifacts(
    specs: &Specs,
) -> Result<Vec<std::sync::Arc<cohort::runtime::KernelArtifact>>, cohort::emit::CompileError> {
    Ok(vec![
        bin_clear::artifact(&specs.clear)?,
        bin_count::artifact(&specs.count)?,
        bin_offsets::artifact(&specs.offsets)?,
        bin_scatter::artifact(&specs.scatter)?,
    ])
}

/// Where a sort works: `keys` and `sorted` of `n` elements, `bins` of
/// [`HISTOGRAM_LEN`], and `cells` from [`cells`].
pub struct SortBuffers<'a> {
    pub cells: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub keys: &'a cohort::runtime::GpuBuffer<u32>,
    pub bins: &'a cohort::runtime::GpuBuffer<u32>,
    pub sorted: &'a cohort::runtime::GpuBuffer<u32>,
}

/// Records the sort of the `count[0] <= n` rays listed in `idrays` into `buf.sorted`:
/// [`DISPATCHES`] dispatches, in order.
#[allow(clippy::too_many_arguments)]
pub fn record(
    batch: &mut cohort::runtime::Batch<'_>,
    specs: &Specs,
    n: u32,
    count: &cohort::runtime::GpuBuffer<u32>,
    idrays: &cohort::runtime::GpuBuffer<u32>,
    state: &cohort::runtime::GpuBuffer<UVec4>,
    ray_o: &cohort::runtime::GpuBuffer<Vec4>,
    ray_d: &cohort::runtime::GpuBuffer<Vec4>,
    buf: &SortBuffers<'_>,
) -> cohort::Result<()> {
    bin_clear::record(batch, &specs.clear, HISTOGRAM_LEN as u32, buf.bins)?;
    bin_count::record(
        batch,
        &specs.count,
        n,
        count,
        idrays,
        state,
        ray_o,
        ray_d,
        buf.cells,
        buf.keys,
        buf.bins,
    )?;
    bin_offsets::record(batch, &specs.offsets, 256u32, buf.bins)?;
    bin_scatter::record(
        batch,
        &specs.scatter,
        n,
        count,
        idrays,
        buf.keys,
        buf.bins,
        buf.sorted,
    )
}
