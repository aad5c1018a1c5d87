//! Mitsuba `normalmap` and `bumpmap`: the nested BSDF shades in a frame whose normal a
//! texture perturbs, as Mitsuba 3.9 computes it (`normalmap.cpp`, `bumpmap.cpp`,
//! `normalmap_helpers.h`).
//!
//! The shading frame (S, T, n_s) is Mitsuba's: S is dp/du made orthogonal to the
//! interpolated normal n_s. A normal map gives the perturbed normal in that frame as
//! 2 rgb - 1; a bump map bends dp/du and dp/dv along n_s by the height's gradient times
//! `scale` and takes their cross product (on the geometric normal's side). Mitsuba then
//! mirrors a normal that faces away from the viewer about n_s (`flip_invalid_normals`), and
//! counts a direction only where it lies on the same side of the shading and the perturbed
//! frames, weighted by Estevez et al.'s shadowing term (`use_shadowing_function`).

use crate::layout::*;
use cohort::prelude::*;

/// dp/du (x axis) and dp/dv (y axis) of the triangle (v0, v1, v2) with texture coordinates
/// `uv01` (u0, v0, u1, v1) and `uv2` (u2, v2) at its corners, as Mitsuba's mesh computes
/// them; a degenerate parameterisation falls back to a basis around the geometric normal
/// `ng` (z axis unused).
#[kernel_fn]
pub fn surface_tangents(v0: Vec3, v1: Vec3, v2: Vec3, uv01: Vec4, uv2: Vec2, ng: Vec3) -> Mat3 {
    let dp0 = v1 - v0;
    let dp1 = v2 - v0;
    let du0 = Vec2::new(uv01.z - uv01.x, uv01.w - uv01.y);
    let du1 = Vec2::new(uv2.x - uv01.x, uv2.y - uv01.y);
    let det = du0.x * du1.y - du0.y * du1.x;
    let mut r = crate::sampling::frame(ng);
    if det != 0.0 {
        let inv = 1.0 / det;
        r = Mat3::from_cols(
            (dp0 * du1.y - dp1 * du0.y) * inv,
            (dp1 * du0.x - dp0 * du1.x) * inv,
            ng,
        );
    }
    r
}

/// [`surface_tangents`] of triangle `tri` (scene index `original`) with its corners'
/// texture coordinates from `tex_coords` (`cohort_kernels::texture::hit_uv`'s layout).
#[kernel_fn]
pub fn hit_tangents(tex_coords: &[Vec4], original: u32, tri: Triangle, ng: Vec3) -> Mat3 {
    let k = original as usize * 2;
    surface_tangents(
        tri.v0,
        tri.v1,
        tri.v2,
        tex_coords[k],
        tex_coords[k + 1].truncate().truncate(),
        ng,
    )
}

/// The shading frame Mitsuba evaluates a BSDF in at a hit on triangle `tri` (geometric
/// normal `ng`; `n` the shading normal turned to the viewer, `front` whether it was
/// already): columns s, t and the normal, where s is dp/du made orthogonal to the normal
/// if `with_tangent` (an anisotropic BSDF needs it; an isotropic one takes any tangent).
/// Under `two_sided` the back side is mirrored to the front, as Mitsuba's `twosided` flips
/// the local z.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn tangent_frame(
    tex_coords: &[Vec4],
    tri: Triangle,
    ng: Vec3,
    n: Vec3,
    front: bool,
    two_sided: bool,
    with_tangent: bool,
) -> Mat3 {
    let mut ns = n;
    if !front {
        ns = -n;
    }
    let mut z = ns;
    if two_sided {
        z = n;
    }
    let mut r = crate::sampling::frame(z);
    if with_tangent {
        let tg = hit_tangents(tex_coords, tri.original, tri, ng);
        let s = shading_tangent(tg.x_axis, ns);
        r = Mat3::from_cols(s, ns.cross(s), z);
    }
    r
}

/// Mitsuba's shading tangent: dp/du made orthogonal to the shading normal `ns` (any tangent
/// where dp/du vanishes or is parallel to `ns`).
#[kernel_fn]
pub fn shading_tangent(dp_du: Vec3, ns: Vec3) -> Vec3 {
    let s = dp_du - ns * ns.dot(dp_du);
    let mut r = crate::sampling::frame(ns).x_axis;
    if s.dot(s) > 1.0e-30 {
        r = s.normalize();
    }
    r
}

/// The bump map's normal in the frame (s, t, ns): dp/du and dp/dv bent along `ns` by the
/// height gradient `grad` (already times `scale`), crossed, turned to the side of the
/// geometric normal `ng`.
#[kernel_fn]
pub fn bump_normal_local(
    grad: Vec2,
    dp_du: Vec3,
    dp_dv: Vec3,
    ns: Vec3,
    ng: Vec3,
    s: Vec3,
    t: Vec3,
) -> Vec3 {
    let du = dp_du + ns * (grad.x - ns.dot(dp_du));
    let dv = dp_dv + ns * (grad.y - ns.dot(dp_dv));
    let c = du.cross(dv);
    let mut r = Vec3::new(0.0, 0.0, 1.0);
    if c.dot(c) > 1.0e-30 {
        let mut nb = c.normalize();
        if ng.dot(nb) < 0.0 {
            nb = -nb;
        }
        r = Vec3::new(nb.dot(s), nb.dot(t), nb.dot(ns));
    }
    r
}

/// The perturbed normal in world space, from its coordinates `local` in the frame (s, t, b)
/// (b: the shading normal of the side the map applies on), for a viewer in direction `wi`;
/// `flip`: Mitsuba's `flip_invalid_normals`.
#[kernel_fn]
pub fn perturbed_normal(local: Vec3, s: Vec3, t: Vec3, b: Vec3, wi: Vec3, flip: bool) -> Vec3 {
    let mut l = local;
    let wl = Vec3::new(wi.dot(s), wi.dot(t), wi.dot(b));
    if flip && wl.z * wl.dot(l) <= 0.0 {
        l = Vec3::new(-l.x, -l.y, l.z);
    }
    let n = s * l.x + t * l.y + b * l.z;
    let mut r = b;
    if n.dot(n) > 1.0e-30 {
        r = n.normalize();
    }
    r
}

/// Squared tangent of the angle between unit vectors whose cosine is `c` (infinite at 0).
#[kernel_fn]
pub fn tan_squared(c: f32) -> f32 {
    let c2 = c * c;
    let mut r = 3.0e38f32;
    if c2 > 0.0 {
        r = (1.0 - c2).max(0.0) / c2;
    }
    r
}

/// What the perturbation multiplies the nested BSDF's value by for direction `wo`: 0 where
/// `wo` lies on different sides of the frame of `b` and of the perturbed normal `np`, else
/// Estevez et al.'s shadowing term (1 without `shadowing`).
#[kernel_fn]
pub fn perturb_weight(b: Vec3, np: Vec3, wo: Vec3, shadowing: bool) -> f32 {
    let co = wo.dot(b);
    let mut w = 0.0f32;
    if co * wo.dot(np) > 0.0 {
        w = 1.0;
        if shadowing {
            let alpha2 = (0.125 * tan_squared(np.dot(b))).min(1.0);
            w = 2.0 / (1.0 + (1.0 + alpha2 * tan_squared(co)).sqrt());
        }
    }
    w
}

/// The perturbed shading normal of material `m` at a hit (world space, unit): `ns` the
/// interpolated normal, `front` whether the viewer (direction `wi`) is on its side, `ng`
/// the geometric normal, `uv` and the triangle's corners and corner coordinates for the
/// tangents. Returns (normal, then b's sign in w: +1 the map applies on `ns`'s side, -1 on
/// the mirrored side).
#[kernel_fn]
pub fn perturb_normal(
    m: Material,
    textures: &[Vec4],
    tex_coords: &[Vec4],
    original: u32,
    tri: Triangle,
    uv: Vec2,
    ns: Vec3,
    ng: Vec3,
    wi: Vec3,
    front: bool,
) -> Vec4 {
    let tg = hit_tangents(tex_coords, original, tri, ng);
    let s = shading_tangent(tg.x_axis, ns);
    let t = ns.cross(s);
    let header = m.perturb_texture - 1;
    let local = if m.flags & BUMP_MAP != 0 {
        let grad = crate::texture::texture_gradient(textures, header, uv) * m.bump_scale;
        bump_normal_local(grad, tg.x_axis, tg.y_axis, ns, ng, s, t)
    } else {
        crate::texture::texture_eval(textures, header, uv) * 2.0 - Vec3::ONE
    };
    let mut sign = 1.0f32;
    if m.flags & PERTURB_PER_SIDE != 0 && !front {
        sign = -1.0;
    }
    perturbed_normal(local, s, t, ns * sign, wi, m.flags & NO_FLIP == 0).extend(sign)
}
