use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    out[gi as usize] = gi;
    if gi % 2 == 0 {
        subgroup_barrier();
        out[gi as usize] = out[(gi + 1) as usize];
    }
}

fn main() {}
