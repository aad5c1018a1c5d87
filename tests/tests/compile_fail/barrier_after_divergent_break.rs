use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(
    #[builtin(local_index)] li: u32,
    #[workgroup] tile: &mut [u32; 64],
    out: &mut [u32],
) {
    let mut step = 0u32;
    while step < 6 {
        if step >= li {
            break;
        }
        tile[li as usize] = step;
        workgroup_barrier();
        step += 1;
    }
    out[li as usize] = tile[li as usize];
}

fn main() {}
