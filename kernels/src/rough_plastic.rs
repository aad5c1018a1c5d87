//! Mitsuba `roughplastic` in the kernels: a diffuse base under a rough dielectric coating.
//! The coating reflects as a microfacet surface (GGX or Beckmann, [`microfacet_eval`]);
//! the base's light crosses the rough interface twice, weighted by the precomputed external
//! transmittance at both cosines (a 64 x 1 table texture, looked up as Mitsuba's
//! `lerp_gather` interpolates it) and by the internal reflections the coating sends back.
//! The table and the internal reflectance come from `cohort_scenes::rough_plastic`.

use crate::layout::*;
use crate::sampling::{fresnel_dielectric, microfacet_eval, plastic_specular_probability};
use crate::texture::texture_eval;
use cohort::prelude::*;

/// The coating's transmittance for light at cosine `cos` to the normal: entry
/// cos × 63 of the table, linearly interpolated (the texture's texel centres sit at
/// (k + 0.5) / 64).
#[kernel_fn]
pub fn transmittance(textures: &[Vec4], m: Material, cos: f32) -> f32 {
    let x = cos.clamp(0.0, 1.0) * 63.0;
    texture_eval(textures, m.table - 1, Vec2::new((x + 0.5) / 64.0, 0.5)).x
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
