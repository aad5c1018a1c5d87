//! A generic kernel over a trait: each `impl` is a new strategy, monomorphised into its
//! own kernel, with trait constants and a default method.
use cohort::prelude::*;

#[kernel_trait]
pub trait Curve {
    const SCALE: f32;
    fn eval(x: f32) -> f32;
    fn scaled(x: f32) -> f32 {
        Self::eval(x) * Self::SCALE
    }
}

pub struct Square;
#[kernel_impl]
impl Curve for Square {
    const SCALE: f32 = 2.0;
    fn eval(x: f32) -> f32 {
        x * x
    }
}

pub struct Tent;
#[kernel_impl]
impl Curve for Tent {
    const SCALE: f32 = 0.5;
    fn eval(x: f32) -> f32 {
        let f = x.fract();
        if f < 0.5 {
            f * 2.0
        } else {
            2.0 - f * 2.0
        }
    }
}

#[kernel(workgroup = 64)]
pub fn apply_curve<C: Curve>(#[builtin(global_index)] i: u32, xs: &[f32], ys: &mut [f32]) {
    let i = i as usize;
    if i < xs.len() {
        ys[i] = C::scaled(xs[i]) + C::eval(1.0);
    }
}
