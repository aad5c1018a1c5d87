use cohort::prelude::*;

#[derive(Clone, Copy, GpuType)]
pub struct Params {
    pub scale: f32,
    pub n: u32,
}

fn main() {}
