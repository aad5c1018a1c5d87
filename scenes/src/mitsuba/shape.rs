//! Mitsuba `<shape>` plugins → triangles in the [`SceneBuilder`]: mesh files (`obj`, `ply`) and the
//! analytic shapes (`rectangle`, `cube`, `sphere` tessellated, see [`crate::shapes`]), each with its
//! BSDF and optional `area` emitter folded into one [`Material`].

use glam::{Mat4, Vec3};

use crate::builder::{SceneBuilder, Shading};
use crate::error::{ErrorKind, SceneError};
use crate::material::Material;
use crate::shapes;

use super::bsdf::{parse_bsdf, ParsedBsdf, DEFAULT_BSDF};
use super::props::{Child, Ctx, Obj};

pub(crate) fn add_shape(
    ctx: &mut Ctx,
    obj: &Obj,
    builder: &mut SceneBuilder,
    bsdfs: &mut Vec<(String, ParsedBsdf)>,
) -> Result<(), SceneError> {
    let plugin = obj.plugin.as_str();
    if !matches!(plugin, "obj" | "ply" | "rectangle" | "cube" | "sphere") {
        ctx.warn(obj.node, format!("unsupported shape '{plugin}' ignored"));
        return Ok(());
    }
    let to_world = obj.transform(ctx, "to_world")?.unwrap_or(Mat4::IDENTITY);
    let flip = obj.boolean(ctx, "flip_normals")?.unwrap_or(false);
    let line = ctx.line(obj.node);

    let (mut mesh, shading, name) = match plugin {
        "obj" | "ply" => {
            let face_normals = obj.boolean(ctx, "face_normals")?.unwrap_or(false);
            let _ = obj.boolean(ctx, "flip_tex_coords")?;
            let Some(filename) = obj.string(ctx, "filename")? else {
                return Err(ctx.err(
                    obj.node,
                    ErrorKind::Syntax,
                    format!("{plugin} shape needs a 'filename'"),
                ));
            };
            let path = ctx.base_dir.join(&filename);
            let outer = ctx.loc(obj.node_of("filename"));
            if !path.is_file() {
                return Err(SceneError::new(
                    ErrorKind::Io,
                    outer,
                    format!("mesh file '{}' not found", path.display()),
                ));
            }
            let mesh = if plugin == "obj" {
                crate::obj::read_obj(&path)
            } else {
                crate::ply::read_ply(&path, &mut ctx.warnings)
            }
            .map_err(|e| e.referenced_from(outer))?;
            let shading = if face_normals {
                Shading::Flat
            } else {
                Shading::Smooth
            };
            (mesh, shading, format!("{plugin} '{filename}'"))
        }
        "rectangle" => (shapes::rectangle(), Shading::Flat, "rectangle".to_string()),
        "cube" => (shapes::cube(), Shading::Flat, "cube".to_string()),
        _ => {
            let center = obj.vector(ctx, "center")?.unwrap_or(Vec3::ZERO);
            let radius = obj.float(ctx, "radius")?.unwrap_or(1.0);
            // Mitsuba: to_world * translate(center) * scale(radius).
            let local = Mat4::from_translation(center) * Mat4::from_scale(Vec3::splat(radius));
            let mesh = shapes::icosphere(shapes::SPHERE_SUBDIVISIONS).transformed(&local);
            (mesh, Shading::Smooth, "sphere".to_string())
        }
    };
    if flip {
        mesh.flip();
    }

    let mut bsdf = None;
    let mut emission = None;
    for child in &obj.children {
        match child {
            Child::Object(o) if o.tag == "bsdf" => {
                let parsed = parse_bsdf(ctx, o, &|id| lookup(bsdfs, id))?;
                if let Some(id) = &o.id {
                    bsdfs.push((id.clone(), parsed));
                }
                set_once(ctx, o.node, &mut bsdf, parsed, "bsdf");
            }
            Child::Ref { id, node } => {
                let parsed = lookup(bsdfs, id).ok_or_else(|| {
                    ctx.err(
                        *node,
                        ErrorKind::Syntax,
                        format!("no BSDF with id '{id}' defined before this point"),
                    )
                })?;
                set_once(ctx, *node, &mut bsdf, parsed, "bsdf");
            }
            Child::Object(o) if o.tag == "emitter" && o.plugin == "area" => {
                let radiance = o.color(ctx, "radiance")?.unwrap_or(Vec3::ONE);
                if !radiance.is_finite() || radiance.min_element() < 0.0 {
                    return Err(ctx.err(
                        o.node_of("radiance"),
                        ErrorKind::Syntax,
                        "radiance must be finite and >= 0",
                    ));
                }
                o.warn_unused(ctx);
                set_once(ctx, o.node, &mut emission, radiance, "emitter");
            }
            Child::Object(o) => {
                ctx.warn(
                    o.node,
                    format!(
                        "<{} type=\"{}\"> inside a shape is not supported and was ignored",
                        o.tag, o.plugin
                    ),
                );
            }
        }
    }
    obj.warn_unused(ctx);

    let ParsedBsdf { bsdf, two_sided } = bsdf.unwrap_or(DEFAULT_BSDF);
    let material = builder.material(Material {
        bsdf,
        two_sided,
        emission,
    });
    let name = obj.id.clone().unwrap_or(format!("{name} (line {line})"));
    let added = builder.add_mesh(&name, &mesh, &to_world, material, shading);
    if added.dropped_degenerate > 0 {
        ctx.warn(
            obj.node,
            format!(
                "{} degenerate (zero-area) triangles of {name} dropped, {} kept",
                added.dropped_degenerate, added.triangles
            ),
        );
    }
    if added.triangles == 0 {
        ctx.warn(obj.node, format!("{name} has no triangles"));
    }
    Ok(())
}

fn lookup(bsdfs: &[(String, ParsedBsdf)], id: &str) -> Option<ParsedBsdf> {
    bsdfs.iter().rev().find(|(i, _)| i == id).map(|(_, b)| *b)
}

fn set_once<T>(ctx: &mut Ctx, node: roxmltree::Node, slot: &mut Option<T>, value: T, what: &str) {
    if slot.is_some() {
        ctx.warn(
            node,
            format!("shape has more than one {what}; the last one is used"),
        );
    }
    *slot = Some(value);
}
