//! Mitsuba 3 XML (the subset in shared/scenes/*/README.md) → [`Scene`] + warnings.
//!
//! Stages: roxmltree parses the text (positions kept for line numbers); `<default>` elements fill
//! the `$parameter` table; each plugin element becomes a typed property bag (`props.rs`); the plugin
//! interpreters (`sensor`, `bsdf.rs`, `shape.rs`, emitters, integrator) consume the properties they
//! support and the rest is reported. Errors stop the load with file and line; anything merely
//! unsupported is a [`Warning`] with file and line.

mod bsdf;
mod props;
mod shape;
mod transform;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use roxmltree::Node;

use crate::builder::SceneBuilder;
use crate::camera::{Camera, FovAxis};
use crate::error::{ErrorKind, Location, SceneError, Warning};
use crate::scene::{Integrator, Scene};

pub use bsdf::named_ior;
use props::{is_object_tag, parse_object, Child, Ctx, Obj};

/// A loaded scene and what the loader had to ignore or approximate (callers print these).
#[derive(Clone, Debug)]
pub struct Loaded {
    pub scene: Scene,
    pub warnings: Vec<Warning>,
}

/// Loads a Mitsuba 3 XML scene; mesh files are resolved relative to the file's directory.
pub fn load_mitsuba(path: impl AsRef<Path>) -> Result<Loaded, SceneError> {
    load_mitsuba_with_params(path, &[])
}

/// Like [`load_mitsuba`], with `$name` parameters overriding the file's `<default>`s (Mitsuba's
/// `-D name=value`).
pub fn load_mitsuba_with_params(
    path: impl AsRef<Path>,
    params: &[(&str, &str)],
) -> Result<Loaded, SceneError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| {
        SceneError::new(
            ErrorKind::Io,
            Location::file(path),
            format!("cannot read scene file: {e}"),
        )
    })?;
    let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    load(&text, path.to_path_buf(), base, params)
}

/// Loads a scene from XML text. Mesh files resolve relative to `base_dir`; locations name the file
/// `<string>`.
pub fn load_mitsuba_str(xml: &str, base_dir: impl AsRef<Path>) -> Result<Loaded, SceneError> {
    load(
        xml,
        PathBuf::from("<string>"),
        base_dir.as_ref().to_path_buf(),
        &[],
    )
}

fn load(
    text: &str,
    file: PathBuf,
    base_dir: PathBuf,
    overrides: &[(&str, &str)],
) -> Result<Loaded, SceneError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        SceneError::new(
            ErrorKind::Xml,
            Location::line(&file, e.pos().row),
            format!("malformed XML: {e}"),
        )
    })?;
    let mut ctx = Ctx {
        file,
        base_dir,
        doc: &doc,
        params: HashMap::new(),
        warnings: Vec::new(),
    };
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        return Err(ctx.err(root, ErrorKind::Syntax, "the root element must be <scene>"));
    }
    match ctx.attr(root, "version")? {
        Some(v) if v.split('.').next() == Some("3") => {}
        Some(v) => ctx.warn(
            root,
            format!("scene version {v}: read with Mitsuba 3 semantics"),
        ),
        None => ctx.warn(root, "scene has no version; read with Mitsuba 3 semantics"),
    }

    // `<default>`s anywhere at the top level apply to the whole file; explicit overrides win.
    for node in root.children().filter(|n| n.has_tag_name("default")) {
        let name = ctx.req_attr(node, "name")?;
        let value = ctx.req_attr(node, "value")?;
        ctx.params.entry(name).or_insert(value);
    }
    for (k, v) in overrides {
        ctx.params.insert(k.to_string(), v.to_string());
    }

    let mut camera = None;
    let mut environment = Vec3::ZERO;
    let mut integrator = Integrator::default();
    let mut sample_count = 1;
    let mut builder = SceneBuilder::new(default_camera());
    let mut bsdfs = Vec::new();

    for node in root.children().filter(Node::is_element) {
        let tag = node.tag_name().name();
        if tag == "default" {
            continue;
        }
        if !is_object_tag(tag) {
            ctx.warn(node, format!("unsupported element <{tag}> ignored"));
            continue;
        }
        let obj = parse_object(&mut ctx, node)?;
        match tag {
            "shape" => shape::add_shape(&mut ctx, &obj, &mut builder, &mut bsdfs)?,
            "bsdf" => {
                let parsed = bsdf::parse_bsdf(&mut ctx, &obj, &|id| {
                    bsdfs.iter().rev().find(|(i, _)| i == id).map(|(_, b)| *b)
                })?;
                match &obj.id {
                    Some(id) => bsdfs.push((id.clone(), parsed)),
                    None => ctx.warn(node, "top-level <bsdf> without an id can never be used"),
                }
            }
            "sensor" if camera.is_some() => {
                ctx.warn(node, "only the first sensor is used; this one is ignored")
            }
            "sensor" => {
                let (cam, spp) = parse_sensor(&mut ctx, &obj)?;
                camera = Some(cam);
                sample_count = spp;
            }
            "integrator" => integrator = parse_integrator(&mut ctx, &obj)?,
            "emitter" => match obj.plugin.as_str() {
                "constant" => {
                    let radiance = obj.color(&ctx, "radiance")?.unwrap_or(Vec3::ONE);
                    if !radiance.is_finite() || radiance.min_element() < 0.0 {
                        return Err(ctx.err(
                            obj.node_of("radiance"),
                            ErrorKind::Syntax,
                            "radiance must be finite and >= 0",
                        ));
                    }
                    obj.warn_unused(&mut ctx);
                    // Mitsuba sums emitters; two constant skies add.
                    environment += radiance;
                }
                "area" => ctx.warn(node, "an area emitter must be nested in a <shape>; ignored"),
                other => ctx.warn(node, format!("unsupported emitter '{other}' ignored")),
            },
            other => ctx.warn(
                node,
                format!(
                    "<{other} type=\"{}\"> is not supported and was ignored",
                    obj.plugin
                ),
            ),
        }
    }

    let camera = camera.unwrap_or_else(|| {
        ctx.warn(root, "scene has no sensor; using Mitsuba's default camera");
        default_camera()
    });
    let scene = builder.scene_mut();
    scene.camera = camera;
    scene.environment = environment;
    scene.integrator = integrator;
    scene.sample_count = sample_count;
    Ok(Loaded {
        scene: builder.finish(),
        warnings: ctx.warnings,
    })
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
    }
}

/// Mitsuba: a focal length on a 36 x 24 mm film gives a diagonal field of view.
fn fov_from_focal_length(mm: f64) -> f32 {
    (2.0 * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm)).atan()).to_degrees() as f32
}

fn parse_sensor(ctx: &mut Ctx, obj: &Obj) -> Result<(Camera, u32), SceneError> {
    if obj.plugin != "perspective" {
        ctx.warn(
            obj.node,
            format!(
                "sensor '{}' treated as a perspective pinhole camera",
                obj.plugin
            ),
        );
    }
    let to_world = obj.transform(ctx, "to_world")?.unwrap_or(Mat4::IDENTITY);
    let (fov, fov_axis) = match (obj.float(ctx, "fov")?, obj.string(ctx, "focal_length")?) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                obj.node,
                ErrorKind::Syntax,
                "give either 'fov' or 'focal_length', not both",
            ))
        }
        (Some(fov), None) => {
            let axis = obj.string(ctx, "fov_axis")?.unwrap_or_else(|| "x".into());
            let axis = FovAxis::parse(&axis).ok_or_else(|| {
                ctx.err(
                    obj.node_of("fov_axis"),
                    ErrorKind::Syntax,
                    format!("fov_axis '{axis}' is not one of x, y, diagonal, smaller, larger"),
                )
            })?;
            (fov, axis)
        }
        (None, focal) => {
            let f = focal.unwrap_or_else(|| "50mm".into());
            let mm = ctx.number(obj.node_of("focal_length"), f.trim_end_matches("mm"))?;
            (fov_from_focal_length(mm), FovAxis::Diagonal)
        }
    };
    if !(fov > 0.0 && fov < 180.0) {
        return Err(ctx.err(
            obj.node_of("fov"),
            ErrorKind::Syntax,
            format!("fov {fov} is not in (0, 180)"),
        ));
    }
    let near_clip = obj.float(ctx, "near_clip")?.unwrap_or(1e-2);
    let far_clip = obj.float(ctx, "far_clip")?.unwrap_or(1e4);
    // Pinhole: lens parameters of thinlens have no effect.
    if obj.plugin == "thinlens" {
        let _ = (
            obj.float(ctx, "aperture_radius")?,
            obj.float(ctx, "focus_distance")?,
        );
    }

    let (mut width, mut height, mut spp) = (768, 576, 4);
    let mut saw_film = false;
    for child in &obj.children {
        let Child::Object(c) = child else {
            if let Child::Ref { node, .. } = child {
                ctx.warn(*node, "<ref> inside a sensor ignored");
            }
            continue;
        };
        match c.tag.as_str() {
            "film" => {
                saw_film = true;
                if c.plugin != "hdrfilm" {
                    ctx.warn(c.node, format!("film '{}' treated as hdrfilm", c.plugin));
                }
                for (slot, name) in [(&mut width, "width"), (&mut height, "height")] {
                    if let Some(v) = c.integer(ctx, name)? {
                        *slot = u32::try_from(v).ok().filter(|&v| v > 0).ok_or_else(|| {
                            ctx.err(
                                c.node_of(name),
                                ErrorKind::Syntax,
                                format!("film {name} must be positive"),
                            )
                        })?;
                    }
                }
                // Output encoding only: nothing to do for an in-memory linear RGB film.
                for name in ["pixel_format", "component_format", "file_format"] {
                    let _ = c.string(ctx, name)?;
                }
                let _ = c.boolean(ctx, "banner")?;
                let mut saw_filter = false;
                for f in &c.children {
                    match f {
                        Child::Object(f) if f.tag == "rfilter" => {
                            saw_filter = true;
                            if f.plugin != "box" {
                                ctx.warn(f.node, format!("rfilter '{}' replaced by box (the renderer splats each sample into its own pixel)", f.plugin));
                            }
                            f.warn_unused(ctx);
                        }
                        Child::Object(f) => {
                            ctx.warn(f.node, format!("<{}> inside a film ignored", f.tag))
                        }
                        Child::Ref { node, .. } => ctx.warn(*node, "<ref> inside a film ignored"),
                    }
                }
                if !saw_filter {
                    ctx.warn(c.node, "film has no rfilter (Mitsuba's default is gaussian); the renderer uses box");
                }
                c.warn_unused(ctx);
            }
            "sampler" => {
                if c.plugin != "independent" {
                    ctx.warn(
                        c.node,
                        format!("sampler '{}' treated as independent", c.plugin),
                    );
                }
                if let Some(n) = c.integer(ctx, "sample_count")? {
                    spp = u32::try_from(n).ok().filter(|&n| n > 0).ok_or_else(|| {
                        ctx.err(
                            c.node_of("sample_count"),
                            ErrorKind::Syntax,
                            "sample_count must be positive",
                        )
                    })?;
                }
                let _ = c.integer(ctx, "seed")?;
                c.warn_unused(ctx);
            }
            other => ctx.warn(c.node, format!("<{other}> inside a sensor ignored")),
        }
    }
    if !saw_film {
        ctx.warn(
            obj.node,
            "sensor has no film; Mitsuba's default 768 x 576 is used",
        );
    }
    obj.warn_unused(ctx);
    Ok((
        Camera {
            to_world,
            fov,
            fov_axis,
            width,
            height,
            near_clip,
            far_clip,
        },
        spp,
    ))
}

fn parse_integrator(ctx: &mut Ctx, obj: &Obj) -> Result<Integrator, SceneError> {
    if obj.plugin != "path" {
        ctx.warn(
            obj.node,
            format!(
                "integrator '{}' is not supported; the renderer is a path tracer",
                obj.plugin
            ),
        );
        return Ok(Integrator::default());
    }
    let defaults = Integrator::default();
    let int = |ctx: &Ctx, name: &str, default: i32| -> Result<i32, SceneError> {
        match obj.integer(ctx, name)? {
            None => Ok(default),
            Some(v) => i32::try_from(v).ok().filter(|&v| v >= -1).ok_or_else(|| {
                ctx.err(
                    obj.node_of(name),
                    ErrorKind::Syntax,
                    format!("{name} must be >= -1"),
                )
            }),
        }
    };
    let integrator = Integrator {
        max_depth: int(ctx, "max_depth", defaults.max_depth)?,
        rr_depth: int(ctx, "rr_depth", defaults.rr_depth)?,
    };
    if obj.boolean(ctx, "hide_emitters")? == Some(true) {
        ctx.warn(
            obj.node_of("hide_emitters"),
            "hide_emitters is not supported: emitters stay visible",
        );
    }
    for child in &obj.children {
        if let Child::Object(o) = child {
            ctx.warn(o.node, format!("<{}> inside the integrator ignored", o.tag));
        }
    }
    obj.warn_unused(ctx);
    Ok(integrator)
}
