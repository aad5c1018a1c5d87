//! Mitsuba `diffuse`: Lambertian reflection, its directions drawn by the diffuse strategy
//! `S` (the paper's coherent samplers, or independent cosine sampling).

use super::{diffuse_direction, scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::DiffuseSampler;
use cohort::prelude::*;

pub struct Diffuse;

#[kernel_impl]
impl Bsdf for Diffuse {
    const KINDS: u32 = 1 << DIFFUSE;
    const NON_DELTA: bool = true;

    /// One-sided, and a black surface absorbs (no light sample, no bounce).
    fn scatters(at: Hit) -> bool {
        (at.front != 0 || at.m.flags & TWO_SIDED != 0) && at.albedo.max_element() > 0.0
    }

    fn sample<S: DiffuseSampler>(
        _textures: &[Vec4],
        _tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let s = diffuse_direction::<S>(at.n, r);
        let dir = s.truncate();
        // MIS weights use the cosine density whatever strategy S drew the direction: every
        // strategy covers the whole hemisphere (over the group's random patch), so any
        // weights that sum to one stay unbiased.
        let c = dir.dot(at.n).max(0.0);
        scattered(
            dir,
            c * core::f32::consts::FRAC_1_PI,
            beta * at.albedo * s.w,
            0.0,
            1.0,
        )
    }

    fn eval(_textures: &[Vec4], _tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let c = wi.dot(at.n).max(0.0);
        let fc = at.albedo * (c * core::f32::consts::FRAC_1_PI);
        fc.extend(c * core::f32::consts::FRAC_1_PI)
    }
}
