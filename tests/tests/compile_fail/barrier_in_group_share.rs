use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, out: &mut [u32]) {
    let v = group_share(|group| {
        workgroup_barrier();
        group * 2
    });
    out[li as usize] = v;
}

fn main() {}
