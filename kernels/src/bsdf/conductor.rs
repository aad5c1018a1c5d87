//! Mitsuba `conductor`: a smooth metal, one mirror direction weighted by the conductor's
//! Fresnel factor (`sampling::fresnel_conductor`; `transmittance` holds eta, `conductor_k`
//! k). One-sided, as in Mitsuba: the back absorbs.

use super::{scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::{fresnel_conductor, DiffuseSampler};
use cohort::prelude::*;

pub struct Conductor;

#[kernel_impl]
impl Bsdf for Conductor {
    const KINDS: u32 = 1 << CONDUCTOR;
    const NON_DELTA: bool = false;

    fn sample<S: DiffuseSampler>(
        _textures: &[Vec4],
        _tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        _r: Draws,
    ) -> Scattered {
        let cos_i = -at.d.dot(at.n);
        scattered(
            at.d + at.n * (2.0 * cos_i),
            0.0,
            beta * at.albedo * fresnel_conductor(cos_i, at.m.transmittance, at.m.conductor_k),
            1.0,
            1.0,
        )
    }

    fn eval(_textures: &[Vec4], _tex_coords: &[Vec4], _at: Hit, _wi: Vec3) -> Vec4 {
        Vec4::ZERO
    }
}
