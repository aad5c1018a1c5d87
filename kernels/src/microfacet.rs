//! Mitsuba's microfacet distribution (`include/mitsuba/render/microfacet.h`): GGX or
//! Beckmann, anisotropic (roughness `a` = (alpha_u, alpha_v) along the shading frame's s
//! and t), with Smith masking and visible-normal sampling (`sample_visible`, Mitsuba's
//! default). Local frame, z the normal; `wi` points towards the viewer.
//!
//! The sampling warps are Mitsuba's (`sample_visible_11`), so that a coherent or stratified
//! choice of `u` means the same here as there; the densities are exact for them.

use cohort::prelude::*;

use crate::sampling::concentric_disk;

const INV_SQRT_PI: f32 = 0.564_189_6;

/// Anisotropic GGX D(m), zero where D cos θ_m is below 1e-20 (as Mitsuba).
#[kernel_fn]
pub fn ggx_d(m: Vec3, a: Vec2) -> f32 {
    let x = m.x / a.x;
    let y = m.y / a.y;
    let t = x * x + y * y + m.z * m.z;
    let d = 1.0 / (core::f32::consts::PI * a.x * a.y * t * t);
    let mut r = 0.0f32;
    if d * m.z > 1.0e-20 {
        r = d;
    }
    r
}

/// Anisotropic Beckmann D(m), zero where D cos θ_m is below 1e-20 (as Mitsuba).
#[kernel_fn]
pub fn beckmann_d(m: Vec3, a: Vec2) -> f32 {
    let x = m.x / a.x;
    let y = m.y / a.y;
    let c2 = m.z * m.z;
    let d = (-(x * x + y * y) / c2).exp() / (core::f32::consts::PI * a.x * a.y * c2 * c2);
    let mut r = 0.0f32;
    if d * m.z > 1.0e-20 {
        r = d;
    }
    r
}

/// Smith's masking of direction `v` for microfacet `m` (anisotropic GGX): zero where `v`
/// sees the microfacet's back.
#[kernel_fn]
pub fn ggx_g1(v: Vec3, m: Vec3, a: Vec2) -> f32 {
    let ax = a.x * v.x;
    let ay = a.y * v.y;
    let xy = ax * ax + ay * ay;
    let mut g = 2.0 / (1.0 + (1.0 + xy / (v.z * v.z)).sqrt());
    if xy == 0.0 {
        g = 1.0;
    }
    if v.dot(m) * v.z <= 0.0 {
        g = 0.0;
    }
    g
}

/// Smith's masking for anisotropic Beckmann, by Mitsuba's rational approximation (under
/// 0.35 % relative error): zero where `v` sees the microfacet's back.
#[kernel_fn]
pub fn beckmann_g1(v: Vec3, m: Vec3, a: Vec2) -> f32 {
    let ax = a.x * v.x;
    let ay = a.y * v.y;
    let xy = ax * ax + ay * ay;
    let b = 1.0 / (xy / (v.z * v.z)).sqrt();
    let mut g = 1.0f32;
    if b < 1.6 {
        g = (3.535 * b + 2.181 * b * b) / (1.0 + 2.276 * b + 2.577 * b * b);
    }
    if xy == 0.0 {
        g = 1.0;
    }
    if v.dot(m) * v.z <= 0.0 {
        g = 0.0;
    }
    g
}

/// D(m) of GGX or Beckmann.
#[kernel_fn]
pub fn d(m: Vec3, a: Vec2, beckmann: bool) -> f32 {
    if beckmann {
        beckmann_d(m, a)
    } else {
        ggx_d(m, a)
    }
}

/// Smith's G1 of GGX or Beckmann.
#[kernel_fn]
pub fn g1(v: Vec3, m: Vec3, a: Vec2, beckmann: bool) -> f32 {
    if beckmann {
        beckmann_g1(v, m, a)
    } else {
        ggx_g1(v, m, a)
    }
}

/// The density of visible normal `m` for a viewer at `wi` (z > 0): D G1 |wi·m| / wi.z.
#[kernel_fn]
pub fn visible_pdf(wi: Vec3, m: Vec3, a: Vec2, beckmann: bool) -> f32 {
    d(m, a, beckmann) * g1(wi, m, a, beckmann) * wi.dot(m).abs() / wi.z
}

/// The error function, |error| < 1.5e-7 (Abramowitz and Stegun 7.1.26).
#[kernel_fn]
pub fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let poly = ((((1.061_405_4 * t - 1.453_152) * t + 1.421_413_8) * t - 0.284_496_74) * t
        + 0.254_829_6)
        * t;
    (1.0 - poly * (-x * x).exp()).copysign(x)
}

/// The inverse error function on (-1, 1) (Giles 2010, single precision).
#[kernel_fn]
pub fn erfinv(x: f32) -> f32 {
    let mut w = -((1.0 - x) * (1.0 + x)).ln();
    let mut p: f32;
    if w < 5.0 {
        w -= 2.5;
        p = 2.810_226_4e-8;
        p = 3.432_739_4e-7 + p * w;
        p = -3.523_387_7e-6 + p * w;
        p = -4.391_506_5e-6 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725 + p * w;
        p = -0.004_177_681_6 + p * w;
        p = 0.246_640_73 + p * w;
        p = 1.501_409_4 + p * w;
    } else {
        w = w.sqrt() - 3.0;
        p = -0.000_200_214_26;
        p = 0.000_100_950_56 + p * w;
        p = 0.001_349_343_2 + p * w;
        p = -0.003_673_428_4 + p * w;
        p = 0.005_739_507_7 + p * w;
        p = -0.007_622_461 + p * w;
        p = 0.009_438_871 + p * w;
        p = 1.001_674 + p * w;
        p = 2.832_976_8 + p * w;
    }
    p * x
}

/// Mitsuba's `sample_visible_11`: the slope of a normal visible from elevation cosine
/// `cos_i` for the distribution of roughness 1. GGX: the concentric-disk construction;
/// Beckmann: Mitsuba's numerical inversion in the erf domain (three Newton steps).
#[kernel_fn]
pub fn slope_11(cos_i: f32, u: Vec2, beckmann: bool) -> Vec2 {
    let slope: Vec2;
    if beckmann {
        let tan_i = (1.0 - cos_i * cos_i).max(0.0).sqrt() / cos_i;
        let cot_i = 1.0 / tan_i;
        let maxval = erf(cot_i);
        let ux = u.x.clamp(1.0e-6, 1.0 - 1.0e-6);
        let uy = u.y.clamp(1.0e-6, 1.0 - 1.0e-6);
        let mut x = maxval - (maxval + 1.0) * erf((-ux.ln()).sqrt());
        let target = ux * (1.0 + maxval + INV_SQRT_PI * tan_i * (-cot_i * cot_i).exp());
        let mut i = 0u32;
        while i < 3 {
            let s = erfinv(x);
            let value = 1.0 + x + INV_SQRT_PI * tan_i * (-s * s).exp() - target;
            let derivative = 1.0 - s * tan_i;
            x -= value / derivative;
            i += 1;
        }
        slope = Vec2::new(erfinv(x), erfinv(2.0 * uy - 1.0));
    } else {
        let p = concentric_disk(u);
        let s = 0.5 * (1.0 + cos_i);
        let x = p.x;
        let y = (1.0 - x * x).max(0.0).sqrt() * (1.0 - s) + p.y * s;
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        let sin_i = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        let norm = 1.0 / (sin_i * y + cos_i * z);
        slope = Vec2::new((cos_i * y - sin_i * z) * norm, x * norm);
    }
    slope
}

/// A normal visible from `wi` (z > 0), by Mitsuba's mapping of `u`: the viewer stretched
/// to roughness 1, [`slope_11`]'s slope, rotated back and unstretched. Its density is
/// [`visible_pdf`].
#[kernel_fn]
pub fn visible_sample(wi: Vec3, a: Vec2, beckmann: bool, u: Vec2) -> Vec3 {
    let wp = Vec3::new(a.x * wi.x, a.y * wi.y, wi.z).normalize();
    let sin2 = 1.0 - wp.z * wp.z;
    let mut cos_phi = 1.0f32;
    let mut sin_phi = 0.0f32;
    // Mitsuba's 4 x drjit's epsilon (2^-24).
    if sin2.abs() > 2.384_185_8e-7 {
        let inv = 1.0 / sin2.sqrt();
        cos_phi = (wp.x * inv).clamp(-1.0, 1.0);
        sin_phi = (wp.y * inv).clamp(-1.0, 1.0);
    }
    let s = slope_11(wp.z, u, beckmann);
    let sx = (cos_phi * s.x - sin_phi * s.y) * a.x;
    let sy = (sin_phi * s.x + cos_phi * s.y) * a.y;
    Vec3::new(-sx, -sy, 1.0).normalize()
}

/// Mitsuba's `roughconductor` for local directions `wi` (viewer) and `wo`: x = f·cos
/// without the Fresnel factor and the specular reflectance, D G / (4 wi.z); y = the density
/// of `wo` under visible-normal sampling and reflection, D G1(wi) / (4 wi.z); z = the
/// cosine between `wi` and the half vector (the Fresnel factor's angle). Zero below either
/// horizon.
#[kernel_fn]
pub fn conductor_eval(wi: Vec3, wo: Vec3, a: Vec2, beckmann: bool) -> Vec4 {
    let mut r = Vec4::ZERO;
    if (wi.z > 0.0) & (wo.z > 0.0) {
        let m = (wi + wo).normalize();
        let dm = d(m, a, beckmann);
        let gi = g1(wi, m, a, beckmann);
        let f = dm * gi * g1(wo, m, a, beckmann) / (4.0 * wi.z);
        let pdf = dm * gi / (4.0 * wi.z);
        r = Vec4::new(f, pdf, wi.dot(m), 0.0);
    }
    r
}
