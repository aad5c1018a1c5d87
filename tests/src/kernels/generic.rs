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

/// A strategy whose method is generic over another strategy: each (implementing type,
/// method type argument) pair is its own function in the kernel.
#[kernel_trait]
pub trait Combine {
    fn after<C: Curve>(x: f32) -> f32;
}

pub struct Twice;
#[kernel_impl]
impl Combine for Twice {
    fn after<C: Curve>(x: f32) -> f32 {
        C::eval(C::eval(x))
    }
}

#[kernel(workgroup = 64)]
pub fn apply_both<K: Combine>(#[builtin(global_index)] i: u32, xs: &[f32], ys: &mut [f32]) {
    let i = i as usize;
    if i < xs.len() {
        ys[i] = K::after::<Square>(xs[i]) - K::after::<Tent>(xs[i]);
    }
}
