//! Mitsuba `roughconductor`'s parameters at a hit: its roughness (alpha_u, alpha_v), each
//! a number or a texture read as a number, and the frame it is anisotropic in. An
//! isotropic, untextured one carries its alpha in `Material::param`; any other one has a
//! parameter block (`Material::table`, laid out by `cohort_scenes::Roughness::gpu_block`):
//! (alpha_u, alpha_v, header + 1 of alpha_u's texture, header + 1 of alpha_v's; 0: none).

use super::{absorbed, scattered, Bsdf, Draws, Hit, Scattered};
use crate::layout::*;
use crate::sampling::{fresnel_conductor, DiffuseSampler};
use crate::texture::{luminance, texture_at_hit};
use cohort::prelude::*;

/// (alpha_u, alpha_v) of rough conductor `m` at hit `h` of triangle `original` (texture
/// coordinates `uv`), at least 1e-4 as Mitsuba clamps them.
#[kernel_fn]
pub fn alpha(textures: &[Vec4], m: Material, uv: Vec2, original: u32, h: Vec4) -> Vec2 {
    roughness(textures, m.param, m.table, uv, original, h)
}

/// A microfacet roughness at a hit: `alpha` both ways, or the parameter block at `table`
/// (index + 1; 0: none), at least 1e-4 as Mitsuba clamps it. Rough conductors and rough
/// dielectrics keep their roughness so.
#[kernel_fn]
pub fn roughness(
    textures: &[Vec4],
    alpha: f32,
    table: u32,
    uv: Vec2,
    original: u32,
    h: Vec4,
) -> Vec2 {
    let mut a = Vec2::new(alpha, alpha);
    if table != 0 {
        let b = textures[(table - 1) as usize];
        a = Vec2::new(b.x, b.y);
        // Both directions' textures through one lookup, so that it is inlined once.
        let mut k = 0u32;
        while k < 2 {
            let texture = if k == 0 { b.z.to_bits() } else { b.w.to_bits() };
            if texture != 0 {
                let v = luminance(texture_at_hit(textures, texture - 1, uv, original, h));
                if k == 0 {
                    a.x = v;
                } else {
                    a.y = v;
                }
            }
            k += 1;
        }
    }
    Vec2::new(a.x.max(1.0e-4), a.y.max(1.0e-4))
}

/// The frame rough conductor `m` scatters in (`crate::perturb::tangent_frame`): along
/// dp/du where it has a parameter block (it may be anisotropic there).
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn frame(
    m: Material,
    tex_coords: &[Vec4],
    tri: Triangle,
    ng: Vec3,
    n: Vec3,
    front: bool,
) -> Mat3 {
    crate::perturb::tangent_frame(
        tex_coords,
        tri,
        ng,
        n,
        front,
        m.flags & TWO_SIDED != 0,
        m.table != 0,
    )
}

/// The BSDF: a visible microfacet normal drawn by [`crate::microfacet::visible_sample`]
/// (GGX or Beckmann, anisotropic), reflection off it weighted by the conductor's Fresnel
/// factor. One-sided, as in Mitsuba: the back absorbs. Coherent glossy sampling draws from
/// the group's shared cell (`Draws::u_glossy`): the warp maps the unit square onto the
/// visible normals preserving measure, so a shared cell keeps each ray's density.
pub struct RoughConductor;

#[kernel_impl]
impl Bsdf for RoughConductor {
    const KINDS: u32 = 1 << ROUGH_CONDUCTOR;
    const NON_DELTA: bool = true;

    fn sample<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let fr = frame(at.m, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let a = alpha(textures, at.m, at.uv, at.t.original, at.h);
        let wo = fr.transpose() * -at.d;
        let beckmann = at.m.flags & BECKMANN != 0;
        let mn = crate::microfacet::visible_sample(wo, a, beckmann, r.u_glossy);
        let wi = mn * (2.0 * wo.dot(mn)) - wo;
        let e = crate::microfacet::conductor_eval(wo, wi, a, beckmann);
        let mut out = absorbed();
        if wi.z > 0.0 && e.y > 0.0 {
            let fresnel = fresnel_conductor(e.z, at.m.transmittance, at.m.conductor_k);
            out = scattered(
                fr * wi,
                e.y,
                beta * at.albedo * fresnel * (e.x / e.y),
                0.0,
                1.0,
            );
        }
        out
    }

    fn eval(textures: &[Vec4], tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let fr = frame(at.m, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let a = alpha(textures, at.m, at.uv, at.t.original, at.h);
        let e = crate::microfacet::conductor_eval(
            fr.transpose() * -at.d,
            fr.transpose() * wi,
            a,
            at.m.flags & BECKMANN != 0,
        );
        let fc = at.albedo * fresnel_conductor(e.z, at.m.transmittance, at.m.conductor_k) * e.x;
        fc.extend(e.y)
    }
}
