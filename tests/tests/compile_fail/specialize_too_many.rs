use cohort::prelude::*;

#[kernel]
pub fn k(
    #[builtin(global_index)] gi: u32,
    #[specialize] a: u32,
    #[specialize] b: u32,
    #[specialize] c: u32,
    #[specialize] d: bool,
    #[specialize] e: u32,
    out: &mut [u32],
) {
    if d {
        out[gi as usize] = a + b + c + e;
    }
}

fn main() {}
