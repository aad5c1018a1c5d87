//! Next-event estimation (light sampling): choosing an emitter triangle in proportion to
//! its power through an alias table, a point uniformly by area on it, or a direction of
//! the constant environment by cosine around the shading normal; and the power heuristic
//! that combines light and BSDF sampling (Veach 1997), as Mitsuba's `path` integrator does.
//!
//! Coherent light sampling (beyond the paper): a coherence group shares the uniform number
//! that picks the light and a stratum (a cell of a K x K grid over the light's unit-square
//! sample domain); each ray draws its own point inside that cell. The group's numbers are
//! uniform, so every ray's sample keeps the distribution (and the pdf) of independent
//! light sampling: the estimator stays unbiased, only the correlation between the rays of
//! a group changes (as with the paper's shared hemisphere patch).

use crate::layout::*;
use cohort::prelude::*;

/// Triangle picked by the alias table for the uniform number `u` in [0, 1).
#[kernel_fn]
pub fn pick_light(lights: &[LightEntry], count: u32, u: f32) -> u32 {
    let scaled = u * count as f32;
    let j = (scaled as u32).min(count - 1);
    let e = lights[j as usize];
    let frac = scaled - j as f32;
    if frac < e.prob {
        e.tri
    } else {
        e.alias_tri
    }
}

/// Point of triangle (v0, v1, v2) for a point `u` of the unit square, uniform by area
/// (the square-root map, which carries equal-area cells of the square to equal-area
/// pieces of the triangle).
#[kernel_fn]
pub fn triangle_point(v0: Vec3, v1: Vec3, v2: Vec3, u: Vec2) -> Vec3 {
    let su = u.x.sqrt();
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    v0 * b0 + v1 * b1 + v2 * (1.0 - b0 - b1)
}

/// The barycentric weights of v1 and v2 (in y and z, as a hit's) of [`triangle_point`]'s
/// point for `u`.
#[kernel_fn]
pub fn triangle_weights(u: Vec2) -> Vec4 {
    let su = u.x.sqrt();
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    Vec4::new(0.0, b1, 1.0 - b0 - b1, 0.0)
}

/// Power-heuristic weight (exponent 2) of a strategy with pdf `a` against one with pdf `b`.
#[kernel_fn]
pub fn mis_power(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// Solid-angle density of picking a point of an emitter triangle with density per area
/// `pdf_area`, seen at distance `dist` under cosine `cos_light` at the light.
#[kernel_fn]
pub fn area_to_solid_angle(pdf_area: f32, dist: f32, cos_light: f32) -> f32 {
    let c = cos_light.abs();
    if c > 0.0 {
        pdf_area * dist * dist / c
    } else {
        0.0
    }
}

/// The group's shared light draws, from the random stream `key`: x = the number that
/// picks the light (and the environment), y = the stratum (cell index, as f32 bits).
#[kernel_fn]
pub fn shared_light_draw(key: u32, cells: u32) -> Vec2 {
    let u = crate::rng::uniform(key, 0);
    let cell = crate::rng::hash(key ^ 0x1d87_2b41) % (cells * cells);
    Vec2::new(u, f32::from_bits(cell))
}

/// Direction from `o` towards delta light `k` (xyz, unit) and the distance to it (w; 3e38
/// for a directional light, which is infinitely far). w = 0: `o` is at the light.
#[kernel_fn]
pub fn delta_light_direction(lights: &[DeltaLight], k: u32, o: Vec3) -> Vec4 {
    let e = lights[k as usize];
    let mut r = Vec4::ZERO;
    if e.kind == DIRECTIONAL_LIGHT {
        r = (-e.direction).extend(3.0e38);
    } else {
        let to = e.position - o;
        let dist = to.length();
        if dist > 0.0 {
            r = (to / dist).extend(dist);
        }
    }
    r
}

/// What delta light `k` delivers along `wi` (towards the light) from `dist` away: its
/// irradiance (directional); its intensity in direction -`wi` over the squared distance
/// (point; spot, with Mitsuba's linear falloff in angle from the beam width to the cutoff,
/// times its texture); or, for a projector, its image's irradiance at the point as Mitsuba
/// defines it (pi scale E(uv) / (z^2 cos), z the depth along its axis).
#[kernel_fn]
pub fn delta_light_arrival(
    lights: &[DeltaLight],
    textures: &[Vec4],
    k: u32,
    wi: Vec3,
    dist: f32,
) -> Vec3 {
    let e = lights[k as usize];
    let mut r = e.intensity;
    if e.kind != DIRECTIONAL_LIGHT {
        let d = -wi;
        let local = Vec3::new(
            e.to_local_x.dot(d),
            e.to_local_y.dot(d),
            e.to_local_z.dot(d),
        );
        if e.kind == PROJECTOR_LIGHT {
            r = Vec3::ZERO;
            let z = local.z * dist;
            let cos = e.direction.dot(d);
            if local.z > 0.0 && cos > 0.0 {
                let t = local.z * e.uv_factor;
                let uv = Vec2::new(0.5 - 0.5 * local.x / t, 0.5 - 0.5 * e.aspect * local.y / t);
                if uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0 {
                    let mut irradiance = e.intensity;
                    if e.texture != 0 {
                        irradiance *= crate::texture::texture_eval(textures, e.texture - 1, uv);
                    }
                    r = irradiance * (core::f32::consts::PI / (z * z * cos));
                }
            }
        } else {
            let mut falloff = 1.0f32;
            if e.kind == SPOT_LIGHT {
                let c = local.z / local.length();
                if c > e.cos_cutoff {
                    if c < e.cos_beam {
                        falloff = (e.cutoff - c.acos()) * e.inv_transition;
                    }
                    if e.texture != 0 {
                        let t = local.z * e.uv_factor;
                        let uv = Vec2::new(0.5 + 0.5 * local.x / t, 0.5 + 0.5 * local.y / t);
                        r = r * crate::texture::texture_eval(textures, e.texture - 1, uv);
                    }
                } else {
                    falloff = 0.0;
                }
            }
            r = r * (falloff / (dist * dist));
        }
    }
    r
}
