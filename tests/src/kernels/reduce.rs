//! Workgroup reduction: workgroup memory, barriers in uniform control flow, a tree
//! reduction loop whose bounds are uniform, and a `for` loop over a uniform range with a
//! barrier in its body (the total is broadcast to every slot by doubling).
use cohort::prelude::*;

#[kernel(workgroup = 256)]
pub fn reduce_sum(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[workgroup] tile: &mut [u32; 256],
    input: &[u32],
    sums: &mut [u32],
) {
    let i = gi as usize;
    let mut v = 0u32;
    if i < input.len() {
        v = input[i];
    }
    tile[li as usize] = v;
    workgroup_barrier();
    let mut stride = 128u32;
    while stride > 0 {
        if li < stride {
            tile[li as usize] = tile[li as usize] + tile[(li + stride) as usize];
        }
        workgroup_barrier();
        stride /= 2;
    }
    // Broadcast: after step `s` the first `2 << s` slots hold the total.
    for s in 0..8u32 {
        let w = 1u32 << s;
        if li >= w && li < 2 * w {
            tile[li as usize] = tile[(li - w) as usize];
        }
        workgroup_barrier();
    }
    if li == 255 {
        sums[wg as usize] = tile[255];
    }
}
