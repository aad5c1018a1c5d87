// Heap allocation in a kernel.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] i: u32, out: &mut [u32]) {
    let mut v = Vec::new();
    v.push(i);
    out[i as usize] = v[0];
}

fn main() {}
