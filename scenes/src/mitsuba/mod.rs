//! Mitsuba 3 XML → [`Scene`] + warnings, read as Mitsuba 3.9 reads it.
//!
//! Stages:
//! 1. `xml.rs`: the files → one element tree: `$parameter` substitution and `<default>`s,
//!    `<include>` (with cycle detection), `<path>` search folders, `version` (and the upgrade of
//!    pre-2.0 names).
//! 2. `props.rs`: elements → plugin objects with typed properties, nested objects and `<ref>`s;
//!    the global `id` table; unresolved and circular references are errors.
//! 3. the plugin interpreters (`sensor`, `bsdf.rs`, `shape.rs`, emitters, integrator) consume
//!    the properties they support.
//!
//! Malformed input is an error with file and line. What Mitsuba itself rejects (unknown plugins,
//! elements, attributes, properties) and plugins the renderer does not implement are errors too,
//! unless [`LoadOptions::lenient`] turns each into a [`Warning`] saying what was done instead.
//! Approximations of supported plugins (e.g. a beckmann roughness read as ggx) are always
//! warnings. The README's table lists what is read, approximated and refused.

mod bsdf;
mod cie_tables;
mod conductor_iors;
mod diag;
mod emitter;
mod plugins;
mod principled;
mod props;
mod shape;
mod spectrum;
mod texture;
mod transform;

use spectrum::SpectrumUse;
mod xml;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use crate::builder::SceneBuilder;
use crate::camera::{Camera, CropWindow, FovAxis, Projection};
use crate::error::{SceneError, Warning};
use crate::film_filter::FilmFilter;
use crate::scene::{Integrator, Scene};

pub use bsdf::named_ior;
use bsdf::ParsedBsdf;
use diag::{syntax, Diag};
use props::{Ids, Kind, Obj};

/// A loaded scene and what the loader had to ignore or approximate (callers print these).
#[derive(Clone, Debug)]
pub struct Loaded {
    pub scene: Scene,
    pub warnings: Vec<Warning>,
}

/// How to read a scene.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `$name` parameters, overriding the file's `<default>`s (Mitsuba's `-D name=value`).
    pub params: Vec<(String, String)>,
    /// Unknown or unsupported plugins, elements, attributes and parameters become warnings (the
    /// object skipped or replaced by the nearest supported one) instead of errors.
    pub lenient: bool,
}

/// Loads a Mitsuba 3 XML scene strictly; file names resolve as in Mitsuba (see `xml.rs`).
pub fn load_mitsuba(path: impl AsRef<Path>) -> Result<Loaded, SceneError> {
    load_mitsuba_with(path, &LoadOptions::default())
}

/// Like [`load_mitsuba`], with `$name` parameters overriding the file's `<default>`s (Mitsuba's
/// `-D name=value`).
pub fn load_mitsuba_with_params(
    path: impl AsRef<Path>,
    params: &[(&str, &str)],
) -> Result<Loaded, SceneError> {
    let options = LoadOptions {
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        lenient: false,
    };
    load_mitsuba_with(path, &options)
}

pub fn load_mitsuba_with(
    path: impl AsRef<Path>,
    options: &LoadOptions,
) -> Result<Loaded, SceneError> {
    load(xml::Source::File(path.as_ref()), options)
}

/// Loads a scene from XML text, strictly. File names resolve relative to `base_dir` (then the
/// working directory); locations name the file `<string>`.
pub fn load_mitsuba_str(xml: &str, base_dir: impl AsRef<Path>) -> Result<Loaded, SceneError> {
    load_mitsuba_str_with(xml, base_dir, &LoadOptions::default())
}

pub fn load_mitsuba_str_with(
    xml: &str,
    base_dir: impl AsRef<Path>,
    options: &LoadOptions,
) -> Result<Loaded, SceneError> {
    load(
        xml::Source::Text {
            text: xml,
            base_dir: base_dir.as_ref(),
        },
        options,
    )
}

/// State of the plugin stage.
pub(crate) struct Ctx<'a> {
    pub diag: Diag,
    pub ids: Ids<'a>,
    /// Folders searched for mesh files.
    pub search: Vec<PathBuf>,
    /// Parsed BSDFs by object address.
    pub bsdfs: HashMap<usize, ParsedBsdf>,
    /// Second BSDFs of `blendbsdf`s (`ParsedBsdf::blend`).
    pub blend_parts: Vec<ParsedBsdf>,
    /// Area emitters already attached to a shape, by object address.
    pub attached: Vec<usize>,
    /// The scene's textures, and their index by object address.
    pub textures: Vec<crate::texture::Texture>,
    pub texture_ids: HashMap<usize, u32>,
}

impl<'a> Ctx<'a> {
    /// The object a child is or refers to.
    pub fn target(&self, c: &'a props::Child) -> Result<&'a Obj, SceneError> {
        match &c.kind {
            Kind::Object(o) => Ok(o),
            Kind::Ref(id) => self
                .ids
                .get(id)
                .copied()
                .ok_or_else(|| syntax(&c.loc, format!("<ref>: no object has id '{id}'"))),
        }
    }

    /// A colour parameter that may vary over the surface: a value, or a `checkerboard` or
    /// `bitmap` texture (then its mean and its index in `textures`).
    pub fn color_or_texture(
        &mut self,
        obj: &'a Obj,
        name: &str,
    ) -> Result<Option<(Vec3, Option<u32>)>, SceneError> {
        if let Some((mean, i)) = self.spatial_texture(obj, name)? {
            return Ok(Some((mean, Some(i))));
        }
        Ok(self.color(obj, name)?.map(|c| (c, None)))
    }

    /// Parameter `name` of `obj` where it is a texture that varies over the surface
    /// (`checkerboard`, `bitmap`, `mesh_attribute`): its mean colour and its index.
    pub fn spatial_texture(
        &mut self,
        obj: &'a Obj,
        name: &str,
    ) -> Result<Option<(Vec3, u32)>, SceneError> {
        if let Some(c) = obj
            .children
            .iter()
            .find(|c| c.name.as_deref() == Some(name))
        {
            let t = self.target(c)?;
            if t.tag == "texture" && texture::is_spatial(&t.plugin) {
                c.take();
                let i = texture::texture_index(self, t)?;
                return Ok(Some((self.textures[i as usize].mean(), i)));
            }
        }
        Ok(None)
    }

    /// A colour parameter given as a value, or as a texture (nested or `<ref name=...>`); a
    /// sampled spectrum is read as a reflectance.
    pub fn color(&mut self, obj: &'a Obj, name: &str) -> Result<Option<Vec3>, SceneError> {
        self.color_as(obj, name, SpectrumUse::Reflectance)
    }

    /// [`color`](Self::color), with a sampled spectrum converted as `used_as` says (Mitsuba
    /// converts an emitter's spectra without the D65 illuminant and clamps them only at 0).
    pub fn color_as(
        &mut self,
        obj: &'a Obj,
        name: &str,
        used_as: SpectrumUse,
    ) -> Result<Option<Vec3>, SceneError> {
        if let Some(samples) = obj.spectrum_samples(name) {
            let (rgb, clamped) = spectrum::to_srgb(&samples, used_as);
            if clamped {
                self.diag.warn(
                    obj.loc_of(name),
                    format!(
                        "spectrum '{name}': out-of-gamut colour clamped to {rgb}, as Mitsuba does"
                    ),
                );
            }
            return Ok(Some(rgb));
        }
        if let Some(v) = obj.color(name)? {
            return Ok(Some(v));
        }
        let Some(c) = obj.child_named(name) else {
            return Ok(None);
        };
        let t = self.target(c)?;
        if t.tag != "texture" {
            return Err(syntax(
                &c.loc,
                format!(
                    "'{name}' of {} '{}' must be a colour or a texture, not a <{}>",
                    obj.tag, obj.plugin, t.tag
                ),
            ));
        }
        self.texture(t).map(Some)
    }

    /// A texture as one colour: exact for the constant plugins, otherwise unsupported (lenient:
    /// its mean where known, grey 0.5 otherwise).
    fn texture(&mut self, t: &'a Obj) -> Result<Vec3, SceneError> {
        let value = match t.plugin.as_str() {
            "uniform" => t
                .float("value")?
                .map(Vec3::splat)
                .ok_or_else(|| syntax(&t.loc, "texture 'uniform' needs a 'value'"))?,
            // Mitsuba's `rawconstant`: the value as given, no colour conversion (an RGB
            // variant converts none anyway).
            "rawconstant" => t
                .float_or_vector("value")?
                .ok_or_else(|| syntax(&t.loc, "texture 'rawconstant' needs a 'value'"))?,
            "srgb" => {
                let _ = t.boolean("unbounded")?;
                t.color("color")?
                    .ok_or_else(|| syntax(&t.loc, "texture 'srgb' needs a 'color'"))?
            }
            plugin if texture::is_spatial(plugin) => {
                let i = texture::texture_index(self, t)?;
                let mean = self.textures[i as usize].mean();
                self.diag.unsupported(
                    &t.loc,
                    format!("a '{plugin}' texture here (this parameter takes one value; textures vary BSDF colours, a rough conductor's roughness, principled parameters, mask opacities and blend weights)"),
                    format!("replaced by its mean colour {mean}"),
                )?;
                return Ok(mean);
            }
            other => {
                self.diag.unsupported(
                    &t.loc,
                    plugins::describe("texture", other),
                    "replaced by grey 0.5",
                )?;
                return Ok(Vec3::splat(0.5));
            }
        };
        t.finish(&mut self.diag)?;
        Ok(value)
    }
}

fn load(source: xml::Source, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let mut diag = Diag::new(options.lenient);
    let doc = xml::read(&mut diag, source, &options.params)?;
    let (scene, warnings) = build(diag, &doc).map_err(|e| doc.with_includes(e))?;
    // A referenced object may be interpreted more than once: report each finding once.
    let mut unique: Vec<Warning> = Vec::new();
    for w in warnings {
        if !unique.contains(&w) {
            unique.push(w);
        }
    }
    Ok(Loaded {
        scene,
        warnings: unique,
    })
}

/// Stages 2 and 3.
fn build(mut diag: Diag, doc: &xml::Document) -> Result<(Scene, Vec<Warning>), SceneError> {
    let (scene_obj, aliases) = props::parse_scene(&mut diag, &doc.root)?;
    let ids = props::index(&scene_obj, &aliases)?;
    props::check_refs(&scene_obj, &ids)?;
    let mut ctx = Ctx {
        diag,
        ids,
        search: doc.search.clone(),
        bsdfs: HashMap::new(),
        blend_parts: Vec::new(),
        attached: Vec::new(),
        textures: Vec::new(),
        texture_ids: HashMap::new(),
    };
    let scene = interpret(&mut ctx, &scene_obj)?;
    Ok((scene, ctx.diag.warnings))
}

fn interpret<'a>(ctx: &mut Ctx<'a>, root: &'a Obj) -> Result<Scene, SceneError> {
    let mut camera: Option<(Camera, u32)> = None;
    let mut emitters = emitter::Emitters {
        environment: None,
        environment_map: None,
        lights: Vec::new(),
    };
    let mut integrator: Option<Integrator> = None;
    let mut builder = SceneBuilder::new(default_camera());

    for c in &root.children {
        c.take();
        let obj = ctx.target(c)?;
        let by_ref = matches!(c.kind, Kind::Ref(_));
        match obj.tag.as_str() {
            // Mitsuba adds a shape (or emitter) once per top-level occurrence, references included.
            "shape" => shape::add_shape(ctx, obj, &mut builder)?,
            "emitter" => emitter::emitter(ctx, obj, &mut emitters)?,
            "sensor" if camera.is_some() => ctx.diag.warn(
                &c.loc,
                "only the first sensor is rendered; this one is ignored",
            ),
            "sensor" => camera = Some(parse_sensor(ctx, obj)?),
            "integrator" if integrator.is_some() => ctx.diag.unsupported(
                &c.loc,
                "a second <integrator> (Mitsuba allows one per scene)",
                "ignored; the first is used",
            )?,
            "integrator" => integrator = Some(parse_integrator(ctx, obj)?),
            // Other objects only matter where they are used (a BSDF by a shape, a film by a
            // sensor...); Mitsuba instantiates them all, so an unknown plugin is still refused,
            // and a supported BSDF is checked.
            _ if by_ref => {}
            "bsdf" if bsdf::SUPPORTED.contains(&obj.plugin.as_str()) => {
                bsdf::parse_bsdf(ctx, obj)?;
                if obj.id.is_none() {
                    ctx.diag
                        .warn(&obj.loc, "top-level <bsdf> without an id can never be used");
                }
            }
            tag if !plugins::is_known(tag, &obj.plugin) => {
                ctx.diag
                    .unsupported(&obj.loc, plugins::describe(tag, &obj.plugin), "ignored")?
            }
            _ => {}
        }
    }
    root.finish(&mut ctx.diag)?;

    let (camera, sample_count) = camera.unwrap_or_else(|| {
        ctx.diag.warn(
            &root.loc,
            "scene has no sensor (Mitsuba renders nothing); using Mitsuba's default camera",
        );
        (default_camera(), 4)
    });
    let integrator = integrator.unwrap_or_else(|| {
        ctx.diag.warn(
            &root.loc,
            "scene has no <integrator> (Mitsuba refuses to render it); using 'path' with Mitsuba's defaults",
        );
        Integrator::default()
    });
    let scene = builder.scene_mut();
    scene.textures = std::mem::take(&mut ctx.textures);
    scene.camera = camera;
    scene.lights = std::mem::take(&mut emitters.lights);
    (scene.environment, scene.environment_map) = emitters.into_environment();
    scene.integrator = integrator;
    scene.sample_count = sample_count;
    Ok(builder.finish())
}

/// Mitsuba's default sensor: perspective at the origin looking down +z, 50 mm lens, 768 x 576 film.
fn default_camera() -> Camera {
    Camera {
        to_world: Mat4::IDENTITY,
        fov: fov_from_focal_length(50.0),
        fov_axis: FovAxis::Diagonal,
        width: 768,
        height: 576,
        near_clip: 1e-2,
        far_clip: 1e4,
        projection: Projection::Perspective,
        aperture_radius: 0.0,
        focus_distance: 1e4,
        crop: None,
        filter: None,
    }
}

/// Mitsuba: a focal length on a 36 x 24 mm film gives a diagonal field of view.
fn fov_from_focal_length(mm: f64) -> f32 {
    (2.0 * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm)).atan()).to_degrees() as f32
}

fn parse_sensor<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<(Camera, u32), SceneError> {
    let camera = match obj.plugin.as_str() {
        "perspective" => {
            let camera = read_perspective(ctx, obj)?;
            for name in ["principal_point_offset_x", "principal_point_offset_y"] {
                if obj.float(name)?.is_some_and(|v| v != 0.0) {
                    ctx.diag.warn(
                        obj.loc_of(name),
                        format!("{name} is not supported: the principal point stays centred"),
                    );
                }
            }
            camera
        }
        "orthographic" => read_orthographic(ctx, obj)?,
        "thinlens" => read_thinlens(ctx, obj)?,
        other => {
            ctx.diag.unsupported(
                &obj.loc,
                plugins::describe("sensor", other),
                "replaced by a perspective camera with its to_world and fov",
            )?;
            // Read what a perspective camera would; the rest is the unsupported plugin's.
            let camera = read_perspective(ctx, obj)?;
            return Ok(read_film_and_sampler(ctx, obj, true)?.fit(camera));
        }
    };
    // No motion blur in a static scene; a spectral response has no effect on an RGB film.
    obj.ignore("shutter_open");
    obj.ignore("shutter_close");
    obj.ignore("srf");
    let film = read_film_and_sampler(ctx, obj, false)?;
    obj.finish(&mut ctx.diag)?;
    Ok(film.fit(camera))
}

/// Mitsuba `thinlens`: a perspective camera with `aperture_radius` (required) and
/// `focus_distance` (default: the far clip plane, as in Mitsuba).
fn read_thinlens(ctx: &mut Ctx, obj: &Obj) -> Result<Camera, SceneError> {
    let camera = read_perspective(ctx, obj)?;
    let Some(aperture_radius) = obj.float("aperture_radius")? else {
        return Err(syntax(
            &obj.loc,
            "sensor 'thinlens' needs an 'aperture_radius' (as in Mitsuba)",
        ));
    };
    let focus_distance = obj.float("focus_distance")?.unwrap_or(camera.far_clip);
    if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
        return Err(syntax(
            obj.loc_of("aperture_radius"),
            "aperture_radius must be finite and >= 0",
        ));
    }
    if !(focus_distance > 0.0 && focus_distance.is_finite()) {
        return Err(syntax(
            obj.loc_of("focus_distance"),
            "focus_distance must be finite and positive",
        ));
    }
    Ok(Camera {
        aperture_radius,
        focus_distance,
        ..camera
    })
}

/// Mitsuba's `fov` + `fov_axis` (default x) or `focal_length` (default 50mm, a diagonal
/// field of view on a 36 x 24 mm film), as its `parse_fov` reads them: (degrees, axis).
pub(crate) fn read_fov(obj: &Obj) -> Result<(f32, FovAxis), SceneError> {
    let (fov, fov_axis) = match (obj.float("fov")?, obj.string("focal_length")?) {
        (Some(_), Some(_)) => {
            return Err(syntax(
                &obj.loc,
                "give either 'fov' or 'focal_length', not both",
            ))
        }
        (Some(fov), None) => {
            let axis = obj.string("fov_axis")?.unwrap_or_else(|| "x".into());
            let axis = FovAxis::parse(&axis).ok_or_else(|| {
                syntax(
                    obj.loc_of("fov_axis"),
                    format!("fov_axis '{axis}' is not one of x, y, diagonal, smaller, larger"),
                )
            })?;
            (fov, axis)
        }
        (None, focal) => {
            let f = focal.unwrap_or_else(|| "50mm".into());
            let mm = props::number(obj.loc_of("focal_length"), f.trim_end_matches("mm"))?;
            (fov_from_focal_length(mm), FovAxis::Diagonal)
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(syntax(
            obj.loc_of("fov"),
            format!("fov {fov} is not in (0, 180)"),
        ));
    }
    Ok((fov, fov_axis))
}

fn read_perspective(ctx: &mut Ctx, obj: &Obj) -> Result<Camera, SceneError> {
    let to_world = obj.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let (fov, fov_axis) = read_fov(obj)?;
    let near_clip = obj.float("near_clip")?.unwrap_or(1e-2);
    let far_clip = obj.float("far_clip")?.unwrap_or(1e4);
    if !(near_clip > 0.0 && near_clip < far_clip) {
        return Err(syntax(
            obj.loc_of("near_clip"),
            "near_clip must be positive and less than far_clip",
        ));
    }
    if near_clip != 1e-2 || far_clip != 1e4 {
        ctx.diag.warn(
            obj.loc_of(if near_clip != 1e-2 {
                "near_clip"
            } else {
                "far_clip"
            }),
            "near_clip/far_clip are not supported by the renderer: nothing is clipped",
        );
    }
    Ok(Camera {
        to_world,
        fov,
        fov_axis,
        width: 768,
        height: 576,
        near_clip,
        far_clip,
        projection: Projection::Perspective,
        aperture_radius: 0.0,
        focus_distance: 1e4,
        crop: None,
        filter: None,
    })
}

/// Mitsuba `orthographic`: `to_world` (its scale sizes the view), `near_clip` (where rays
/// start), `far_clip`.
fn read_orthographic(ctx: &mut Ctx, obj: &Obj) -> Result<Camera, SceneError> {
    let to_world = obj.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let near_clip = obj.float("near_clip")?.unwrap_or(1e-2);
    let far_clip = obj.float("far_clip")?.unwrap_or(1e4);
    if !(near_clip >= 0.0 && near_clip < far_clip) {
        return Err(syntax(
            obj.loc_of("near_clip"),
            "near_clip must be >= 0 and less than far_clip",
        ));
    }
    if far_clip != 1e4 {
        ctx.diag.warn(
            obj.loc_of("far_clip"),
            "far_clip is not supported by the renderer: nothing is clipped behind it",
        );
    }
    Ok(Camera {
        near_clip,
        far_clip,
        projection: Projection::Orthographic,
        ..Camera {
            to_world,
            ..default_camera()
        }
    })
}

/// The sensor's film size and sample count (Mitsuba's defaults: 768 x 576, 4 samples).
fn read_film_and_sampler<'a>(
    ctx: &mut Ctx<'a>,
    obj: &'a Obj,
    quiet: bool,
) -> Result<FilmAndSampler, SceneError> {
    let (mut width, mut height, mut spp) = (768, 576, 4);
    let mut crop = None;
    let mut filter = None;
    let mut saw_film = false;
    for child in &obj.children {
        let c = ctx.target(child)?;
        match c.tag.as_str() {
            "film" => {
                child.take();
                saw_film = true;
                if c.plugin != "hdrfilm" {
                    ctx.diag.unsupported(
                        &c.loc,
                        plugins::describe("film", &c.plugin),
                        "read as hdrfilm",
                    )?;
                }
                for (slot, name) in [(&mut width, "width"), (&mut height, "height")] {
                    if let Some(v) = c.integer(name)? {
                        *slot = u32::try_from(v).ok().filter(|&v| v > 0).ok_or_else(|| {
                            syntax(c.loc_of(name), format!("film {name} must be positive"))
                        })?;
                    }
                }
                crop = read_crop(c, width, height)?;
                if let Some(f) = c.string("pixel_format")? {
                    if !matches!(f.to_ascii_lowercase().as_str(), "rgb" | "rgba") {
                        ctx.diag.warn(
                            c.loc_of("pixel_format"),
                            format!("pixel_format '{f}' is not supported: the image is RGB"),
                        );
                    }
                }
                // Output encoding and options without effect on a linear RGB film.
                for name in [
                    "pixel_format",
                    "component_format",
                    "file_format",
                    "banner",
                    "compensate",
                ] {
                    c.ignore(name);
                }
                let sample_border = c.boolean("sample_border")?.unwrap_or(false);
                // Mitsuba's default filter.
                filter = Some(FilmFilter::gaussian(0.5));
                for f in &c.children {
                    let fo = ctx.target(f)?;
                    if fo.tag != "rfilter" {
                        continue;
                    }
                    f.take();
                    filter = rfilter(ctx, fo)?;
                }
                if let Some(f) = &mut filter {
                    f.sample_border = sample_border;
                }
                if !quiet {
                    c.finish(&mut ctx.diag)?;
                }
            }
            "sampler" => {
                child.take();
                match c.plugin.as_str() {
                    "independent" => {}
                    "stratified" | "multijitter" | "orthogonal" | "ldsampler" => {
                        ctx.diag.warn(
                            &c.loc,
                            format!("sampler '{}' replaced by independent (the same expected image, different noise)", c.plugin),
                        );
                        c.ignore("jitter");
                        c.ignore("strength");
                    }
                    other => ctx.diag.unsupported(
                        &c.loc,
                        plugins::describe("sampler", other),
                        "replaced by independent",
                    )?,
                }
                if let Some(n) = c.integer("sample_count")? {
                    spp = u32::try_from(n).ok().filter(|&n| n > 0).ok_or_else(|| {
                        syntax(c.loc_of("sample_count"), "sample_count must be positive")
                    })?;
                }
                let _ = c.integer("seed")?;
                if !quiet {
                    c.finish(&mut ctx.diag)?;
                }
            }
            "medium" => {
                child.take();
                ctx.diag.unsupported(
                    &c.loc,
                    "a medium around the sensor is not supported by the renderer",
                    "ignored",
                )?;
            }
            _ => {}
        }
    }
    if !saw_film {
        ctx.diag.warn(
            &obj.loc,
            "sensor has no film; Mitsuba's default 768 x 576 is used",
        );
    }
    if !saw_film {
        // Mitsuba's default film filters with its default gaussian.
        filter = Some(FilmFilter::gaussian(0.5));
    }
    Ok(match crop {
        Some((w, h, window)) => FilmAndSampler {
            width: w,
            height: h,
            spp,
            crop: Some(window),
            filter,
        },
        None => FilmAndSampler {
            width,
            height,
            spp,
            crop: None,
            filter,
        },
    })
}

/// What a sensor's film and sampler say: the rendered size (a crop window's, if any), the
/// samples per pixel and the crop window.
struct FilmAndSampler {
    width: u32,
    height: u32,
    spp: u32,
    crop: Option<CropWindow>,
    filter: Option<FilmFilter>,
}

impl FilmAndSampler {
    /// `camera` rendering this film, and the samples per pixel.
    fn fit(self, camera: Camera) -> (Camera, u32) {
        let camera = Camera {
            width: self.width,
            height: self.height,
            crop: self.crop,
            filter: self.filter,
            ..camera
        };
        (camera, self.spp)
    }
}

/// Mitsuba's crop window (`crop_offset_x/y`, `crop_width/height`; by default the whole
/// film): its size and position, or `None` when it is the whole film.
fn read_crop(
    film: &Obj,
    width: u32,
    height: u32,
) -> Result<Option<(u32, u32, CropWindow)>, SceneError> {
    let get = |name: &str, default: u32| -> Result<u32, SceneError> {
        match film.integer(name)? {
            None => Ok(default),
            Some(v) => u32::try_from(v)
                .map_err(|_| syntax(film.loc_of(name), format!("film {name} must be >= 0"))),
        }
    };
    let ox = get("crop_offset_x", 0)?;
    let oy = get("crop_offset_y", 0)?;
    let w = get("crop_width", width.saturating_sub(ox))?;
    let h = get("crop_height", height.saturating_sub(oy))?;
    if w == 0
        || h == 0
        || ox as u64 + w as u64 > width as u64
        || oy as u64 + h as u64 > height as u64
    {
        return Err(syntax(
            &film.loc,
            format!(
                "film crop window {w} x {h} at ({ox}, {oy}) is empty or leaves the {width} x {height} film"
            ),
        ));
    }
    if (ox, oy, w, h) == (0, 0, width, height) {
        return Ok(None);
    }
    Ok(Some((
        w,
        h,
        CropWindow {
            film_width: width,
            film_height: height,
            offset_x: ox,
            offset_y: oy,
        },
    )))
}

/// Mitsuba's `<rfilter>`: `None` for the box (each sample in its own pixel).
fn rfilter(ctx: &mut Ctx, f: &Obj) -> Result<Option<FilmFilter>, SceneError> {
    let positive = |name: &str, default: f32| -> Result<f32, SceneError> {
        let v = f.float(name)?.unwrap_or(default);
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(syntax(
                f.loc_of(name),
                format!("rfilter {name} must be positive"),
            ))
        }
    };
    let filter = match f.plugin.as_str() {
        "box" => None,
        "gaussian" => Some(FilmFilter::gaussian(positive("stddev", 0.5)?)),
        "tent" => Some(FilmFilter::tent(positive("radius", 1.0)?)),
        "mitchell" => Some(FilmFilter::mitchell(
            f.float("B")?.unwrap_or(1.0 / 3.0),
            f.float("C")?.unwrap_or(1.0 / 3.0),
        )),
        "catmullrom" => Some(FilmFilter::catmull_rom()),
        "lanczos" => {
            let lobes = f.integer("lobes")?.unwrap_or(3);
            if !(1..=64).contains(&lobes) {
                return Err(syntax(f.loc_of("lobes"), "rfilter lobes must be in 1..=64"));
            }
            Some(FilmFilter::lanczos(lobes as u32))
        }
        other => {
            ctx.diag.unsupported(
                &f.loc,
                plugins::describe("rfilter", other),
                "replaced by box",
            )?;
            return Ok(None);
        }
    };
    f.finish(&mut ctx.diag)?;
    Ok(filter)
}

/// The integrator the renderer follows: `path` (and what renders the same image as `path`), or
/// the first nested integrator of `aov` and `moment`.
fn parse_integrator<'a>(ctx: &mut Ctx<'a>, obj: &'a Obj) -> Result<Integrator, SceneError> {
    match obj.plugin.as_str() {
        "path" => {}
        "volpath" | "volpathmis" | "prb" | "prb_basic" | "prbvolpath" | "prb_projective" => {
            ctx.diag.warn(
                &obj.loc,
                format!(
                    "integrator '{}' read as 'path' (the same image without participating media)",
                    obj.plugin
                ),
            );
        }
        "ptracer" => {
            ctx.diag.warn(
                &obj.loc,
                "integrator 'ptracer' (light tracing) rendered by 'path' (the same expected image)",
            );
            obj.ignore("samples_per_pass");
        }
        "aov" | "moment" => {
            obj.ignore("aovs");
            let mut inner = None;
            for c in &obj.children {
                let t = ctx.target(c)?;
                if t.tag == "integrator" {
                    c.take();
                    if inner.is_none() {
                        inner = Some(parse_integrator(ctx, t)?);
                    } else {
                        ctx.diag
                            .warn(&c.loc, "only the first nested integrator is rendered");
                    }
                }
            }
            obj.finish(&mut ctx.diag)?;
            return match inner {
                Some(i) => {
                    ctx.diag.warn(
                        &obj.loc,
                        format!(
                            "integrator '{}': its extra channels are not written; the nested integrator renders the image",
                            obj.plugin
                        ),
                    );
                    Ok(i)
                }
                None => {
                    ctx.diag.unsupported(
                        &obj.loc,
                        format!("integrator '{}' without a nested integrator", obj.plugin),
                        "'path' used",
                    )?;
                    Ok(Integrator::default())
                }
            };
        }
        "direct" | "direct_projective" => {
            // Direct illumination is the path integrator's image at max_depth 2; the sample
            // counts only change how the same expectation is estimated.
            ctx.diag.warn(
                &obj.loc,
                format!(
                    "integrator '{}' rendered by 'path' with max_depth 2 (the same expected image)",
                    obj.plugin
                ),
            );
            for name in ["emitter_samples", "bsdf_samples", "shading_samples"] {
                obj.ignore(name);
            }
            let hide_emitters = obj.boolean("hide_emitters")?.unwrap_or(false);
            obj.finish(&mut ctx.diag)?;
            return Ok(Integrator {
                max_depth: 2,
                hide_emitters,
                ..Integrator::default()
            });
        }
        other => {
            ctx.diag.unsupported(
                &obj.loc,
                plugins::describe("integrator", other),
                "'path' with Mitsuba's defaults used",
            )?;
            return Ok(Integrator::default());
        }
    }
    let defaults = Integrator::default();
    let max_depth = match obj.integer("max_depth")? {
        None => defaults.max_depth,
        Some(v) => i32::try_from(v).ok().filter(|&v| v >= -1).ok_or_else(|| {
            syntax(
                obj.loc_of("max_depth"),
                "max_depth must be -1 (unlimited) or >= 0",
            )
        })?,
    };
    let rr_depth = match obj.integer("rr_depth")? {
        None => defaults.rr_depth,
        Some(v) => i32::try_from(v)
            .ok()
            .filter(|&v| v > 0)
            .ok_or_else(|| syntax(obj.loc_of("rr_depth"), "rr_depth must be > 0"))?,
    };
    let hide_emitters = obj.boolean("hide_emitters")?.unwrap_or(false);
    obj.finish(&mut ctx.diag)?;
    Ok(Integrator {
        max_depth,
        rr_depth,
        hide_emitters,
    })
}
