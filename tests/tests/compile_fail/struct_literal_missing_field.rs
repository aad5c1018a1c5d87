use cohort::prelude::*;

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Params {
    pub scale: f32,
    pub n: u32,
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, out: &mut [Params]) {
    out[gi as usize] = Params { n: gi };
}

fn main() {}
