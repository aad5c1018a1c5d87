use cohort::prelude::*;

#[kernel(workgroup = 64, group = Block(64))]
pub fn k(#[builtin(global_index)] gi: u32, values: &[u32], out: &mut [u32]) {
    let i = gi as usize;
    if values[i] != 0 {
        // Invocations where the value is zero never join the vote: the group would hang.
        if group_any(values[i] > 7) {
            out[i] = 1;
        }
    }
}

fn main() {}
