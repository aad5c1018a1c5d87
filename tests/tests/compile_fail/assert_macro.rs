use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    assert!(gi < 1024, "thread {}", gi);
    out[gi as usize] = gi;
}

fn main() {}
