//! Mitsuba `roughplastic` in the kernels: a diffuse base under a rough dielectric coating.
//! The coating reflects as a microfacet surface (GGX or Beckmann, [`microfacet_eval`]);
//! the base's light crosses the rough interface twice, weighted by the precomputed external
//! transmittance at both cosines (a 64 x 1 table texture, looked up as Mitsuba's
//! `lerp_gather` interpolates it) and by the internal reflections the coating sends back.
//! The table and the internal reflectance come from `cohort_scenes::rough_plastic`.

use super::{absorbed, diffuse_direction, scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::{
    fresnel_dielectric, microfacet_eval, microfacet_sample, plastic_specular_probability,
    DiffuseSampler,
};
use crate::texture::TEXTURE_HEADER;
use cohort::prelude::*;

/// The coating's transmittance for light at cosine `cos` to the normal: entry
/// cos × 63 of the table, linearly interpolated (the texture's texel centres sit at
/// (k + 0.5) / 64).
///
/// The table is a 64 x 1 bitmap, bilinear, clamped, with the identity `to_uv`, written by
/// the scene loader. This is `texture_eval`'s bilinear lookup of it, the same operations
/// on the same texels (its second row is the first, clamped, weighted 0), written out
/// for one row: the BSDF reads the table five times, and a whole texture lookup inlined
/// at each would add some 3,000 SPIR-V words to every kernel with a rough plastic
/// (pipeline creation grows faster than the code).
#[kernel_fn]
pub fn transmittance(textures: &[Vec4], m: Material, cos: f32) -> f32 {
    let x = cos.clamp(0.0, 1.0) * 63.0;
    let header = m.table - 1;
    let w = textures[header as usize].y.to_bits() as i32;
    let at = (x + 0.5) / 64.0 * w as f32 - 0.5;
    let x0 = at.floor();
    let fx = at - x0;
    let xi = x0 as i32;
    let base = header + TEXTURE_HEADER;
    let a = textures[(base + xi.clamp(0, w - 1) as u32) as usize].x;
    let b = textures[(base + (xi + 1).clamp(0, w - 1) as u32) as usize].x;
    a * (1.0 - fx) + b * fx
}

/// The base's diffuse albedo as it leaves the coating, without the cosine, 1 / π and the
/// two transmittances: divided by (1 - the internal reflections) and by eta².
#[kernel_fn]
pub fn base(albedo: Vec3, m: Material) -> Vec3 {
    let internal = m.conductor_k.y;
    let mut denominator = Vec3::splat(1.0 - internal);
    if m.flags & NONLINEAR != 0 {
        denominator = Vec3::ONE - albedo * internal;
    }
    albedo / denominator / (m.param * m.param)
}

/// The probability of sampling the coating rather than the base, for light arriving with
/// transmittance `t_i` (Mitsuba: by the reflected and transmitted shares, weighted by the
/// mean specular and diffuse reflectances).
#[kernel_fn]
pub fn specular_probability(t_i: f32, albedo: Vec3, m: Material) -> f32 {
    plastic_specular_probability(1.0 - t_i, albedo, m.transmittance)
}

/// f·cos (xyz) for local directions `wo` (towards the viewer) and `wi` (z up), and (w) the
/// density with which the extend kernel's sampling produces `wi`: the coating's with the
/// specular probability, cosine-weighted otherwise. `t_i`, `t_o`: [`transmittance`] at
/// `wo.z` and `wi.z`. Zero below either horizon.
#[kernel_fn]
pub fn eval(wo: Vec3, wi: Vec3, m: Material, albedo: Vec3, t_i: f32, t_o: f32) -> Vec4 {
    let mut r = Vec4::ZERO;
    if (wo.z > 0.0) & (wi.z > 0.0) {
        let e = microfacet_eval(wo, wi, m.conductor_k.x, m.flags & BECKMANN != 0);
        let specular = m.transmittance * (fresnel_dielectric(e.z, m.param) * e.x);
        let diffuse = base(albedo, m) * (wi.z * t_i * t_o * core::f32::consts::FRAC_1_PI);
        let ps = specular_probability(t_i, albedo, m);
        let pdf = ps * e.y + (1.0 - ps) * wi.z * core::f32::consts::FRAC_1_PI;
        r = (specular + diffuse).extend(pdf);
    }
    r
}

/// The BSDF: the coating's glossy reflection or the base, chosen by their shares
/// ([`specular_probability`]); each sample weighted by its own lobe over the probability of
/// choosing it (unbiased without the other lobe's density), the base's directions drawn by
/// the diffuse strategy `S`; the mixture's density serves MIS. One-sided.
pub struct RoughPlastic;

#[kernel_impl]
impl Bsdf for RoughPlastic {
    const KINDS: u32 = 1 << ROUGH_PLASTIC;
    const NON_DELTA: bool = true;

    fn sample<S: DiffuseSampler>(
        textures: &[Vec4],
        _tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let fr = crate::sampling::frame(at.n);
        let wo = fr.transpose() * -at.d;
        let t_i = transmittance(textures, at.m, wo.z);
        let ps = specular_probability(t_i, at.albedo, at.m);
        let wi: Vec3;
        let mut weight = Vec3::ZERO;
        if r.choice < ps {
            let beckmann = at.m.flags & BECKMANN != 0;
            let mn = microfacet_sample(wo, at.m.conductor_k.x, beckmann, r.u);
            wi = mn * (2.0 * wo.dot(mn)) - wo;
            let e = microfacet_eval(wo, wi, at.m.conductor_k.x, beckmann);
            if wi.z > 0.0 && e.y > 0.0 {
                let fresnel = fresnel_dielectric(e.z, at.m.param);
                weight = at.m.transmittance * (fresnel * e.x / (e.y * ps));
            }
        } else {
            let s = diffuse_direction::<S>(at.n, r);
            wi = fr.transpose() * s.truncate();
            if wi.z > 0.0 {
                let t_o = transmittance(textures, at.m, wi.z);
                weight = base(at.albedo, at.m) * (t_i * t_o * s.w / (1.0 - ps));
            }
        }
        let mut out = absorbed();
        if weight.max_element() > 0.0 {
            let t_o = transmittance(textures, at.m, wi.z);
            let e = eval(wo, wi, at.m, at.albedo, t_i, t_o);
            out = scattered(fr * wi, e.w, beta * weight, 0.0, 1.0);
        }
        out
    }

    fn eval(textures: &[Vec4], _tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let fr = crate::sampling::frame(at.n);
        let wo = fr.transpose() * -at.d;
        let wl = fr.transpose() * wi;
        let t_i = transmittance(textures, at.m, wo.z);
        let t_o = transmittance(textures, at.m, wl.z);
        eval(wo, wl, at.m, at.albedo, t_i, t_o)
    }
}
