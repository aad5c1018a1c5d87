//! Stream compaction (PAPER.md §3 kernel 2): a stable partition of `idrays` with the
//! extended rays (flag 1) first and the regenerated ones (flag 0) after them, built on a
//! scan: per-workgroup counts, one workgroup scanning the counts, then a scatter that
//! ranks each ray inside its workgroup. Correct for any size; `count[0]` is the number of
//! rays and `total[0]` receives the number of extended ones.

use cohort::prelude::*;

pub const BLOCK: u32 = 256;

/// Inclusive scan of `tile` (256 entries) in workgroup memory (Hillis–Steele); every
/// invocation must call it.
#[kernel_fn]
pub fn block_scan(li: u32, v: u32, tile: &mut [u32; 256]) -> u32 {
    tile[li as usize] = v;
    workgroup_barrier();
    let mut acc = v;
    for k in 0..8u32 {
        let off = 1u32 << k;
        let mut add = 0u32;
        if li >= off {
            add = tile[(li - off) as usize];
        }
        workgroup_barrier();
        acc += add;
        tile[li as usize] = acc;
        workgroup_barrier();
    }
    acc
}

#[kernel(workgroup = 256)]
pub fn compact_count(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[workgroup] tile: &mut [u32; 256],
    count: &[u32],
    flags: &[u32],
    block_sums: &mut [u32],
) {
    let mut v = 0u32;
    if gi < count[0] {
        v = flags[gi as usize];
    }
    tile[li as usize] = v;
    workgroup_barrier();
    for k in 0..8u32 {
        let half = 128u32 >> k;
        if li < half {
            tile[li as usize] = tile[li as usize] + tile[(li + half) as usize];
        }
        workgroup_barrier();
    }
    if li == 0 {
        block_sums[wg as usize] = tile[0];
    }
}

/// One workgroup turns the block counts into exclusive block offsets.
#[kernel(workgroup = 256)]
pub fn compact_offsets(
    #[builtin(local_index)] li: u32,
    #[workgroup] tile: &mut [u32; 256],
    count: &[u32],
    block_sums: &mut [u32],
    total: &mut [u32],
) {
    let blocks = (count[0] + 255) / 256;
    let per = (blocks + 255) / 256;
    let start = li * per;
    let mut sum = 0u32;
    for b in start..start + per {
        if b < blocks {
            sum += block_sums[b as usize];
        }
    }
    let incl = block_scan(li, sum, tile);
    let mut run = incl - sum;
    for b in start..start + per {
        if b < blocks {
            let s = block_sums[b as usize];
            block_sums[b as usize] = run;
            run += s;
        }
    }
    if li == 255 {
        total[0] = incl;
    }
}

#[kernel(workgroup = 256)]
pub fn compact_scatter(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[workgroup] tile: &mut [u32; 256],
    count: &[u32],
    flags: &[u32],
    block_offsets: &[u32],
    total: &[u32],
    idrays: &[u32],
    out: &mut [u32],
) {
    let n = count[0];
    let mut v = 0u32;
    if gi < n {
        v = flags[gi as usize];
    }
    let incl = block_scan(li, v, tile);
    if gi < n {
        let before = block_offsets[wg as usize] + incl - v;
        let mut dst = before;
        if v == 0 {
            dst = total[0] + gi - before;
        }
        out[dst as usize] = idrays[gi as usize];
    }
}
