//! Mitsuba `<bsdf>` plugins → [`Bsdf`]. Unsupported plugins and parameters become warnings with a
//! documented stand-in, never a silent change.

use glam::Vec3;

use crate::error::{ErrorKind, SceneError};
use crate::material::Bsdf;

use super::props::{Child, Ctx, Obj};

/// A BSDF as the shape will use it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ParsedBsdf {
    pub bsdf: Bsdf,
    pub two_sided: bool,
}

/// Mitsuba's default BSDF for shapes that name none.
pub(crate) const DEFAULT_BSDF: ParsedBsdf = ParsedBsdf {
    bsdf: Bsdf::Diffuse {
        reflectance: Vec3::splat(0.5),
    },
    two_sided: false,
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

fn ior(ctx: &Ctx, obj: &Obj, name: &str, default: f32) -> Result<f32, SceneError> {
    if let Ok(Some(v)) = obj.float(ctx, name) {
        return Ok(v);
    }
    match obj.string(ctx, name)? {
        None => Ok(default),
        Some(s) => named_ior(&s).ok_or_else(|| {
            ctx.err(
                obj.node_of(name),
                ErrorKind::Syntax,
                format!("unknown IOR name '{s}'"),
            )
        }),
    }
}

/// Conductors are only supported without Fresnel (`material` = none); a named metal is approximated
/// by a perfect reflector tinted by `specular_reflectance`.
fn conductor_material(ctx: &mut Ctx, obj: &Obj) -> Result<(), SceneError> {
    let material = obj
        .string(ctx, "material")?
        .unwrap_or_else(|| "none".into());
    if material != "none" || obj.has("eta") || obj.has("k") {
        ctx.warn(
            obj.node,
            format!(
                "conductor Fresnel (material '{material}', eta/k) is not supported: treated as material 'none' (F = 1)"
            ),
        );
        // Mark them read so they are not reported twice.
        let _ = (obj.color(ctx, "eta"), obj.color(ctx, "k"));
    }
    Ok(())
}

/// `resolve` looks up `<ref id>` children (BSDFs defined earlier with an `id`).
pub(crate) fn parse_bsdf(
    ctx: &mut Ctx,
    obj: &Obj,
    resolve: &dyn Fn(&str) -> Option<ParsedBsdf>,
) -> Result<ParsedBsdf, SceneError> {
    let color = |ctx: &Ctx, name: &str, default: f32| -> Result<Vec3, SceneError> {
        Ok(obj.color(ctx, name)?.unwrap_or(Vec3::splat(default)))
    };
    let bsdf = match obj.plugin.as_str() {
        "diffuse" => Bsdf::Diffuse {
            reflectance: color(ctx, "reflectance", 0.5)?,
        },
        "conductor" => {
            conductor_material(ctx, obj)?;
            Bsdf::Conductor {
                specular_reflectance: color(ctx, "specular_reflectance", 1.0)?,
            }
        }
        "roughconductor" => {
            conductor_material(ctx, obj)?;
            let distribution = obj
                .string(ctx, "distribution")?
                .unwrap_or_else(|| "beckmann".into());
            if distribution != "ggx" {
                ctx.warn(
                    obj.node,
                    format!("microfacet distribution '{distribution}' approximated by ggx (Mitsuba's default is beckmann)"),
                );
            }
            let _ = obj.boolean(ctx, "sample_visible")?;
            let alpha = match (obj.float(ctx, "alpha_u")?, obj.float(ctx, "alpha_v")?) {
                (Some(u), Some(v)) => {
                    if u != v {
                        ctx.warn(
                            obj.node,
                            "anisotropic roughness approximated by sqrt(alpha_u * alpha_v)",
                        );
                    }
                    (u * v).sqrt()
                }
                _ => obj.float(ctx, "alpha")?.unwrap_or(0.1),
            };
            if alpha <= 0.0 {
                return Err(ctx.err(
                    obj.node_of("alpha"),
                    ErrorKind::Syntax,
                    "alpha must be positive",
                ));
            }
            Bsdf::RoughConductor {
                alpha,
                specular_reflectance: color(ctx, "specular_reflectance", 1.0)?,
            }
        }
        "dielectric" => {
            let int_ior = ior(ctx, obj, "int_ior", 1.5046)?;
            let ext_ior = ior(ctx, obj, "ext_ior", 1.00028)?;
            if !(int_ior > 0.0 && ext_ior > 0.0) {
                return Err(ctx.err(
                    obj.node,
                    ErrorKind::Syntax,
                    "indices of refraction must be positive",
                ));
            }
            Bsdf::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance: color(ctx, "specular_reflectance", 1.0)?,
                specular_transmittance: color(ctx, "specular_transmittance", 1.0)?,
            }
        }
        "twosided" => {
            let mut inner = Vec::new();
            for child in &obj.children {
                match child {
                    Child::Object(o) if o.tag == "bsdf" => inner.push(parse_bsdf(ctx, o, resolve)?),
                    Child::Ref { id, node } => inner.push(resolve(id).ok_or_else(|| {
                        ctx.err(*node, ErrorKind::Syntax, format!("no BSDF with id '{id}'"))
                    })?),
                    Child::Object(o) => {
                        ctx.warn(o.node, format!("<{}> inside twosided ignored", o.tag));
                    }
                }
            }
            let Some(front) = inner.first().copied() else {
                return Err(ctx.err(
                    obj.node,
                    ErrorKind::Syntax,
                    "twosided needs a nested <bsdf>",
                ));
            };
            if inner.len() > 1 {
                ctx.warn(
                    obj.node,
                    "twosided with a different back BSDF: the front BSDF is used on both sides",
                );
            }
            obj.warn_unused(ctx);
            return Ok(ParsedBsdf {
                bsdf: front.bsdf,
                two_sided: true,
            });
        }
        other => {
            // Keep whatever colour the author gave so the stand-in is at least the right shade.
            let reflectance = ["reflectance", "diffuse_reflectance", "base_color"]
                .iter()
                .find_map(|n| obj.color(ctx, n).ok().flatten())
                .unwrap_or(Vec3::splat(0.5));
            ctx.warn(
                obj.node,
                format!("unsupported bsdf '{other}' replaced by diffuse {reflectance}"),
            );
            return Ok(ParsedBsdf {
                bsdf: Bsdf::Diffuse { reflectance },
                two_sided: false,
            });
        }
    };
    for child in &obj.children {
        match child {
            Child::Object(o) => ctx.warn(
                o.node,
                format!("<{}> inside bsdf '{}' ignored", o.tag, obj.plugin),
            ),
            Child::Ref { node, .. } => {
                ctx.warn(*node, format!("<ref> inside bsdf '{}' ignored", obj.plugin))
            }
        }
    }
    obj.warn_unused(ctx);
    Ok(ParsedBsdf {
        bsdf,
        two_sided: false,
    })
}
