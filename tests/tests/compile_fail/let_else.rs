use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, input: &[u32], out: &mut [u32]) {
    let i = gi as usize;
    let Some(v) = input.get(i) else {
        return;
    };
    out[i] = *v;
}

fn main() {}
