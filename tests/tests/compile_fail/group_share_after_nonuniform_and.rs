use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, out: &mut [u32]) {
    let even = li < 32 && group_share(|group| group % 2) == 0;
    if even {
        out[li as usize] = 1;
    }
}

fn main() {}
