//! Mitsuba `principled` and `principledthin` (Disney's principled BSDF as Mitsuba 3.9
//! defines it: `principled.cpp`, `principledthin.cpp`, `principledhelpers.h`).
//!
//! Everything here is in the shading frame (z the shading normal), with `wi` pointing
//! towards the viewer and `wo` the other direction, as in Mitsuba. The functions follow
//! Mitsuba's arithmetic step by step, quirks included, because the image must match its
//! expectation: `principled` picks its lobe with probabilities from the Fresnel factor of
//! the specular normal drawn with the same 2D sample that then places the diffuse or
//! clearcoat direction, and weighs the sample by `eval / pdf` where `pdf` uses the Fresnel
//! factor of the half vector. So the warps are Mitsuba's too: its GGX visible-normal
//! sampling (`sample_visible_11`) and its concentric cosine hemisphere.
//!
//! Transmission scales radiance by 1 / eta², as Mitsuba's radiance transport and
//! `rough_dielectric` do.

use super::{absorbed, scattered, Bsdf, Draws, Hit, Scattered, Shaded};
use crate::layout::*;
use crate::microfacet::{ggx_d, ggx_g1, visible_pdf, visible_sample};
use crate::sampling::{concentric_disk, fresnel_dielectric, DiffuseSampler};
use crate::texture::luminance;
use cohort::prelude::*;

const INV_PI: f32 = core::f32::consts::FRAC_1_PI;

/// The parameters of material `m` (kind `PRINCIPLED` or `PRINCIPLED_THIN`) with base
/// colour `base_color`, at hit `h` of triangle `original` (texture coordinates `uv`): its
/// parameter block (`m.table`), laid out by `cohort_scenes::Principled::gpu_block`, with
/// each textured parameter read there.
#[kernel_fn]
pub fn params(
    textures: &[Vec4],
    m: Material,
    base_color: Vec3,
    uv: Vec2,
    original: u32,
    h: Vec4,
) -> Principled {
    let at = (m.table - 1) as usize;
    let c = textures[at + 2];
    let r = textures[at + 3];
    // The eleven numbers that may be textured (roughness .. diff_trans, four to a texel,
    // their texture headers three texels on): one texture read site in a loop rather than
    // eleven inlined copies of it, since pipeline creation time grows with the code.
    let mut v = [0.0f32; 11];
    let mut k = 0u32;
    while k < 11 {
        let q = at + (k / 4) as usize;
        let header = component(textures[q + 4], k % 4);
        v[k as usize] = number_at(
            textures,
            header,
            component(textures[q], k % 4),
            uv,
            original,
            h,
        );
        k += 1;
    }
    Principled {
        base_color,
        roughness: v[0],
        anisotropic: v[1],
        metallic: v[2],
        spec_trans: v[3],
        spec_tint: v[4],
        sheen: v[5],
        sheen_tint: v[6],
        clearcoat: v[7],
        clearcoat_gloss: v[8],
        flatness: v[9],
        diff_trans: v[10],
        eta: c.w,
        rate_a: r.x,
        rate_b: r.y,
        rate_c: r.z,
        rate_d: r.w,
        pad: 0,
    }
}

/// Component `i` (0 to 3) of `v`.
#[kernel_fn]
pub fn component(v: Vec4, i: u32) -> f32 {
    let mut c = v.w;
    if i == 0 {
        c = v.x;
    } else if i == 1 {
        c = v.y;
    } else if i == 2 {
        c = v.z;
    }
    c
}

/// A parameter given as `value`, or, where `header` holds a texture's header + 1 (as
/// bits), that texture read as a number at the hit (Mitsuba's `eval_1`: its luminance).
#[kernel_fn]
pub fn number_at(
    textures: &[Vec4],
    header: f32,
    value: f32,
    uv: Vec2,
    original: u32,
    h: Vec4,
) -> f32 {
    let k = header.to_bits();
    let mut v = value;
    if k != 0 {
        v = luminance(crate::texture::texture_at_hit(
            textures,
            k - 1,
            uv,
            original,
            h,
        ));
    }
    v
}

/// Schlick's weight (1 - cos)^5, with 1 - cos clamped to [0, 1].
#[kernel_fn]
pub fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    m * m * m * m * m
}

/// Mitsuba's `calc_schlick`: Schlick's Fresnel from `r0` at microfacet cosine `cos_i`
/// (negative: from inside), using the transmitted angle where the light leaves a denser
/// medium.
#[kernel_fn]
pub fn schlick(r0: Vec3, cos_i: f32, eta: f32) -> Vec3 {
    let mut eta_it = eta;
    if cos_i < 0.0 {
        eta_it = 1.0 / eta;
    }
    let eta_ti = 1.0 / eta_it;
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (eta_ti * eta_ti);
    let mut w = schlick_weight(cos_i.abs());
    if eta_it <= 1.0 {
        w = schlick_weight(cos_t2.max(0.0).sqrt());
    }
    r0 + (Vec3::ONE - r0) * w
}

/// Schlick's reflectance at normal incidence for relative index `eta`.
#[kernel_fn]
pub fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Mitsuba's `fresnel` reflectance for a signed cosine `cos_i` (negative: arriving from
/// inside, where the index ratio inverts) at relative index `eta`.
#[kernel_fn]
pub fn fresnel_signed(cos_i: f32, eta: f32) -> f32 {
    let mut f = 0.0f32;
    if eta != 1.0 {
        if cos_i >= 0.0 {
            f = fresnel_dielectric(cos_i, eta);
        } else {
            f = fresnel_dielectric(-cos_i, 1.0 / eta);
        }
    }
    f
}

/// Mitsuba's `calc_dist_params`: GGX (alpha_x, alpha_y) from roughness and anisotropy.
#[kernel_fn]
pub fn dist_alpha(roughness: f32, anisotropic: f32) -> Vec2 {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).sqrt();
    Vec2::new((r2 / aspect).max(0.001), (r2 * aspect).max(0.001))
}

/// Mitsuba's cosine-weighted hemisphere (through the concentric disk).
#[kernel_fn]
pub fn cosine_concentric(u: Vec2) -> Vec3 {
    let p = concentric_disk(u);
    Vec3::new(p.x, p.y, (1.0 - p.x * p.x - p.y * p.y).max(0.0).sqrt())
}

/// The clearcoat's GTR1 distribution D(m) of roughness `alpha`.
#[kernel_fn]
pub fn gtr1_d(m: Vec3, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = (a2 - 1.0) / (core::f32::consts::PI * a2.ln() * (1.0 + (a2 - 1.0) * m.z * m.z));
    let mut r = 0.0f32;
    if d * m.z > 1.0e-20 {
        r = d;
    }
    r
}

/// A GTR1 normal drawn with density D(m) cos θ_m.
#[kernel_fn]
pub fn gtr1_sample(alpha: f32, u: Vec2) -> Vec3 {
    let phi = 2.0 * core::f32::consts::PI * u.x;
    let a2 = alpha * alpha;
    let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
    let sin = (1.0 - cos2).max(0.0).sqrt();
    let cos = cos2.max(0.0).sqrt();
    Vec3::new(phi.cos() * sin, phi.sin() * sin, cos)
}

/// The clearcoat's separable masking term for one direction (`smith_ggx1`).
#[kernel_fn]
pub fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    let c = v.z.abs();
    let tan2 = (1.0 - c * c) / (c * c);
    let mut g = 2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt());
    if v.z == 1.0 {
        g = 1.0;
    }
    if v.dot(m) * v.z <= 0.0 {
        g = 0.0;
    }
    g
}

/// Mitsuba's `mac_mic_compatibility`: both directions see the microfacet `m` (turned to
/// the viewer's side of the surface, `ci` the viewer's cosine) from its front, or for
/// refraction `wo` from its back.
#[kernel_fn]
pub fn compatible(m: Vec3, wi: Vec3, wo: Vec3, ci: f32, reflection: bool) -> bool {
    let mut s = m;
    if ci < 0.0 {
        s = -m;
    }
    let o = wo.dot(s);
    wi.dot(s) > 0.0 && ((reflection && o > 0.0) || (!reflection && o < 0.0))
}

/// `reflect` of Mitsuba: `wi` mirrored about `m`.
#[kernel_fn]
pub fn reflect(wi: Vec3, m: Vec3) -> Vec3 {
    m * (2.0 * wi.dot(m)) - wi
}

/// The colour tint of the base colour (itself over its luminance; white where black).
#[kernel_fn]
pub fn tint(base: Vec3) -> Vec3 {
    let lum = luminance(base);
    let mut c = Vec3::ONE;
    if lum > 0.0 {
        c = base / lum;
    }
    c
}

/// Mitsuba's `principled_fresnel`: on the front, the dielectric Fresnel factor `f` blended
/// with Schlick's metallic and tinted responses; on the back, `bsdf` times `f`.
#[kernel_fn]
pub fn principled_fresnel(p: Principled, f: f32, cos_i: f32, front: bool, bsdf: f32) -> Vec3 {
    let mut r = Vec3::splat(bsdf * f);
    if front {
        let mut eta_it = p.eta;
        if cos_i < 0.0 {
            eta_it = 1.0 / p.eta;
        }
        let mut fs = Vec3::ZERO;
        if p.metallic != 0.0 {
            fs += schlick(p.base_color, cos_i, p.eta) * p.metallic;
        }
        if p.spec_tint != 0.0 {
            let f0 = tint(p.base_color) * schlick_r0(eta_it);
            fs += schlick(f0, cos_i, p.eta) * ((1.0 - p.metallic) * p.spec_tint);
        }
        r = Vec3::splat((1.0 - p.metallic) * (1.0 - p.spec_tint) * f) + fs;
    }
    r
}

/// The diffuse lobes' shape (Burley's diffuse and retro-reflection, blended towards the
/// fake subsurface term by `flatness`) for cosines `ci`, `co` and half-vector cosine `cd`.
#[kernel_fn]
pub fn diffuse_shape(p: Principled, ci: f32, co: f32, cd: f32) -> f32 {
    let fo = schlick_weight(co.abs());
    let fi = schlick_weight(ci.abs());
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * p.roughness * cd * cd;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    let mut shape = f_diff + f_retro;
    if p.flatness != 0.0 {
        let fss90 = rr / 2.0;
        let fss = (1.0 - fo + fss90 * fo) * (1.0 - fi + fss90 * fi);
        let f_ss = 1.25 * (fss * (1.0 / (co.abs() + ci.abs()) - 0.5) + 0.5);
        shape = shape * (1.0 - p.flatness) + f_ss * p.flatness;
    }
    shape
}

/// The sheen lobe's colour for half-vector cosine `cd` (without the weights).
#[kernel_fn]
pub fn sheen_color(p: Principled, cd: f32) -> Vec3 {
    let mut c = Vec3::ONE;
    if p.sheen_tint != 0.0 {
        c = Vec3::ONE * (1.0 - p.sheen_tint) + tint(p.base_color) * p.sheen_tint;
    }
    c * schlick_weight(cd.abs())
}

/// Three lobes' sampling weights `w` as probabilities, a fourth of weight `rest` taking the
/// remainder (all zero where every weight is).
#[kernel_fn]
pub fn shares(w: Vec3, rest: f32) -> Vec3 {
    let total = w.x + w.y + w.z + rest;
    let mut r = Vec3::ZERO;
    if total > 0.0 {
        r = w / total;
    }
    r
}

/// The clearcoat's GTR1 roughness: 0.1 to 0.001 as `clearcoat_gloss` goes from 0 to 1.
#[kernel_fn]
pub fn clearcoat_alpha(p: Principled) -> f32 {
    0.1 * (1.0 - p.clearcoat_gloss) + 0.001 * p.clearcoat_gloss
}

/// `principledthin`'s transmission roughness: the roughness scaled by the film's index.
#[kernel_fn]
pub fn thin_transmission_alpha(p: Principled) -> Vec2 {
    dist_alpha((0.65 * p.eta - 0.35) * p.roughness, p.anisotropic)
}

/// `principled`'s lobe probabilities for specular Fresnel factor `f`: x diffuse,
/// y clearcoat, z specular transmission (specular reflection takes the rest), normalised.
#[kernel_fn]
pub fn lobe_probabilities(p: Principled, f: f32, front: bool) -> Vec3 {
    let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
    let bsdf = (1.0 - p.metallic) * p.spec_trans;
    let mut reflect = f;
    let mut trans = 0.0f32;
    let mut clearcoat = 0.0f32;
    let mut diffuse = 0.0f32;
    if front {
        reflect = p.rate_a * (1.0 - bsdf * (1.0 - f));
        clearcoat = 0.25 * p.clearcoat * p.rate_b;
        diffuse = brdf * p.rate_c;
    }
    if p.spec_trans != 0.0 {
        trans = 1.0 - f;
        if front {
            trans = p.rate_a * bsdf * (1.0 - f);
        }
    }
    shares(Vec3::new(diffuse, clearcoat, trans), reflect)
}

/// `principled`: xyz = f·|cos| for directions `wi`, `wo`, w = the density with which
/// [`sample`] draws `wo` by Mitsuba's `pdf`.
#[kernel_fn]
pub fn eval(p: Principled, wi: Vec3, wo: Vec3) -> Vec4 {
    let ci = wi.z;
    let mut value = Vec3::ZERO;
    let mut pdf = 0.0f32;
    if ci != 0.0 {
        let brdf = (1.0 - p.metallic) * (1.0 - p.spec_trans);
        let bsdf = (1.0 - p.metallic) * p.spec_trans;
        let co = wo.z;
        let reflect = ci * co > 0.0;
        let refract = ci * co < 0.0;
        let front = ci > 0.0;
        let mut eta_path = p.eta;
        if !front {
            eta_path = 1.0 / p.eta;
        }
        let a = dist_alpha(p.roughness, p.anisotropic);
        let mut k = 1.0f32;
        if !reflect {
            k = eta_path;
        }
        let mut wh = (wi + wo * k).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let cih = wi.dot(wh);
        let coh = wo.dot(wh);
        let f = fresnel_signed(cih, p.eta);
        let reflect_ok = reflect && compatible(wh, wi, wo, ci, true);
        let refract_ok = refract && compatible(wh, wi, wo, ci, false);
        let d = ggx_d(wh, a);
        let g = ggx_g1(wi, wh, a) * ggx_g1(wo, wh, a);
        let cc_alpha = clearcoat_alpha(p);
        if reflect_ok && f > 0.0 {
            value += principled_fresnel(p, f, cih, front, bsdf) * (d * g / (4.0 * ci.abs()));
        }
        if p.spec_trans != 0.0 && bsdf > 0.0 && refract_ok && f < 1.0 {
            let den = cih + eta_path * coh;
            // Mitsuba's radiance scale 1 / eta_path² cancels the eta_path² of the
            // transmission term.
            let t = (1.0 - f) * d * g * cih * coh / (ci * den * den);
            let b = p.base_color;
            value += Vec3::new(b.x.sqrt(), b.y.sqrt(), b.z.sqrt()) * (bsdf * t.abs());
        }
        if p.clearcoat > 0.0 && reflect_ok && front {
            let fcc = schlick(Vec3::splat(0.04), cih, p.eta).x;
            let gcc = smith_ggx1(wi, wh, 0.25) * smith_ggx1(wo, wh, 0.25);
            value += Vec3::splat(p.clearcoat * 0.25 * fcc * gtr1_d(wh, cc_alpha) * gcc * co.abs());
        }
        // Sheen only with the diffuse lobe: Mitsuba's scalar variants add it inside that
        // branch.
        if brdf > 0.0 && reflect && front {
            let cd = wh.dot(wo);
            value += p.base_color * (brdf * co.abs() * INV_PI * diffuse_shape(p, ci, co, cd));
            if p.sheen > 0.0 && 1.0 - p.metallic > 0.0 {
                value += sheen_color(p, cd) * (p.sheen * (1.0 - p.metallic) * co.abs());
            }
        }
        let probs = lobe_probabilities(p, f, front);
        let p_reflect = 1.0 - probs.x - probs.y - probs.z;
        let mut dwh = (1.0 / (4.0 * coh)).abs();
        if p.spec_trans != 0.0 && !reflect {
            let den = cih + eta_path * coh;
            dwh = (eta_path * eta_path * coh / (den * den)).abs();
        }
        let mut wi_up = wi;
        if !front {
            wi_up = -wi;
        }
        if reflect_ok {
            pdf += p_reflect * visible_pdf(wi_up, wh, a, false) * dwh;
            if p.clearcoat != 0.0 {
                let mut cc = 0.0f32;
                if wh.z >= 0.0 {
                    cc = wh.z * gtr1_d(wh, cc_alpha);
                }
                pdf += probs.y * cc * dwh;
            }
        }
        if reflect {
            pdf += probs.x * INV_PI * co;
        }
        if p.spec_trans != 0.0 && refract_ok {
            pdf += probs.z * visible_pdf(wi_up, wh, a, false) * dwh;
        }
    }
    value.extend(pdf)
}

/// `principled`: a direction `wo` for the viewer at `wi`, drawn as Mitsuba draws it (`u`
/// places it, `choice` picks the lobe); zero where the sample fails. Its weight is
/// [`eval`]'s value over its density.
#[kernel_fn]
pub fn sample(p: Principled, wi: Vec3, u: Vec2, choice: f32) -> Vec3 {
    let ci = wi.z;
    let mut wo = Vec3::ZERO;
    let front = ci > 0.0;
    let bsdf = (1.0 - p.metallic) * p.spec_trans;
    if ci != 0.0 && (front || bsdf > 0.0) {
        let a = dist_alpha(p.roughness, p.anisotropic);
        let mut wi_up = wi;
        if !front {
            wi_up = -wi;
        }
        let m = visible_sample(wi_up, a, false, u);
        let cim = wi.dot(m);
        let f = fresnel_signed(cim, p.eta);
        let probs = lobe_probabilities(p, f, front);
        // The microfacet the direction reflects or refracts through (none for diffuse).
        let mut mm = m;
        let mut reflection = true;
        let mut microfacet = true;
        if choice < probs.x {
            wo = cosine_concentric(u);
            microfacet = false;
        } else if choice < probs.x + probs.y {
            let cc_alpha = clearcoat_alpha(p);
            mm = gtr1_sample(cc_alpha, u);
            wo = reflect(wi, mm);
        } else if choice < probs.x + probs.y + probs.z {
            let mut eta_ti = 1.0 / p.eta;
            if cim < 0.0 {
                eta_ti = p.eta;
            }
            let ct = (1.0 - (1.0 - cim * cim) * eta_ti * eta_ti).max(0.0).sqrt();
            let mut cos_t = -ct;
            if cim < 0.0 {
                cos_t = ct;
            }
            wo = m * (cim * eta_ti + cos_t) - wi * eta_ti;
            reflection = false;
        } else {
            wo = reflect(wi, m);
        }
        let mut ok = ci * wo.z > 0.0;
        if !reflection {
            ok = ci * wo.z < 0.0;
        }
        if microfacet {
            ok = ok && compatible(mm, wi, wo, ci, reflection);
        }
        if !ok {
            wo = Vec3::ZERO;
        }
    }
    wo
}

/// `principledthin`'s lobe probabilities: x specular reflection, y specular
/// transmission, z diffuse reflection (diffuse transmission takes the rest), normalised.
#[kernel_fn]
pub fn thin_probabilities(p: Principled) -> Vec3 {
    let dt = p.diff_trans * 0.5;
    let mut sr = 0.0f32;
    let mut st = 0.0f32;
    if p.spec_trans != 0.0 {
        sr = p.spec_trans * p.rate_a * 0.5;
        st = p.spec_trans * p.rate_b * 0.5;
    }
    let dr = p.rate_d * (1.0 - p.spec_trans) * (1.0 - dt);
    let mut dtp = 0.0f32;
    if p.diff_trans != 0.0 {
        dtp = p.rate_c * (1.0 - p.spec_trans) * dt;
    }
    shares(Vec3::new(sr, st, dr), dtp)
}

/// `principledthin`: as [`eval`].
#[kernel_fn]
pub fn thin_eval(p: Principled, wi0: Vec3, wo0: Vec3) -> Vec4 {
    let mut value = Vec3::ZERO;
    let mut pdf = 0.0f32;
    if wi0.z != 0.0 {
        let dt = p.diff_trans * 0.5;
        // Both sides alike: turn the viewer up.
        let mut wi = wi0;
        let mut wo = wo0;
        if wi0.z < 0.0 {
            wi = -wi0;
            wo = -wo0;
        }
        let ci = wi.z;
        let co = wo.z;
        let reflect = co > 0.0;
        let refract = co < 0.0;
        let wr = Vec3::new(wo.x, wo.y, co.abs());
        let wh = (wi + wr).normalize();
        let reflect_ok = reflect && compatible(wh, wi, wo, ci, true);
        let refract_ok = refract && compatible(wh, wi, wo, ci, false);
        let a = dist_alpha(p.roughness, p.anisotropic);
        let at = thin_transmission_alpha(p);
        let probs = thin_probabilities(p);
        if p.spec_trans != 0.0 {
            let cih = wi.dot(wh);
            let f = fresnel_signed(cih, p.eta);
            let dwh = (1.0 / (4.0 * wr.dot(wh))).abs();
            if reflect_ok {
                let mut ft = Vec3::splat(f * (1.0 - p.spec_tint));
                if p.spec_tint != 0.0 {
                    let f0 = tint(p.base_color) * schlick_r0(p.eta);
                    ft += schlick(f0, cih, p.eta) * p.spec_tint;
                }
                let g = ggx_g1(wi, wh, a) * ggx_g1(wo, wh, a);
                value += ft * (p.spec_trans * ggx_d(wh, a) * g / (4.0 * ci));
                pdf += probs.x * visible_pdf(wi, wh, a, false) * dwh;
            }
            if refract_ok {
                let g = ggx_g1(wi, wh, at) * ggx_g1(wo, wh, at);
                value += p.base_color * (p.spec_trans * (1.0 - f) * ggx_d(wh, at) * g / (4.0 * ci));
                pdf += probs.y * visible_pdf(wi, wh, at, false) * dwh;
            }
        }
        if reflect && p.spec_trans < 1.0 && dt < 1.0 {
            let cd = wh.dot(wo);
            let w = (1.0 - p.spec_trans) * (1.0 - dt);
            value += p.base_color * (w * co * INV_PI * diffuse_shape(p, ci, co, cd));
            if p.sheen > 0.0 {
                value += sheen_color(p, cd) * (p.sheen * w * co.abs());
            }
        }
        if p.diff_trans != 0.0 && refract && p.spec_trans < 1.0 && dt > 0.0 {
            value += p.base_color * ((1.0 - p.spec_trans) * dt * INV_PI * co.abs());
        }
        if reflect {
            pdf += probs.z * INV_PI * co;
        }
        if p.diff_trans != 0.0 && refract {
            pdf += (1.0 - probs.x - probs.y - probs.z) * INV_PI * -co;
        }
    }
    value.extend(pdf)
}

/// `principledthin`: as [`sample`].
#[kernel_fn]
pub fn thin_sample(p: Principled, wi0: Vec3, u: Vec2, choice: f32) -> Vec3 {
    let mut wo = Vec3::ZERO;
    if wi0.z != 0.0 {
        let mut wi = wi0;
        if wi0.z < 0.0 {
            wi = -wi0;
        }
        let probs = thin_probabilities(p);
        let mut ok = true;
        if choice < probs.x {
            let m = visible_sample(wi, dist_alpha(p.roughness, p.anisotropic), false, u);
            wo = reflect(wi, m);
            ok = compatible(m, wi, wo, wi.z, true) && wo.z > 0.0;
        } else if choice < probs.x + probs.y {
            let at = thin_transmission_alpha(p);
            let m = visible_sample(wi, at, false, u);
            let r = reflect(wi, m);
            wo = Vec3::new(r.x, r.y, -r.z);
            ok = compatible(m, wi, wo, wi.z, false) && wo.z < 0.0;
        } else if choice < probs.x + probs.y + probs.z {
            wo = cosine_concentric(u);
        } else if p.diff_trans != 0.0 {
            wo = -cosine_concentric(u);
        } else {
            ok = false;
        }
        if !ok {
            wo = Vec3::ZERO;
        }
        if wi0.z < 0.0 {
            wo = -wo;
        }
    }
    wo
}

/// The shading frame Mitsuba evaluates the BSDF of material `m` in at a hit on triangle
/// `tri` (`crate::perturb::tangent_frame`); an isotropic one takes any tangent.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn frame(
    m: Material,
    textures: &[Vec4],
    tex_coords: &[Vec4],
    tri: Triangle,
    ng: Vec3,
    n: Vec3,
    front: bool,
) -> Mat3 {
    let anisotropic = textures[(m.table - 1) as usize].y;
    crate::perturb::tangent_frame(
        tex_coords,
        tri,
        ng,
        n,
        front,
        m.flags & TWO_SIDED != 0,
        anisotropic != 0.0,
    )
}

/// [`eval`] or [`thin_eval`] by material kind.
#[kernel_fn]
pub fn eval_kind(p: Principled, kind: u32, wi: Vec3, wo: Vec3) -> Vec4 {
    if kind == PRINCIPLED_THIN {
        thin_eval(p, wi, wo)
    } else {
        eval(p, wi, wo)
    }
}

/// [`sample`] or [`thin_sample`] by material kind.
#[kernel_fn]
pub fn sample_kind(p: Principled, kind: u32, wi: Vec3, u: Vec2, choice: f32) -> Vec3 {
    if kind == PRINCIPLED_THIN {
        thin_sample(p, wi, u, choice)
    } else {
        sample(p, wi, u, choice)
    }
}

/// The BSDF, `principled` and `principledthin` alike (they share the parameter block and
/// the frame; [`sample_kind`] and [`eval_kind`] pick the lobes by kind). Both sides
/// scatter (the back as Mitsuba's BSDF does there, or as the front under `twosided`).
pub struct PrincipledBsdf;

#[kernel_impl]
impl Bsdf for PrincipledBsdf {
    const KINDS: u32 = (1 << PRINCIPLED) | (1 << PRINCIPLED_THIN);
    const NON_DELTA: bool = true;

    fn scatters(_at: Hit) -> bool {
        true
    }

    fn sample<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        beta: Vec3,
        r: Draws,
    ) -> Scattered {
        let fr = frame(at.m, textures, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let pp = params(textures, at.m, at.albedo, at.uv, at.t.original, at.h);
        sample_in(fr, pp, at, beta, r)
    }

    fn eval(textures: &[Vec4], tex_coords: &[Vec4], at: Hit, wi: Vec3) -> Vec4 {
        let fr = frame(at.m, textures, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let pp = params(textures, at.m, at.albedo, at.uv, at.t.original, at.h);
        eval_in(fr, pp, at, wi)
    }

    /// The frame and the parameters (a texture read each, where textured) are read once
    /// for both uses.
    fn shade<S: DiffuseSampler>(
        textures: &[Vec4],
        tex_coords: &[Vec4],
        at: Hit,
        wi: Vec3,
        evaluate: bool,
        beta: Vec3,
        r: Draws,
        draw: bool,
    ) -> Shaded {
        let fr = frame(at.m, textures, tex_coords, at.t, at.ng, at.n, at.front != 0);
        let pp = params(textures, at.m, at.albedo, at.uv, at.t.original, at.h);
        let mut eval = Vec4::ZERO;
        if evaluate {
            eval = eval_in(fr, pp, at, wi);
        }
        let mut next = absorbed();
        if draw {
            next = sample_in(fr, pp, at, beta, r);
        }
        Shaded { eval, next }
    }
}

/// [`Bsdf::sample`] of the principled BSDF in frame `fr` with parameters `pp`.
#[kernel_fn]
pub fn sample_in(fr: Mat3, pp: Principled, at: Hit, beta: Vec3, r: Draws) -> Scattered {
    let wi_l = fr.transpose() * -at.d;
    let wl = sample_kind(pp, at.m.kind, wi_l, r.u, r.choice);
    let mut out = absorbed();
    if wl.dot(wl) > 0.0 {
        let e = eval_kind(pp, at.m.kind, wi_l, wl);
        if e.w > 0.0 {
            // A refraction through `principled` (its value carries the 1 / eta²);
            // `principledthin` stays on its side of the index.
            let mut eta2 = 1.0f32;
            if at.m.kind == PRINCIPLED && wi_l.z * wl.z < 0.0 {
                let eta_path = if wi_l.z > 0.0 { pp.eta } else { 1.0 / pp.eta };
                eta2 = eta_path * eta_path;
            }
            out = scattered(
                (fr * wl).normalize(),
                e.w,
                beta * e.truncate() / e.w,
                0.0,
                eta2,
            );
        }
    }
    out
}

/// [`Bsdf::eval`] of the principled BSDF in frame `fr` with parameters `pp`.
#[kernel_fn]
pub fn eval_in(fr: Mat3, pp: Principled, at: Hit, wi: Vec3) -> Vec4 {
    eval_kind(pp, at.m.kind, fr.transpose() * -at.d, fr.transpose() * wi)
}
