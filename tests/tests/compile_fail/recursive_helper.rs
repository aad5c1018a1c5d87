// A helper that calls itself: GPUs have no call stack.
use cohort::prelude::*;

#[kernel_fn]
pub fn factorial(n: u32) -> u32 {
    if n <= 1 {
        1
    } else {
        n * factorial(n - 1)
    }
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] i: u32, out: &mut [u32]) {
    out[i as usize] = factorial(i);
}

fn main() {}
