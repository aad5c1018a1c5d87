use cohort::prelude::*;

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    pub fn area(&self) -> f32 {
        4.0 * core::f32::consts::PI * self.radius * self.radius
    }
}

#[kernel(workgroup = 64)]
pub fn k(#[builtin(global_index)] gi: u32, spheres: &[Sphere], out: &mut [f32]) {
    let s = spheres[gi as usize];
    out[gi as usize] = s.area();
}

fn main() {}
