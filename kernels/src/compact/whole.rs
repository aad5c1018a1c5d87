//! The CPU backend's whole-dispatch forms of the three compaction kernels
//! (`cohort::runtime::cpu::DispatchForm`): each dispatch runs as one loop on one thread,
//! writing what the kernel's invocations write, word for word.
//!
//! Why: the kernels' subgroup scans and workgroup barriers leave them without a vector
//! form, and their host form runs each workgroup's 256 invocations as coroutines that
//! switch at every barrier. A render's retirements of finished slots (`crate::retire`)
//! spent 11-12 ms of a 560 ms stanford-like render there (the first `compact_count`
//! alone 4.7 ms), for partitions of at most 65536 slots that a loop does in tens of
//! microseconds.
//!
//! Buffers are bound as [`Words`] (`crate::words`).

use super::{block_count, BLOCK, PER_THREAD, WG, WORDS};
use crate::words::Words;
use cohort::runtime::cpu::LaneArgs;

/// Workgroups of a dispatch of `invocations` (the kernels' workgroup is [`WG`]).
fn groups(invocations: u64) -> u32 {
    crate::words::groups(invocations, WG)
}

/// `compact_count`: each block's column words (bit `j` of word `c`: the flag of ray
/// `j * WG + c`) and, after all of them, its count of flags.
/// Buffers: count, flags, scratch.
#[doc(hidden)]
pub fn compact_count_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds compact_count's buffers in parameter order.
    let (count, flags, scratch) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "flags"),
            Words::bound(a, 2, "scratch"),
        )
    };
    let n = count.get(0);
    let blocks = block_count(n);
    for wg in 0..groups(invocations).min(blocks) {
        let mut sum = 0u32;
        for li in 0..WG {
            let base = wg * BLOCK + li;
            let mut col = 0u32;
            for j in 0..PER_THREAD {
                let g = base + j * WG;
                if g < n {
                    col |= u32::from(flags.get(g as usize) != 0) << j;
                }
            }
            scratch.set((wg * WORDS + li) as usize, col);
            sum += col.count_ones();
        }
        scratch.set((blocks * WORDS + wg) as usize, sum);
    }
    true
}

/// `compact_offsets`: the block counts turned into exclusive offsets in place, and the
/// total. Buffers: count, scratch, total.
#[doc(hidden)]
pub fn compact_offsets_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds compact_offsets' buffers in parameter order.
    let (count, scratch, total) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "scratch"),
            Words::bound(a, 2, "total"),
        )
    };
    if groups(invocations) == 0 {
        return true;
    }
    let blocks = block_count(count.get(0));
    let sums = (blocks * WORDS) as usize;
    let mut run = 0u32;
    for b in 0..blocks as usize {
        let s = scratch.get(sums + b);
        scratch.set(sums + b, run);
        run = run.wrapping_add(s);
    }
    total.set(0, run);
    true
}

/// `compact_scatter`: every ray's id moved to its place in the stable partition (flag 1
/// first, after the ones before it; flag 0 after all the ones and the zeros before it).
/// Buffers: count, scratch, total, idrays, out.
#[doc(hidden)]
pub fn compact_scatter_whole(a: &LaneArgs<'_>, invocations: u64) -> bool {
    // SAFETY: the backend binds compact_scatter's buffers in parameter order.
    let (count, scratch, total, idrays, out) = unsafe {
        (
            Words::bound(a, 0, "count"),
            Words::bound(a, 1, "scratch"),
            Words::bound(a, 2, "total"),
            Words::bound(a, 3, "idrays"),
            Words::bound(a, 4, "out"),
        )
    };
    let n = count.get(0);
    let blocks = block_count(n);
    let wgs = groups(invocations).min(blocks);
    if wgs == 0 {
        return true;
    }
    let alive = total.get(0);
    for wg in 0..wgs {
        let mut ones = scratch.get((blocks * WORDS + wg) as usize);
        let base = wg * BLOCK;
        // Rays in order: ray `e` of the block is bit `e / WG` of column word `e % WG`.
        for e in 0..BLOCK.min(n - base) {
            let g = base + e;
            let col = scratch.get((wg * WORDS + e % WG) as usize);
            let dst = if (col >> (e / WG)) & 1 != 0 {
                ones += 1;
                ones - 1
            } else {
                alive.wrapping_add(g).wrapping_sub(ones)
            };
            out.set(dst as usize, idrays.get(g as usize));
        }
    }
    true
}
