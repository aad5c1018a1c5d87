use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_idx)] gi: u32, out: &mut [u32]) {
    out[gi as usize] = gi;
}

fn main() {}
