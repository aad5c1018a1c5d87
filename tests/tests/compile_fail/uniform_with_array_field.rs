// A uniform struct with an array of 4-byte elements: WGSL's uniform layout needs a
// 16-byte array stride.
use cohort::prelude::*;

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Weights {
    pub count: u32,
    pub pad: [u32; 3],
    pub w: [f32; 8],
}

#[kernel(workgroup = 64)]
pub fn weigh(#[builtin(global_index)] i: u32, p: &Weights, out: &mut [f32]) {
    out[i as usize] = p.w[(i % 8) as usize];
}

fn main() {}
