use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [u32]) {
    let x = xs[gi as usize];
    println!("{:.*}", 3, x);
    out[gi as usize] = gi;
}

fn main() {}
