//! `#[specialize]` parameters: values fixed when the kernel is built. Every branch on them
//! is decided then (the other branch is not in the shader); on the host they are ordinary
//! arguments. `mode` picks the operations as bits, `clamp` a last step.
use cohort::prelude::*;

/// `mode` bit 0: double; bit 1: square root of the magnitude; bit 2: negate.
pub const DOUBLE: u32 = 1;
pub const ROOT: u32 = 2;
pub const NEGATE: u32 = 4;

#[kernel(workgroup = 64)]
pub fn specialized_steps(
    #[builtin(global_index)] i: u32,
    #[specialize] mode: u32,
    #[specialize] clamp: bool,
    x: &[f32],
    y: &mut [f32],
) {
    let i = i as usize;
    // The constants combine as any value does; the combination is folded too.
    let root = mode & ROOT != 0;
    if i < x.len() {
        let mut v = x[i];
        if mode & DOUBLE != 0 {
            v *= 2.0;
        }
        if root && v != 0.0 {
            v = v.abs().sqrt();
        }
        if mode & NEGATE != 0 || (clamp && mode == 0) {
            v = -v;
        }
        if clamp {
            v = v.max(-1.0).min(1.0);
        }
        y[i] = v;
    }
}
