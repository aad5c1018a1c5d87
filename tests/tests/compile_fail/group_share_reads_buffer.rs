use cohort::prelude::*;

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(global_index)] gi: u32, input: &[u32], out: &mut [u32]) {
    let first = group_share(|group| input[group as usize]);
    out[gi as usize] = first;
}

fn main() {}
