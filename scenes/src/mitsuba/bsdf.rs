//! Mitsuba `<bsdf>` plugins → [`Bsdf`]. Supported: diffuse, conductor, roughconductor,
//! dielectric, roughdielectric, plastic, roughplastic, principled, principledthin, mask,
//! twosided, blendbsdf, normalmap, bumpmap (each parameter read or reported). Other plugins are errors, or under
//! `--lenient` replaced by the nearest supported BSDF with a warning saying which.

use glam::Vec3;

use crate::error::SceneError;
use crate::material::{Bsdf, Mask, Microfacet, Perturb, PerturbKind, Roughness, PERFECT_CONDUCTOR};

use super::conductor_iors::CONDUCTOR_IORS;
use super::diag::syntax;
use super::plugins;
use super::props::Obj;
use super::Ctx;

/// The plugins read exactly (or with per-parameter warnings).
pub(crate) const SUPPORTED: &[&str] = &[
    "diffuse",
    "conductor",
    "roughconductor",
    "dielectric",
    "plastic",
    "roughplastic",
    "roughdielectric",
    "twosided",
    "mask",
    "blendbsdf",
    "normalmap",
    "bumpmap",
    "principled",
    "principledthin",
];

/// A BSDF as the shape will use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ParsedBsdf {
    pub bsdf: Bsdf,
    pub two_sided: bool,
    /// The texture that gives the BSDF's colour (`Material::texture`).
    pub texture: Option<u32>,
    /// Mitsuba `mask` around it (`Material::mask`).
    pub mask: Option<Mask>,
    /// Mitsuba `blendbsdf`: its weight (a number, or the texture whose luminance it is)
    /// and, in `Ctx::blend_parts`, its second BSDF.
    pub blend: Option<(f32, Option<u32>, u32)>,
    /// Mitsuba `normalmap` / `bumpmap` around it (`Material::perturb`).
    pub perturb: Option<Perturb>,
}

/// Mitsuba's default BSDF for shapes that name none.
pub(crate) const DEFAULT_BSDF: ParsedBsdf = ParsedBsdf {
    bsdf: Bsdf::Diffuse {
        reflectance: Vec3::splat(0.5),
    },
    two_sided: false,
    texture: None,
    mask: None,
    blend: None,
    perturb: None,
};

/// Mitsuba's named indices of refraction (`src/render/ior.h`).
const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.00004),
    ("hydrogen", 1.00013),
    ("air", 1.00028),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

pub fn named_ior(name: &str) -> Option<f32> {
    let name = name.trim().to_ascii_lowercase();
    IORS.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

fn ior(obj: &Obj, name: &str, default: f32) -> Result<f32, SceneError> {
    match obj.float_or_string(name)? {
        None => Ok(default),
        Some(Ok(v)) => Ok(v),
        Some(Err(s)) => named_ior(&s).ok_or_else(|| {
            syntax(
                obj.loc_of(name),
                format!(
                    "unknown IOR name '{s}' (Mitsuba's names: {})",
                    IORS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                ),
            )
        }),
    }
}

/// A conductor's complex index of refraction (eta, k), as Mitsuba reads it: `eta` and `k`
/// (defaults 0 and 1, a Fresnel factor of 1) or a `material` name (default none), not both.
fn conductor_ior<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<(Vec3, Vec3), SceneError> {
    let material = obj.string("material")?;
    let explicit = obj.has("eta");
    match material.as_deref() {
        None | Some("none") => {
            let eta = ctx.color(obj, "eta")?.unwrap_or(PERFECT_CONDUCTOR.0);
            let k = ctx.color(obj, "k")?.unwrap_or(PERFECT_CONDUCTOR.1);
            Ok((eta, k))
        }
        Some(name) => {
            if explicit {
                return Err(syntax(
                    obj.loc_of("eta"),
                    "give either 'eta' and 'k' or 'material', not both (as Mitsuba)",
                ));
            }
            match CONDUCTOR_IORS.iter().find(|(n, _, _)| *n == name) {
                Some((_, eta, k)) => {
                    obj.ignore("k");
                    Ok((Vec3::from(*eta), Vec3::from(*k)))
                }
                None => Err(syntax(
                    obj.loc_of("material"),
                    format!(
                        "unknown conductor material '{name}' (Mitsuba's names: {})",
                        CONDUCTOR_IORS
                            .iter()
                            .map(|(n, _, _)| *n)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                )),
            }
        }
    }
}

/// A microfacet distribution's name (Mitsuba's default: beckmann).
fn distribution(obj: &Obj) -> Result<Microfacet, SceneError> {
    match obj.string("distribution")?.as_deref() {
        None | Some("beckmann") => Ok(Microfacet::Beckmann),
        Some("ggx") => Ok(Microfacet::Ggx),
        Some(other) => Err(syntax(
            obj.loc_of("distribution"),
            format!("microfacet distribution '{other}' is not one of beckmann, ggx"),
        )),
    }
}

/// Microfacet roughness: isotropic `alpha` (default 0.1) or `alpha_u` and `alpha_v` together.
fn alpha(ctx: &mut Ctx, obj: &Obj) -> Result<f32, SceneError> {
    let _ = obj.boolean("sample_visible")?;
    let alpha = match (obj.float("alpha_u")?, obj.float("alpha_v")?) {
        (Some(u), Some(v)) => {
            if u != v {
                ctx.diag.warn(
                    &obj.loc,
                    "anisotropic roughness approximated by sqrt(alpha_u * alpha_v)",
                );
            }
            if obj.has("alpha") {
                return Err(syntax(
                    obj.loc_of("alpha"),
                    "give either 'alpha' or 'alpha_u' and 'alpha_v', not both",
                ));
            }
            (u * v).sqrt()
        }
        (None, None) => obj.float("alpha")?.unwrap_or(0.1),
        _ => {
            return Err(syntax(
                &obj.loc,
                "both 'alpha_u' and 'alpha_v' must be given",
            ))
        }
    };
    if alpha.is_nan() || alpha < 0.0 {
        return Err(syntax(obj.loc_of("alpha"), "alpha must be >= 0"));
    }
    Ok(alpha)
}

/// Microfacet roughness of a `roughconductor` or `roughdielectric`: isotropic `alpha`
/// (default 0.1) or
/// `alpha_u` and `alpha_v` together, each a number or a texture read as a number (Mitsuba's
/// `get_unbounded_texture` and `eval_1`).
fn roughness<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<Roughness, SceneError> {
    let _ = obj.boolean("sample_visible")?;
    let mut one = |name: &str, default: f32| -> Result<(f32, Option<u32>), SceneError> {
        let (value, texture) = match ctx.color_or_texture(obj, name)? {
            None => (default, None),
            Some((colour, Some(t))) => (
                crate::texture::luminance(colour),
                Some(super::texture::scalar_use(ctx, t)),
            ),
            // A number as given; a colour (or constant texture) as its luminance.
            Some((colour, None)) => (
                obj.float(name)
                    .ok()
                    .flatten()
                    .unwrap_or(crate::texture::luminance(colour)),
                None,
            ),
        };
        if texture.is_none() && (value.is_nan() || value < 0.0) {
            return Err(syntax(obj.loc_of(name), format!("{name} must be >= 0")));
        }
        Ok((value, texture))
    };
    let r = match (obj.has("alpha_u"), obj.has("alpha_v")) {
        (true, true) => {
            if obj.has("alpha") {
                return Err(syntax(
                    obj.loc_of("alpha"),
                    "give either 'alpha' or 'alpha_u' and 'alpha_v', not both",
                ));
            }
            let (u, u_texture) = one("alpha_u", 0.1)?;
            let (v, v_texture) = one("alpha_v", 0.1)?;
            Roughness {
                u,
                v,
                u_texture,
                v_texture,
            }
        }
        (false, false) => {
            let (a, texture) = one("alpha", 0.1)?;
            Roughness {
                u: a,
                v: a,
                u_texture: texture,
                v_texture: texture,
            }
        }
        _ => {
            return Err(syntax(
                &obj.loc,
                "both 'alpha_u' and 'alpha_v' must be given",
            ))
        }
    };
    Ok(r)
}

/// The BSDF of `obj`, parsed once per object (a BSDF referenced by many shapes is reported once).
pub(crate) fn parse_bsdf<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let key = obj as *const Obj as usize;
    if let Some(b) = ctx.bsdfs.get(&key) {
        return Ok(*b);
    }
    let b = parse_uncached(ctx, obj)?;
    ctx.bsdfs.insert(key, b);
    Ok(b)
}

fn parse_uncached<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let mut texture = None;
    let bsdf = match obj.plugin.as_str() {
        "diffuse" => {
            let (reflectance, t) = ctx
                .color_or_texture(obj, "reflectance")?
                .unwrap_or((Vec3::splat(0.5), None));
            texture = t;
            Bsdf::Diffuse { reflectance }
        }
        "conductor" => {
            let (eta, k) = conductor_ior(ctx, obj)?;
            let (specular_reflectance, t) = ctx
                .color_or_texture(obj, "specular_reflectance")?
                .unwrap_or((Vec3::ONE, None));
            texture = t;
            Bsdf::Conductor {
                specular_reflectance,
                eta,
                k,
            }
        }
        "roughconductor" => {
            let (eta, k) = conductor_ior(ctx, obj)?;
            let distribution = distribution(obj)?;
            let alpha = roughness(ctx, obj)?;
            let (specular_reflectance, t) = ctx
                .color_or_texture(obj, "specular_reflectance")?
                .unwrap_or((Vec3::ONE, None));
            texture = t;
            if alpha.is_constant_isotropic() && alpha.u == 0.0 {
                ctx.diag.warn(
                    obj.loc_of("alpha"),
                    "roughconductor with alpha 0 rendered as a smooth conductor",
                );
                Bsdf::Conductor {
                    specular_reflectance,
                    eta,
                    k,
                }
            } else {
                Bsdf::RoughConductor {
                    alpha,
                    distribution,
                    specular_reflectance,
                    eta,
                    k,
                }
            }
        }
        "dielectric" => dielectric(ctx, obj)?,
        "roughdielectric" => {
            let distribution = distribution(obj)?;
            let alpha = roughness(ctx, obj)?;
            let Bsdf::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } = dielectric(ctx, obj)?
            else {
                unreachable!("dielectric() makes a Bsdf::Dielectric")
            };
            if int_ior == ext_ior {
                return Err(syntax(
                    &obj.loc,
                    "roughdielectric needs different int_ior and ext_ior (as in Mitsuba)",
                ));
            }
            if alpha.is_constant_isotropic() && alpha.u == 0.0 {
                ctx.diag.warn(
                    obj.loc_of("alpha"),
                    "roughdielectric with alpha 0 rendered as a smooth dielectric",
                );
                Bsdf::Dielectric {
                    int_ior,
                    ext_ior,
                    specular_reflectance,
                    specular_transmittance,
                }
            } else {
                Bsdf::RoughDielectric {
                    eta: int_ior / ext_ior,
                    alpha,
                    distribution,
                    specular_reflectance,
                    specular_transmittance,
                }
            }
        }
        "plastic" => {
            let (b, t) = plastic(ctx, obj)?;
            texture = t;
            b
        }
        "roughplastic" => {
            let (b, t) = rough_plastic(ctx, obj)?;
            texture = t;
            b
        }
        "principled" | "principledthin" => {
            let thin = obj.plugin == "principledthin";
            let (b, t) = super::principled::principled(ctx, obj, thin)?;
            texture = t;
            b
        }
        "twosided" => return twosided(ctx, obj),
        "mask" => return mask(ctx, obj),
        "blendbsdf" => return blend(ctx, obj),
        "normalmap" | "bumpmap" => return perturb(ctx, obj),
        _ => return stand_in(ctx, obj),
    };
    obj.finish(&mut ctx.diag)?;
    Ok(ParsedBsdf {
        bsdf,
        two_sided: false,
        texture,
        mask: None,
        blend: None,
        perturb: None,
    })
}

fn dielectric<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<Bsdf, SceneError> {
    let int_ior = ior(obj, "int_ior", 1.5046)?;
    let ext_ior = ior(obj, "ext_ior", 1.00028)?;
    if !(int_ior > 0.0 && ext_ior > 0.0) {
        return Err(syntax(&obj.loc, "indices of refraction must be positive"));
    }
    Ok(Bsdf::Dielectric {
        int_ior,
        ext_ior,
        specular_reflectance: ctx.color(obj, "specular_reflectance")?.unwrap_or(Vec3::ONE),
        specular_transmittance: ctx
            .color(obj, "specular_transmittance")?
            .unwrap_or(Vec3::ONE),
    })
}

/// Mitsuba `plastic`: a diffuse base under a smooth dielectric coating (defaults: diffuse
/// 0.5, specular 1, polypropylene in air, linear).
fn plastic<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<(Bsdf, Option<u32>), SceneError> {
    let int_ior = ior(obj, "int_ior", 1.49)?;
    let ext_ior = ior(obj, "ext_ior", 1.000277)?;
    if !(int_ior > 0.0 && ext_ior > 0.0) {
        return Err(syntax(&obj.loc, "indices of refraction must be positive"));
    }
    let (diffuse_reflectance, texture) = ctx
        .color_or_texture(obj, "diffuse_reflectance")?
        .unwrap_or((Vec3::splat(0.5), None));
    let specular_reflectance = ctx.color(obj, "specular_reflectance")?.unwrap_or(Vec3::ONE);
    if diffuse_reflectance.max_element() + specular_reflectance.max_element() <= 0.0 {
        // Mitsuba samples the coating by the ratio of the two means, undefined at 0 / 0.
        return Err(syntax(
            &obj.loc,
            "plastic needs a non-zero diffuse_reflectance or specular_reflectance",
        ));
    }
    let bsdf = Bsdf::Plastic {
        eta: int_ior / ext_ior,
        diffuse_reflectance,
        specular_reflectance,
        nonlinear: obj.boolean("nonlinear")?.unwrap_or(false),
    };
    Ok((bsdf, texture))
}

/// Mitsuba `roughplastic`: [`plastic`]'s parameters plus the coating's `distribution`
/// (default Beckmann) and `alpha` (0.1). Its transmittance table becomes one more texture.
fn rough_plastic<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<(Bsdf, Option<u32>), SceneError> {
    let distribution = distribution(obj)?;
    let alpha = alpha(ctx, obj)?;
    if alpha <= 0.0 {
        return Err(syntax(
            obj.loc_of("alpha"),
            "roughplastic needs alpha > 0 (use plastic for a smooth coating)",
        ));
    }
    let (plastic, texture) = plastic(ctx, obj)?;
    let Bsdf::Plastic {
        eta,
        diffuse_reflectance,
        specular_reflectance,
        nonlinear,
    } = plastic
    else {
        unreachable!("plastic() makes a Bsdf::Plastic")
    };
    let tables = crate::rough_plastic::tables(alpha, distribution == Microfacet::Beckmann, eta);
    ctx.textures.push(crate::texture::Texture::Bitmap {
        width: crate::rough_plastic::TABLE_SIZE as u32,
        height: 1,
        texels: tables
            .external_transmittance
            .iter()
            .map(|&t| Vec3::splat(t))
            .collect(),
        filter: crate::texture::Filter::Bilinear,
        wrap: crate::texture::Wrap::Clamp,
        to_uv: crate::texture::UvTransform::IDENTITY,
    });
    let bsdf = Bsdf::RoughPlastic {
        eta,
        alpha,
        distribution,
        diffuse_reflectance,
        specular_reflectance,
        nonlinear,
        internal_reflectance: tables.internal_reflectance,
        table: (ctx.textures.len() - 1) as u32,
    };
    Ok((bsdf, texture))
}

/// The BSDFs nested in (or referenced by) a wrapper such as `twosided` or `mask`.
fn nested_bsdfs<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<Vec<ParsedBsdf>, SceneError> {
    let mut inner = Vec::new();
    for c in &obj.children {
        let t = ctx.target(c)?;
        if t.tag == "bsdf" {
            c.take();
            inner.push(parse_bsdf(ctx, t)?);
        }
    }
    Ok(inner)
}

/// The one BSDF nested in (or referenced by) a wrapper that takes exactly one (`mask`,
/// `normalmap`, `bumpmap`).
fn single_nested<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let plugin = &obj.plugin;
    match nested_bsdfs(ctx, obj)?.as_slice() {
        [nested] => Ok(*nested),
        [] => Err(syntax(
            &obj.loc,
            format!("{plugin} needs a nested <bsdf> (or a <ref> to one)"),
        )),
        _ => Err(syntax(
            &obj.loc,
            format!("{plugin} takes one nested BSDF (as Mitsuba)"),
        )),
    }
}

fn twosided<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let inner = nested_bsdfs(ctx, obj)?;
    if inner
        .iter()
        .any(|b| matches!(b.bsdf, Bsdf::Dielectric { .. }))
    {
        return Err(syntax(
            &obj.loc,
            "twosided can only wrap materials without transmission (not a dielectric)",
        ));
    }
    let front = match inner.as_slice() {
        [] => {
            return Err(syntax(
                &obj.loc,
                "twosided needs a nested <bsdf> (or a <ref> to one)",
            ))
        }
        [front] => *front,
        [front, back] => {
            if front.bsdf != back.bsdf {
                ctx.diag.warn(
                    &obj.loc,
                    "twosided with a different back BSDF: the front BSDF is used on both sides",
                );
            }
            *front
        }
        _ => return Err(syntax(&obj.loc, "twosided takes at most two nested BSDFs")),
    };
    obj.finish(&mut ctx.diag)?;
    Ok(ParsedBsdf {
        two_sided: true,
        // Mitsuba's twosided hands the back side to the map as if it were the front.
        perturb: front.perturb.map(|p| Perturb {
            per_side: true,
            ..p
        }),
        ..front
    })
}

/// Mitsuba `mask`: one nested BSDF and its `opacity` (a number, colour or texture, whose
/// luminance counts; default 0.5).
fn mask<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let nested = single_nested(ctx, obj)?;
    if nested.mask.is_some() {
        return Err(syntax(&obj.loc, "a mask inside a mask is not supported"));
    }
    let (colour, texture) = ctx
        .color_or_texture(obj, "opacity")?
        .unwrap_or((Vec3::splat(0.5), None));
    let texture = texture.map(|i| super::texture::scalar_use(ctx, i));
    let opacity = crate::texture::luminance(colour);
    obj.finish(&mut ctx.diag)?;
    Ok(ParsedBsdf {
        mask: Some(Mask { opacity, texture }),
        ..nested
    })
}

/// Mitsuba `blendbsdf`: two nested BSDFs, the second scattering with probability `weight`
/// (required as in Mitsuba: a number, or a texture whose luminance is read per hit, clamped
/// to [0, 1]). The first becomes the material; the second is kept in `Ctx::blend_parts` for
/// the shape to register. A blend nested first is moved second (weight 1 - w); two nested
/// blends are refused.
fn blend<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let Some((colour, texture)) = ctx.color_or_texture(obj, "weight")? else {
        return Err(syntax(
            &obj.loc,
            "blendbsdf needs a 'weight' (as in Mitsuba)",
        ));
    };
    let texture = texture.map(|i| super::texture::scalar_use(ctx, i));
    let weight = crate::texture::luminance(colour);
    if texture.is_none() && !(0.0..=1.0).contains(&weight) {
        return Err(syntax(
            obj.loc_of("weight"),
            "blendbsdf weight must be in [0, 1]",
        ));
    }
    let inner = nested_bsdfs(ctx, obj)?;
    let [first, second] = inner.as_slice() else {
        return Err(syntax(
            &obj.loc,
            format!(
                "blendbsdf needs exactly two nested BSDFs, not {}",
                inner.len()
            ),
        ));
    };
    let (first, second, weight) = match (first.blend, second.blend) {
        (Some(_), Some(_)) => {
            return Err(syntax(
                &obj.loc,
                "a blendbsdf of two blendbsdfs is not supported; nest one of them only",
            ))
        }
        (Some(_), None) if texture.is_some() => {
            return Err(syntax(
                &obj.loc,
                "a blendbsdf with a textured weight and a nested blendbsdf first is not \
                 supported; nest the blend second",
            ))
        }
        (Some(_), None) => (*second, *first, 1.0 - weight),
        _ => (*first, *second, weight),
    };
    // The kernels weigh a delta direction drawn in a blend as Mitsuba does only where every
    // BSDF of the blend shares the surface (`cohort_kernels::scatter`); with a mask or a
    // normal or bump map in it, each hit takes the BSDF it picks for everything.
    let mut chain = vec![&first, &second];
    let mut next = second.blend.map(|b| b.2);
    while let Some(i) = next {
        let part = &ctx.blend_parts[i as usize];
        chain.push(part);
        next = part.blend.map(|b| b.2);
    }
    let delta = chain.iter().any(|b| {
        matches!(
            b.bsdf,
            Bsdf::Conductor { .. } | Bsdf::Dielectric { .. } | Bsdf::Plastic { .. }
        )
    });
    let not_plain = chain
        .iter()
        .any(|b| b.mask.is_some() || b.perturb.is_some());
    if delta && not_plain {
        ctx.diag.warn(
            &obj.loc,
            "blendbsdf of a smooth (delta) BSDF and a masked or normal- or bump-mapped one: \
             each hit uses the BSDF it picks, so delta directions get the exact weighted sum, \
             where Mitsuba weighs them by the blend's density and its image differs",
        );
    }
    obj.finish(&mut ctx.diag)?;
    ctx.blend_parts.push(second);
    Ok(ParsedBsdf {
        blend: Some((weight, texture, (ctx.blend_parts.len() - 1) as u32)),
        ..first
    })
}

/// Mitsuba `normalmap` (the texture `normalmap`: RGB = (n + 1) / 2 in the shading frame) or
/// `bumpmap` (a nested texture whose luminance is a height, times `scale`) around one nested
/// BSDF; `flip_invalid_normals`, `use_shadowing_function`.
fn perturb<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let plugin = obj.plugin.as_str();
    let mut texture = None;
    if plugin == "bumpmap" {
        for c in &obj.children {
            let t = ctx.target(c)?;
            if t.tag != "texture" {
                continue;
            }
            if texture.is_some() {
                return Err(syntax(&t.loc, "bumpmap takes one texture (as in Mitsuba)"));
            }
            if t.plugin != "bitmap" {
                return Err(syntax(
                    &t.loc,
                    format!(
                        "bumpmap needs a 'bitmap' height texture (Mitsuba has no gradient for '{}')",
                        t.plugin
                    ),
                ));
            }
            c.take();
            texture = Some(super::texture::texture_index(ctx, t)?);
        }
    } else {
        let Some((colour, t)) = ctx.color_or_texture(obj, "normalmap")? else {
            return Err(syntax(&obj.loc, "normalmap needs a 'normalmap' texture"));
        };
        if let Some(i) = t {
            super::texture::image_only(ctx, i, obj.loc_of("normalmap"), "a normal map")?;
        }
        // A constant normal: a texture of one colour.
        texture = Some(t.unwrap_or_else(|| {
            ctx.textures.push(crate::texture::Texture::Checkerboard {
                color0: colour,
                color1: colour,
                to_uv: crate::texture::UvTransform::IDENTITY,
            });
            (ctx.textures.len() - 1) as u32
        }));
    }
    let Some(texture) = texture else {
        return Err(syntax(
            &obj.loc,
            "bumpmap needs a nested <texture> (its height)",
        ));
    };
    let kind = if plugin == "bumpmap" {
        PerturbKind::Bump {
            scale: obj.float("scale")?.unwrap_or(1.0),
        }
    } else {
        PerturbKind::Normal
    };
    let shadowing = obj.boolean("use_shadowing_function")?.unwrap_or(true);
    let flip_invalid = obj.boolean("flip_invalid_normals")?.unwrap_or(true);
    let nested = single_nested(ctx, obj)?;
    if nested.perturb.is_some() {
        return Err(syntax(
            &obj.loc,
            "a normalmap or bumpmap inside another is not supported",
        ));
    }
    obj.finish(&mut ctx.diag)?;
    Ok(ParsedBsdf {
        perturb: Some(Perturb {
            kind,
            texture,
            shadowing,
            flip_invalid,
            per_side: false,
        }),
        ..nested
    })
}

/// A plugin the renderer does not implement: an error, or (lenient) the nearest supported BSDF.
fn stand_in<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<ParsedBsdf, SceneError> {
    let what = plugins::describe("bsdf", &obj.plugin);
    if !ctx.diag.lenient {
        // Fail on the plugin itself, before anything its parameters could report.
        let instead = match obj.plugin.as_str() {
            "thindielectric" | "null" => "replaced by a smooth dielectric",
            _ => "replaced by a diffuse BSDF of its colour",
        };
        ctx.diag.unsupported(&obj.loc, &what, instead)?;
    }
    // A colour for the stand-in: the first of `names` given as a plain value or texture.
    let colour = |ctx: &mut Ctx<'a>, names: &[&str], default: f32| -> Result<Vec3, SceneError> {
        for n in names {
            if let Ok(Some(c)) = ctx.color(obj, n) {
                return Ok(c);
            }
        }
        Ok(Vec3::splat(default))
    };
    let diffuse = |reflectance: Vec3| ParsedBsdf {
        bsdf: Bsdf::Diffuse { reflectance },
        ..DEFAULT_BSDF
    };
    let (parsed, instead) = match obj.plugin.as_str() {
        "thindielectric" => {
            let b = ParsedBsdf {
                bsdf: dielectric(ctx, obj)?,
                ..DEFAULT_BSDF
            };
            (b, "replaced by a smooth dielectric with its IORs".to_string())
        }
        "null" => (
            ParsedBsdf {
                bsdf: Bsdf::Dielectric {
                    int_ior: 1.0,
                    ext_ior: 1.0,
                    specular_reflectance: Vec3::ONE,
                    specular_transmittance: Vec3::ONE,
                },
                ..DEFAULT_BSDF
            },
            "replaced by an index-matched dielectric (invisible to paths, but it blocks light samples)"
                .to_string(),
        ),
        _ => {
            let r = colour(
                ctx,
                &["diffuse_reflectance", "reflectance", "base_color"],
                0.5,
            )?;
            (diffuse(r), format!("replaced by diffuse {r}"))
        }
    };
    ctx.diag.unsupported(&obj.loc, what, instead)?;
    Ok(parsed)
}
