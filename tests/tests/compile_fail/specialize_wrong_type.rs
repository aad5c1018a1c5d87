use cohort::prelude::*;

#[kernel]
pub fn k(#[builtin(global_index)] gi: u32, #[specialize] scale: f32, out: &mut [f32]) {
    out[gi as usize] = scale;
}

fn main() {}
