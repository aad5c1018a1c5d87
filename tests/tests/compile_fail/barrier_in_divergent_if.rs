use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(
    #[builtin(local_index)] li: u32,
    #[workgroup] tile: &mut [u32; 64],
    out: &mut [u32],
) {
    tile[li as usize] = li;
    if li < 32 {
        workgroup_barrier();
        out[li as usize] = tile[(li + 32) as usize];
    }
}

fn main() {}
