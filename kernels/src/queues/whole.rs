//! The CPU backend's whole-dispatch forms of the three queue kernels
//! (`cohort::runtime::cpu::DispatchForm`): each dispatch runs as one loop on one thread,
//! writing what the kernel's invocations write, word for word.
//!
//! Why: the kernels' workgroup barriers and workgroup arrays leave them without a vector
//! form, and their host form runs each workgroup's 256 invocations as coroutines that
//! switch at every barrier, with a loop over the workgroup's keys in each invocation. A
//! stanford-like render over material queues spent 961 ms of its 1618 ms there (256x256,
//! 32 paths, 2-core Xeon), for partitions of at most 65536 rays.
//!
//! The `u32` buffers are bound as [`Words`] (`crate::words`); the scene's and the paths'
//! buffers of other types, which no queue kernel writes, as slices.

use super::{queue_blocks, queue_of, BLEND_ENTRY, MAX_QUEUES, WG};
use crate::layout::{Material, Triangle};
use crate::words::Words;
use cohort::runtime::cpu::LaneArgs;
use glam::{UVec4, Vec4};

/// Workgroups of a dispatch of `invocations` (the kernels' workgroup is [`WG`]).
fn groups(invocations: u64) -> u32 {
    crate::words::groups(invocations, WG)
}

/// The number of queues in a table (`table[BLEND_ENTRY + 1]`).
fn queue_count_of(table: &Words) -> u32 {
    table.get(BLEND_ENTRY + 1)
}

/// `queue_count`: each listed ray's queue (`keys`) and each block's count per queue
/// (`hist[q * blocks + b]`). Buffers: count, idrays, state, hits, tris, materials, table,
/// keys, hist.
#[doc(hidden)]
pub fn queue_count_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds queue_count's buffers in parameter order; state, hits,
    // tris and materials are of types no `u32` buffer of the dispatch has, and the
    // kernel writes none of them.
    let (count, idrays, state, hits, tris, materials, table, keys, hist) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "idrays"),
            a.storage::<UVec4>(2),
            a.storage::<Vec4>(3),
            a.storage::<Triangle>(4),
            a.storage::<Material>(5),
            Words::bound(a, 6, "table"),
            Words::bound(a, 7, "keys"),
            Words::bound(a, 8, "hist"),
        )
    };
    let n = count.get(0);
    let blocks = queue_blocks(n);
    // `queue_of` reads the table as a slice: a copy, since a dispatch may bind it twice.
    let table_words: [u32; super::TABLE_LEN] = std::array::from_fn(|i| table.get(i));
    let queues = queue_count_of(&table);
    let mut per_queue = [0u32; WG as usize];
    for wg in 0..groups(invocations).min(blocks) {
        per_queue.fill(0);
        let first = wg * WG;
        let last = n.min(first + WG);
        for g in first..last {
            let r = idrays.get(g as usize) as usize;
            let key = queue_of(r, state, hits, tris, materials, &table_words);
            keys.set(g as usize, key);
            if let Some(c) = per_queue.get_mut(key as usize) {
                *c += 1;
            }
        }
        // Invocations past the list hold the key MAX_QUEUES, and the kernel counts them as
        // that queue's (a table made by the renderer has fewer queues).
        per_queue[MAX_QUEUES as usize] += WG - (last - first);
        // The invocations below the table's queue count write their queue's count.
        for q in 0..queues.min(WG) {
            hist.set((q * blocks + wg) as usize, per_queue[q as usize]);
        }
    }
    true
}

/// `queue_offsets`: the block counts' exclusive prefix sums, queue-major, in place; each
/// queue's size, start and list length (`queued[4 q ..]`) and its indirect dispatch
/// (`args[3 q ..]`). Buffers: count, table, hist, queued, args.
#[doc(hidden)]
pub fn queue_offsets_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds queue_offsets' buffers in parameter order.
    let (count, table, hist, queued, args) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "table"),
            Words::bound(a, 2, "hist"),
            Words::bound(a, 3, "queued"),
            Words::bound(a, 4, "args"),
        )
    };
    if groups(invocations) == 0 {
        return true;
    }
    let n = count.get(0);
    let blocks = queue_blocks(n);
    let queues = queue_count_of(&table);
    let entries = queues.wrapping_mul(blocks);
    // Where each queue starts: the scan at its first block (0 for a queue of no blocks).
    let mut starts = [0u32; WG as usize];
    let mut run = 0u32;
    for k in 0..entries {
        let c = hist.get(k as usize);
        hist.set(k as usize, run);
        if k % blocks == 0 {
            if let Some(s) = starts.get_mut((k / blocks) as usize) {
                *s = run;
            }
        }
        run = run.wrapping_add(c);
    }
    let total = run;
    for q in 0..queues.min(WG) {
        let start = starts[q as usize];
        let end = if q + 1 < queues {
            starts.get((q + 1) as usize).copied().unwrap_or(0)
        } else {
            total
        };
        let size = end.wrapping_sub(start);
        let at = 4 * q as usize;
        queued.set(at, size);
        queued.set(at + 1, start);
        queued.set(at + 2, n);
        queued.set(at + 3, 0);
        // Workgroups of the `extend` that reads the queue, folded into y past the
        // device's limit in x, as `Grid::Threads` folds them.
        let wgs = table.get(BLEND_ENTRY + 2);
        let max_x = table.get(BLEND_ENTRY + 3);
        let groups = size.div_ceil(wgs);
        let x = groups.min(max_x);
        let y = match x {
            0 => 1,
            x => groups.div_ceil(x),
        };
        let at = 3 * q as usize;
        args.set(at, x);
        args.set(at + 1, y);
        args.set(at + 2, 1);
    }
    true
}

/// `queue_scatter`: each listed ray to its place in its queue (stable), its slot at
/// `out[at]` and its position in the live list at `out[n + at]`. Buffers: count, idrays,
/// keys, hist, out.
#[doc(hidden)]
pub fn queue_scatter_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds queue_scatter's buffers in parameter order.
    let (count, idrays, keys, hist, out) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "idrays"),
            Words::bound(a, 2, "keys"),
            Words::bound(a, 3, "hist"),
            Words::bound(a, 4, "out"),
        )
    };
    let n = count.get(0);
    let blocks = queue_blocks(n);
    // Rays of each key placed so far in the block: the kernel's count of the same key
    // before an invocation. Keys are queue indices below MAX_QUEUES; any other key is
    // counted as the kernel counts it, over the block's keys before the ray.
    let mut before = [0u32; MAX_QUEUES as usize];
    for wg in 0..groups(invocations).min(blocks) {
        before.fill(0);
        let first = wg * WG;
        for g in first..n.min(first + WG) {
            let key = keys.get(g as usize);
            let seen = match before.get_mut(key as usize) {
                Some(s) => {
                    *s += 1;
                    *s - 1
                }
                None => (first..g).filter(|&j| keys.get(j as usize) == key).count() as u32,
            };
            let at = hist
                .get(key.wrapping_mul(blocks).wrapping_add(wg) as usize)
                .wrapping_add(seen);
            out.set(at as usize, idrays.get(g as usize));
            out.set(n.wrapping_add(at) as usize, g);
        }
    }
    true
}
