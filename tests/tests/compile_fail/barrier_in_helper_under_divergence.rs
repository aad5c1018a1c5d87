// A helper that waits at a barrier, through another helper, called by only some invocations.
use cohort::prelude::*;

#[kernel_fn]
pub fn sync() {
    workgroup_barrier();
}

#[kernel_fn]
pub fn step(x: u32) -> u32 {
    sync();
    x + 1
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, out: &mut [u32]) {
    if li < 32 {
        out[li as usize] = step(li);
    }
}

fn main() {}
