//! Stream compaction (the paper's §3, kernel 2): a stable partition of `idrays` with the
//! extended rays (flag 1) first and the regenerated ones (flag 0) after them, both in
//! their original order. `count[0]` is the number of rays and `total[0]` receives the
//! number of extended ones. Correct for any size and any subgroup width.
//!
//! Three dispatches over blocks of [`BLOCK`] = 8192 rays; in a block, ray `j * 256 + c`
//! (row `j` < 32, column `c` < 256) is handled by invocation `c`, so every load and
//! store of a row is coalesced:
//! 1. `compact_count`: invocation `c` reads its 32 flags and packs them into one
//!    *column word* (bit `j` = flag of ray `j * 256 + c`), written to
//!    `scratch[b * 256 + c]`; the block's count (a subgroup sum, then one pass over the
//!    subgroups' sums) goes to `scratch[blocks * 256 + b]`. No workgroup arrays besides
//!    one 256-entry array of subgroup sums.
//! 2. `compact_offsets` (one workgroup) turns the block counts into exclusive block
//!    offsets in place and writes `total[0]`.
//! 3. `compact_scatter`: loads the block's 256 column words (1 KB) into workgroup
//!    memory, transposes them into *row words* (bit `b` of row word `w` = flag of ray
//!    `32 w + b`, in ray order), scans the row words' popcounts, and moves each ray id to
//!    `offset + ones before it` (flag 1) or `total + zeros before it` (flag 0), where
//!    the ones before a ray inside its row word are a popcount of the bits below it.
//!
//! On the CPU backend each of the three runs as one loop per dispatch that writes the
//! same words (`whole`), instead of as coroutines switching at every barrier.
//!
//! Traffic per ray: 4 B of flags and 4 B of ids read, 4 B written (the minimum, 12 B),
//! plus 1 bit written and read back. The kernels have 1, 2 and 3 workgroup barriers.
//!
//! Subgroups: scans use subgroup operations, but nothing assumes how subgroups map onto
//! `local_index`, that subgroups are full, or how wide they are (Vulkan promises none of
//! it). Where a scan needs an order, an invocation's *slot* is `(active invocations of
//! lower subgroup ids) + (active lanes before it in its subgroup)`, both from subgroup
//! sums and one pass over a workgroup array of per-subgroup values; slots are a bijection
//! onto 0..256 in which each subgroup holds a contiguous run in lane order — exactly the
//! order of subgroup scans. Subgroup operations are only reached in uniform control flow
//! (after `if`s have merged, after loops whose trip count is the same for every
//! invocation). Where no order is needed (flag and id loads, the scatter), `local_index`
//! is used directly.

use cohort::prelude::*;

mod whole;

/// Invocations per workgroup of every compaction kernel.
pub const WG: u32 = 256;
/// Rays per invocation in `compact_count` and `compact_scatter` (one bit each of a word).
pub const PER_THREAD: u32 = 32;
/// Rays per block (one workgroup of `compact_count` / `compact_scatter`).
pub const BLOCK: u32 = WG * PER_THREAD;
/// Bit words per block (one column word per invocation).
pub const WORDS: u32 = BLOCK / 32;
/// Dispatches that [`record`] adds to a batch.
pub const DISPATCHES: usize = 3;

const _: () = assert!(WORDS == WG && PER_THREAD == 32 && WG.is_multiple_of(32));

/// Blocks for `n` rays (no overflow near `u32::MAX`).
#[kernel_fn]
pub fn block_count(n: u32) -> u32 {
    n / BLOCK + (n % BLOCK != 0) as u32
}

/// Sum of `part[s]` over the subgroups `s < sg` (a loop over the uniform range
/// `0..nsg` with a branch-free body, so control stays uniform).
#[kernel_fn]
pub fn sum_before(sg: u32, nsg: u32, part: &mut [u32; 256]) -> u32 {
    let mut acc = 0u32;
    for s in 0..nsg {
        acc += part[s as usize] * (s < sg) as u32;
    }
    acc
}

/// Sum of `part[s]` over all subgroups.
#[kernel_fn]
pub fn sum_all(nsg: u32, part: &mut [u32; 256]) -> u32 {
    let mut acc = 0u32;
    for s in 0..nsg {
        acc += part[s as usize];
    }
    acc
}

/// Per block: pack each column's 32 flags into a word and count the block's flags.
#[kernel(workgroup = 256, cpu_dispatch = crate::compact::whole::compact_count_whole)]
pub fn compact_count(
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[builtin(subgroup_id)] sg: u32,
    #[builtin(num_subgroups)] nsg: u32,
    #[workgroup] part: &mut [u32; 256],
    count: &[u32],
    flags: &[u32],
    scratch: &mut [u32],
) {
    let n = count[0];
    let blocks = block_count(n);
    let base = wg * BLOCK + li;
    let mut col = 0u32;
    // Full blocks (all but the last) load without bounds checks, so that the 32
    // independent loads are easy to issue back to back.
    if wg < n / BLOCK {
        for j in 0..PER_THREAD {
            col |= ((flags[(base + j * WG) as usize] != 0) as u32) << j;
        }
    } else {
        for j in 0..PER_THREAD {
            let g = base + j * WG;
            if g < n {
                col |= ((flags[g as usize] != 0) as u32) << j;
            }
        }
    }
    let sum = subgroup_add(col.count_ones());
    let rank = subgroup_exclusive_add(1u32);
    if rank == 0 {
        part[sg as usize] = sum;
    }
    if wg < blocks {
        scratch[(wg * WORDS + li) as usize] = col;
    }
    workgroup_barrier();
    if li == 0 {
        if wg < blocks {
            scratch[(blocks * WORDS + wg) as usize] = sum_all(nsg, part);
        }
    }
}

/// One workgroup turns the block counts into exclusive block offsets (in place) and
/// writes the total. The invocation in slot `p` handles a contiguous run of blocks.
#[kernel(workgroup = 256, cpu_dispatch = crate::compact::whole::compact_offsets_whole)]
pub fn compact_offsets(
    #[builtin(local_index)] li: u32,
    #[builtin(subgroup_id)] sg: u32,
    #[builtin(num_subgroups)] nsg: u32,
    #[workgroup] part_m: &mut [u32; 256],
    #[workgroup] part_c: &mut [u32; 256],
    count: &[u32],
    scratch: &mut [u32],
    total: &mut [u32],
) {
    // Slot of this invocation: a bijection onto 0..WG, contiguous per subgroup.
    let rank = subgroup_exclusive_add(1u32);
    let active = subgroup_add(1u32);
    if rank == 0 {
        part_m[sg as usize] = active;
    }
    let n = count[0];
    let blocks = block_count(n);
    let sums = blocks * WORDS;
    let per = blocks / WG + (blocks % WG != 0) as u32;
    workgroup_barrier();
    let p = sum_before(sg, nsg, part_m) + rank;
    let start = p * per;
    // Same trip count everywhere; clamped, masked loads keep the body branch-free
    // (`per > 0` implies `blocks > 0`).
    let mut sum = 0u32;
    for i in 0..per {
        let b = start + i;
        let v = scratch[(sums + b.min(blocks - 1)) as usize];
        sum += v * (b < blocks) as u32;
    }
    let incl = subgroup_inclusive_add(sum);
    let sg_total = subgroup_add(sum);
    if rank == 0 {
        part_c[sg as usize] = sg_total;
    }
    workgroup_barrier();
    let mut run = sum_before(sg, nsg, part_c) + incl - sum;
    for i in 0..per {
        let b = start + i;
        if b < blocks {
            let s = scratch[(sums + b) as usize];
            scratch[(sums + b) as usize] = run;
            run += s;
        }
    }
    if li == 0 {
        total[0] = sum_all(nsg, part_c);
    }
}

/// Per block: rank every ray from the packed bits and move its id to its place.
#[kernel(workgroup = 256, cpu_dispatch = crate::compact::whole::compact_scatter_whole)]
pub fn compact_scatter(
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[builtin(subgroup_id)] sg: u32,
    #[builtin(num_subgroups)] nsg: u32,
    #[workgroup] words: &mut [u32; 256],
    #[workgroup] part_m: &mut [u32; 256],
    #[workgroup] part_c: &mut [u32; 256],
    count: &[u32],
    scratch: &[u32],
    total: &[u32],
    idrays: &[u32],
    out: &mut [u32],
) {
    // Slot of this invocation (see `compact_offsets`).
    let rank = subgroup_exclusive_add(1u32);
    let active = subgroup_add(1u32);
    if rank == 0 {
        part_m[sg as usize] = active;
    }
    let n = count[0];
    let blocks = block_count(n);
    // The block's column words, its offset and the total (loaded early: their latency
    // overlaps the scan below).
    let mut col = 0u32;
    let mut offset = 0u32;
    let mut alive = 0u32;
    if wg < blocks {
        col = scratch[(wg * WORDS + li) as usize];
        offset = scratch[(blocks * WORDS + wg) as usize];
        alive = total[0];
    }
    words[li as usize] = col;
    workgroup_barrier();
    // Slot p builds row word p (rays 32p..32p+31 of the block: row p / 8, columns
    // 32 (p % 8) + b); reads are skewed by p so that consecutive slots hit distinct banks.
    let p = sum_before(sg, nsg, part_m) + rank;
    let row = p / 8;
    let c0 = (p % 8) * 32;
    let mut word = 0u32;
    for k in 0..32u32 {
        let b = (k + p) % 32;
        word |= ((words[(c0 + b) as usize] >> row) & 1) << b;
    }
    let c = word.count_ones();
    let excl = subgroup_exclusive_add(c);
    let sg_total = subgroup_add(c);
    if rank == 0 {
        part_c[sg as usize] = sg_total;
    }
    workgroup_barrier();
    // Every read of `words` (column words) and `part_m` (subgroup sizes) is done: reuse
    // them for the row words and the ones before each row word.
    let ones = sum_before(sg, nsg, part_c) + excl;
    words[p as usize] = word;
    part_m[p as usize] = ones;
    workgroup_barrier();
    if wg < blocks {
        let base = wg * BLOCK;
        if wg < n / BLOCK {
            for j in 0..PER_THREAD {
                let e = j * WG + li;
                move_ray(e, base + e, offset, alive, words, part_m, idrays, out);
            }
        } else {
            for j in 0..PER_THREAD {
                let e = j * WG + li;
                if base + e < n {
                    move_ray(e, base + e, offset, alive, words, part_m, idrays, out);
                }
            }
        }
    }
}

/// Moves ray `g` (slot `e` of its block) to its place in the partition: after the
/// `offset` (block) + `before` (row words of the block) + lower bits (own row word) ones
/// before it when its flag is 1, else after the `alive` ones and the zeros before it.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn move_ray(
    e: u32,
    g: u32,
    offset: u32,
    alive: u32,
    words: &mut [u32; 256],
    before: &mut [u32; 256],
    idrays: &[u32],
    out: &mut [u32],
) {
    let id = idrays[g as usize];
    let w = words[(e / 32) as usize];
    let bit = e % 32;
    let ones_before = offset + before[(e / 32) as usize] + (w & ((1u32 << bit) - 1)).count_ones();
    let mut dst = ones_before;
    if (w >> bit) & 1 == 0 {
        dst = alive + g - ones_before;
    }
    out[dst as usize] = id;
}

/// Scratch words the compaction of up to `n` rays needs (bits and block counts).
pub fn scratch_len(n: usize) -> usize {
    let blocks = n.div_ceil(BLOCK as usize);
    (blocks * (WORDS as usize + 1)).max(1)
}

/// The three kernels' specialisations for a device.
#[derive(Clone, Copy, Debug)]
pub struct Specs {
    pub count: cohort::Spec,
    pub offsets: cohort::Spec,
    pub scatter: cohort::Spec,
}

pub fn specs(device: &cohort::runtime::Device) -> Specs {
    Specs {
        count: compact_count::spec(device, None),
        offsets: compact_offsets::spec(device, None),
        scatter: compact_scatter::spec(device, None),
    }
}

/// The three kernels' compiled artifacts (to prepare their pipelines ahead of use).
pub fn artifacts(
    specs: &Specs,
) -> Result<Vec<std::sync::Arc<cohort::runtime::KernelArtifact>>, cohort::emit::CompileError> {
    Ok(vec![
        compact_count::artifact(&specs.count)?,
        compact_offsets::artifact(&specs.offsets)?,
        compact_scatter::artifact(&specs.scatter)?,
    ])
}

/// Records the compaction of up to `n` rays (`count[0] <= n` are compacted) into
/// `batch`: [`DISPATCHES`] dispatches, in order. `scratch` needs [`scratch_len`]`(n)`
/// elements; `out` receives the partition of `idrays` and `total[0]` the number of
/// flag-1 rays.
#[allow(clippy::too_many_arguments)]
pub fn record(
    batch: &mut cohort::runtime::Batch<'_>,
    specs: &Specs,
    n: u32,
    count: &cohort::runtime::GpuBuffer<u32>,
    flags: &cohort::runtime::GpuBuffer<u32>,
    scratch: &cohort::runtime::GpuBuffer<u32>,
    total: &cohort::runtime::GpuBuffer<u32>,
    idrays: &cohort::runtime::GpuBuffer<u32>,
    out: &cohort::runtime::GpuBuffer<u32>,
) -> cohort::Result<()> {
    let threads = n.div_ceil(BLOCK) * WG;
    compact_count::record(batch, &specs.count, threads, count, flags, scratch)?;
    compact_offsets::record(
        batch,
        &specs.offsets,
        cohort::Grid::Groups([1, 1, 1]),
        count,
        scratch,
        total,
    )?;
    compact_scatter::record(
        batch,
        &specs.scatter,
        threads,
        count,
        scratch,
        total,
        idrays,
        out,
    )?;
    Ok(())
}
