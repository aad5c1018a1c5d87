//! Mitsuba `dielectric`: a smooth interface between two indices (`Material::param` is
//! int_ior / ext_ior, entering through the front face), reflecting with the Fresnel
//! probability, else refracting. Both sides scatter.

use super::{scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::{fresnel_dielectric, DiffuseSampler};
use cohort::prelude::*;

pub struct Dielectric;

#[kernel_impl]
impl Bsdf for Dielectric {
    const KINDS: u32 = 1 << DIELECTRIC;
    const NON_DELTA: bool = false;

    fn scatters(_at: Hit) -> bool {
        true
    }

    fn sample<S: DiffuseSampler>(
        _textures: &[Vec4],
        _tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let eta = if at.front != 0 {
            at.m.param
        } else {
            1.0 / at.m.param
        };
        let cos_i = -at.d.dot(at.n);
        let fr = fresnel_dielectric(cos_i, eta);
        let dir: Vec3;
        let out: Vec3;
        let mut eta2 = 1.0f32;
        let delta_p: f32;
        if r.choice < fr {
            dir = at.d + at.n * (2.0 * cos_i);
            out = beta * at.m.color;
            delta_p = fr;
        } else {
            let inv = 1.0 / eta;
            let cos_t = (1.0 - inv * inv * (1.0 - cos_i * cos_i)).max(0.0).sqrt();
            dir = (at.d * inv + at.n * (inv * cos_i - cos_t)).normalize();
            // Mitsuba's radiance scale of a refraction.
            out = beta * at.m.transmittance * (inv * inv);
            eta2 = eta * eta;
            delta_p = 1.0 - fr;
        }
        scattered(dir, 0.0, out, delta_p, eta2)
    }

    fn eval(_textures: &[Vec4], _tex_coords: &[Vec4], _at: Hit, _wi: Vec3) -> Vec4 {
        Vec4::ZERO
    }
}
