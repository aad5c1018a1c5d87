use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, counter: &mut u32) {
    *counter = gi;
}

fn main() {}
