use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, input: &[u32], out: &mut [u32]) {
    let mut sum = 0u32;
    for v in input.iter() {
        sum += *v;
    }
    out[gi as usize] = sum;
}

fn main() {}
