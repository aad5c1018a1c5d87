use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, scale: f32, out: &mut [f32]) {
    out[gi as usize] = scale;
}

fn main() {}
