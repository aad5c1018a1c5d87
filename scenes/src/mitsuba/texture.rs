//! Mitsuba's `checkerboard` and `bitmap` textures, read into [`crate::texture::Texture`]s.

use glam::{Mat4, Vec2, Vec3};

use crate::error::SceneError;
use crate::image_file::read_image;
use crate::texture::{Filter, Texture, UvTransform, Wrap};

use super::diag::syntax;
use super::props::Obj;
use super::shape::find_file;
use super::Ctx;

/// Whether the renderer evaluates `plugin` per surface point (else it is a constant colour).
pub(crate) fn is_spatial(plugin: &str) -> bool {
    matches!(plugin, "checkerboard" | "bitmap" | "mesh_attribute")
}

/// Refuses texture `i` where only an image texture can stand (it is read at (u, v), not at
/// a surface point): a `mesh_attribute` there is an error at `at`.
pub(crate) fn image_only(
    ctx: &Ctx,
    i: u32,
    at: &crate::error::Location,
    what: &str,
) -> Result<(), SceneError> {
    match ctx.textures[i as usize] {
        Texture::MeshAttribute { .. } => Err(syntax(
            at,
            format!(
                "a 'mesh_attribute' texture cannot be {what} (it is read at surface points: a \
                 BSDF's colour, a mask's opacity or a blend's weight)"
            ),
        )),
        _ => Ok(()),
    }
}

/// Index in `ctx.textures` of texture `t` (a `checkerboard` or `bitmap`), read once per object.
pub(crate) fn texture_index<'a>(ctx: &mut Ctx<'a>, t: &'a Obj) -> Result<u32, SceneError> {
    let key = t as *const Obj as usize;
    if let Some(&i) = ctx.texture_ids.get(&key) {
        return Ok(i);
    }
    let to_uv = uv_transform(t.transform("to_uv")?.unwrap_or(Mat4::IDENTITY));
    let texture = match t.plugin.as_str() {
        "checkerboard" => Texture::Checkerboard {
            color0: ctx.color(t, "color0")?.unwrap_or(Vec3::splat(0.4)),
            color1: ctx.color(t, "color1")?.unwrap_or(Vec3::splat(0.2)),
            to_uv,
        },
        "mesh_attribute" => mesh_attribute(t)?,
        _ => bitmap(ctx, t, to_uv)?,
    };
    t.finish(&mut ctx.diag)?;
    ctx.textures.push(texture);
    let i = (ctx.textures.len() - 1) as u32;
    ctx.texture_ids.insert(key, i);
    Ok(i)
}

/// Mitsuba `mesh_attribute`: `name` (a mesh attribute: `vertex_color` from a PLY's r, g, b,
/// `face_color`, any other `vertex_*` / `face_*` property group) and `scale`. Whether the
/// shape has the attribute is checked where the shape uses the texture.
fn mesh_attribute(t: &Obj) -> Result<Texture, SceneError> {
    let Some(name) = t.string("name")? else {
        return Err(syntax(
            &t.loc,
            "texture 'mesh_attribute' needs a 'name' (as in Mitsuba)",
        ));
    };
    if !name.starts_with("vertex_") && !name.starts_with("face_") {
        return Err(syntax(
            t.loc_of("name"),
            format!(
                "texture 'mesh_attribute': attribute '{name}' (Mitsuba's names start with \
                 'vertex_' or 'face_')"
            ),
        ));
    }
    Ok(Texture::MeshAttribute {
        name,
        scale: t.float("scale")?.unwrap_or(1.0),
    })
}

/// Mitsuba's `to_uv`: the 2D affine part of a 4x4 transform (x and y rows, translation).
fn uv_transform(m: Mat4) -> UvTransform {
    UvTransform {
        x: Vec2::new(m.x_axis.x, m.x_axis.y),
        y: Vec2::new(m.y_axis.x, m.y_axis.y),
        offset: Vec2::new(m.w_axis.x, m.w_axis.y),
    }
}

fn bitmap<'a>(ctx: &mut Ctx<'a>, t: &'a Obj, to_uv: UvTransform) -> Result<Texture, SceneError> {
    let Some(filename) = t.string("filename")? else {
        return Err(syntax(&t.loc, "texture 'bitmap' needs a 'filename'"));
    };
    let at = t.loc_of("filename").clone();
    let path = find_file(ctx, "image", &filename, &at)?;
    let raw = t.boolean("raw")?.unwrap_or(false);
    let filter = match t.string("filter_type")?.as_deref() {
        None | Some("bilinear") => Filter::Bilinear,
        Some("nearest") => Filter::Nearest,
        Some(other) => {
            return Err(syntax(
                t.loc_of("filter_type"),
                format!("filter_type '{other}' is not one of bilinear, nearest"),
            ))
        }
    };
    let wrap = match t.string("wrap_mode")?.as_deref() {
        None | Some("repeat") => Wrap::Repeat,
        Some("mirror") => Wrap::Mirror,
        Some("clamp") => Wrap::Clamp,
        Some(other) => {
            return Err(syntax(
                t.loc_of("wrap_mode"),
                format!("wrap_mode '{other}' is not one of repeat, mirror, clamp"),
            ))
        }
    };
    // Storage precision and acceleration: no effect on the image.
    t.ignore("format");
    t.ignore("accel");
    let image = read_image(&path, raw)
        .map_err(|e| syntax(&at, format!("image '{}': {e}", path.display())))?;
    Ok(Texture::Bitmap {
        width: image.width,
        height: image.height,
        texels: image.texels,
        filter,
        wrap,
        to_uv,
    })
}

/// The index of texture `i` as Mitsuba evaluates it for a number (`eval_1`, e.g. a mask's
/// opacity): the luminance of the colour lookup, except that its `checkerboard` then takes
/// `color0` where the parities of u and v differ, the opposite of its colour lookup; such a
/// checkerboard is added again with its colours exchanged.
pub(crate) fn scalar_use(ctx: &mut Ctx, i: u32) -> u32 {
    match &ctx.textures[i as usize] {
        Texture::Checkerboard {
            color0,
            color1,
            to_uv,
        } => {
            let swapped = Texture::Checkerboard {
                color0: *color1,
                color1: *color0,
                to_uv: *to_uv,
            };
            ctx.textures.push(swapped);
            (ctx.textures.len() - 1) as u32
        }
        Texture::Bitmap { .. } | Texture::MeshAttribute { .. } => i,
    }
}
