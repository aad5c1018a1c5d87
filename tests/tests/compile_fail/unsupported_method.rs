use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    out[gi as usize] = gi.saturating_sub(3);
}

fn main() {}
