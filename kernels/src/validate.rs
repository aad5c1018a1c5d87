//! The kernels of the statistical tests of sampling routines (`cohort_render::validate`):
//! they run a strategy's or a BSDF's own compiled code on the device and write what it
//! drew, for the host to histogram.
//!
//! - [`sample_sampler`]: directions and weights of a [`DiffuseSampler`] for many rays about
//!   a set of normals, the group's draw keyed by the group index and a draw index exactly
//!   as `extend` keys it (`stream(seed, group, draw, 0x5eed)`), at the group level the
//!   kernel is built for.
//! - [`sample_bsdf`] and [`eval_bsdf`]: directions drawn by a BSDF's sampling routine for
//!   one incident direction, with their weights, and the BSDF's density and value at given
//!   directions (for the quadrature of the density per cell).

use crate::layout::*;
use crate::rng::{hash, stream, uniform};
use crate::sampling::{
    cell_point, cosine_hemisphere, fresnel_dielectric, microfacet_eval, microfacet_sample,
    DiffuseSampler,
};
use cohort::prelude::*;

/// What [`sample_sampler`] reads besides the buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct SamplerParams {
    /// Rays of this launch (invocations past it write nothing).
    pub n: u32,
    pub seed: u32,
    /// The draw index: the group draws of one launch are keyed by (group, draw), as
    /// `extend`'s by (group, iteration); a grid-level test launches once per draw.
    pub draw: u32,
    /// N of the N x 4N patches.
    pub patches_n: u32,
    /// Ray `i` samples about normal `i % normals_n`.
    pub normals_n: u32,
    pub pad_a: u32,
    pub pad_b: u32,
    pub pad_c: u32,
}

/// One direction per ray from strategy `S`: `out[i]` = `S::sample(normal, u, group value,
/// patches_n)` (xyz: the world direction, w: its weight), the group value shared by the
/// group of the level the kernel is built for.
#[kernel(workgroup = 64)]
pub fn sample_sampler<S: DiffuseSampler>(
    #[builtin(global_index)] gi: u32,
    p: &SamplerParams,
    normals: &[Vec4],
    out: &mut [Vec4],
) {
    let shared =
        group_share(|group| S::group_value(stream(p.seed, group, p.draw, 0x5eed), p.patches_n));
    if gi < p.n {
        let key = stream(p.seed ^ 0x0ba5_e5ed, gi, p.draw, 1);
        let u = Vec2::new(uniform(key, 0), uniform(key, 1));
        let n = normals[(gi % p.normals_n) as usize].truncate();
        out[gi as usize] = S::sample(n, u, shared, p.patches_n);
    }
}

/// [`BsdfParams::kind`]: the rough conductor (`microfacet::visible_sample`, reflection,
/// `microfacet::conductor_eval`; Fresnel factor 1).
pub const VALIDATE_CONDUCTOR: u32 = 0;
/// The rough dielectric (`rough_dielectric::sample` and `eval`), tints 1.
pub const VALIDATE_DIELECTRIC: u32 = 1;
/// The rough plastic's coating alone (`sampling::microfacet_sample` and
/// `microfacet_eval`, isotropic, Fresnel factor 1).
pub const VALIDATE_COATING: u32 = 2;
/// The rough plastic's sampling as `extend` does it: the coating with probability
/// `choose`, else cosine sampling of the base (albedo `base`), each sample weighted by its
/// own lobe over the probability of choosing it; its density for MIS is the mixture's.
pub const VALIDATE_ROUGH_PLASTIC: u32 = 3;
/// `principled` (the parameters in `principled[0]`).
pub const VALIDATE_PRINCIPLED: u32 = 4;
/// `principledthin`.
pub const VALIDATE_PRINCIPLED_THIN: u32 = 5;
/// The diffuse BSDF (cosine sampling).
pub const VALIDATE_DIFFUSE: u32 = 6;

/// What [`sample_bsdf`] and [`eval_bsdf`] read besides the buffers. Directions are local
/// (z the shading normal); `wo` points towards the viewer.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct BsdfParams {
    /// The viewer direction (unit, local frame).
    pub wo: Vec3,
    /// Invocations of this launch.
    pub n: u32,
    /// Roughness (alpha_u, alpha_v).
    pub alpha: Vec2,
    /// Relative index of refraction (dielectric, plastic coating).
    pub eta: f32,
    /// One of the `VALIDATE_*` kinds.
    pub kind: u32,
    /// 1: Beckmann; 0: GGX.
    pub beckmann: u32,
    pub seed: u32,
    /// Rough plastic: the probability of sampling the coating.
    pub choose: f32,
    /// Rough plastic: the base's diffuse albedo (f = base cos / pi).
    pub base: f32,
    /// Coherent glossy sampling as `extend` does it (`coherent_glossy`): the group shares a
    /// cell of the `cells` x `cells` grid over the unit square, and each invocation's `u` is
    /// placed in it; 0: off.
    pub cells: u32,
    pub pad_a: u32,
    pub pad_b: u32,
    pub pad_c: u32,
}

/// Smith's masking of direction `v` (z > 0) for anisotropic Beckmann, exact:
/// 1 / (1 + Λ), Λ = (erf(b) − 1) / 2 + exp(−b²) / (2 b √π), b = 1 / (α tan θ) (the
/// renderer uses Mitsuba's rational approximation, [`crate::microfacet::beckmann_g1`]).
#[kernel_fn]
pub fn beckmann_g1_exact(v: Vec3, a: Vec2) -> f32 {
    let ax = a.x * v.x;
    let ay = a.y * v.y;
    let xy = ax * ax + ay * ay;
    let mut g = 1.0f32;
    if xy > 0.0 {
        let b = v.z.abs() / xy.sqrt();
        let lambda = 0.5 * (crate::microfacet::erf(b) - 1.0)
            + (-b * b).exp() / (2.0 * b * core::f32::consts::PI.sqrt());
        g = 1.0 / (1.0 + lambda.max(0.0));
    }
    g
}

/// The factor from the density the renderer reports (Mitsuba's, with the rational
/// approximation of Beckmann's G1(wo), off by up to 0.35 %) to the density its
/// visible-normal sampling has (the exact G1(wo)): 1 except for Beckmann's rough conductor
/// and rough dielectric. G1(wo) does not depend on the microfacet, so the factor is one
/// number per viewer direction.
#[kernel_fn]
pub fn sampling_density_factor(p: &BsdfParams) -> f32 {
    let mut k = 1.0f32;
    let visible = (p.kind == VALIDATE_CONDUCTOR) | (p.kind == VALIDATE_DIELECTRIC);
    if (p.beckmann != 0) & visible & (p.wo.z > 0.0) {
        let approx = crate::microfacet::beckmann_g1(p.wo, Vec3::Z, p.alpha);
        if approx > 0.0 {
            k = beckmann_g1_exact(p.wo, p.alpha) / approx;
        }
    }
    k
}

/// The BSDF of `p` at the pair (`wo`, `wi`): x = f·|cos wi| (a scalar: the mean of the
/// channels, tints 1), y = the density the renderer reports for `wi` (its MIS density, what
/// it weighs [`bsdf_sample`]'s samples by), z = the density with which [`bsdf_sample`]
/// actually draws `wi` (y, except where Mitsuba approximates: see
/// [`sampling_density_factor`]).
#[kernel_fn]
pub fn bsdf_eval(p: &BsdfParams, pr: Principled, wi: Vec3) -> Vec3 {
    let r = bsdf_eval_reported(p, pr, wi);
    Vec3::new(r.x, r.y, r.y * sampling_density_factor(p))
}

/// [`bsdf_eval`]'s x and y.
#[kernel_fn]
pub fn bsdf_eval_reported(p: &BsdfParams, pr: Principled, wi: Vec3) -> Vec2 {
    let wo = p.wo;
    let beckmann = p.beckmann != 0;
    let mut r = Vec2::ZERO;
    if p.kind == VALIDATE_CONDUCTOR {
        let e = crate::microfacet::conductor_eval(wo, wi, p.alpha, beckmann);
        r = Vec2::new(e.x, e.y);
    } else if p.kind == VALIDATE_DIELECTRIC {
        let e = crate::bsdf::rough_dielectric::eval(
            wo,
            wi,
            Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::Z),
            p.eta,
            p.alpha,
            beckmann,
        );
        r = Vec2::new(e.x, e.y);
    } else if p.kind == VALIDATE_COATING {
        let e = microfacet_eval(wo, wi, p.alpha.x, beckmann);
        r = Vec2::new(e.x, e.y);
    } else if p.kind == VALIDATE_ROUGH_PLASTIC {
        if (wo.z > 0.0) & (wi.z > 0.0) {
            let e = microfacet_eval(wo, wi, p.alpha.x, beckmann);
            let c = wi.z * core::f32::consts::FRAC_1_PI;
            r = Vec2::new(
                fresnel_dielectric(e.z, p.eta) * e.x + p.base * c,
                p.choose * e.y + (1.0 - p.choose) * c,
            );
        }
    } else if (p.kind == VALIDATE_PRINCIPLED) | (p.kind == VALIDATE_PRINCIPLED_THIN) {
        let kind = if p.kind == VALIDATE_PRINCIPLED_THIN {
            PRINCIPLED_THIN
        } else {
            PRINCIPLED
        };
        let e = crate::bsdf::principled::eval_kind(pr, kind, wo, wi);
        r = Vec2::new((e.x + e.y + e.z) / 3.0, e.w);
    } else if wi.z > 0.0 {
        let c = wi.z * core::f32::consts::FRAC_1_PI;
        r = Vec2::new(c, c);
    }
    r
}

/// One sample of the BSDF of `p` from the random numbers `u` and `choice`: xyz = the
/// direction, w = its weight (f·|cos| / density as the renderer weighs it; 0: no sample).
#[kernel_fn]
pub fn bsdf_sample(p: &BsdfParams, pr: Principled, u: Vec2, choice: f32) -> Vec4 {
    let wo = p.wo;
    let beckmann = p.beckmann != 0;
    let mut r = Vec4::ZERO;
    if p.kind == VALIDATE_CONDUCTOR {
        if wo.z > 0.0 {
            let m = crate::microfacet::visible_sample(wo, p.alpha, beckmann, u);
            let wi = m * (2.0 * wo.dot(m)) - wo;
            let e = crate::microfacet::conductor_eval(wo, wi, p.alpha, beckmann);
            if (wi.z > 0.0) & (e.y > 0.0) {
                r = wi.extend(e.x / e.y);
            }
        }
    } else if p.kind == VALIDATE_DIELECTRIC {
        r = crate::bsdf::rough_dielectric::sample(
            wo,
            Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::Z),
            p.eta,
            p.alpha,
            beckmann,
            u,
            choice,
        );
    } else if p.kind == VALIDATE_COATING {
        let m = microfacet_sample(wo, p.alpha.x, beckmann, u);
        let wi = m * (2.0 * wo.dot(m)) - wo;
        let e = microfacet_eval(wo, wi, p.alpha.x, beckmann);
        if (wi.z > 0.0) & (e.y > 0.0) {
            r = wi.extend(e.x / e.y);
        }
    } else if p.kind == VALIDATE_ROUGH_PLASTIC {
        if choice < p.choose {
            let m = microfacet_sample(wo, p.alpha.x, beckmann, u);
            let wi = m * (2.0 * wo.dot(m)) - wo;
            let e = microfacet_eval(wo, wi, p.alpha.x, beckmann);
            if (wi.z > 0.0) & (e.y > 0.0) {
                let f = fresnel_dielectric(e.z, p.eta);
                r = wi.extend(f * e.x / (e.y * p.choose));
            }
        } else {
            let wi = cosine_hemisphere(u);
            r = wi.extend(p.base / (1.0 - p.choose));
        }
    } else if (p.kind == VALIDATE_PRINCIPLED) | (p.kind == VALIDATE_PRINCIPLED_THIN) {
        let kind = if p.kind == VALIDATE_PRINCIPLED_THIN {
            PRINCIPLED_THIN
        } else {
            PRINCIPLED
        };
        let wl = crate::bsdf::principled::sample_kind(pr, kind, wo, u, choice);
        if wl.dot(wl) > 0.0 {
            let e = crate::bsdf::principled::eval_kind(pr, kind, wo, wl);
            if e.w > 0.0 {
                r = wl.normalize().extend((e.x + e.y + e.z) / (3.0 * e.w));
            }
        }
    } else {
        r = cosine_hemisphere(u).extend(1.0);
    }
    r
}

/// One sample per invocation (the group sharing its cell of `u` where `p.cells` is not 0,
/// at the level the kernel is built for): `out[i]` = [`bsdf_sample`] (direction, weight) and
/// `evals[i]` = [`bsdf_eval`]'s x and y at that direction (f·|cos|, the reported density;
/// zero for no sample).
#[kernel(workgroup = 64)]
pub fn sample_bsdf(
    #[builtin(global_index)] gi: u32,
    p: &BsdfParams,
    principled: &[Principled],
    out: &mut [Vec4],
    evals: &mut [Vec2],
) {
    let shared = group_share(|group| hash(stream(p.seed ^ 0x61c8, group, 0, 0x9e37)));
    if gi < p.n {
        let key = stream(p.seed, gi, 0, 2);
        let mut u = Vec2::new(uniform(key, 0), uniform(key, 1));
        if p.cells != 0 {
            u = cell_point(shared % (p.cells * p.cells), p.cells, u);
        }
        let s = bsdf_sample(p, principled[0], u, uniform(key, 2));
        out[gi as usize] = s;
        let mut e = Vec2::ZERO;
        if s.w != 0.0 {
            e = bsdf_eval_reported(p, principled[0], s.truncate());
        }
        evals[gi as usize] = e;
    }
}

/// [`bsdf_eval`] at each direction `dirs[i]` (xyz), into `out[i]` (xyz; w 0).
#[kernel(workgroup = 64)]
pub fn eval_bsdf(
    #[builtin(global_index)] gi: u32,
    p: &BsdfParams,
    principled: &[Principled],
    dirs: &[Vec4],
    out: &mut [Vec4],
) {
    if gi < p.n {
        out[gi as usize] = bsdf_eval(p, principled[0], dirs[gi as usize].truncate()).extend(0.0);
    }
}
