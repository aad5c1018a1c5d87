use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let (a, b) = (gi, gi + 1);
    out[gi as usize] = a + b;
}

fn main() {}
