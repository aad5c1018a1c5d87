use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let v = match gi % 2 {
        0 => 10u32,
        _ => 20u32,
    };
    out[gi as usize] = v;
}

fn main() {}
