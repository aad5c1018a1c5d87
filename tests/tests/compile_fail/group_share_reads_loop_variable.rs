use cohort::prelude::*;

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut sum = 0u32;
    for bounce in 0..4u32 {
        sum += group_share(|group| group * 4 + bounce);
    }
    out[gi as usize] = sum;
}

fn main() {}
