use cohort::prelude::*;

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let v = group_share(|group| {
        workgroup_barrier();
        group
    });
    out[gi as usize] = v;
}

fn main() {}
