use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_id)] id: u32, out: &mut [u32]) {
    out[id as usize] = id;
}

fn main() {}
