//! Mitsuba `<shape>` plugins → triangles in the [`SceneBuilder`]: mesh files (`obj`, `ply`) and the
//! analytic shapes (`rectangle`, `cube`, and `sphere`, `disk`, `cylinder` tessellated, see
//! [`crate::shapes`]), each with its BSDF and optional `area` emitter folded into one [`Material`].

use std::path::Path;

use glam::{Mat4, Quat, Vec2, Vec3};

use crate::builder::{SceneBuilder, Shading};
use crate::error::{ErrorKind, Location, SceneError};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::shapes;

use super::bsdf::{parse_bsdf, ParsedBsdf, DEFAULT_BSDF};
use super::diag::{err, syntax};
use super::plugins;
use super::props::Obj;
use super::xml::{resolve, show_list};
use super::Ctx;

/// Mitsuba evaluates a `mesh_attribute` texture (of a BSDF or of the shape's area emitter)
/// on the shape it is hit on: the shape must have the attribute, and where the texture is
/// read as a number (a mask's opacity, a blend's weight, a roughness: `eval_1`), the
/// attribute must be a number (Mitsuba's scalar variants throw otherwise). Either mistake
/// is an error at the shape.
fn check_mesh_attributes(
    ctx: &Ctx,
    parsed: &ParsedBsdf,
    emission_texture: Option<u32>,
    mesh: &TriMesh,
    at: &Location,
    shape: &str,
) -> Result<(), SceneError> {
    // (texture, read as a number) of the emitter, the BSDF and each BSDF it blends with.
    let mut reads: Vec<(u32, bool)> = emission_texture.map(|t| (t, false)).into_iter().collect();
    let mut next = Some(*parsed);
    let mut depth = 0;
    while let Some(b) = next.take() {
        reads.extend(b.texture.map(|t| (t, false)));
        reads.extend(b.mask.and_then(|m| m.texture).map(|t| (t, true)));
        if let crate::material::Bsdf::Principled(p) = b.bsdf {
            reads.extend(p.textures.into_iter().flatten().map(|t| (t, true)));
        }
        if let crate::material::Bsdf::RoughConductor { alpha, .. } = b.bsdf {
            reads.extend(
                [alpha.u_texture, alpha.v_texture]
                    .into_iter()
                    .flatten()
                    .map(|t| (t, true)),
            );
        }
        if let Some((_, weight, part)) = b.blend {
            reads.extend(weight.map(|t| (t, true)));
            depth += 1;
            if depth < 8 {
                next = Some(ctx.blend_parts[part as usize]);
            }
        }
    }
    for (t, number) in reads {
        let crate::texture::Texture::MeshAttribute { name, .. } = &ctx.textures[t as usize] else {
            continue;
        };
        let Some(a) = mesh.attributes.iter().find(|a| a.name == *name) else {
            let have: Vec<&str> = mesh.attributes.iter().map(|a| a.name.as_str()).collect();
            return Err(syntax(
                at,
                format!(
                    "shape {shape} has no mesh attribute '{name}' for its 'mesh_attribute' \
                     texture (it has: {}; a PLY's r, g, b give 'vertex_color')",
                    if have.is_empty() {
                        "none".to_string()
                    } else {
                        have.join(", ")
                    }
                ),
            ));
        };
        if a.channels == 4 || (number && a.channels != 1) {
            let wanted = if number {
                "1 (it is read as a number)"
            } else {
                "1 or 3"
            };
            return Err(syntax(
                at,
                format!(
                    "mesh attribute '{name}' of shape {shape} has {} channels; Mitsuba reads {wanted}",
                    a.channels
                ),
            ));
        }
    }
    Ok(())
}

/// Segments around a tessellated disk or cylinder.
const ROUND_SEGMENTS: u32 = 128;

pub(crate) fn add_shape<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    builder: &mut SceneBuilder,
) -> Result<(), SceneError> {
    match obj.plugin.as_str() {
        // A group is drawn only where an instance places it.
        "shapegroup" => group_members(ctx, obj).map(|_| ()),
        "instance" => add_instance(ctx, obj, builder),
        _ => add_placed(ctx, obj, builder, Mat4::IDENTITY, false),
    }
}

/// The shapes of a `shapegroup`, checked as Mitsuba checks them: shapes only, no nested
/// groups or instances, nothing that emits.
fn group_members<'a>(ctx: &mut Ctx<'a>, group: &'a Obj) -> Result<Vec<&'a Obj>, SceneError> {
    let mut members = Vec::new();
    for c in &group.children {
        let t = ctx.target(c)?;
        if t.tag != "shape" {
            continue; // reported as unused by `finish`
        }
        c.take();
        if matches!(t.plugin.as_str(), "shapegroup" | "instance") {
            return Err(syntax(
                &c.loc,
                format!(
                    "a '{}' inside a shapegroup: Mitsuba does not permit nested instancing",
                    t.plugin
                ),
            ));
        }
        members.push(t);
    }
    group.finish(&mut ctx.diag)?;
    Ok(members)
}

/// Mitsuba `instance`: the shapes of the referenced `shapegroup`, placed by its `to_world`.
fn add_instance<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    builder: &mut SceneBuilder,
) -> Result<(), SceneError> {
    let to_world = obj.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let mut group = None;
    for c in &obj.children {
        let t = ctx.target(c)?;
        if t.tag == "shape" && t.plugin == "shapegroup" {
            c.take();
            if group.replace(t).is_some() {
                return Err(syntax(
                    &c.loc,
                    "an instance refers to exactly one shapegroup",
                ));
            }
        }
    }
    obj.finish(&mut ctx.diag)?;
    let Some(group) = group else {
        return Err(syntax(
            &obj.loc,
            "an instance needs a shapegroup: <ref id=\"...\"/> to a <shape type=\"shapegroup\">",
        ));
    };
    for member in group_members(ctx, group)? {
        add_placed(ctx, member, builder, to_world, true)?;
    }
    Ok(())
}

/// One shape, its own `to_world` preceded by `outer` (an instance's placement).
fn add_placed<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    builder: &mut SceneBuilder,
    outer: Mat4,
    in_group: bool,
) -> Result<(), SceneError> {
    let plugin = obj.plugin.as_str();
    if !matches!(
        plugin,
        "obj" | "ply" | "serialized" | "rectangle" | "cube" | "sphere" | "disk" | "cylinder"
    ) {
        return ctx
            .diag
            .unsupported(&obj.loc, plugins::describe("shape", plugin), "skipped");
    }
    let to_world = outer * obj.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let flip = obj.boolean("flip_normals")?.unwrap_or(false);

    let (mut mesh, shading, name) = match plugin {
        "obj" | "ply" | "serialized" => {
            let face_normals = obj.boolean("face_normals")?.unwrap_or(false);
            // Mitsuba flips v (v = 1 - v) of OBJ files by default.
            let flip_tex_coords = obj.boolean("flip_tex_coords")?.unwrap_or(plugin == "obj");
            let shape_index = if plugin == "serialized" {
                let i = obj.integer("shape_index")?.unwrap_or(0);
                u32::try_from(i)
                    .map_err(|_| syntax(obj.loc_of("shape_index"), "shape_index must be >= 0"))?
            } else {
                0
            };
            let Some(filename) = obj.string("filename")? else {
                return Err(syntax(
                    &obj.loc,
                    format!("{plugin} shape needs a 'filename'"),
                ));
            };
            let outer = obj.loc_of("filename").clone();
            let path = find_mesh(ctx, &filename, &outer)?;
            let mesh = match plugin {
                "obj" => crate::obj::read_obj(&path),
                "ply" => crate::ply::read_ply(&path, &mut ctx.diag.warnings),
                _ => crate::serialized::read_serialized(&path, shape_index),
            }
            .map_err(|e| e.referenced_from(outer))?;
            let mut mesh = mesh;
            if flip_tex_coords {
                for uv in mesh.uvs.iter_mut().flatten() {
                    uv.y = 1.0 - uv.y;
                }
            }
            let shading = if face_normals {
                Shading::Flat
            } else {
                Shading::Smooth
            };
            (mesh, shading, format!("{plugin} '{filename}'"))
        }
        "rectangle" => (shapes::rectangle(), Shading::Flat, "rectangle".to_string()),
        "cube" => (shapes::cube(), Shading::Flat, "cube".to_string()),
        // Mitsuba's texture coordinates: (radius, angle / 2 pi).
        "disk" => (
            disk().with_corner_uvs(
                |p| Vec2::new(p.truncate().length(), turn(p.y, p.x)),
                1,
                |p| p.truncate().length() < 1e-6,
            ),
            Shading::Flat,
            "disk".to_string(),
        ),
        "cylinder" => {
            let p0 = obj.vector("p0")?.unwrap_or(Vec3::ZERO);
            let p1 = obj.vector("p1")?.unwrap_or(Vec3::Z);
            let radius = obj.float("radius")?.unwrap_or(1.0);
            let axis = p1 - p0;
            let Some(dir) = axis.try_normalize().filter(|_| radius > 0.0) else {
                return Err(syntax(
                    &obj.loc,
                    "cylinder needs p0 != p1 and a positive radius",
                ));
            };
            // Mitsuba: to_world * translate(p0) * frame(p1 - p0) * scale(r, r, |p1 - p0|).
            let local = Mat4::from_translation(p0)
                * Mat4::from_quat(Quat::from_rotation_arc(Vec3::Z, dir))
                * Mat4::from_scale(Vec3::new(radius, radius, axis.length()));
            // Mitsuba's texture coordinates: (angle / 2 pi, height).
            let mesh =
                open_cylinder().with_corner_uvs(|p| Vec2::new(turn(p.y, p.x), p.z), 0, |_| false);
            (
                mesh.transformed(&local),
                Shading::Smooth,
                "cylinder".to_string(),
            )
        }
        _ => {
            let center = obj.vector("center")?.unwrap_or(Vec3::ZERO);
            let radius = obj.float("radius")?.unwrap_or(1.0);
            // Mitsuba: to_world * translate(center) * scale(radius).
            let local = Mat4::from_translation(center) * Mat4::from_scale(Vec3::splat(radius));
            // Mitsuba's texture coordinates: (azimuth / 2 pi, polar angle from +z / pi).
            let mesh = shapes::icosphere(shapes::SPHERE_SUBDIVISIONS)
                .with_corner_uvs(
                    |p| {
                        Vec2::new(
                            turn(p.y, p.x),
                            p.z.clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI,
                        )
                    },
                    0,
                    |p| p.truncate().length() < 1e-6,
                )
                .transformed(&local);
            (mesh, Shading::Smooth, "sphere".to_string())
        }
    };
    if flip {
        mesh.flip();
    }

    let mut bsdf: Option<ParsedBsdf> = None;
    let mut emission: Option<Vec3> = None;
    let mut emission_texture: Option<u32> = None;
    for c in &obj.children {
        let t = ctx.target(c)?;
        match (t.tag.as_str(), t.plugin.as_str()) {
            ("bsdf", _) => {
                c.take();
                let parsed = parse_bsdf(ctx, t)?;
                if bsdf.is_some() {
                    ctx.diag.unsupported(
                        &c.loc,
                        "a second BSDF in one shape (Mitsuba allows one)",
                        "ignored; the first is used",
                    )?;
                } else {
                    bsdf = Some(parsed);
                }
            }
            ("emitter", _) if in_group => {
                return Err(syntax(
                    &c.loc,
                    "an emitter on a shape inside a shapegroup: Mitsuba does not support instancing emitters",
                ));
            }
            ("emitter", "area") => {
                c.take();
                let key = t as *const Obj as usize;
                if ctx.attached.contains(&key) {
                    ctx.diag.unsupported(
                        &c.loc,
                        "this area emitter is already attached to another shape (Mitsuba allows one)",
                        "each shape emits",
                    )?;
                }
                ctx.attached.push(key);
                // Mitsuba's `radiance` may be a texture: its value per point (its mean
                // weighs the light among the others).
                let (radiance, texture) = match ctx.spatial_texture(t, "radiance")? {
                    Some((mean, i)) => (mean, Some(i)),
                    None => (
                        ctx.color_as(t, "radiance", super::SpectrumUse::Emission)?
                            .unwrap_or(Vec3::ONE),
                        None,
                    ),
                };
                if !radiance.is_finite() || radiance.min_element() < 0.0 {
                    return Err(syntax(
                        t.loc_of("radiance"),
                        "radiance must be finite and >= 0",
                    ));
                }
                t.finish(&mut ctx.diag)?;
                if emission.is_some() {
                    ctx.diag.unsupported(
                        &c.loc,
                        "a second emitter in one shape (Mitsuba allows one)",
                        "ignored; the first is used",
                    )?;
                } else {
                    emission = Some(radiance);
                    emission_texture = texture;
                }
            }
            ("emitter", other) => {
                c.take();
                ctx.diag.unsupported(
                    &c.loc,
                    format!(
                        "emitter '{other}' inside a shape (only 'area' emitters attach to shapes)"
                    ),
                    "ignored",
                )?;
            }
            ("medium", _) | ("sensor", _) => {
                c.take();
                ctx.diag.unsupported(
                    &c.loc,
                    format!(
                        "<{} type=\"{}\"> attached to a shape is not supported by the renderer",
                        t.tag, t.plugin
                    ),
                    "ignored",
                )?;
            }
            // Anything else is reported as unused by `finish`.
            _ => {}
        }
    }
    obj.finish(&mut ctx.diag)?;

    // Mitsuba's default BSDF is diffuse 0.5, but black on a shape that emits.
    let parsed = match (bsdf, emission) {
        (Some(b), _) => b,
        (None, Some(_)) => ParsedBsdf {
            bsdf: crate::material::Bsdf::Diffuse {
                reflectance: Vec3::ZERO,
            },
            ..DEFAULT_BSDF
        },
        (None, None) => DEFAULT_BSDF,
    };
    check_mesh_attributes(ctx, &parsed, emission_texture, &mesh, &obj.loc, &name)?;
    let material = register_material(ctx, builder, parsed, emission, emission_texture);
    let line = obj.loc.line_number().unwrap_or(0);
    let name = obj.id.clone().unwrap_or(format!("{name} (line {line})"));
    let added = builder.add_mesh(&name, &mesh, &to_world, material, shading);
    if added.dropped_degenerate > 0 {
        ctx.diag.warn(
            &obj.loc,
            format!(
                "{} degenerate (zero-area) triangles of {name} dropped, {} kept",
                added.dropped_degenerate, added.triangles
            ),
        );
    }
    if added.triangles == 0 {
        ctx.diag.warn(&obj.loc, format!("{name} has no triangles"));
    }
    Ok(())
}

/// Resolves a mesh file name as Mitsuba does: in the main scene file's `<path>` folders, its
/// folder, then the working directory.
fn find_mesh(ctx: &Ctx, filename: &str, at: &Location) -> Result<std::path::PathBuf, SceneError> {
    find_file(ctx, "mesh", filename, at)
}

/// The file `filename` that a `what` (mesh, image...) names, searched as Mitsuba does.
pub(crate) fn find_file(
    ctx: &Ctx,
    what: &str,
    filename: &str,
    at: &Location,
) -> Result<std::path::PathBuf, SceneError> {
    if let Some(p) = resolve(&ctx.search, Path::new(filename)) {
        if p.is_file() {
            return Ok(p);
        }
    }
    let mut msg = format!(
        "{what} file '{filename}' not found (searched in {})",
        show_list(&ctx.search)
    );
    // A shape written in an included file still resolves against the main file's folders.
    if let Some(dir) = at.file.parent() {
        let beside = dir.join(filename);
        if beside.is_file() && !ctx.search.iter().any(|s| s == dir) {
            msg += &format!(
                "; note: '{}' exists, but as in Mitsuba, file names in an included file are resolved from the main scene file's folder and <path>s",
                beside.display()
            );
        }
    }
    Err(err(at, ErrorKind::Io, msg))
}

/// The angle of (x, y) around +z in turns, in [0, 1).
fn turn(y: f32, x: f32) -> f32 {
    let t = y.atan2(x) * (0.5 * std::f32::consts::FRAC_1_PI);
    if t < 0.0 {
        t + 1.0
    } else {
        t
    }
}

/// Mitsuba `disk`: the unit disk in z = 0, normal +z.
fn disk() -> TriMesh {
    lathe_z(&[Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)])
}

/// Mitsuba `cylinder` before its placement: radius 1 around +z from z = 0 to 1, open ends,
/// normals outward.
fn open_cylinder() -> TriMesh {
    lathe_z(&[Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0)])
}

/// [`shapes::lathe`] (about +y) turned so that its axis is +z.
fn lathe_z(profile: &[Vec2]) -> TriMesh {
    let y_to_z = Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    shapes::lathe(profile, ROUND_SEGMENTS).transformed(&y_to_z)
}

/// The material of a parsed BSDF on a shape with `emission`, registered with the builder;
/// a `blendbsdf`'s second BSDF first, as its own material with the blend's emission,
/// sidedness and mask (whichever BSDF scatters, the surface is the same).
fn register_material(
    ctx: &Ctx,
    builder: &mut SceneBuilder,
    parsed: ParsedBsdf,
    emission: Option<Vec3>,
    emission_texture: Option<u32>,
) -> u32 {
    let blend = parsed.blend.map(|(weight, texture, part)| {
        let other = ParsedBsdf {
            two_sided: parsed.two_sided || ctx.blend_parts[part as usize].two_sided,
            mask: parsed.mask.or(ctx.blend_parts[part as usize].mask),
            perturb: parsed.perturb.or(ctx.blend_parts[part as usize].perturb),
            ..ctx.blend_parts[part as usize]
        };
        crate::material::Blend {
            weight,
            texture,
            other: register_material(ctx, builder, other, emission, emission_texture),
        }
    });
    builder.material(Material {
        bsdf: parsed.bsdf,
        two_sided: parsed.two_sided,
        emission,
        texture: parsed.texture,
        mask: parsed.mask,
        blend,
        perturb: parsed.perturb,
        emission_texture,
    })
}
