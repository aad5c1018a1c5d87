use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, x: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    out[i] = x[i] + gi;
}

fn main() {}
