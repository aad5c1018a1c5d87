//! Printing from a kernel: a scalar and a vector argument, under a divergent branch.

use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn debug_print(#[builtin(global_index)] gi: u32, xs: &[Vec4], out: &mut [f32]) {
    if gi < xs.len() as u32 {
        let v = xs[gi as usize];
        if v.w < 0.0 {
            println!("invocation {gi}: negative w in {v:?}");
        }
        out[gi as usize] = v.w;
    }
}
