//! Second stage of the Mitsuba loader: the element tree (`xml.rs`) → plugin objects with typed
//! properties, nested objects and `<ref>`s, each remembering its file and line. The plugin stage
//! then asks for properties by name and type; whatever it never asks for is reported, as Mitsuba
//! reports "unreferenced properties" (an error, or a warning under `--lenient`), so a misspelt or
//! unsupported parameter never silently changes the image.

use std::cell::Cell;
use std::collections::{HashMap, HashSet};

use glam::{Mat4, Vec3};

use crate::error::{ErrorKind, Location, SceneError};

use super::diag::{err, syntax, Diag};
use super::transform::parse_transform;
use super::xml::{check_attrs, Elem};

#[derive(Clone, Debug)]
pub(crate) enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Color(Vec3),
    /// A sampled spectrum, (wavelength in nm, value) with wavelengths increasing: its colour
    /// depends on what it describes (`spectrum::SpectrumUse`).
    Spectrum(Vec<(f64, f64)>),
    Vector(Vec3),
    Transform(Mat4),
}

impl Value {
    fn type_name(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Color(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Vector(_) => "point/vector",
            Value::Transform(_) => "transform",
        }
    }
}

pub(crate) struct Prop {
    pub name: String,
    pub value: Value,
    pub loc: Location,
    used: Cell<bool>,
}

pub(crate) enum Kind {
    Object(Obj),
    /// `<ref id="..."/>`: resolved through [`Ids`].
    Ref(String),
}

/// A nested object or reference, with its optional `name` (`<ref name="reflectance" id="tex"/>`).
pub(crate) struct Child {
    pub name: Option<String>,
    pub kind: Kind,
    pub loc: Location,
    used: Cell<bool>,
}

impl Child {
    /// Marks the child as consumed by the plugin code.
    pub fn take(&self) {
        self.used.set(true);
    }

    fn describe(&self) -> String {
        match &self.kind {
            Kind::Object(o) => format!("<{} type=\"{}\">", o.tag, o.plugin),
            Kind::Ref(id) => format!("<ref id=\"{id}\">"),
        }
    }
}

/// A plugin element (`<bsdf type="diffuse">`, `<shape type="obj">`...) or the `<scene>` itself.
pub(crate) struct Obj {
    pub tag: String,
    pub plugin: String,
    pub id: Option<String>,
    pub loc: Location,
    pub props: Vec<Prop>,
    pub children: Vec<Child>,
}

/// `<alias id="a" as="b"/>`: `b` names the object `a`.
pub(crate) struct Alias {
    id: String,
    alias: String,
    loc: Location,
}

const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "shape",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "texture",
    "medium",
    "phase",
    "volume",
    "field",
];

const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
];

/// The `<scene>` root as an object whose children are the top-level objects.
pub(crate) fn parse_scene(diag: &mut Diag, root: &Elem) -> Result<(Obj, Vec<Alias>), SceneError> {
    check_attrs(
        diag,
        &root.loc,
        "scene",
        &root.attrs,
        &["type", "id", "name"],
    )?;
    let mut aliases = Vec::new();
    let mut scene = Obj {
        tag: "scene".into(),
        plugin: "scene".into(),
        id: root.attr("id").map(str::to_string),
        loc: root.loc.clone(),
        props: Vec::new(),
        children: Vec::new(),
    };
    fill(diag, &mut scene, root, &mut aliases)?;
    Ok((scene, aliases))
}

fn parse_object(diag: &mut Diag, e: &Elem, aliases: &mut Vec<Alias>) -> Result<Obj, SceneError> {
    check_attrs(diag, &e.loc, &e.tag, &e.attrs, &["!type", "id", "name"])?;
    let mut obj = Obj {
        // `<spectrum type="...">` is a texture plugin in Mitsuba 3.
        tag: if e.tag == "spectrum" {
            "texture".into()
        } else {
            e.tag.clone()
        },
        plugin: e.attr("type").unwrap_or_default().to_string(),
        id: e.attr("id").map(str::to_string),
        loc: e.loc.clone(),
        props: Vec::new(),
        children: Vec::new(),
    };
    fill(diag, &mut obj, e, aliases)?;
    Ok(obj)
}

fn fill(
    diag: &mut Diag,
    obj: &mut Obj,
    e: &Elem,
    aliases: &mut Vec<Alias>,
) -> Result<(), SceneError> {
    for c in &e.children {
        let tag = c.tag.as_str();
        let name = c.attr("name").map(str::to_string);
        if OBJECT_TAGS.contains(&tag) || (tag == "spectrum" && c.attr("type").is_some()) {
            let o = parse_object(diag, c, aliases)?;
            obj.children.push(Child {
                name,
                kind: Kind::Object(o),
                loc: c.loc.clone(),
                used: Cell::new(false),
            });
            continue;
        }
        if PROPERTY_TAGS.contains(&tag) {
            let value = parse_value(diag, c)?;
            let name = name.unwrap_or_default();
            if obj.props.iter().any(|p| p.name == name) {
                diag.unsupported(
                    &c.loc,
                    format!("property '{name}' is given twice (Mitsuba rejects this)"),
                    "the last one is used",
                )?;
                obj.props.retain(|p| p.name != name);
            }
            obj.props.push(Prop {
                name,
                value,
                loc: c.loc.clone(),
                used: Cell::new(false),
            });
            continue;
        }
        match tag {
            "ref" => {
                check_attrs(diag, &c.loc, tag, &c.attrs, &["!id", "name"])?;
                obj.children.push(Child {
                    name,
                    kind: Kind::Ref(c.attr("id").unwrap_or_default().to_string()),
                    loc: c.loc.clone(),
                    used: Cell::new(false),
                });
            }
            "alias" => {
                check_attrs(diag, &c.loc, tag, &c.attrs, &["!id", "!as"])?;
                aliases.push(Alias {
                    id: c.attr("id").unwrap_or_default().to_string(),
                    alias: c.attr("as").unwrap_or_default().to_string(),
                    loc: c.loc.clone(),
                });
            }
            "translate" | "rotate" | "scale" | "lookat" | "matrix" => {
                return Err(syntax(
                    &c.loc,
                    format!("<{tag}> can only appear inside a <transform>"),
                ))
            }
            other => diag.unsupported(
                &c.loc,
                format!("unknown element <{other}> inside <{}>", obj.tag),
                "ignored",
            )?,
        }
    }
    Ok(())
}

fn parse_value(diag: &mut Diag, c: &Elem) -> Result<Value, SceneError> {
    let tag = c.tag.as_str();
    let allowed: &[&str] = match tag {
        "spectrum" => &["!name", "value", "filename"],
        "point" | "vector" => &["!name", "value", "x", "y", "z"],
        "transform" => &["!name"],
        _ => &["!name", "!value"],
    };
    check_attrs(diag, &c.loc, tag, &c.attrs, allowed)?;
    if tag != "transform" && !c.children.is_empty() {
        diag.unsupported(
            &c.loc,
            format!("<{tag}> cannot have child elements"),
            "they are ignored",
        )?;
    }
    let loc = &c.loc;
    let value = || c.attr("value").unwrap_or_default();
    Ok(match tag {
        "float" => Value::Float(number(loc, value())?),
        "integer" => Value::Integer(
            value()
                .trim()
                .parse()
                .map_err(|_| syntax(loc, format!("'{}' is not an integer", value())))?,
        ),
        "boolean" => Value::Boolean(match value().trim().to_ascii_lowercase().as_str() {
            "true" => true,
            "false" => false,
            _ => {
                return Err(syntax(
                    loc,
                    format!("'{}' is not a boolean (true/false)", value()),
                ))
            }
        }),
        "string" => Value::String(value().to_string()),
        "rgb" => Value::Color(rgb(loc, value())?),
        "spectrum" => match (c.attr("value"), c.attr("filename")) {
            (Some(v), None) => spectrum(loc, v)?,
            (None, Some(f)) => {
                diag.unsupported(
                    loc,
                    format!("spectrum file '{f}' is not supported (the renderer is RGB)"),
                    "replaced by grey 0.5",
                )?;
                Value::Color(Vec3::splat(0.5))
            }
            _ => {
                return Err(syntax(
                    loc,
                    "<spectrum> needs either a 'value' or a 'filename' attribute",
                ))
            }
        },
        "point" | "vector" => Value::Vector(xyz(c, None)?),
        _ => Value::Transform(parse_transform(diag, c)?),
    })
}

pub(crate) fn number(loc: &Location, text: &str) -> Result<f64, SceneError> {
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| syntax(loc, format!("'{text}' is not a finite number")))
}

/// Numbers separated by commas and/or whitespace.
pub(crate) fn numbers(loc: &Location, text: &str) -> Result<Vec<f64>, SceneError> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| number(loc, s))
        .collect()
}

pub(crate) fn vec3_text(loc: &Location, text: &str) -> Result<Vec3, SceneError> {
    match numbers(loc, text)?.as_slice() {
        [x, y, z] => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
        _ => Err(syntax(loc, format!("expected 3 numbers, got '{text}'"))),
    }
}

/// A vector given as `value` (1 number for all three components, or 3) or as `x`/`y`/`z`, as
/// Mitsuba reads points, vectors and transform steps. `default` is the value of a missing
/// component; `None` makes all three required (points and vectors).
pub(crate) fn xyz(e: &Elem, default: Option<f32>) -> Result<Vec3, SceneError> {
    let loc = &e.loc;
    let has_xyz = ["x", "y", "z"].iter().any(|a| e.attr(a).is_some());
    if let Some(v) = e.attr("value") {
        if has_xyz {
            return Err(syntax(loc, "cannot mix 'value' and 'x'/'y'/'z' attributes"));
        }
        return match numbers(loc, v)?.as_slice() {
            [s] => Ok(Vec3::splat(*s as f32)),
            [x, y, z] => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
            _ => Err(syntax(
                loc,
                format!("'value' needs 1 or 3 numbers, got '{v}'"),
            )),
        };
    }
    let mut out = Vec3::ZERO;
    for (k, a) in ["x", "y", "z"].iter().enumerate() {
        out[k] = match (e.attr(a), default) {
            (Some(v), _) => number(loc, v)? as f32,
            (None, Some(d)) => d,
            (None, None) => {
                return Err(syntax(
                    loc,
                    format!("<{}> needs x, y and z (or value)", e.tag),
                ))
            }
        };
    }
    Ok(out)
}

/// `"r, g, b"` or a single grey value.
fn rgb(loc: &Location, text: &str) -> Result<Vec3, SceneError> {
    match numbers(loc, text)?.as_slice() {
        [v] => Ok(Vec3::splat(*v as f32)),
        [r, g, b] => Ok(Vec3::new(*r as f32, *g as f32, *b as f32)),
        _ => Err(syntax(
            loc,
            format!("rgb value '{text}' needs 1 or 3 numbers"),
        )),
    }
}

/// A constant `<spectrum value="0.5"/>` is grey (three numbers are not a spectrum); a sampled
/// one ("400:0.1, 500:0.2, ...", wavelengths in nm, increasing) is kept as samples and
/// converted to a colour where it is used, as Mitsuba's RGB variants do (`spectrum.rs`).
fn spectrum(loc: &Location, text: &str) -> Result<Value, SceneError> {
    if !text.contains(':') {
        return match numbers(loc, text)?.as_slice() {
            [v] => Ok(Value::Color(Vec3::splat(*v as f32))),
            _ => Err(syntax(
                loc,
                format!("spectrum value '{text}' is neither one number nor wavelength:value pairs"),
            )),
        };
    }
    let mut samples: Vec<(f64, f64)> = Vec::new();
    for pair in text.split(',').filter(|s| !s.trim().is_empty()) {
        let Some((w, v)) = pair.split_once(':') else {
            return Err(syntax(
                loc,
                format!(
                    "bad spectrum entry '{}' (write wavelength:value)",
                    pair.trim()
                ),
            ));
        };
        let w = number(loc, w)?;
        if let Some(&(prev, _)) = samples.last() {
            if w <= prev {
                return Err(syntax(
                    loc,
                    format!("spectrum wavelengths must increase: {w} nm follows {prev} nm"),
                ));
            }
        }
        samples.push((w, number(loc, v)?));
    }
    if samples.len() < 2 {
        return Err(syntax(
            loc,
            format!("sampled spectrum '{text}' needs at least two wavelength:value pairs"),
        ));
    }
    Ok(Value::Spectrum(samples))
}

impl Obj {
    fn prop(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
            || self
                .children
                .iter()
                .any(|c| c.name.as_deref() == Some(name))
    }

    /// Marks parameter `name` (property or named child) as read without using it: a Mitsuba
    /// parameter with no effect on this renderer's image.
    pub fn ignore(&self, name: &str) {
        let _ = self.prop(name);
        for c in self
            .children
            .iter()
            .filter(|c| c.name.as_deref() == Some(name))
        {
            c.take();
        }
    }

    /// The nested object or reference called `name`, marked as read.
    pub fn child_named(&self, name: &str) -> Option<&Child> {
        let c = self
            .children
            .iter()
            .find(|c| c.name.as_deref() == Some(name))?;
        c.take();
        Some(c)
    }

    fn mismatch(&self, p: &Prop, wanted: &str) -> SceneError {
        syntax(
            &p.loc,
            format!(
                "property '{}' of {} '{}' must be {wanted}, found {}",
                p.name,
                self.tag,
                self.plugin,
                p.value.type_name()
            ),
        )
    }

    pub fn float(&self, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Float(v) => Ok(Some(v as f32)),
            Value::Integer(v) => Ok(Some(v as f32)),
            _ => Err(self.mismatch(p, "a float")),
        }
    }

    pub fn integer(&self, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Integer(v) => Ok(Some(v)),
            _ => Err(self.mismatch(p, "an integer")),
        }
    }

    pub fn boolean(&self, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Boolean(v) => Ok(Some(v)),
            _ => Err(self.mismatch(p, "a boolean")),
        }
    }

    pub fn string(&self, name: &str) -> Result<Option<String>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::String(v) => Ok(Some(v.clone())),
            _ => Err(self.mismatch(p, "a string")),
        }
    }

    /// A float or a named constant (Mitsuba's IORs accept both).
    pub fn float_or_string(&self, name: &str) -> Result<Option<Result<f32, String>>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::Float(v) => Ok(Some(Ok(*v as f32))),
            Value::Integer(v) => Ok(Some(Ok(*v as f32))),
            Value::String(s) => Ok(Some(Err(s.clone()))),
            _ => Err(self.mismatch(p, "a float or a name")),
        }
    }

    /// Colours accept `<rgb>`, `<spectrum>` and, as Mitsuba does, `<float>`/`<integer>` (grey).
    /// Textures given as nested objects or references are read by `Ctx::color`.
    pub fn color(&self, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::Color(v) => Ok(Some(*v)),
            Value::Spectrum(samples) => Ok(Some(
                super::spectrum::to_srgb(samples, super::spectrum::SpectrumUse::Reflectance).0,
            )),
            Value::Float(v) => Ok(Some(Vec3::splat(*v as f32))),
            Value::Integer(v) => Ok(Some(Vec3::splat(*v as f32))),
            _ => Err(self.mismatch(p, "a colour (rgb, spectrum or float)")),
        }
    }

    /// The samples of a sampled-spectrum property (marking it used), where it is one.
    pub fn spectrum_samples(&self, name: &str) -> Option<Vec<(f64, f64)>> {
        match &self.prop(name)?.value {
            Value::Spectrum(samples) => Some(samples.clone()),
            _ => None,
        }
    }

    /// A float (broadcast to three channels) or a vector: what Mitsuba's `rawconstant` takes.
    pub fn float_or_vector(&self, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Float(v) => Ok(Some(Vec3::splat(v as f32))),
            Value::Integer(v) => Ok(Some(Vec3::splat(v as f32))),
            Value::Vector(v) => Ok(Some(v)),
            _ => Err(self.mismatch(p, "a float or a vector")),
        }
    }

    pub fn vector(&self, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Vector(v) => Ok(Some(v)),
            _ => Err(self.mismatch(p, "a point")),
        }
    }

    pub fn transform(&self, name: &str) -> Result<Option<Mat4>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Transform(m) => Ok(Some(m)),
            _ => Err(self.mismatch(p, "a transform")),
        }
    }

    /// The place of property `name` (or of the object), for errors about its value.
    pub fn loc_of(&self, name: &str) -> &Location {
        self.props
            .iter()
            .find(|p| p.name == name)
            .map_or(&self.loc, |p| &p.loc)
    }

    /// Reports every property and nested object that no plugin code read, as Mitsuba reports
    /// unreferenced properties.
    pub fn finish(&self, diag: &mut Diag) -> Result<(), SceneError> {
        let whose = if self.tag == "scene" {
            "the <scene>".to_string()
        } else {
            format!("{} '{}'", self.tag, self.plugin)
        };
        for p in self.props.iter().filter(|p| !p.used.get()) {
            diag.unsupported(
                &p.loc,
                format!(
                    "{whose} has no parameter '{}' (Mitsuba: unreferenced property)",
                    p.name
                ),
                "ignored",
            )?;
        }
        for c in self.children.iter().filter(|c| !c.used.get()) {
            diag.unsupported(
                &c.loc,
                format!("{} inside {whose} is not used there", c.describe()),
                "ignored",
            )?;
        }
        Ok(())
    }
}

/// Every object with an `id`, wherever it is nested (Mitsuba's ids are global, and a `<ref>` may
/// come before the object it names).
pub(crate) type Ids<'a> = HashMap<String, &'a Obj>;

pub(crate) fn index<'a>(scene: &'a Obj, aliases: &[Alias]) -> Result<Ids<'a>, SceneError> {
    fn walk<'a>(o: &'a Obj, ids: &mut Ids<'a>) -> Result<(), SceneError> {
        for c in &o.children {
            if let Kind::Object(child) = &c.kind {
                if let Some(id) = &child.id {
                    if let Some(prev) = ids.insert(id.clone(), child) {
                        return Err(syntax(
                            &child.loc,
                            format!("duplicate id '{id}' (first defined at {})", prev.loc),
                        ));
                    }
                }
                walk(child, ids)?;
            }
        }
        Ok(())
    }
    let mut ids = Ids::new();
    walk(scene, &mut ids)?;
    for a in aliases {
        let Some(target) = ids.get(&a.id).copied() else {
            return Err(syntax(
                &a.loc,
                format!("alias source id '{}' not found", a.id),
            ));
        };
        if ids.insert(a.alias.clone(), target).is_some() {
            return Err(syntax(
                &a.loc,
                format!("alias id '{}' is already defined", a.alias),
            ));
        }
    }
    Ok(ids)
}

/// Every `<ref>` names an object, and no chain of nested objects and references leads back to
/// where it started (checked for the whole file, used or not, as Mitsuba does).
pub(crate) fn check_refs(scene: &Obj, ids: &Ids) -> Result<(), SceneError> {
    fn visit<'a>(
        o: &'a Obj,
        ids: &Ids<'a>,
        path: &mut Vec<&'a Obj>,
        done: &mut HashSet<*const Obj>,
    ) -> Result<(), SceneError> {
        if done.contains(&(o as *const Obj)) {
            return Ok(());
        }
        if let Some(i) = path.iter().position(|p| std::ptr::eq(*p, o)) {
            let name = |o: &Obj| {
                o.id.clone()
                    .unwrap_or_else(|| format!("<{} type=\"{}\">", o.tag, o.plugin))
            };
            let cycle: Vec<String> = path[i..].iter().map(|o| name(o)).chain([name(o)]).collect();
            return Err(err(
                &o.loc,
                ErrorKind::Cycle,
                format!("circular reference: {}", cycle.join(" -> ")),
            ));
        }
        if path.len() >= super::xml::MAX_NESTING {
            return Err(syntax(
                &o.loc,
                format!(
                    "objects and references nested deeper than {} levels",
                    super::xml::MAX_NESTING
                ),
            ));
        }
        path.push(o);
        for c in &o.children {
            let target = match &c.kind {
                Kind::Object(x) => x,
                Kind::Ref(id) => *ids.get(id).ok_or_else(|| {
                    syntax(
                        &c.loc,
                        format!("<ref>: no object has id '{id}' (Mitsuba: unresolved reference)"),
                    )
                })?,
            };
            visit(target, ids, path, done)?;
        }
        path.pop();
        done.insert(o as *const Obj);
        Ok(())
    }
    visit(scene, ids, &mut Vec::new(), &mut HashSet::new())
}
