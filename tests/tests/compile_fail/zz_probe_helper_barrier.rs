use cohort::prelude::*;

#[kernel_fn]
pub fn sync_and_read(tile: &[u32], i: u32) -> u32 {
    workgroup_barrier();
    tile[i as usize]
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, input: &[u32], out: &mut [u32]) {
    if li < 32 {
        out[li as usize] = sync_and_read(input, li);
    }
}

fn main() {}
