use cohort::prelude::*;

#[kernel_fn]
pub fn pick(seed: u32) -> u32 {
    group_share(|group| seed ^ group)
}

fn main() {}
