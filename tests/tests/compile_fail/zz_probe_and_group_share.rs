use cohort::prelude::*;

#[kernel(workgroup = 64, group = Warp)]
pub fn k(#[builtin(local_index)] li: u32, out: &mut [u32]) {
    let ok = li < 32 && group_share(|group| group) > 0;
    if ok {
        out[li as usize] = 1u32;
    }
}

fn main() {}
