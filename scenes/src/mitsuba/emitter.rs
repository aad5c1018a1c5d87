//! Mitsuba emitters that are not attached to a shape: `constant` and `envmap` (the
//! environment), `point`, `spot` (with its `texture`), `projector` and `directional`, read with Mitsuba 3.9's parameters and defaults. (`area` emitters
//! are read where their shape is, in `shape.rs`.)

use glam::{Mat4, Vec3};

use super::diag::syntax;
use super::props::Obj;
use super::{plugins, Ctx};
use crate::environment_map::EnvironmentMap;
use crate::error::SceneError;
use crate::image_file::read_image;
use crate::scene::Light;

/// What a top-level `<emitter>` adds to the scene.
pub(crate) struct Emitters {
    /// Constant environment radiance (Mitsuba `constant`).
    pub environment: Option<Vec3>,
    /// Mitsuba `envmap` (with a `constant` given too, under `--lenient`, the constant is
    /// added to its texels).
    pub environment_map: Option<EnvironmentMap>,
    pub lights: Vec<Light>,
}

impl Emitters {
    /// The environment of the scene: a map (with any constant radiance added to it), or the
    /// constant radiance alone.
    pub fn into_environment(self) -> (Vec3, Option<EnvironmentMap>) {
        let constant = self.environment.unwrap_or(Vec3::ZERO);
        match self.environment_map {
            Some(mut map) => {
                map.texels.iter_mut().for_each(|t| *t += constant);
                (Vec3::ZERO, Some(map))
            }
            None => (constant, None),
        }
    }

    /// Whether an environment emitter has been read already.
    fn has_environment(&self) -> bool {
        self.environment.is_some() || self.environment_map.is_some()
    }
}

/// Reads one top-level `<emitter>` into `out`.
pub(crate) fn emitter<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    out: &mut Emitters,
) -> Result<(), SceneError> {
    match obj.plugin.as_str() {
        "constant" => {
            let radiance = spectrum(ctx, obj, "radiance")?;
            obj.finish(&mut ctx.diag)?;
            if out.has_environment() {
                ctx.diag.unsupported(
                    &obj.loc,
                    "a second environment emitter (Mitsuba allows one per scene)",
                    "added to the first",
                )?;
            }
            *out.environment.get_or_insert(Vec3::ZERO) += radiance;
        }
        "envmap" => {
            let map = environment_map(ctx, obj)?;
            if out.has_environment() {
                ctx.diag.unsupported(
                    &obj.loc,
                    "a second environment emitter (Mitsuba allows one per scene)",
                    if out.environment_map.is_some() {
                        "skipped"
                    } else {
                        "the constant radiance is added to the map"
                    },
                )?;
            }
            if out.environment_map.is_none() {
                out.environment_map = Some(map);
            }
        }
        "point" => {
            let intensity = spectrum(ctx, obj, "intensity")?;
            let position = match vector_or_to_world(obj, "position")? {
                Ok(p) => p,
                Err(to_world) => to_world.transform_point3(Vec3::ZERO),
            };
            obj.finish(&mut ctx.diag)?;
            out.lights.push(Light::Point {
                position,
                intensity,
            });
        }
        "spot" => {
            let intensity = spectrum(ctx, obj, "intensity")?;
            let to_world = invertible_to_world(obj)?;
            let cutoff = obj.float("cutoff_angle")?.unwrap_or(20.0);
            let beam = obj.float("beam_width")?.unwrap_or(cutoff * 0.75);
            if !(cutoff > 0.0 && cutoff <= 180.0) {
                return Err(syntax(
                    obj.loc_of("cutoff_angle"),
                    format!("emitter 'spot': cutoff_angle {cutoff} must be in (0, 180] degrees"),
                ));
            }
            // Mitsuba asserts cutoff_angle >= beam_width; equal angles make a hard-edged cone.
            if !(beam >= 0.0 && beam <= cutoff) {
                return Err(syntax(
                    obj.loc_of("beam_width"),
                    format!(
                        "emitter 'spot': beam_width {beam} must be in [0, cutoff_angle = {cutoff}] degrees"
                    ),
                ));
            }
            // Mitsuba: the texture must vary over the beam (a bitmap or checkerboard).
            let texture = match ctx.color_or_texture(obj, "texture")? {
                None => None,
                Some((_, Some(t))) => {
                    super::texture::image_only(ctx, t, obj.loc_of("texture"), "a spot's texture")?;
                    Some(t)
                }
                Some((_, None)) => {
                    return Err(syntax(
                        obj.loc_of("texture"),
                        "emitter 'spot': 'texture' must be spatially varying (e.g. a bitmap), as in Mitsuba",
                    ))
                }
            };
            obj.finish(&mut ctx.diag)?;
            out.lights.push(Light::Spot {
                to_world,
                intensity,
                cutoff_angle: cutoff.to_radians(),
                beam_width: beam.to_radians(),
                texture,
            });
        }
        "projector" => {
            let scale = obj.float("scale")?.unwrap_or(1.0);
            if !(scale.is_finite() && scale >= 0.0) {
                return Err(syntax(
                    obj.loc_of("scale"),
                    format!("emitter 'projector': scale {scale} must be finite and >= 0"),
                ));
            }
            let (irradiance, texture) = match ctx.color_or_texture(obj, "irradiance")? {
                None => (Vec3::ONE, None),
                Some((c, None)) => (c, None),
                Some((_, Some(t))) => {
                    super::texture::image_only(
                        ctx,
                        t,
                        obj.loc_of("irradiance"),
                        "a projector's image",
                    )?;
                    (Vec3::ONE, Some(t))
                }
            };
            if !(irradiance.is_finite() && irradiance.min_element() >= 0.0) {
                return Err(syntax(
                    obj.loc_of("irradiance"),
                    "emitter 'projector': irradiance must be finite and >= 0",
                ));
            }
            // The image's aspect ratio shapes the projection (1 for a constant).
            let aspect = match texture.map(|t| &ctx.textures[t as usize]) {
                Some(crate::texture::Texture::Bitmap { width, height, .. }) => {
                    *width as f32 / *height as f32
                }
                _ => 1.0,
            };
            let (fov, axis) = super::read_fov(obj)?;
            let fov_x = crate::camera::fov_x(fov, axis, aspect);
            let to_world = invertible_to_world(obj)?;
            obj.finish(&mut ctx.diag)?;
            out.lights.push(Light::Projector {
                to_world,
                irradiance: irradiance * scale,
                texture,
                tan_half_fov: (0.5 * fov_x.to_radians()).tan(),
                aspect,
            });
        }
        "directional" => {
            let irradiance = spectrum(ctx, obj, "irradiance")?;
            let direction = match vector_or_to_world(obj, "direction")? {
                Ok(d) => d,
                Err(to_world) => to_world.transform_vector3(Vec3::Z),
            };
            if !(direction.length() > 0.0 && direction.is_finite()) {
                return Err(syntax(
                    obj.loc_of("direction"),
                    "emitter 'directional': the direction is zero",
                ));
            }
            obj.finish(&mut ctx.diag)?;
            out.lights.push(Light::Directional {
                direction: direction.normalize(),
                irradiance,
            });
        }
        // With an id it is attached where a shape refers to it; Mitsuba drops a bare one.
        "area" if obj.id.is_some() => {}
        "area" => ctx.diag.warn(
            &obj.loc,
            "an area emitter must be nested in a <shape>; ignored (as Mitsuba does)",
        ),
        other => ctx
            .diag
            .unsupported(&obj.loc, plugins::describe("emitter", other), "skipped")?,
    }
    Ok(())
}

/// Mitsuba `envmap`: `filename` (any image a `bitmap` texture reads, sRGB-decoded where
/// the format is), `scale`, `to_world` (its linear part, which must be invertible);
/// `mis_compensation` only changes how Mitsuba samples the map, not the image.
fn environment_map<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<EnvironmentMap, SceneError> {
    let Some(filename) = obj.string("filename")? else {
        return Err(syntax(&obj.loc, "emitter 'envmap' needs a 'filename'"));
    };
    let at = obj.loc_of("filename").clone();
    let path = super::shape::find_file(ctx, "image", &filename, &at)?;
    let scale = obj.float("scale")?.unwrap_or(1.0);
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(syntax(
            obj.loc_of("scale"),
            format!("emitter 'envmap': scale {scale} must be finite and >= 0"),
        ));
    }
    let to_world = glam::Mat3::from_mat4(invertible_to_world(obj)?);
    obj.ignore("mis_compensation");
    obj.finish(&mut ctx.diag)?;
    let image = read_image(&path, false)
        .map_err(|e| syntax(&at, format!("image '{}': {e}", path.display())))?;
    if let Some(bad) = image
        .texels
        .iter()
        .find(|t| !t.is_finite() || t.min_element() < 0.0)
    {
        return Err(syntax(
            &at,
            format!(
                "image '{}': emitter 'envmap' needs finite radiance >= 0, found {bad}",
                path.display()
            ),
        ));
    }
    Ok(EnvironmentMap::new(
        image.width,
        image.height,
        &image.texels,
        scale,
        to_world,
    ))
}

/// The emitter's `to_world` (identity when absent), which must be invertible.
fn invertible_to_world(obj: &Obj) -> Result<Mat4, SceneError> {
    let m = obj.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let linear = glam::Mat3::from_mat4(m);
    if !(linear.determinant() != 0.0 && linear.is_finite()) {
        return Err(syntax(
            obj.loc_of("to_world"),
            format!("emitter '{}': to_world is singular", obj.plugin),
        ));
    }
    Ok(m)
}

/// Mitsuba's rule for `point` (`position`) and `directional` (`direction`): the vector
/// parameter `name` (Ok), or else `to_world` (Err, identity when absent), never both.
fn vector_or_to_world(obj: &Obj, name: &str) -> Result<Result<Vec3, Mat4>, SceneError> {
    match (obj.vector(name)?, obj.transform("to_world")?) {
        (Some(_), Some(_)) => Err(syntax(
            obj.loc_of(name),
            format!(
                "emitter '{}': give either '{name}' or 'to_world', not both",
                obj.plugin
            ),
        )),
        (Some(v), None) => Ok(Ok(v)),
        (None, m) => Ok(Err(m.unwrap_or(Mat4::IDENTITY))),
    }
}

/// A non-negative colour parameter, 1 when absent (Mitsuba's default for every emitter).
fn spectrum<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj, name: &str) -> Result<Vec3, SceneError> {
    let v = ctx
        .color_as(obj, name, super::SpectrumUse::Emission)?
        .unwrap_or(Vec3::ONE);
    if !v.is_finite() || v.min_element() < 0.0 {
        return Err(syntax(
            obj.loc_of(name),
            format!("emitter '{}': {name} must be finite and >= 0", obj.plugin),
        ));
    }
    Ok(v)
}
