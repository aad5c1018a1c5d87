//! Transcendental and float math mapped to naga math functions; compared across
//! backends and with the host within a stated ulp bound.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn mathfns(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [Vec4]) {
    let i = gi as usize;
    if i >= xs.len() {
        return;
    }
    let x = xs[i];
    let a = x.sin() * x.cos() + (x * 0.25).exp();
    let b = (x.abs() + 1.0).ln() + (x.abs() + 0.5).sqrt() + x.abs().powf(1.5);
    let c = x.floor() + x.fract() + x.mul_add(2.0, 1.0) + x.clamp(-1.0, 1.0) + x.signum();
    let d = x.atan2(1.5) + x.tanh() + x.max(0.25).min(2.0);
    out[i] = Vec4::new(a, b, c, d);
}

/// `acos`: the CPU backend's vector form computes it in vector instructions for |x| <= 1
/// and calls the C library beyond, and must give the host's bits either way.
#[kernel(workgroup = 64)]
pub fn arccosines(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    if i >= xs.len() {
        return;
    }
    out[i] = xs[i].acos();
}

/// `sin` and `cos` alone and paired with each other: the CPU backend's vector form computes
/// them in vector instructions below |x| = 120 and calls the C library beyond, and must give
/// the host's bits either way.
#[kernel(workgroup = 64)]
pub fn sines(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [Vec4]) {
    let i = gi as usize;
    if i >= xs.len() {
        return;
    }
    let x = xs[i];
    let y = -x;
    out[i] = Vec4::new(x.sin(), x.cos(), y.sin(), (x * 0.5).cos());
}
