use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let total = 0u32;
    for j in 0..4u32 {
        total += gi * j;
    }
    out[gi as usize] = total;
}

fn main() {}
