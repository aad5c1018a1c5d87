// A helper that votes with `group_any`, called by only some invocations.
use cohort::prelude::*;

#[kernel_fn]
pub fn anyone(p: bool) -> bool {
    group_any(p)
}

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(global_index)] gi: u32, xs: &[u32], out: &mut [u32]) {
    if xs[gi as usize] > 3 {
        out[gi as usize] = anyone(gi > 7) as u32;
    }
}

fn main() {}
