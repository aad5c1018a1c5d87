//! Mitsuba `plastic`: a diffuse base under a smooth dielectric coating. The coating's
//! specular reflection or the base's diffuse scattering is chosen by their
//! Fresnel-weighted mean albedos (`sampling::plastic_specular_probability`); the base's
//! directions are drawn by the diffuse strategy `S`. One-sided.

use super::{diffuse_direction, scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::{
    fresnel_dielectric, plastic_base, plastic_specular_probability, DiffuseSampler,
};
use cohort::prelude::*;

pub struct Plastic;

#[kernel_impl]
impl Bsdf for Plastic {
    const KINDS: u32 = 1 << PLASTIC;
    const NON_DELTA: bool = true;

    fn sample<S: DiffuseSampler>(
        _textures: &[Vec4],
        _tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let cos_i = -at.d.dot(at.n);
        let f_i = fresnel_dielectric(cos_i, at.m.param);
        let p_spec = plastic_specular_probability(f_i, at.albedo, at.m.transmittance);
        let dir: Vec3;
        let out: Vec3;
        let mut pdf = 0.0f32;
        let mut delta_p = 0.0f32;
        if r.choice < p_spec {
            dir = at.d + at.n * (2.0 * cos_i);
            out = beta * at.m.transmittance * (f_i / p_spec);
            delta_p = p_spec;
        } else {
            let s = diffuse_direction::<S>(at.n, r);
            dir = s.truncate();
            let c = dir.dot(at.n).max(0.0);
            let f_o = fresnel_dielectric(c, at.m.param);
            let base = plastic_base(at.albedo, at.m.param, at.m.flags & NONLINEAR != 0);
            out = beta * base * ((1.0 - f_i) * (1.0 - f_o) / (1.0 - p_spec) * s.w);
            // As for diffuse bounces: cosine densities whatever S drew.
            pdf = (1.0 - p_spec) * c * core::f32::consts::FRAC_1_PI;
        }
        scattered(dir, pdf, out, delta_p, 1.0)
    }

    /// The coating's delta reflection cannot meet a light sample: only the base scatters
    /// towards it.
    fn eval(_textures: &[Vec4], _tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let c = wi.dot(at.n).max(0.0);
        let f_i = fresnel_dielectric(-at.d.dot(at.n), at.m.param);
        let f_o = fresnel_dielectric(c, at.m.param);
        let p_spec = plastic_specular_probability(f_i, at.albedo, at.m.transmittance);
        let base = plastic_base(at.albedo, at.m.param, at.m.flags & NONLINEAR != 0);
        let fc = base * ((1.0 - f_i) * (1.0 - f_o) * c * core::f32::consts::FRAC_1_PI);
        fc.extend((1.0 - p_spec) * c * core::f32::consts::FRAC_1_PI)
    }
}
