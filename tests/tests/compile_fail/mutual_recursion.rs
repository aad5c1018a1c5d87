// Two helpers that call each other: refused at compile time through the constant that
// carries uniformity along the call graph (docs/LANGUAGE.md, section 10).
use cohort::prelude::*;

#[kernel_fn]
pub fn even(n: u32) -> u32 {
    if n == 0 {
        1
    } else {
        odd(n - 1)
    }
}

#[kernel_fn]
pub fn odd(n: u32) -> u32 {
    if n == 0 {
        0
    } else {
        even(n - 1)
    }
}

fn main() {}
