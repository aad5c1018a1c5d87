//! Mitsuba's `blendbsdf`: what a blend of the table's BSDFs (`crate::bsdf`) scatters
//! towards a given direction, `f · cos` and the density with which BSDF sampling draws it.
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

use crate::bsdf::principled::component;
use crate::bsdf::{bsdf_eval, hit};
use crate::layout::*;
use crate::shading::*;
use crate::texture::{hit_uv, luminance, texture_at_hit};
use cohort::prelude::*;

/// Blends nested deeper than this take their last BSDF as it is (as `extend`'s choice does).
pub const BLEND_LEVELS: u32 = 4;
/// [`blend_eval`]'s `skip` that leaves no BSDF out.
pub const BLEND_NONE: u32 = BLEND_LEVELS + 1;

/// The weight of a blend material `m`'s second BSDF at the hit: its number, or the
/// luminance of its texture, clamped to [0, 1] (Mitsuba's `eval_weight`). A texture is
/// read only where the scene's set `shading` has textures.
#[kernel_fn]
pub fn blend_weight(
    shading: u32,
    textures: &[Vec4],
    tex_coords: &[Vec4],
    m: Material,
    t: Triangle,
    h: Vec4,
) -> f32 {
    let mut weight = m.blend_weight;
    if shading & SHADES_TEXTURES != 0 && m.blend_texture != 0 {
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

/// The weights of blend `root`'s levels 0 to 3 (x to w; 0 past its last blend), read once
/// per vertex: `extend`'s choice and [`blend_eval`] both take them from here (level k's
/// is `component(weights, k)`), so that a weight's texture lookup is inlined once.
#[kernel_fn]
pub fn blend_weights(
    shading: u32,
    materials: &[Material],
    textures: &[Vec4],
    tex_coords: &[Vec4],
    root: Material,
    t: Triangle,
    h: Vec4,
) -> Vec4 {
    let mut m = root;
    let mut weights = Vec4::ZERO;
    let mut level = 0u32;
    while level < BLEND_LEVELS && m.blend != 0 {
        let w = blend_weight(shading, textures, tex_coords, m, t, h);
        if level == 0 {
            weights.x = w;
        } else if level == 1 {
            weights.y = w;
        } else if level == 2 {
            weights.z = w;
        } else {
            weights.w = w;
        }
        m = materials[(m.blend - 1) as usize];
        level += 1;
    }
    weights
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

/// [`bsdf_eval`] of a blend: the sum over its BSDFs, each weighted by the probability
/// that `extend`'s choice reaches it (the first BSDF of blend level k: the product of the
/// weights above it times one minus its own), leaving out the BSDF of level `skip`
/// ([`BLEND_NONE`]: none) and descending at most `levels` levels (0: `root`'s own BSDF
/// alone, weight 1, whether or not it is a blend). `weights` are `root`'s
/// [`blend_weights`].
///
/// In a kernel that shades blends this is the only call site of [`bsdf_eval`]: `extend`
/// evaluates every light sample through it, a blend's or not, so that each BSDF's `eval`
/// is inlined once (pipeline creation time grows faster than the code).
#[kernel_fn]
pub fn blend_eval(
    shading: u32,
    materials: &[Material],
    textures: &[Vec4],
    tex_coords: &[Vec4],
    root: Material,
    weights: Vec4,
    t: Triangle,
    h: Vec4,
    uv: Vec2,
    d: Vec3,
    wi: Vec3,
    n: Vec3,
    ng: Vec3,
    front: bool,
    skip: u32,
    levels: u32,
) -> Vec4 {
    let mut m = root;
    let mut reach = 1.0f32;
    let mut sum = Vec4::ZERO;
    let mut level = 0u32;
    while level <= BLEND_LEVELS {
        let nested = m.blend != 0 && level < levels;
        let mut w = 0.0f32;
        if nested {
            w = component(weights, level);
        }
        let p = reach * (1.0 - w);
        if p > 0.0 && level != skip {
            let mut albedo = m.color;
            if shading & SHADES_TEXTURES != 0 && m.texture != 0 {
                albedo = texture_at_hit(textures, m.texture - 1, uv, t.original, h);
            }
            let at = hit(m, t, h, albedo, uv, d, n, ng, front);
            sum += bsdf_eval(shading, textures, tex_coords, at, wi) * p;
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
