//! Vectors and matrices: constructors, swizzle-like methods, dot/cross/normalize,
//! Mat3/Mat4 products, `if` as a value, `&&`/`||`, constants (`core::f32::consts`, `Vec3::Z`).
use cohort::prelude::*;

const TILT: f32 = 0.25;

#[kernel(workgroup = 64)]
pub fn vectors(#[builtin(global_index)] gi: u32, input: &[Vec4], out: &mut [Vec4]) {
    let i = gi as usize;
    if i >= input.len() {
        return;
    }
    let v = input[i];
    let n = v.truncate().normalize();
    let t = n.cross(Vec3::Z) + Vec3::splat(TILT);
    let m = Mat3::from_cols(n, t, Vec3::new(0.0, 1.0, core::f32::consts::FRAC_PI_4));
    let r = m * Vec3::new(1.0, 2.0, 3.0);
    let m4 = Mat4::from_cols(v, v * 2.0, Vec4::W, Vec4::ONE);
    let q = m4.transpose() * Vec4::new(0.5, 0.25, 0.125, 1.0);
    let side = if r.x > 0.0 && v.w < 1.0 || v.y > 2.0 {
        1.0
    } else {
        -1.0
    };
    out[i] = Vec4::new(
        r.dot(t),
        q.x + q.w,
        side * n.length(),
        (r * 2.0 - t).length_squared(),
    );
}
