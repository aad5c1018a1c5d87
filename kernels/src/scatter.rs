//! What a surface scatters towards a given direction: `f · cos` and the density with which
//! BSDF sampling draws that direction, for every BSDF with a non-delta lobe. Light sampling
//! weighs its samples with it, and a `blendbsdf` sums it over its BSDFs.
//!
//! Mitsuba's `blendbsdf` is a mixture: `eval` and `pdf` are the weighted sums of its two
//! BSDFs', and `sample` picks one of them by weight (checked against the `mitsuba` package:
//! the density its `sample` reports is the mixture's). `extend` picks one BSDF per vertex
//! for sampling, as Mitsuba does; light sampling and the MIS density of the sampled
//! direction take the mixture ([`blend_eval`]), so that a light sample sees the blend's
//! value, not one of its BSDFs' (whose choice would add variance Mitsuba's image lacks).
//!
//! A delta lobe in a blend: Mitsuba 3.9's `sample` weighs a delta direction drawn by one
//! BSDF by the blend's value over its density there, where the drawing BSDF adds its
//! delta value and lobe probability and the others their `eval` and `pdf` (the drawing
//! BSDF's own non-delta lobes are left out). That is not the blend's expectation (the
//! other BSDFs' densities, a different measure, dilute the delta lobe), but it is
//! Mitsuba's image, so `extend` reproduces it with [`blend_eval`] leaving the drawing
//! BSDF out (checked against the `mitsuba` package: reference scene `blendbsdf_delta`).

use crate::layout::*;
use crate::sampling::{
    fresnel_conductor, fresnel_dielectric, plastic_base, plastic_specular_probability,
};
use crate::shading::*;
use crate::texture::{hit_uv, luminance, texture_at_hit};
use cohort::prelude::*;

/// Blends nested deeper than this take their last BSDF as it is (as `extend`'s choice does).
pub const BLEND_LEVELS: u32 = 4;
/// [`blend_eval`]'s `skip` that leaves no BSDF out.
pub const BLEND_NONE: u32 = BLEND_LEVELS + 1;

/// The weight of a blend material `m`'s second BSDF at the hit: its number, or the
/// luminance of its texture, clamped to [0, 1] (Mitsuba's `eval_weight`).
#[kernel_fn]
pub fn blend_weight(
    textures: &[Vec4],
    tex_coords: &[Vec4],
    m: Material,
    t: Triangle,
    h: Vec4,
) -> f32 {
    let mut weight = m.blend_weight;
    if m.blend_texture != 0 {
        let buv = hit_uv(tex_coords, t.original, h);
        weight = luminance(texture_at_hit(
            textures,
            m.blend_texture - 1,
            buv,
            t.original,
            h,
        ))
        .clamp(0.0, 1.0);
    }
    weight
}

/// [`blend_traits`]: some BSDF of the blend has a mask or a normal or bump map. Then each
/// vertex takes the one BSDF it picked for everything (unbiased, noisier): the mixture
/// needs the BSDFs to share the surface as light sampling sees it.
pub const BLEND_NOT_PLAIN: u32 = 1;
/// [`blend_traits`]: some BSDF of the blend reads texture coordinates (a texture, or a
/// parameter looked up at (u, v)), so [`blend_eval`] needs the hit's (u, v).
pub const BLEND_READS_UV: u32 = 2;

/// What the BSDFs of blend `root` have, together: [`BLEND_NOT_PLAIN`], [`BLEND_READS_UV`].
#[kernel_fn]
pub fn blend_traits(materials: &[Material], root: Material) -> u32 {
    let mut m = root;
    let mut traits = 0u32;
    let mut level = 0u32;
    while level <= BLEND_LEVELS {
        if m.flags & MASKED != 0 || m.perturb_texture != 0 {
            traits |= BLEND_NOT_PLAIN;
        }
        if m.texture != 0 || m.flags & READS_UV != 0 {
            traits |= BLEND_READS_UV;
        }
        if m.blend != 0 && level < BLEND_LEVELS {
            m = materials[(m.blend - 1) as usize];
            level += 1;
        } else {
            level = BLEND_LEVELS + 1;
        }
    }
    traits
}

/// `f · cos` (xyz) and the BSDF-sampling density (w) of material `m` (one BSDF, its colour
/// `albedo` already looked up) for light arriving from `wi`, seen along the ray direction
/// `d` at a hit with shading normal `n` (on the side the ray arrives from; `front`: the
/// surface's front side) and geometric normal `ng`. Zero for BSDFs without a non-delta
/// lobe (smooth conductors and dielectrics) and for one-sided BSDFs seen from the back.
/// Only the kinds in `shading` (the scene's set, `crate::shading`) are built.
#[kernel_fn]
pub fn scatter_eval(
    shading: u32,
    textures: &[Vec4],
    tex_coords: &[Vec4],
    m: Material,
    albedo: Vec3,
    t: Triangle,
    h: Vec4,
    uv: Vec2,
    d: Vec3,
    wi: Vec3,
    n: Vec3,
    ng: Vec3,
    front: bool,
) -> Vec4 {
    let two_sided = m.flags & TWO_SIDED != 0;
    let faces = front || two_sided;
    let mut out = Vec4::ZERO;
    if shading & SHADES_DIFFUSE != 0 && m.kind == DIFFUSE && faces && albedo.max_element() > 0.0 {
        let c = wi.dot(n).max(0.0);
        let fc = albedo * (c * core::f32::consts::FRAC_1_PI);
        out = fc.extend(c * core::f32::consts::FRAC_1_PI);
    } else if shading & SHADES_PLASTIC != 0 && m.kind == PLASTIC && faces {
        // The coating's delta reflection cannot meet a light sample: only the base
        // scatters towards it.
        let c = wi.dot(n).max(0.0);
        let f_i = fresnel_dielectric(-d.dot(n), m.param);
        let f_o = fresnel_dielectric(c, m.param);
        let p_spec = plastic_specular_probability(f_i, albedo, m.transmittance);
        let base = plastic_base(albedo, m.param, m.flags & NONLINEAR != 0);
        let fc = base * ((1.0 - f_i) * (1.0 - f_o) * c * core::f32::consts::FRAC_1_PI);
        out = fc.extend((1.0 - p_spec) * c * core::f32::consts::FRAC_1_PI);
    } else if shading & SHADES_ROUGH_DIELECTRIC != 0 && m.kind == ROUGH_DIELECTRIC {
        // The index ratio across the interface, far side over near.
        let eta_rd = if front { m.param } else { 1.0 / m.param };
        let a = crate::rough_dielectric::alpha(textures, m, uv, t.original, h);
        let fr = crate::rough_dielectric::frame(m, tex_coords, t, ng, n, front);
        let e = crate::rough_dielectric::eval(-d, wi, fr, eta_rd, a, m.flags & BECKMANN != 0);
        let tint = if e.z > 0.0 { m.color } else { m.transmittance };
        out = (tint * e.x).extend(e.y);
    } else if shading & SHADES_PRINCIPLED != 0
        && (m.kind == PRINCIPLED || m.kind == PRINCIPLED_THIN)
    {
        // Both sides scatter (the back as Mitsuba's BSDF does there, or as the front under
        // `twosided`).
        let fr = crate::principled::frame(m, textures, tex_coords, t, ng, n, front);
        let pp = crate::principled::params(textures, m, albedo, uv, t.original, h);
        out = crate::principled::eval_kind(pp, m.kind, fr.transpose() * -d, fr.transpose() * wi);
    } else if shading & SHADES_ROUGH_PLASTIC != 0 && m.kind == ROUGH_PLASTIC && faces {
        let fr = crate::sampling::frame(n);
        let wo = fr.transpose() * -d;
        let wl = fr.transpose() * wi;
        let t_i = crate::rough_plastic::transmittance(textures, m, wo.z);
        let t_o = crate::rough_plastic::transmittance(textures, m, wl.z);
        out = crate::rough_plastic::eval(wo, wl, m, albedo, t_i, t_o);
    } else if shading & SHADES_ROUGH_CONDUCTOR != 0 && m.kind == ROUGH_CONDUCTOR && faces {
        // Conductors are one-sided, as in Mitsuba: the back absorbs.
        let fr = crate::rough_conductor::frame(m, tex_coords, t, ng, n, front);
        let a = crate::rough_conductor::alpha(textures, m, uv, t.original, h);
        let e = crate::microfacet::conductor_eval(
            fr.transpose() * -d,
            fr.transpose() * wi,
            a,
            m.flags & BECKMANN != 0,
        );
        let fc = albedo * fresnel_conductor(e.z, m.transmittance, m.conductor_k) * e.x;
        out = fc.extend(e.y);
    }
    out
}

/// [`scatter_eval`] of a blend: the sum over its BSDFs, each weighted by the probability
/// that `extend`'s choice reaches it (the first BSDF of blend level k: the product of the
/// weights above it times one minus its own), leaving out the BSDF of level `skip`
/// ([`BLEND_NONE`]: none).
#[kernel_fn]
pub fn blend_eval(
    shading: u32,
    materials: &[Material],
    textures: &[Vec4],
    tex_coords: &[Vec4],
    root: Material,
    t: Triangle,
    h: Vec4,
    uv: Vec2,
    d: Vec3,
    wi: Vec3,
    n: Vec3,
    ng: Vec3,
    front: bool,
    skip: u32,
) -> Vec4 {
    let mut m = root;
    let mut reach = 1.0f32;
    let mut sum = Vec4::ZERO;
    let mut level = 0u32;
    while level <= BLEND_LEVELS {
        let nested = m.blend != 0 && level < BLEND_LEVELS;
        let mut w = 0.0f32;
        if nested {
            w = blend_weight(textures, tex_coords, m, t, h);
        }
        let p = reach * (1.0 - w);
        if p > 0.0 && level != skip {
            let mut albedo = m.color;
            if shading & SHADES_TEXTURES != 0 && m.texture != 0 {
                albedo = texture_at_hit(textures, m.texture - 1, uv, t.original, h);
            }
            sum += scatter_eval(
                shading, textures, tex_coords, m, albedo, t, h, uv, d, wi, n, ng, front,
            ) * p;
        }
        if nested {
            reach *= w;
            m = materials[(m.blend - 1) as usize];
            level += 1;
        } else {
            level = BLEND_LEVELS + 1;
        }
    }
    sum
}
