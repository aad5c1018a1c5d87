use cohort::prelude::*;

pub fn twice(x: u32) -> u32 {
    x * 2
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    out[gi as usize] = twice(gi);
}

fn main() {}
