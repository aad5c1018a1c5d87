use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut n = gi;
    while let Some(m) = n.checked_sub(3) {
        n = m;
    }
    out[gi as usize] = n;
}

fn main() {}
