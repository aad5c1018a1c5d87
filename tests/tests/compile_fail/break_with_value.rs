use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut n = gi;
    let steps = loop {
        if n <= 1 {
            break n;
        }
        n /= 2;
    };
    out[gi as usize] = steps;
}

fn main() {}
