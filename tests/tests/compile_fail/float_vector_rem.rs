use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, x: &[Vec4], out: &mut [Vec4]) {
    let i = gi as usize;
    out[i] = x[i] % Vec4::splat(2.0);
}

fn main() {}
