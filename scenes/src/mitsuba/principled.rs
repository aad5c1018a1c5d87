//! Mitsuba `principled` and `principledthin` → [`Bsdf::Principled`], with Mitsuba's
//! defaults and its derivation of `eta` from `specular`.

use glam::Vec3;

use crate::error::SceneError;
use crate::material::{Bsdf, Principled};

use super::diag::syntax;
use super::props::Obj;
use super::Ctx;

/// A scalar parameter of `obj` in [lo, hi] (Mitsuba's default `default`), given as a
/// number.
fn scalar(obj: &Obj, name: &str, default: f32, lo: f32, hi: f32) -> Result<f32, SceneError> {
    let v = obj.float(name)?.unwrap_or(default);
    if !(lo..=hi).contains(&v) {
        return Err(syntax(
            obj.loc_of(name),
            format!("'{name}' must lie in [{lo}, {hi}], not {v}"),
        ));
    }
    Ok(v)
}

/// A parameter Mitsuba reads with `get_texture` and `eval_1`: a number in [lo, hi], or a
/// texture read as a number per hit (its mean luminance stands for it where one number is
/// needed). The texture's index goes to `textures` at the parameter's place in
/// `Principled::TEXTURED`.
fn scalar_or_texture<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    name: &str,
    default: f32,
    (lo, hi): (f32, f32),
    textures: &mut [Option<u32>; 11],
) -> Result<f32, SceneError> {
    if obj.child_named(name).is_some() {
        if let Some((colour, t)) = ctx.color_or_texture(obj, name)? {
            let value = crate::texture::luminance(colour);
            match t {
                Some(t) => {
                    let k = Principled::TEXTURED
                        .iter()
                        .position(|n| *n == name)
                        .unwrap();
                    textures[k] = Some(super::texture::scalar_use(ctx, t));
                }
                None if !(lo..=hi).contains(&value) => {
                    return Err(syntax(
                        obj.loc_of(name),
                        format!("'{name}' must lie in [{lo}, {hi}], not {value}"),
                    ))
                }
                None => {}
            }
            return Ok(value);
        }
    }
    scalar(obj, name, default, lo, hi)
}

/// Mitsuba `principled` (`thin` false) or `principledthin`: its parameters, and the
/// texture of its base colour if it has one.
pub(super) fn principled<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    thin: bool,
) -> Result<(Bsdf, Option<u32>), SceneError> {
    let (base_color, texture) = ctx
        .color_or_texture(obj, "base_color")?
        .unwrap_or((Vec3::splat(0.5), None));
    let mut textures = [None; 11];
    let mut unit = |ctx: &mut Ctx<'a>, name: &str, default: f32| {
        scalar_or_texture(ctx, obj, name, default, (0.0, 1.0), &mut textures)
    };
    let roughness = unit(ctx, "roughness", 0.5)?;
    let anisotropic = unit(ctx, "anisotropic", 0.0)?;
    let spec_trans = unit(ctx, "spec_trans", 0.0)?;
    let sheen = unit(ctx, "sheen", 0.0)?;
    let sheen_tint = unit(ctx, "sheen_tint", 0.0)?;
    let flatness = unit(ctx, "flatness", 0.0)?;
    let spec_tint = unit(ctx, "spec_tint", 0.0)?;
    let rate = |name: &str| scalar(obj, name, 1.0, 0.0, f32::MAX);
    let (metallic, clearcoat, clearcoat_gloss, diff_trans, eta, sampling_rates);
    if thin {
        metallic = 0.0;
        clearcoat = 0.0;
        clearcoat_gloss = 0.0;
        // Mitsuba's range for the diffuse transmission is 0..2.
        diff_trans = scalar_or_texture(ctx, obj, "diff_trans", 0.0, (0.0, 2.0), &mut textures)?;
        eta = scalar(obj, "eta", 1.5, 1.0e-3, f32::MAX)?;
        sampling_rates = [
            rate("specular_reflectance_sampling_rate")?,
            rate("specular_transmittance_sampling_rate")?,
            rate("diffuse_transmittance_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
        ];
    } else {
        metallic = unit(ctx, "metallic", 0.0)?;
        clearcoat = unit(ctx, "clearcoat", 0.0)?;
        clearcoat_gloss = unit(ctx, "clearcoat_gloss", 0.0)?;
        diff_trans = 0.0;
        eta = match (obj.has("eta"), obj.has("specular")) {
            (true, true) => {
                return Err(syntax(
                    obj.loc_of("specular"),
                    "give either 'eta' or 'specular', not both (as Mitsuba)",
                ))
            }
            (true, false) => {
                let eta = scalar(obj, "eta", 1.5, 1.0e-3, f32::MAX)?;
                // Mitsuba: a transmitting material needs an interface.
                if spec_trans != 0.0 && eta == 1.0 {
                    1.001
                } else {
                    eta
                }
            }
            (false, _) => {
                let mut specular = scalar(obj, "specular", 0.5, 0.0, 1.0)?;
                if spec_trans != 0.0 && specular == 0.0 {
                    specular = 1.0e-3;
                }
                2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
            }
        };
        sampling_rates = [
            rate("main_specular_sampling_rate")?,
            rate("clearcoat_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
            0.0,
        ];
    }
    let params = Principled {
        thin,
        base_color,
        roughness,
        anisotropic,
        metallic,
        spec_trans,
        spec_tint,
        sheen,
        sheen_tint,
        clearcoat,
        clearcoat_gloss,
        flatness,
        diff_trans,
        eta,
        sampling_rates,
        textures,
    };
    Ok((Bsdf::Principled(params), texture))
}
