use cohort::prelude::*;

#[kernel_fn]
pub fn bump(c: &[AtomicU32]) -> u32 {
    c[0].fetch_add(1, Ordering::Relaxed)
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(local_index)] li: u32, #[workgroup] tile: &mut [u32; 64], counter: &[AtomicU32], out: &mut [u32]) {
    if bump(counter) == 0 {
        workgroup_barrier();
    }
    out[li as usize] = tile[0];
}

fn main() {}
