use cohort::prelude::*;

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let leader = group_share(|group| gi);
    out[gi as usize] = leader;
}

fn main() {}
