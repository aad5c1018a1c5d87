//! First stage of the Mitsuba loader: XML elements → typed objects with properties, each remembering
//! its line. The plugin stage (`plugins.rs`) then asks for properties by name and type; whatever it
//! never asks for is reported as ignored, so an unsupported parameter is a warning with a line
//! instead of a silent difference from Mitsuba's image.

use std::cell::Cell;
use std::collections::HashMap;
use std::path::PathBuf;

use glam::{Mat4, Vec3};
use roxmltree::Node;

use crate::error::{ErrorKind, Location, SceneError, Warning};

use super::transform::parse_transform;

/// Loader state shared by all stages: where we are, `$parameters`, collected warnings.
pub(crate) struct Ctx<'a, 'input> {
    pub file: PathBuf,
    pub base_dir: PathBuf,
    pub doc: &'a roxmltree::Document<'input>,
    pub params: HashMap<String, String>,
    pub warnings: Vec<Warning>,
}

impl Ctx<'_, '_> {
    pub fn line(&self, node: Node) -> u32 {
        self.doc.text_pos_at(node.range().start).row
    }

    pub fn loc(&self, node: Node) -> Location {
        Location::line(&self.file, self.line(node))
    }

    pub fn err(&self, node: Node, kind: ErrorKind, msg: impl Into<String>) -> SceneError {
        SceneError::new(kind, self.loc(node), msg)
    }

    pub fn warn(&mut self, node: Node, msg: impl Into<String>) {
        let w = Warning::new(self.loc(node), msg);
        self.warnings.push(w);
    }

    /// Attribute value with `$name` parameters substituted.
    pub fn attr(&self, node: Node, name: &str) -> Result<Option<String>, SceneError> {
        node.attribute(name)
            .map(|v| self.substitute(node, v))
            .transpose()
    }

    pub fn req_attr(&self, node: Node, name: &str) -> Result<String, SceneError> {
        self.attr(node, name)?.ok_or_else(|| {
            self.err(
                node,
                ErrorKind::Syntax,
                format!("<{}> needs a '{name}' attribute", node.tag_name().name()),
            )
        })
    }

    fn substitute(&self, node: Node, value: &str) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::new();
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(after.len());
            let name = &after[..len];
            match self.params.get(name) {
                Some(v) if !name.is_empty() => out.push_str(v),
                _ => {
                    return Err(self.err(
                        node,
                        ErrorKind::Syntax,
                        format!(
                            "undefined parameter '${name}' (no <default name=\"{name}\" .../>)"
                        ),
                    ))
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    pub fn number(&self, node: Node, text: &str) -> Result<f64, SceneError> {
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                self.err(
                    node,
                    ErrorKind::Syntax,
                    format!("'{text}' is not a finite number"),
                )
            })
    }

    /// Numbers separated by commas and/or whitespace.
    pub fn numbers(&self, node: Node, text: &str) -> Result<Vec<f64>, SceneError> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| self.number(node, s))
            .collect()
    }

    pub fn vec3_text(&self, node: Node, text: &str) -> Result<Vec3, SceneError> {
        match self.numbers(node, text)?.as_slice() {
            [x, y, z] => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
            _ => Err(self.err(
                node,
                ErrorKind::Syntax,
                format!("expected 3 numbers, got '{text}'"),
            )),
        }
    }

    /// A vector given either as `value="x, y, z"` or as x/y/z attributes (missing ones = `default`).
    pub fn vec3_attrs(&self, node: Node, default: f32) -> Result<Vec3, SceneError> {
        if let Some(v) = self.attr(node, "value")? {
            return self.vec3_text(node, &v);
        }
        let mut out = Vec3::splat(default);
        for (k, a) in ["x", "y", "z"].iter().enumerate() {
            if let Some(v) = self.attr(node, a)? {
                out[k] = self.number(node, &v)? as f32;
            }
        }
        Ok(out)
    }
}

#[derive(Clone, Debug)]
pub(crate) enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Color(Vec3),
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
            Value::Vector(_) => "point/vector",
            Value::Transform(_) => "transform",
        }
    }
}

pub(crate) struct Prop<'a, 'input> {
    pub name: String,
    pub value: Value,
    pub node: Node<'a, 'input>,
    used: Cell<bool>,
}

pub(crate) enum Child<'a, 'input> {
    Object(Obj<'a, 'input>),
    /// `<ref id="..."/>`, resolved by the plugin stage.
    Ref {
        id: String,
        node: Node<'a, 'input>,
    },
}

/// A plugin element (`<bsdf type="diffuse">`, `<shape type="obj">`...) with its properties.
pub(crate) struct Obj<'a, 'input> {
    pub tag: String,
    pub plugin: String,
    pub id: Option<String>,
    pub node: Node<'a, 'input>,
    pub props: Vec<Prop<'a, 'input>>,
    pub children: Vec<Child<'a, 'input>>,
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
    "spectrum_plugin",
];

pub(crate) fn is_object_tag(tag: &str) -> bool {
    OBJECT_TAGS.contains(&tag)
}

pub(crate) fn parse_object<'a, 'input>(
    ctx: &mut Ctx<'a, 'input>,
    node: Node<'a, 'input>,
) -> Result<Obj<'a, 'input>, SceneError> {
    let tag = node.tag_name().name().to_string();
    let plugin = ctx.req_attr(node, "type")?;
    let id = ctx.attr(node, "id")?;
    let mut obj = Obj {
        tag,
        plugin,
        id,
        node,
        props: Vec::new(),
        children: Vec::new(),
    };
    for child in node.children().filter(Node::is_element) {
        let tag = child.tag_name().name();
        if is_object_tag(tag) {
            obj.children.push(Child::Object(parse_object(ctx, child)?));
            continue;
        }
        if tag == "ref" {
            let id = ctx.req_attr(child, "id")?;
            obj.children.push(Child::Ref { id, node: child });
            continue;
        }
        let value = match tag {
            "float" => Value::Float(ctx.number(child, &ctx.req_attr(child, "value")?)?),
            "integer" => {
                let v = ctx.req_attr(child, "value")?;
                Value::Integer(v.trim().parse().map_err(|_| {
                    ctx.err(child, ErrorKind::Syntax, format!("'{v}' is not an integer"))
                })?)
            }
            "boolean" => {
                let v = ctx.req_attr(child, "value")?;
                Value::Boolean(match v.trim().to_ascii_lowercase().as_str() {
                    "true" => true,
                    "false" => false,
                    _ => {
                        return Err(ctx.err(
                            child,
                            ErrorKind::Syntax,
                            format!("'{v}' is not a boolean (true/false)"),
                        ))
                    }
                })
            }
            "string" => Value::String(ctx.req_attr(child, "value")?),
            "rgb" => Value::Color(parse_rgb(ctx, child)?),
            "spectrum" => Value::Color(parse_spectrum(ctx, child)?),
            "point" | "vector" => Value::Vector(ctx.vec3_attrs(child, 0.0)?),
            "transform" => Value::Transform(parse_transform(ctx, child)?),
            other => {
                ctx.warn(
                    child,
                    format!("unknown element <{other}> inside <{}> ignored", obj.tag),
                );
                continue;
            }
        };
        let name = ctx.req_attr(child, "name")?;
        if obj.props.iter().any(|p| p.name == name) {
            ctx.warn(
                child,
                format!("property '{name}' given twice; the last one is used"),
            );
            obj.props.retain(|p| p.name != name);
        }
        obj.props.push(Prop {
            name,
            value,
            node: child,
            used: Cell::new(false),
        });
    }
    Ok(obj)
}

/// `"r, g, b"` or a single grey value.
fn parse_rgb(ctx: &Ctx, node: Node) -> Result<Vec3, SceneError> {
    let text = ctx.req_attr(node, "value")?;
    match ctx.numbers(node, &text)?.as_slice() {
        [v] => Ok(Vec3::splat(*v as f32)),
        [r, g, b] => Ok(Vec3::new(*r as f32, *g as f32, *b as f32)),
        _ => Err(ctx.err(
            node,
            ErrorKind::Syntax,
            format!("rgb value '{text}' needs 1 or 3 numbers"),
        )),
    }
}

/// A constant `<spectrum value="0.5"/>` is grey; a sampled one ("400:0.1, 500:0.2, ...") is
/// approximated by its mean, with a warning, since the renderer is RGB.
fn parse_spectrum(ctx: &mut Ctx, node: Node) -> Result<Vec3, SceneError> {
    let text = ctx.req_attr(node, "value")?;
    if !text.contains(':') {
        return parse_rgb(ctx, node);
    }
    let mut values = Vec::new();
    for pair in text.split(',').filter(|s| !s.trim().is_empty()) {
        let Some((_, v)) = pair.split_once(':') else {
            return Err(ctx.err(
                node,
                ErrorKind::Syntax,
                format!("bad spectrum entry '{pair}'"),
            ));
        };
        values.push(ctx.number(node, v)?);
    }
    if values.is_empty() {
        return Err(ctx.err(node, ErrorKind::Syntax, "empty spectrum"));
    }
    ctx.warn(
        node,
        "sampled spectrum approximated by its mean value (grey)",
    );
    Ok(Vec3::splat(
        (values.iter().sum::<f64>() / values.len() as f64) as f32,
    ))
}

impl<'a, 'input> Obj<'a, 'input> {
    fn prop(&self, name: &str) -> Option<&Prop<'a, 'input>> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }

    fn mismatch(&self, ctx: &Ctx, p: &Prop, wanted: &str) -> SceneError {
        ctx.err(
            p.node,
            ErrorKind::Syntax,
            format!(
                "property '{}' of {} '{}' must be {wanted}, found {}",
                p.name,
                self.tag,
                self.plugin,
                p.value.type_name()
            ),
        )
    }

    pub fn float(&self, ctx: &Ctx, name: &str) -> Result<Option<f32>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Float(v) => Ok(Some(v as f32)),
            Value::Integer(v) => Ok(Some(v as f32)),
            _ => Err(self.mismatch(ctx, p, "a float")),
        }
    }

    pub fn integer(&self, ctx: &Ctx, name: &str) -> Result<Option<i64>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Integer(v) => Ok(Some(v)),
            _ => Err(self.mismatch(ctx, p, "an integer")),
        }
    }

    pub fn boolean(&self, ctx: &Ctx, name: &str) -> Result<Option<bool>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Boolean(v) => Ok(Some(v)),
            _ => Err(self.mismatch(ctx, p, "a boolean")),
        }
    }

    pub fn string(&self, ctx: &Ctx, name: &str) -> Result<Option<String>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match &p.value {
            Value::String(v) => Ok(Some(v.clone())),
            _ => Err(self.mismatch(ctx, p, "a string")),
        }
    }

    /// Colours accept `<rgb>`, `<spectrum>` and, as Mitsuba does, a plain `<float>` (grey).
    pub fn color(&self, ctx: &Ctx, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Color(v) => Ok(Some(v)),
            Value::Float(v) => Ok(Some(Vec3::splat(v as f32))),
            _ => Err(self.mismatch(ctx, p, "a colour (rgb, spectrum or float)")),
        }
    }

    pub fn vector(&self, ctx: &Ctx, name: &str) -> Result<Option<Vec3>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Vector(v) => Ok(Some(v)),
            _ => Err(self.mismatch(ctx, p, "a point")),
        }
    }

    pub fn transform(&self, ctx: &Ctx, name: &str) -> Result<Option<Mat4>, SceneError> {
        let Some(p) = self.prop(name) else {
            return Ok(None);
        };
        match p.value {
            Value::Transform(m) => Ok(Some(m)),
            _ => Err(self.mismatch(ctx, p, "a transform")),
        }
    }

    /// The element of property `name`, for errors about its value.
    pub fn node_of(&self, name: &str) -> Node<'a, 'input> {
        self.props
            .iter()
            .find(|p| p.name == name)
            .map_or(self.node, |p| p.node)
    }

    /// Warns about every property no plugin code asked for.
    pub fn warn_unused(&self, ctx: &mut Ctx) {
        for p in &self.props {
            if !p.used.get() {
                ctx.warn(
                    p.node,
                    format!(
                        "property '{}' of {} '{}' is not supported and was ignored",
                        p.name, self.tag, self.plugin
                    ),
                );
            }
        }
    }
}
