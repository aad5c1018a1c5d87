use cohort::prelude::*;

#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct Particle {
    pub mass: f32,
    pub position: Vec3,
}

fn main() {}
