use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[workgroup] tile: &mut [u32; 64],
    input: &[u32],
    out: &mut [u32],
) {
    let i = gi as usize;
    if i >= input.len() {
        return;
    }
    tile[li as usize] = input[i];
    workgroup_barrier();
    out[i] = tile[(63 - li) as usize];
}

fn main() {}
