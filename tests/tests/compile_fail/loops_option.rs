use cohort::prelude::*;

#[kernel(workgroup = 64, loops = bounded)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    out[gi as usize] = gi;
}

fn main() {}
