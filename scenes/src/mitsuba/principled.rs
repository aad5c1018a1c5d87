//! Mitsuba `principled` and `principledthin` → [`Bsdf::Principled`], with Mitsuba's
//! defaults and its derivation of `eta` from `specular`.

use glam::Vec3;

use crate::error::SceneError;
use crate::material::{Bsdf, Principled};

use super::diag::syntax;
use super::props::Obj;
use super::Ctx;

/// A scalar parameter of `obj` in [lo, hi] (Mitsuba's default `default`). Textures are
/// only read for `base_color`: a texture here is an error at its line.
fn scalar(obj: &Obj, name: &str, default: f32, lo: f32, hi: f32) -> Result<f32, SceneError> {
    if let Some(c) = obj.child_named(name) {
        return Err(syntax(
            &c.loc,
            format!(
                "{} '{}': a texture for '{name}' is not supported (only base_color may be \
                 textured); give a float",
                obj.tag, obj.plugin
            ),
        ));
    }
    let v = obj.float(name)?.unwrap_or(default);
    if !(lo..=hi).contains(&v) {
        return Err(syntax(
            obj.loc_of(name),
            format!("'{name}' must lie in [{lo}, {hi}], not {v}"),
        ));
    }
    Ok(v)
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
    let unit = |name: &str, default: f32| scalar(obj, name, default, 0.0, 1.0);
    let roughness = unit("roughness", 0.5)?;
    let anisotropic = unit("anisotropic", 0.0)?;
    let spec_trans = unit("spec_trans", 0.0)?;
    let sheen = unit("sheen", 0.0)?;
    let sheen_tint = unit("sheen_tint", 0.0)?;
    let flatness = unit("flatness", 0.0)?;
    let spec_tint = unit("spec_tint", 0.0)?;
    let rate = |name: &str| scalar(obj, name, 1.0, 0.0, f32::MAX);
    let (metallic, clearcoat, clearcoat_gloss, diff_trans, eta, sampling_rates);
    if thin {
        metallic = 0.0;
        clearcoat = 0.0;
        clearcoat_gloss = 0.0;
        // Mitsuba's range for the diffuse transmission is 0..2.
        diff_trans = scalar(obj, "diff_trans", 0.0, 0.0, 2.0)?;
        eta = scalar(obj, "eta", 1.5, 1.0e-3, f32::MAX)?;
        sampling_rates = [
            rate("specular_reflectance_sampling_rate")?,
            rate("specular_transmittance_sampling_rate")?,
            rate("diffuse_transmittance_sampling_rate")?,
            rate("diffuse_reflectance_sampling_rate")?,
        ];
    } else {
        metallic = unit("metallic", 0.0)?;
        clearcoat = unit("clearcoat", 0.0)?;
        clearcoat_gloss = unit("clearcoat_gloss", 0.0)?;
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
    };
    Ok((Bsdf::Principled(params), texture))
}
