//! Material queues: the second design of shading specialised on the scene, as pbrt-v4's
//! wavefront integrator organises it (one shading kernel per material type present, each
//! over the queue of the hits of its type). After the traversal, a stable partition of the
//! live rays by *queue* (the BSDF kind of the material hit, or one queue for blends; misses
//! and done slots go to queue 0), then one `extend` per queue, specialised on that queue's
//! kind alone and dispatched indirectly over the queue (sizes never read back by the host).
//!
//! Three dispatches ([`DISPATCHES`]), over blocks of [`WG`] rays:
//! 1. [`queue_count`]: each ray's queue (`keys`) and each block's count per queue
//!    (`hist[q * blocks + b]`, queue-major, so that one scan gives every queue's start).
//! 2. [`queue_offsets`] (one workgroup): the counts' exclusive prefix sums in place; each
//!    queue's size and start (`queued[4 q ..]`) and its indirect dispatch (`args[3 q ..]`).
//! 3. [`queue_scatter`]: each ray to `start of its block's run + rays of its queue before
//!    it in the block`: a stable partition, so that the queues and the groups of coherent
//!    sampling that `extend` forms over them do not depend on scheduling.
//!
//! On the CPU backend each of the three runs as one loop per dispatch that writes the
//! same words (`whole`), instead of as coroutines switching at every barrier.
//!
//! The queues (`out`, twice the slots) hold each ray's slot, then at `n +` the same place
//! its position in the live list, where `extend` writes its compaction flag.

use crate::layout::{Material, Triangle, DONE, MISS};
use cohort::prelude::*;

mod whole;

/// Invocations per workgroup, and rays per block, of the three kernels.
pub const WG: u32 = 256;
/// Queues at most: one per BSDF kind (kinds are below 16, `crate::shading`) and blends.
pub const MAX_QUEUES: u32 = 17;
/// The queue of blend materials in the table (the kinds' queues come first).
pub const BLEND_ENTRY: usize = 16;
/// Table entries: the queue of each kind and of blends, then the number of queues, the
/// workgroup size of the `extend` the queues feed and the device's most workgroups in x.
pub const TABLE_LEN: usize = 20;
/// Dispatches that [`record`] adds to a batch.
pub const DISPATCHES: usize = 3;

/// Blocks of [`WG`] rays for `n` rays.
#[kernel_fn]
pub fn queue_blocks(n: u32) -> u32 {
    n / WG + (n % WG != 0) as u32
}

/// The queue of the ray in slot `r`: that of its material's kind, or of blends; queue 0 for
/// a miss or a done slot.
#[kernel_fn]
pub fn queue_of(
    r: usize,
    state: &[UVec4],
    hits: &[Vec4],
    tris: &[Triangle],
    materials: &[Material],
    table: &[u32],
) -> u32 {
    let mut q = 0u32;
    let tri = hits[r].w.to_bits();
    if state[r].w & DONE == 0 && tri != MISS {
        let m = materials[tris[tri as usize].material as usize];
        if m.blend != 0 {
            q = table[BLEND_ENTRY];
        } else {
            q = table[m.kind as usize];
        }
    }
    q
}

/// Per block: each listed ray's queue, and the block's count of each queue.
#[kernel(workgroup = 256, loops = finite, cpu_dispatch = crate::queues::whole::queue_count_whole)]
#[allow(clippy::too_many_arguments)]
pub fn queue_count(
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[workgroup] wkeys: &mut [u32; 256],
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    hits: &[Vec4],
    tris: &[Triangle],
    materials: &[Material],
    table: &[u32],
    keys: &mut [u32],
    hist: &mut [u32],
) {
    let n = count[0];
    let blocks = queue_blocks(n);
    let g = wg * WG + li;
    // Past the end: a key no queue has.
    let mut key = MAX_QUEUES;
    if g < n {
        let r = idrays[g as usize] as usize;
        key = queue_of(r, state, hits, tris, materials, table);
        keys[g as usize] = key;
    }
    wkeys[li as usize] = key;
    workgroup_barrier();
    let queues = table[BLEND_ENTRY + 1];
    if li < queues && wg < blocks {
        let mut c = 0u32;
        for j in 0..WG {
            c += (wkeys[j as usize] == li) as u32;
        }
        hist[(li * blocks + wg) as usize] = c;
    }
}

/// One workgroup: the block counts' exclusive prefix sums, queue-major, in place; each
/// queue's size, start and list length (`queued[4 q ..]`), and its indirect dispatch.
#[kernel(workgroup = 256, loops = finite, cpu_dispatch = crate::queues::whole::queue_offsets_whole)]
pub fn queue_offsets(
    #[builtin(local_index)] li: u32,
    #[workgroup] part: &mut [u32; 256],
    #[workgroup] starts: &mut [u32; 256],
    count: &[u32],
    table: &[u32],
    hist: &mut [u32],
    queued: &mut [u32],
    args: &mut [u32],
) {
    let n = count[0];
    let blocks = queue_blocks(n);
    let queues = table[BLEND_ENTRY + 1];
    let entries = queues * blocks;
    let per = entries / WG + (entries % WG != 0) as u32;
    let mut sum = 0u32;
    for j in 0..per {
        let k = li * per + j;
        if k < entries {
            sum += hist[k as usize];
        }
    }
    part[li as usize] = sum;
    starts[li as usize] = 0;
    workgroup_barrier();
    let mut step = 1u32;
    while step < WG {
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
        let k = li * per + j;
        if k < entries {
            let c = hist[k as usize];
            hist[k as usize] = run;
            // The first block of a queue: where the queue starts.
            if k % blocks == 0 {
                starts[(k / blocks) as usize] = run;
            }
            run += c;
        }
    }
    workgroup_barrier();
    if li < queues {
        let total = part[(WG - 1) as usize];
        let start = starts[li as usize];
        let mut end = total;
        if li + 1 < queues {
            end = starts[(li + 1) as usize];
        }
        let size = end - start;
        let q = li as usize;
        queued[4 * q] = size;
        queued[4 * q + 1] = start;
        queued[4 * q + 2] = n;
        queued[4 * q + 3] = 0;
        // Workgroups of the `extend` that reads the queue, folded into y past the
        // device's limit in x, as `Grid::Threads` folds them.
        let wgs = table[BLEND_ENTRY + 2];
        let max_x = table[BLEND_ENTRY + 3];
        let groups = size / wgs + (size % wgs != 0) as u32;
        let x = groups.min(max_x);
        let mut y = 1u32;
        if x > 0 {
            y = groups / x + (groups % x != 0) as u32;
        }
        args[3 * q] = x;
        args[3 * q + 1] = y;
        args[3 * q + 2] = 1;
    }
}

/// Per block: each listed ray to its place in its queue (stable), its slot at `out[at]`
/// and its position in the live list at `out[n + at]`.
#[kernel(workgroup = 256, loops = finite, cpu_dispatch = crate::queues::whole::queue_scatter_whole)]
pub fn queue_scatter(
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[workgroup] wkeys: &mut [u32; 256],
    count: &[u32],
    idrays: &[u32],
    keys: &[u32],
    hist: &[u32],
    out: &mut [u32],
) {
    let n = count[0];
    let blocks = queue_blocks(n);
    let g = wg * WG + li;
    let mut key = MAX_QUEUES;
    if g < n {
        key = keys[g as usize];
    }
    wkeys[li as usize] = key;
    workgroup_barrier();
    if g < n {
        let mut before = 0u32;
        for j in 0..li {
            before += (wkeys[j as usize] == key) as u32;
        }
        let at = hist[(key * blocks + wg) as usize] + before;
        out[at as usize] = idrays[g as usize];
        out[(n + at) as usize] = g;
    }
}

/// The three kernels' specialisations for a device.
pub struct Specs {
    pub count: cohort::Spec,
    pub offsets: cohort::Spec,
    pub scatter: cohort::Spec,
}

pub fn specs(device: &cohort::runtime::Device) -> Specs {
    Specs {
        count: queue_count::spec(device, None),
        offsets: queue_offsets::spec(device, None),
        scatter: queue_scatter::spec(device, None),
    }
}

/// The three kernels' compiled artifacts (to prepare their pipelines ahead of use).
pub fn artifacts(
    specs: &Specs,
) -> Result<Vec<std::sync::Arc<cohort::runtime::KernelArtifact>>, cohort::emit::CompileError> {
    Ok(vec![
        queue_count::artifact(&specs.count)?,
        queue_offsets::artifact(&specs.offsets)?,
        queue_scatter::artifact(&specs.scatter)?,
    ])
}

/// Length of the `hist` buffer for `slots` rays.
pub fn hist_len(slots: u32) -> usize {
    (MAX_QUEUES * slots.div_ceil(WG)).max(1) as usize
}

/// Where the queues are built: `table` ([`TABLE_LEN`]), `keys` (slots), `hist`
/// ([`hist_len`]), `queued` (4 per queue), `args` (3 per queue) and `out` (twice the
/// slots).
pub struct QueueBuffers<'a> {
    pub table: &'a cohort::runtime::GpuBuffer<u32>,
    pub keys: &'a cohort::runtime::GpuBuffer<u32>,
    pub hist: &'a cohort::runtime::GpuBuffer<u32>,
    pub queued: &'a cohort::runtime::GpuBuffer<u32>,
    pub args: &'a cohort::runtime::GpuBuffer<u32>,
    pub out: &'a cohort::runtime::GpuBuffer<u32>,
}

/// Records the partition of the `count[0] <= n` rays listed in `idrays` into queues:
/// [`DISPATCHES`] dispatches, in order.
#[allow(clippy::too_many_arguments)]
pub fn record(
    batch: &mut cohort::runtime::Batch<'_>,
    specs: &Specs,
    n: u32,
    count: &cohort::runtime::GpuBuffer<u32>,
    idrays: &cohort::runtime::GpuBuffer<u32>,
    state: &cohort::runtime::GpuBuffer<UVec4>,
    hits: &cohort::runtime::GpuBuffer<Vec4>,
    tris: &cohort::runtime::GpuBuffer<Triangle>,
    materials: &cohort::runtime::GpuBuffer<Material>,
    buf: &QueueBuffers<'_>,
) -> cohort::Result<()> {
    let threads = n.div_ceil(WG) * WG;
    queue_count::record(
        batch,
        &specs.count,
        threads,
        count,
        idrays,
        state,
        hits,
        tris,
        materials,
        buf.table,
        buf.keys,
        buf.hist,
    )?;
    queue_offsets::record(
        batch,
        &specs.offsets,
        cohort::Grid::Groups([1, 1, 1]),
        count,
        buf.table,
        buf.hist,
        buf.queued,
        buf.args,
    )?;
    queue_scatter::record(
        batch,
        &specs.scatter,
        threads,
        count,
        idrays,
        buf.keys,
        buf.hist,
        buf.out,
    )
}
