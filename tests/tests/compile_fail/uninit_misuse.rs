use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn immutable(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let stack: [u32; 4] = uninit();
    out[gi as usize] = stack[0];
}

#[kernel(workgroup = 64)]
pub fn untyped(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut stack = uninit();
    stack = [gi; 4];
    out[gi as usize] = stack[0];
}

#[kernel(workgroup = 64)]
pub fn as_a_value(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    let mut stack = [0u32; 4];
    stack = uninit();
    out[gi as usize] = stack[0];
}

fn main() {}
