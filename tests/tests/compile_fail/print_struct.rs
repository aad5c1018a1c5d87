use cohort::prelude::*;

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Hit {
    pub t: f32,
    pub id: u32,
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, hits: &[Hit], out: &mut [u32]) {
    let h = hits[gi as usize];
    println!("hit {}", h);
    out[gi as usize] = h.id;
}

fn main() {}
