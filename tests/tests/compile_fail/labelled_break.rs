use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut found = 0u32;
    'outer: for a in 0..8u32 {
        for b in 0..8u32 {
            if a * b == gi {
                found = a;
                break 'outer;
            }
        }
    }
    out[gi as usize] = found;
}

fn main() {}
