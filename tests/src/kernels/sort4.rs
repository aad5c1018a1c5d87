//! `&mut` helpers: a sorting network over four values through helpers that take
//! `&mut f32` arguments, and a helper with a `mut` by-value parameter.
use cohort::prelude::*;

#[kernel_fn]
pub fn order(a: &mut f32, b: &mut f32) {
    let lo = a.min(*b);
    let hi = a.max(*b);
    *a = lo;
    *b = hi;
}

#[kernel_fn]
pub fn clamp_count(mut x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        x = lo;
    }
    if x > hi {
        x = hi;
    }
    x
}

#[kernel(workgroup = 32)]
pub fn sort4(#[builtin(global_index)] i: u32, values: &mut [Vec4]) {
    let i = i as usize;
    if i >= values.len() {
        return;
    }
    let v = values[i];
    let mut a = v.x;
    let mut b = v.y;
    let mut c = v.z;
    let mut d = v.w;
    order(&mut a, &mut b);
    order(&mut c, &mut d);
    order(&mut a, &mut c);
    order(&mut b, &mut d);
    order(&mut b, &mut c);
    values[i] = Vec4::new(a, b, c, clamp_count(d, -100.0, 100.0));
}
