// A 64-bit integer in a kernel.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] i: u32, out: &mut [u32]) {
    let wide = i as u64 * 3;
    out[i as usize] = wide as u32;
}

fn main() {}
