//! Mitsuba `roughdielectric` in the kernels: sampling a microfacet normal visible from the
//! viewer (GGX; Beckmann by D(m) cos θ_m), then reflection off it with the Fresnel
//! probability or refraction through it, weighted as Mitsuba weights its samples.

use crate::sampling::{beckmann_g1, frame, fresnel_dielectric, microfacet_sample, smith_g1};
use cohort::prelude::*;

/// Masking of direction cosine `cos` (to the macro normal, either side).
#[kernel_fn]
fn g1(cos: f32, alpha: f32, beckmann: bool) -> f32 {
    let c = cos.abs();
    if beckmann {
        beckmann_g1(c, alpha)
    } else {
        smith_g1(c, alpha)
    }
}

/// One scattering of the ray arriving from direction `wo` (pointing away from the surface,
/// on the side `n` faces) at an interface of relative index `eta` (the far side's over the
/// near side's): xyz = the new direction (world space), w = its weight without the
/// reflectance / transmittance tint (0 when
/// the sample is invalid: a microfacet facing away, or a direction on the wrong side).
/// Radiance is not scaled by 1 / eta² on refraction (Mitsuba's importance transport, as
/// the smooth dielectric): the factors of entering and leaving cancel, and the throughput
/// then reads as Mitsuba's path integrator weighs it for Russian roulette.
/// `u` picks the normal, `choice` reflection (below the Fresnel reflectance) or refraction.
#[kernel_fn]
pub fn sample(
    wo: Vec3,
    n: Vec3,
    eta: f32,
    alpha: f32,
    beckmann: bool,
    u: Vec2,
    choice: f32,
) -> Vec4 {
    let fr = frame(n);
    let o = fr.transpose() * wo;
    let mut r = Vec4::ZERO;
    if o.z > 0.0 {
        let m = microfacet_sample(o, alpha, beckmann, u);
        let cos_om = o.dot(m);
        if cos_om > 0.0 {
            let f = fresnel_dielectric(cos_om, eta);
            let i: Vec3;
            let valid: bool;
            if choice < f {
                i = m * (2.0 * cos_om) - o;
                valid = i.z > 0.0;
            } else {
                let sin2_t = (1.0 - cos_om * cos_om) / (eta * eta);
                let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
                i = m * (cos_om / eta - cos_t) - o / eta;
                valid = i.z < 0.0;
            }
            if valid {
                // GGX samples visible normals: the weight is the masking of the new
                // direction; Beckmann samples D(m) cos θ_m: G |o·m| / (o.z m.z).
                let mut w = g1(i.z, alpha, beckmann);
                if beckmann {
                    w *= g1(o.z, alpha, beckmann) * cos_om / (o.z * m.z);
                }
                r = (fr * i).normalize().extend(w);
            }
        }
    }
    r
}

/// The microfacet normal density with which [`sample`] draws `m` for a viewer at `o`
/// (local): the visible normals' (GGX) or D(m) cos θ_m (Beckmann).
#[kernel_fn]
fn normal_pdf(o: Vec3, m: Vec3, alpha: f32, beckmann: bool) -> f32 {
    if beckmann {
        crate::sampling::beckmann_d(m.z, alpha) * m.z
    } else {
        crate::sampling::ggx_d(m.z, alpha) * g1(o.z, alpha, false) * o.dot(m).max(0.0) / o.z
    }
}

/// For the viewer direction `wo` and a direction `wi` (both pointing away from the
/// surface, world space; `n` faces the viewer): x = f·|cos| without the tint (which is the
/// specular reflectance where z = 1, reflection, else the specular transmittance), y = the
/// density with which [`sample`] produces `wi`, z = 1 for reflection. Mitsuba's
/// `roughdielectric` `eval` and `pdf` without the radiance scale (see [`sample`]).
#[kernel_fn]
pub fn eval(wo: Vec3, wi: Vec3, n: Vec3, eta: f32, alpha: f32, beckmann: bool) -> Vec4 {
    let fr = frame(n);
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
            let d = if beckmann {
                crate::sampling::beckmann_d(m.z, alpha)
            } else {
                crate::sampling::ggx_d(m.z, alpha)
            };
            let f = fresnel_dielectric(om, eta);
            let g = g1(o.z, alpha, beckmann) * g1(i.z, alpha, beckmann);
            let pm = normal_pdf(o, m, alpha, beckmann);
            if reflect {
                r = Vec4::new(f * d * g / (4.0 * o.z), pm * f / (4.0 * im), 1.0, 0.0);
            } else {
                let denom = om + eta * im;
                let jacobian = (eta * eta * im / (denom * denom)).abs();
                r = Vec4::new(
                    ((1.0 - f) * d * g * eta * eta * om * im / (o.z * denom * denom)).abs(),
                    pm * (1.0 - f) * jacobian,
                    0.0,
                    0.0,
                );
            }
        }
    }
    r
}
