// A kernel generic over a constant.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k<const N: u32>(#[builtin(global_index)] i: u32, out: &mut [u32]) {
    out[i as usize] = N;
}

fn main() {}
