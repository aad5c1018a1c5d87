use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, #[workgroup] tile: &mut [u32; 64], out: &mut [u32]) {
    for s in 0..4u32 {
        tile[li as usize] = s;
        workgroup_barrier();
    }
    out[li as usize] = tile[0];
}

fn main() {}
