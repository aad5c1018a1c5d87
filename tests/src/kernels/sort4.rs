//! `&mut` helpers: a sorting network over four values through helpers that take
//! `&mut f32` arguments, a helper with a `mut` by-value parameter, and a stack in a local
//! array that helpers push to and pop from through `&mut` (a different depth per lane).
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

/// Pushes `v` onto `stack` at `*sp`.
#[kernel_fn]
pub fn push(stack: &mut [u32; 8], sp: &mut u32, v: u32) {
    stack[*sp as usize] = v;
    *sp += 1;
}

/// Pops the top of `stack`.
#[kernel_fn]
pub fn pop(stack: &mut [u32; 8], sp: &mut u32) -> u32 {
    *sp -= 1;
    stack[*sp as usize]
}

/// The positions of the set bits of the low byte of `xs[i]`, pushed in increasing order
/// and popped: as base-8 digits, highest position first, below a leading 1.
#[kernel(workgroup = 32)]
pub fn bit_stack(#[builtin(global_index)] i: u32, xs: &[u32], out: &mut [u32]) {
    let i = i as usize;
    if i >= xs.len() {
        return;
    }
    let x = xs[i];
    let mut stack: [u32; 8] = uninit();
    let mut sp = 0u32;
    for b in 0..8u32 {
        if (x >> b) & 1 != 0 {
            push(&mut stack, &mut sp, b);
        }
    }
    let mut r = 1u32;
    while sp > 0 {
        r = r * 8 + pop(&mut stack, &mut sp);
    }
    out[i] = r;
}
