//! y = a·x + y: buffers, a uniform, the global index builtin and a bounds check.
use cohort::prelude::*;

#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct SaxpyParams {
    pub a: f32,
    pub n: u32,
}

#[kernel(workgroup = 64)]
pub fn saxpy(#[builtin(global_index)] i: u32, p: &SaxpyParams, x: &[f32], y: &mut [f32]) {
    let i = i as usize;
    if i < p.n as usize {
        y[i] = p.a * x[i] + y[i];
    }
}
