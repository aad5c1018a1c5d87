//! The environment, what rays that leave the scene see: Mitsuba's `constant` emitter
//! (`Frame::environment`) or its `envmap`, a latitude-longitude image laid out in the
//! textures array by `cohort_scenes::EnvironmentMap::gpu_layout` (mapping, density and
//! layout are described there). Its radiance by direction, light sampling towards it, and
//! the density of that sampling for MIS:
//! - constant: a cosine-distributed direction around the shading normal;
//! - map: Mitsuba's density, the bilinear interpolation of luminance x sin(theta) over the
//!   texel centres, sampled exactly (a cell through an alias table, then a point of the
//!   cell by inverting its bilinear density).

use crate::layout::*;
use crate::shading::SHADES_ENV_MAP;
use cohort::prelude::*;

/// Entries of the map's header in the textures array (`cohort_scenes::environment_map`).
pub const ENV_HEADER: u32 = 7;

/// 1 / (2 pi^2): the Jacobian of the (u, v) square to the sphere's solid angle, over sin(theta).
const INV_TWO_PI_SQUARED: f32 = 0.050_660_59;

/// World direction `d` in the frame of the map at `base` (unit length).
#[kernel_fn]
pub fn env_local(textures: &[Vec4], base: u32, d: Vec3) -> Vec3 {
    Vec3::new(
        textures[(base + 1) as usize].truncate().dot(d),
        textures[(base + 2) as usize].truncate().dot(d),
        textures[(base + 3) as usize].truncate().dot(d),
    )
    .normalize()
}

/// Continuous texel coordinates of the map-frame direction `l`: x in [0, w) along the
/// longitude (texel centres at integers, periodic), y in [0, h - 1] along the colatitude.
#[kernel_fn]
pub fn env_texel_coords(l: Vec3, w: f32, h: f32) -> Vec2 {
    let u = l.x.atan2(-l.z) * (0.5 * core::f32::consts::FRAC_1_PI);
    let v = l.y.clamp(-1.0, 1.0).acos() * core::f32::consts::FRAC_1_PI;
    let mut x = u * w - 0.5;
    x -= w * (x / w).floor();
    Vec2::new(x.min(w - 0.0001), v * (h - 1.0))
}

/// Radiance the map at `base` sends along world direction `d` (towards the scene from -`d`):
/// the texels interpolated bilinearly, as Mitsuba's `envmap` evaluates it.
#[kernel_fn]
pub fn env_map_radiance(textures: &[Vec4], base: u32, d: Vec3) -> Vec3 {
    let h0 = textures[base as usize];
    let w = h0.x.to_bits();
    let h = h0.y.to_bits();
    let c = env_texel_coords(env_local(textures, base, d), w as f32, h as f32);
    let x0 = (c.x as u32).min(w - 1);
    let y0 = (c.y as u32).min(h - 2);
    let fx = c.x - x0 as f32;
    let fy = c.y - y0 as f32;
    let x1 = (x0 + 1) % w;
    let t = base + ENV_HEADER;
    let a = textures[(t + y0 * w + x0) as usize].truncate();
    let b = textures[(t + y0 * w + x1) as usize].truncate();
    let cc = textures[(t + (y0 + 1) * w + x0) as usize].truncate();
    let dd = textures[(t + (y0 + 1) * w + x1) as usize].truncate();
    (a * (1.0 - fx) + b * fx) * (1.0 - fy) + (cc * (1.0 - fx) + dd * fx) * fy
}

/// The normalised (u, v) density of the map at `base` at texel coordinates `c` (the bilinear
/// interpolation of the density at the four surrounding texel centres).
#[kernel_fn]
pub fn env_uv_density(textures: &[Vec4], base: u32, w: u32, h: u32, c: Vec2) -> f32 {
    let x0 = (c.x as u32).min(w - 1);
    let y0 = (c.y as u32).min(h - 2);
    let fx = c.x - x0 as f32;
    let fy = c.y - y0 as f32;
    let t = base + ENV_HEADER + w * h;
    let k = t + y0 * (w + 1) + x0;
    let a = textures[k as usize].z;
    let b = textures[(k + 1) as usize].z;
    let cc = textures[(k + w + 1) as usize].z;
    let dd = textures[(k + w + 2) as usize].z;
    (a * (1.0 - fx) + b * fx) * (1.0 - fy) + (cc * (1.0 - fx) + dd * fx) * fy
}

/// Solid-angle density with which `env_map_sample` draws world direction `d` (Mitsuba's
/// `pdf_direction`).
#[kernel_fn]
pub fn env_map_pdf(textures: &[Vec4], base: u32, d: Vec3) -> f32 {
    let h0 = textures[base as usize];
    let w = h0.x.to_bits();
    let h = h0.y.to_bits();
    let l = env_local(textures, base, d);
    let c = env_texel_coords(l, w as f32, h as f32);
    let sin_theta = (l.x * l.x + l.z * l.z).max(1.0e-14).sqrt();
    env_uv_density(textures, base, w, h, c) * INV_TWO_PI_SQUARED / sin_theta
}

/// A point t in [0, 1] with density proportional to (1 - t) a + t b, for the uniform `u`.
#[kernel_fn]
pub fn sample_linear(a: f32, b: f32, u: f32) -> f32 {
    let mut t = u;
    if (a - b).abs() > 1.0e-6 * (a + b) {
        t = (a - (a * a * (1.0 - u) + b * b * u).max(0.0).sqrt()) / (a - b);
    }
    t.clamp(0.0, 1.0)
}

/// A world direction drawn from the map at `base` for the uniform point `u` (xyz), and its
/// solid-angle density (w; 0 where the map is black).
#[kernel_fn]
pub fn env_map_sample(textures: &[Vec4], base: u32, u: Vec2) -> Vec4 {
    let h0 = textures[base as usize];
    let w = h0.x.to_bits();
    let h = h0.y.to_bits();
    let t = base + ENV_HEADER + w * h;
    // The cell, through the alias table; what is left of u.x places the point across it.
    let cells = w * (h - 1);
    let scaled = u.x * cells as f32;
    let j = (scaled as u32).min(cells - 1);
    let e = textures[(t + j) as usize];
    let mut frac = scaled - j as f32;
    let mut cell = j;
    if frac < e.x {
        frac /= e.x;
    } else {
        cell = e.y.to_bits();
        frac = (frac - e.x) / (1.0 - e.x);
    }
    let cx = cell % w;
    let cy = cell / w;
    let k = t + cy * (w + 1) + cx;
    let v00 = textures[k as usize].z;
    let v10 = textures[(k + 1) as usize].z;
    let v01 = textures[(k + w + 1) as usize].z;
    let v11 = textures[(k + w + 2) as usize].z;
    // Across the cell (marginal: linear), then down it given x (linear again).
    let tx = sample_linear(v00 + v01, v10 + v11, frac.clamp(0.0, 1.0));
    let top = v00 + (v10 - v00) * tx;
    let bottom = v01 + (v11 - v01) * tx;
    let ty = sample_linear(top, bottom, u.y);
    let density = top + (bottom - top) * ty;
    let uu = (cx as f32 + tx + 0.5) / w as f32;
    let vv = (cy as f32 + ty) / (h - 1) as f32;
    let theta = vv * core::f32::consts::PI;
    let phi = uu * (2.0 * core::f32::consts::PI);
    let sin_theta = theta.sin();
    let l = Vec3::new(phi.sin() * sin_theta, theta.cos(), -phi.cos() * sin_theta);
    let world = Vec3::new(
        textures[(base + 4) as usize].truncate().dot(l),
        textures[(base + 5) as usize].truncate().dot(l),
        textures[(base + 6) as usize].truncate().dot(l),
    )
    .normalize();
    let mut pdf = 0.0f32;
    if sin_theta > 0.0 {
        pdf = density * INV_TWO_PI_SQUARED / sin_theta;
    }
    world.extend(pdf)
}

/// Radiance of the environment arriving along direction `d` (a ray leaving the scene).
/// `shading`: the scene's set (`crate::shading`); the map is read where it has one.
#[kernel_fn]
pub fn environment_radiance(shading: u32, f: &Frame, textures: &[Vec4], d: Vec3) -> Vec3 {
    let mut r = f.environment;
    if shading & SHADES_ENV_MAP != 0 && f.env_map != 0 {
        r = env_map_radiance(textures, f.env_map - 1, d);
    }
    r
}

/// A light-sampling direction towards the environment from a surface with normal `n`, for
/// the uniform point `u` (xyz), and its solid-angle density (w), not yet times the
/// probability `Frame::env_light` of choosing the environment.
#[kernel_fn]
pub fn environment_sample(shading: u32, f: &Frame, textures: &[Vec4], n: Vec3, u: Vec2) -> Vec4 {
    if shading & SHADES_ENV_MAP != 0 && f.env_map != 0 {
        env_map_sample(textures, f.env_map - 1, u)
    } else {
        let wi = crate::sampling::frame(n) * crate::sampling::cosine_hemisphere(u);
        wi.extend(wi.dot(n).max(0.0) * core::f32::consts::FRAC_1_PI)
    }
}

/// Density with which light sampling at a surface of normal `n` draws direction `d`
/// towards the environment, the choice of the environment included (0 without one): what
/// MIS weighs a BSDF-sampled ray that leaves the scene against.
#[kernel_fn]
pub fn environment_pdf(shading: u32, f: &Frame, textures: &[Vec4], n: Vec3, d: Vec3) -> f32 {
    let mut p = 0.0f32;
    if f.env_light > 0.0 {
        if shading & SHADES_ENV_MAP != 0 && f.env_map != 0 {
            p = env_map_pdf(textures, f.env_map - 1, d);
        } else {
            p = d.dot(n).max(0.0) * core::f32::consts::FRAC_1_PI;
        }
        p *= f.env_light;
    }
    p
}
