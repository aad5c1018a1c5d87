// A `&[Vec3]` storage buffer: 12-byte elements on the host, 16 bytes apart on the GPU.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn sum_vec3(#[builtin(global_index)] i: u32, xs: &[Vec3], out: &mut [f32]) {
    if (i as usize) < xs.len() {
        out[i as usize] = xs[i as usize].x + xs[i as usize].y + xs[i as usize].z;
    }
}

fn main() {}
