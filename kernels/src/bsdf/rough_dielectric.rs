//! Mitsuba `roughdielectric` in the kernels: sampling a microfacet normal visible from the
//! viewer (GGX or Beckmann, anisotropic: Mitsuba's `sample_visible`, its default), then
//! reflection off it with the Fresnel probability or refraction through it, weighted as
//! Mitsuba weights its samples. Its roughness is read as the rough conductor's
//! (`crate::rough_conductor`): a number in `Material::conductor_k.x`, or a parameter block
//! (`Material::table`) where it is anisotropic or textured.

use super::{absorbed, scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::microfacet::{d, g1, visible_pdf, visible_sample};
use crate::sampling::{fresnel_dielectric, DiffuseSampler};
use cohort::prelude::*;

/// (alpha_u, alpha_v) of rough dielectric `m` at hit `h` of triangle `original` (texture
/// coordinates `uv`), at least 1e-4 as Mitsuba clamps them.
#[kernel_fn]
pub fn alpha(textures: &[Vec4], m: Material, uv: Vec2, original: u32, h: Vec4) -> Vec2 {
    crate::bsdf::rough_conductor::roughness(textures, m.conductor_k.x, m.table, uv, original, h)
}

/// The frame rough dielectric `m` scatters in: z the shading normal `n` on the viewer's
/// side (the interface is seen from either side, its index ratio inverted behind), x along
/// dp/du where it has a parameter block (it may be anisotropic there).
#[kernel_fn]
pub fn frame(
    m: Material,
    tex_coords: &[Vec4],
    tri: Triangle,
    ng: Vec3,
    n: Vec3,
    front: bool,
) -> Mat3 {
    crate::perturb::tangent_frame(tex_coords, tri, ng, n, front, true, m.table != 0)
}

/// One scattering of the ray arriving from direction `wo` (pointing away from the surface,
/// on the side the frame `fr`'s z faces) at an interface of relative index `eta` (the far
/// side's over the near side's), roughness `a`: xyz = the new direction (world space), w =
/// its weight without the reflectance / transmittance tint (0 when the sample is invalid:
/// a microfacet facing away, or a direction on the wrong side).
/// A refraction scales radiance by 1 / eta², as Mitsuba's radiance transport does
/// (the ray's solid angle widens or narrows across the interface); the path's Russian
/// roulette undoes it with the accumulated eta² (`extend`).
/// `u` picks the normal, `choice` reflection (below the Fresnel reflectance) or refraction.
#[kernel_fn]
pub fn sample(wo: Vec3, fr: Mat3, eta: f32, a: Vec2, beckmann: bool, u: Vec2, choice: f32) -> Vec4 {
    let o = fr.transpose() * wo;
    let mut r = Vec4::ZERO;
    if o.z > 0.0 {
        let m = visible_sample(o, a, beckmann, u);
        let cos_om = o.dot(m);
        if cos_om > 0.0 {
            let f = fresnel_dielectric(cos_om, eta);
            let i: Vec3;
            let valid: bool;
            let mut scale = 1.0f32;
            if choice < f {
                i = m * (2.0 * cos_om) - o;
                valid = i.z > 0.0;
            } else {
                let sin2_t = (1.0 - cos_om * cos_om) / (eta * eta);
                let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
                i = m * (cos_om / eta - cos_t) - o / eta;
                valid = i.z < 0.0;
                scale = 1.0 / (eta * eta);
            }
            if valid {
                // Visible normals drawn, reflection or refraction chosen by the Fresnel
                // term: what remains is the masking of the new direction.
                let w = g1(i, m, a, beckmann) * scale;
                r = (fr * i).normalize().extend(w);
            }
        }
    }
    r
}

/// For the viewer direction `wo` and a direction `wi` (both pointing away from the
/// surface, world space; the frame `fr`'s z faces the viewer): x = f·|cos| without the
/// tint (which is the specular reflectance where z = 1, reflection, else the specular
/// transmittance), y = the density with which [`sample`] produces `wi`, z = 1 for
/// reflection. Mitsuba's `roughdielectric` `eval` and `pdf`, the radiance scale 1 / eta²
/// of a refraction included (see [`sample`]).
#[kernel_fn]
pub fn eval(wo: Vec3, wi: Vec3, fr: Mat3, eta: f32, a: Vec2, beckmann: bool) -> Vec4 {
    let o = fr.transpose() * wo;
    let i = fr.transpose() * wi;
    let mut r = Vec4::ZERO;
    if o.z > 0.0 && i.z != 0.0 {
        let reflect = i.z > 0.0;
        let k = if reflect { 1.0 } else { eta };
        let mut m = (o + i * k).normalize();
        if m.z < 0.0 {
            m = -m;
        }
        let om = o.dot(m);
        let im = i.dot(m);
        // Each direction must see the microfacet's front from its side of the surface.
        if om > 0.0 && im * i.z > 0.0 {
            let dm = d(m, a, beckmann);
            let f = fresnel_dielectric(om, eta);
            let g = g1(o, m, a, beckmann) * g1(i, m, a, beckmann);
            let pm = visible_pdf(o, m, a, beckmann);
            if reflect {
                r = Vec4::new(f * dm * g / (4.0 * o.z), pm * f / (4.0 * im), 1.0, 0.0);
            } else {
                let denom = om + eta * im;
                let jacobian = (eta * eta * im / (denom * denom)).abs();
                r = Vec4::new(
                    ((1.0 - f) * dm * g * om * im / (o.z * denom * denom)).abs(),
                    pm * (1.0 - f) * jacobian,
                    0.0,
                    0.0,
                );
            }
        }
    }
    r
}

/// The BSDF: [`sample`] and [`eval`] at the interface seen from the ray's side (the index
/// ratio `Material::param` inverted behind), tinted by the specular reflectance
/// (`Material::color`) or transmittance. Both sides scatter.
pub struct RoughDielectric;

#[kernel_impl]
impl Bsdf for RoughDielectric {
    const KINDS: u32 = 1 << ROUGH_DIELECTRIC;
    const NON_DELTA: bool = true;

    fn scatters(_at: Hit) -> bool {
        true
    }

    fn sample<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        // The index ratio across the interface, far side over near.
        let eta = if at.front != 0 {
            at.m.param
        } else {
            1.0 / at.m.param
        };
        let beckmann = at.m.flags & BECKMANN != 0;
        let a = alpha(textures, at.m, at.uv, at.t.original, at.h);
        let fr = frame(at.m, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let s = sample(-at.d, fr, eta, a, beckmann, r.u, r.choice);
        let mut out = absorbed();
        if s.w > 0.0 {
            let dir = s.truncate();
            // The weight carries a refraction's 1 / eta² (`sample`).
            let mut tint = at.m.color;
            let mut eta2 = 1.0f32;
            if dir.dot(at.n) <= 0.0 {
                tint = at.m.transmittance;
                eta2 = eta * eta;
            }
            let e = eval(-at.d, dir, fr, eta, a, beckmann);
            out = scattered(dir, e.y, beta * tint * s.w, 0.0, eta2);
        }
        out
    }

    fn eval(textures: &[Vec4], tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let eta = if at.front != 0 {
            at.m.param
        } else {
            1.0 / at.m.param
        };
        let a = alpha(textures, at.m, at.uv, at.t.original, at.h);
        let fr = frame(at.m, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let e = eval(-at.d, wi, fr, eta, a, at.m.flags & BECKMANN != 0);
        let tint = if e.z > 0.0 {
            at.m.color
        } else {
            at.m.transmittance
        };
        (tint * e.x).extend(e.y)
    }
}
