//! Numeric conformance kernels (the numeric-semantics work, docs/LANGUAGE.md sections 3-9):
//! each invocation computes many operators, methods and casts on one input (or one pair of
//! inputs) and writes every result, so that `tests/conformance_numeric.rs` can compare
//! wgpu, Vulkan and the host bit for bit on edge values.
// The kernels test the meaning of `x != x`, `v == v` and `!(x < y)` on purpose.
#![allow(clippy::eq_op, clippy::neg_cmp_op_on_partial_ord)]
use cohort::prelude::*;

/// Results per input of `float_compare` (one word of flags).
#[kernel(workgroup = 64)]
pub fn float_compare(#[builtin(global_index)] gi: u32, a: &[f32], b: &[f32], out: &mut [u32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let y = b[i];
    let v = Vec3::new(x, y, 1.0);
    let w = Vec3::new(y, x, 1.0);
    let r = (x < y) as u32
        | ((x <= y) as u32) << 1
        | ((x > y) as u32) << 2
        | ((x >= y) as u32) << 3
        | ((x == y) as u32) << 4
        | ((x != y) as u32) << 5
        | (x.is_nan() as u32) << 6
        | (x.is_finite() as u32) << 7
        | (x.is_infinite() as u32) << 8
        | (x.is_sign_negative() as u32) << 9
        | (x.is_sign_positive() as u32) << 10
        | (x.is_normal() as u32) << 11
        | (x.is_subnormal() as u32) << 12
        | ((v == w) as u32) << 13
        | ((v != w) as u32) << 14
        | ((v == v) as u32) << 15
        | ((v != v) as u32) << 16
        | (!(x < y) as u32) << 17
        | ((x != x) as u32) << 18;
    out[i] = r;
}
pub const COMPARE_FLAGS: u32 = 19;

/// Float methods of one argument, exact (bit for bit) on every target.
pub const UNARY_N: usize = 20;
#[kernel(workgroup = 64)]
pub fn float_unary(#[builtin(global_index)] gi: u32, a: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let o = i * 20;
    out[o] = x.round();
    out[o + 1] = x.floor();
    out[o + 2] = x.ceil();
    out[o + 3] = x.trunc();
    out[o + 4] = x.fract();
    out[o + 5] = x.abs();
    out[o + 6] = x.signum();
    out[o + 7] = -x;
    out[o + 8] = x.clamp(-1.5, 2.5);
    out[o + 9] = x.round_ties_even();
    out[o + 10] = x.to_degrees();
    out[o + 11] = x.to_radians();
    out[o + 12] = x.copysign(-1.0);
    out[o + 13] = x.powi(3);
    out[o + 14] = x.powi(-2);
    out[o + 15] = x.powi(0);
    out[o + 16] = x.max(0.0);
    out[o + 17] = x.min(1.0);
    out[o + 18] = x.sqrt();
    out[o + 19] = x.recip();
}

/// Float methods of one argument with results that drivers compute to a stated precision
/// (docs/LANGUAGE.md, section 7): special values exact, the rest within a bound.
pub const TRANSC_N: usize = 13;
#[kernel(workgroup = 64)]
pub fn float_transcendental(#[builtin(global_index)] gi: u32, a: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let o = i * 13;
    out[o] = x.exp();
    out[o + 1] = x.exp2();
    out[o + 2] = x.ln();
    out[o + 3] = x.log2();
    out[o + 4] = x.sin();
    out[o + 5] = x.cos();
    out[o + 6] = x.tan();
    out[o + 7] = x.asin();
    out[o + 8] = x.acos();
    out[o + 9] = x.atan();
    out[o + 10] = x.sinh();
    out[o + 11] = x.cosh();
    out[o + 12] = x.tanh();
}

/// Float operators and methods of two arguments.
pub const BINARY_N: usize = 18;
#[kernel(workgroup = 64)]
pub fn float_binary(#[builtin(global_index)] gi: u32, a: &[f32], b: &[f32], out: &mut [f32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let y = b[i];
    let o = i * 18;
    out[o] = x + y;
    out[o + 1] = x - y;
    out[o + 2] = x * y;
    out[o + 3] = x / y;
    out[o + 4] = x % y;
    out[o + 5] = x.min(y);
    out[o + 6] = x.max(y);
    out[o + 7] = x.copysign(y);
    out[o + 8] = x.powf(y);
    out[o + 9] = x.mul_add(y, 0.25);
    out[o + 10] = x.atan2(y);
    let v = Vec2::new(x, y);
    let w = Vec2::new(y, x);
    out[o + 11] = v.min(w).x;
    out[o + 12] = v.max(w).x;
    let q = Vec4::new(x, y, -x, 1.0);
    out[o + 13] = q.min_element();
    out[o + 14] = q.max_element();
    out[o + 15] = q.element_sum();
    out[o + 16] = Vec3::new(x, y, 0.5)
        .clamp(Vec3::splat(-2.0), Vec3::splat(3.0))
        .x;
    let mut acc = x;
    acc %= y;
    out[o + 17] = acc;
}

/// Casts from `f32` (saturating) and from integers; one `UVec4` per input.
#[kernel(workgroup = 64)]
pub fn float_casts(#[builtin(global_index)] gi: u32, a: &[f32], out: &mut [UVec4]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let s = x as i32;
    let u = x as u32;
    let v = Vec3::new(x, -x, 0.5).as_uvec3();
    let w = Vec3::new(x, -x, 0.5).as_ivec3();
    out[i] = UVec4::new(
        s as u32,
        u,
        v.x ^ (v.y << 1),
        (w.x as u32) ^ ((w.y as u32) >> 1),
    );
}

/// Casts from integers: `i32`/`u32` → `f32` (round to nearest even), `i32` ↔ `u32` (bits),
/// `bool` → integers.
#[kernel(workgroup = 64)]
pub fn int_casts(#[builtin(global_index)] gi: u32, a: &[u32], out: &mut [UVec4]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let s = x as i32;
    let f = x as f32;
    let g = s as f32;
    let flags = (s < 0) as u32
        | ((x > 7) as i32 as u32) << 1
        | ((x as usize % 3 == 0) as usize as u32) << 2;
    out[i] = UVec4::new(f.to_bits(), g.to_bits(), (s as u32) ^ x, flags);
}

/// Integer operators: wrapping `+ - *`, division and remainder with defined results at 0
/// and `MIN / -1`, masked shifts, negation, `abs`, `pow`, compound assignment.
pub const INT_N: usize = 20;
#[kernel(workgroup = 64)]
pub fn int_ops(#[builtin(global_index)] gi: u32, a: &[i32], b: &[i32], out: &mut [i32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let y = b[i];
    let ux = x as u32;
    let uy = y as u32;
    let o = i * 20;
    out[o] = x + y;
    out[o + 1] = x - y;
    out[o + 2] = x * y;
    out[o + 3] = x / y;
    out[o + 4] = x % y;
    out[o + 5] = x << uy;
    out[o + 6] = x >> uy;
    out[o + 7] = -x;
    out[o + 8] = x.abs();
    out[o + 9] = x.pow(uy & 7);
    out[o + 10] = (ux + uy) as i32;
    out[o + 11] = (ux - uy) as i32;
    out[o + 12] = (ux * uy) as i32;
    out[o + 13] = (ux / uy) as i32;
    out[o + 14] = (ux % uy) as i32;
    out[o + 15] = (ux << uy) as i32;
    out[o + 16] = (ux >> uy) as i32;
    let mut acc = x;
    acc *= y;
    acc += x;
    acc <<= uy;
    acc /= y;
    out[o + 17] = acc;
    let n = ux as usize;
    let m = uy as usize;
    out[o + 18] = ((n - m) * (n + 1) / (m + 1)) as u32 as i32;
    let iv = IVec2::new(x, y) / IVec2::new(y, 0) + IVec2::new(x, y) % IVec2::splat(y);
    out[o + 19] = iv.x ^ iv.y;
}

/// The `f32` constants, as values and in expressions.
#[kernel(workgroup = 64)]
#[allow(invalid_nan_comparisons)]
pub fn float_constants(#[builtin(global_index)] gi: u32, a: &[f32], out: &mut [u32]) {
    let i = gi as usize;
    if i >= a.len() {
        return;
    }
    let x = a[i];
    let o = i * 16;
    out[o] = f32::INFINITY.to_bits();
    out[o + 1] = f32::NEG_INFINITY.to_bits();
    out[o + 2] = f32::NAN.is_nan() as u32;
    out[o + 3] = f32::MAX.to_bits();
    out[o + 4] = f32::MIN.to_bits();
    out[o + 5] = f32::MIN_POSITIVE.to_bits();
    out[o + 6] = f32::EPSILON.to_bits();
    out[o + 7] = (x < f32::INFINITY) as u32
        | ((x > f32::NEG_INFINITY) as u32) << 1
        | ((x == f32::NAN) as u32) << 2;
    out[o + 8] = (x * f32::INFINITY).to_bits();
    out[o + 9] = (f32::MAX * 2.0).to_bits();
    out[o + 10] = (-f32::INFINITY).to_bits();
    out[o + 11] = (x + f32::MIN_POSITIVE).to_bits();
    out[o + 12] = Vec3::INFINITY.min_element().to_bits();
    out[o + 13] = x.max(f32::NEG_INFINITY).to_bits();
    out[o + 14] = (core::f32::consts::PI * x).to_bits();
    out[o + 15] = (i32::MIN as u32) ^ u32::MAX ^ (f32::NAN != f32::NAN) as u32;
}
pub const CONST_N: usize = 16;

/// Writes each invocation's `global_index` where it points and counts visits, to check
/// that `global_index` is unique and dense over 1-D, 2-D and 3-D dispatches.
#[kernel(workgroup = 64)]
pub fn global_index_map(
    #[builtin(global_index)] gi: u32,
    #[builtin(workgroup_index)] wg: u32,
    #[builtin(local_index)] li: u32,
    out: &mut [u32],
    visits: &[AtomicU32],
) {
    let i = gi as usize;
    if i < out.len() {
        out[i] = wg * 64 + li;
        visits[i].fetch_add(1, Ordering::Relaxed);
    }
}
