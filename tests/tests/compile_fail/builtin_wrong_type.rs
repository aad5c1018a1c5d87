use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: f32, out: &mut [f32]) {
    out[0] = gi;
}

fn main() {}
