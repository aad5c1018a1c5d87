use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, input: &[u32]) -> u32 {
    input[gi as usize] * 2
}

fn main() {}
