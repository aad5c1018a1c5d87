use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let double = |x: u32| x * 2;
    out[gi as usize] = gi;
}

fn main() {}
