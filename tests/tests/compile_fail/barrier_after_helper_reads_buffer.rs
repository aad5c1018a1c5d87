use cohort::prelude::*;

#[kernel_fn]
pub fn first(buf: &[u32]) -> u32 {
    buf[0]
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, #[workgroup] tile: &mut [u32; 64], input: &[u32], out: &mut [u32]) {
    tile[li as usize] = li;
    let n = first(input);
    if n > 0 {
        workgroup_barrier();
    }
    out[li as usize] = tile[(63 - li) as usize];
}

fn main() {}
