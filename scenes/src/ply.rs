//! Stanford PLY → [`TriMesh`], for Mitsuba `ply` shapes. ASCII, binary little- and big-endian.
//!
//! Hand-written rather than a crate because the loader must say WHERE a file is broken (line for
//! ASCII, byte offset + element for binary) and must read `tristrips` elements (igea.ply stores its
//! faces as one strip list), neither of which the available PLY crates offer.
//!
//! Read: `vertex` (x, y, z; nx, ny, nz when all three exist; any numeric type), `face` (a list named
//! `vertex_indices` or `vertex_index`, polygons triangulated as fans), `tristrips` (a list named
//! `vertex_indices`, strips separated by -1, alternate triangles flipped to keep one winding).
//! Other properties of `vertex` and `face` become Mitsuba's mesh attributes
//! (`crate::ply_attributes`); other elements are read past and ignored.

use std::path::Path;

use glam::Vec3;

use crate::error::{ErrorKind, Location, SceneError, Warning};
use crate::mesh::{MeshAttribute, TriMesh};
use crate::ply_attributes::{group_attributes, AttributeFields};

pub fn read_ply(path: &Path, warnings: &mut Vec<Warning>) -> Result<TriMesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| {
        SceneError::new(
            ErrorKind::Io,
            Location::file(path),
            format!("cannot read PLY file: {e}"),
        )
    })?;
    parse_ply(&bytes, path, warnings)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
enum PropertyType {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    ty: PropertyType,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
    /// Header line that declared it.
    line: u32,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    LittleEndian,
    BigEndian,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Line number of the first body line (ASCII).
    body_line: u32,
}

fn syntax(file: &Path, line: u32, msg: impl Into<String>) -> SceneError {
    SceneError::new(ErrorKind::Syntax, Location::line(file, line), msg)
}

fn parse_header(bytes: &[u8], file: &Path) -> Result<Header, SceneError> {
    let mut pos = 0;
    let mut line_no = 0u32;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(len) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(syntax(
                file,
                line_no.max(1),
                "header has no 'end_header' line",
            ));
        };
        let raw = &bytes[pos..pos + len];
        pos += len + 1;
        line_no += 1;
        let line = std::str::from_utf8(raw)
            .map_err(|_| syntax(file, line_no, "header line is not text"))?
            .trim();
        let mut words = line.split_whitespace();
        let first = words.next().unwrap_or("");
        if line_no == 1 {
            if line != "ply" {
                return Err(syntax(file, 1, "not a PLY file (first line is not 'ply')"));
            }
            continue;
        }
        match first {
            "" | "comment" | "obj_info" => {}
            "format" => {
                format = Some(match (words.next(), words.next()) {
                    (Some("ascii"), Some("1.0")) => Format::Ascii,
                    (Some("binary_little_endian"), Some("1.0")) => Format::LittleEndian,
                    (Some("binary_big_endian"), Some("1.0")) => Format::BigEndian,
                    _ => {
                        return Err(syntax(
                            file,
                            line_no,
                            format!("unsupported format '{line}'"),
                        ))
                    }
                });
            }
            "element" => {
                let (Some(name), Some(count)) = (words.next(), words.next()) else {
                    return Err(syntax(file, line_no, "expected 'element <name> <count>'"));
                };
                let count = count
                    .parse()
                    .map_err(|_| syntax(file, line_no, format!("bad element count '{count}'")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            "property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(syntax(file, line_no, "property before any element"));
                };
                let words: Vec<&str> = words.collect();
                let bad_type =
                    |t: &str| syntax(file, line_no, format!("unknown property type '{t}'"));
                let (ty, name) = match words.as_slice() {
                    ["list", count, item, name] => {
                        let count = Scalar::parse(count).ok_or_else(|| bad_type(count))?;
                        let item = Scalar::parse(item).ok_or_else(|| bad_type(item))?;
                        if !count.is_integer() {
                            return Err(syntax(
                                file,
                                line_no,
                                "list count type must be an integer",
                            ));
                        }
                        (PropertyType::List { count, item }, name)
                    }
                    [ty, name] => (
                        PropertyType::Scalar(Scalar::parse(ty).ok_or_else(|| bad_type(ty))?),
                        name,
                    ),
                    _ => {
                        return Err(syntax(
                            file,
                            line_no,
                            format!("malformed property line '{line}'"),
                        ))
                    }
                };
                element.properties.push(Property {
                    name: name.to_string(),
                    ty,
                });
            }
            "end_header" => break,
            other => {
                return Err(syntax(
                    file,
                    line_no,
                    format!("unknown header keyword '{other}'"),
                ))
            }
        }
    }
    let format = format.ok_or_else(|| syntax(file, 2, "header has no 'format' line"))?;
    Ok(Header {
        format,
        elements,
        body: pos,
        body_line: line_no + 1,
    })
}

type Lines<'a> = std::iter::Enumerate<std::slice::Split<'a, u8, fn(&u8) -> bool>>;

/// Reads one value at a time from the body, and knows how to name where it is.
enum Body<'a> {
    Ascii {
        lines: Lines<'a>,
        first_line: u32,
        /// Tokens of the current entry's line.
        tokens: Vec<&'a str>,
        next: usize,
        line: u32,
    },
    Binary {
        data: &'a [u8],
        pos: usize,
        /// Offset of the current entry, the place errors name.
        entry: usize,
        big_endian: bool,
    },
}

struct Reader<'a> {
    body: Body<'a>,
    file: &'a Path,
    element: String,
    index: u64,
}

fn is_newline(b: &u8) -> bool {
    *b == b'\n'
}

impl<'a> Reader<'a> {
    fn location(&self) -> Location {
        match &self.body {
            Body::Ascii { line, .. } => Location::line(self.file, *line),
            Body::Binary { entry, .. } => {
                Location::byte(self.file, *entry as u64, &self.element, self.index)
            }
        }
    }

    fn error(&self, kind: ErrorKind, msg: impl Into<String>) -> SceneError {
        SceneError::new(kind, self.location(), msg)
    }

    /// Starts entry `index` of `element`: ASCII entries are one line each.
    fn begin_entry(&mut self, element: &str, index: u64) -> Result<(), SceneError> {
        self.element.clear();
        self.element.push_str(element);
        self.index = index;
        if let Body::Binary { pos, entry, .. } = &mut self.body {
            *entry = *pos;
        }
        if let Body::Ascii {
            lines,
            first_line,
            tokens,
            next,
            line,
        } = &mut self.body
        {
            loop {
                let Some((i, raw)) = lines.next() else {
                    return Err(SceneError::new(
                        ErrorKind::Truncated,
                        Location::line(self.file, *line),
                        format!("file ends before element '{element}' #{index}"),
                    ));
                };
                *line = *first_line + i as u32;
                let text = std::str::from_utf8(raw).map_err(|_| {
                    SceneError::new(
                        ErrorKind::Syntax,
                        Location::line(self.file, *line),
                        "line is not text",
                    )
                })?;
                tokens.clear();
                tokens.extend(text.split_whitespace());
                *next = 0;
                if !tokens.is_empty() {
                    return Ok(());
                }
            }
        }
        Ok(())
    }

    fn end_entry(&mut self) -> Result<(), SceneError> {
        if let Body::Ascii { tokens, next, .. } = &self.body {
            if *next != tokens.len() {
                return Err(self.error(
                    ErrorKind::Syntax,
                    format!(
                        "element '{}' #{} has {} values, its properties need {}",
                        self.element,
                        self.index,
                        tokens.len(),
                        next
                    ),
                ));
            }
        }
        Ok(())
    }

    fn value(&mut self, ty: Scalar) -> Result<f64, SceneError> {
        match &mut self.body {
            Body::Ascii { tokens, next, .. } => {
                let Some(tok) = tokens.get(*next).copied() else {
                    return Err(self.error(
                        ErrorKind::Syntax,
                        format!(
                            "element '{}' #{} has too few values",
                            self.element, self.index
                        ),
                    ));
                };
                *next += 1;
                let v = if ty.is_integer() {
                    tok.parse::<i64>().map(|v| v as f64).ok()
                } else {
                    tok.parse::<f64>().ok()
                };
                v.ok_or_else(|| {
                    self.error(ErrorKind::Syntax, format!("'{tok}' is not a valid {ty:?}"))
                })
            }
            Body::Binary {
                data,
                pos,
                big_endian,
                ..
            } => {
                let n = ty.size();
                let Some(b) = data.get(*pos..*pos + n) else {
                    let (len, at) = (data.len(), *pos);
                    return Err(self.error(
                        ErrorKind::Truncated,
                        format!(
                            "file ends at byte {len}, reading byte {at} of element '{}' #{}",
                            self.element, self.index
                        ),
                    ));
                };
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if *big_endian {
                    a[..n].reverse();
                }
                *pos += n;
                Ok(match ty {
                    Scalar::I8 => a[0] as i8 as f64,
                    Scalar::U8 => a[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(a),
                })
            }
        }
    }

    fn list(&mut self, count: Scalar, item: Scalar, out: &mut Vec<f64>) -> Result<(), SceneError> {
        let n = self.value(count)?;
        if !(0.0..=1e9).contains(&n) {
            return Err(self.error(ErrorKind::Syntax, format!("bad list length {n}")));
        }
        out.clear();
        for _ in 0..n as u64 {
            out.push(self.value(item)?);
        }
        Ok(())
    }
}

/// Parses PLY bytes; `file` is used only to name locations. Faces with fewer than 3 vertices are
/// skipped with a warning.
pub fn parse_ply(
    bytes: &[u8],
    file: &Path,
    warnings: &mut Vec<Warning>,
) -> Result<TriMesh, SceneError> {
    let header = parse_header(bytes, file)?;
    let body = match header.format {
        Format::Ascii => Body::Ascii {
            lines: bytes[header.body..]
                .split(is_newline as fn(&u8) -> bool)
                .enumerate(),
            first_line: header.body_line,
            tokens: Vec::new(),
            next: 0,
            line: header.body_line,
        },
        f => Body::Binary {
            data: bytes,
            pos: header.body,
            entry: header.body,
            big_endian: f == Format::BigEndian,
        },
    };
    let mut r = Reader {
        body,
        file,
        element: String::new(),
        index: 0,
    };

    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut mesh = TriMesh::new();
    let mut normals: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<glam::Vec2> = Vec::new();
    // One entry's scalar values, by property index (mesh attributes are read from it).
    let mut row: Vec<f32> = Vec::new();
    let mut list = Vec::new();
    let mut short_faces = 0u64;

    for element in &header.elements {
        let find = |names: &[&str]| {
            element
                .properties
                .iter()
                .position(|p| names.contains(&p.name.as_str()))
        };
        match element.name.as_str() {
            "vertex" if !mesh.positions.is_empty() => {
                return Err(syntax(file, element.line, "more than one 'vertex' element"));
            }
            "vertex" => {
                let xyz = [find(&["x"]), find(&["y"]), find(&["z"])];
                let nxyz = [find(&["nx"]), find(&["ny"]), find(&["nz"])];
                // Texture coordinates under the names Mitsuba reads, in its order of preference.
                let uv_names = [["u", "v"], ["texture_u", "texture_v"], ["s", "t"]]
                    .into_iter()
                    .find(|pair| pair.iter().all(|n| find(&[n]).is_some()))
                    .unwrap_or(["u", "v"]);
                let uv = uv_names.map(|n| find(&[n]));
                let has_uvs = uv.iter().all(Option::is_some);
                let mut reserved = vec!["x", "y", "z", "nx", "ny", "nz", "u", "v"];
                reserved.extend(uv_names);
                let attributes = mesh_attributes(file, element, "vertex_", &reserved, warnings);
                if xyz.iter().any(Option::is_none) {
                    return Err(syntax(
                        file,
                        element.line,
                        "element 'vertex' lacks x, y or z",
                    ));
                }
                let has_normals = nxyz.iter().all(Option::is_some);
                // A header may announce more than the file holds; never reserve beyond what it could hold.
                mesh.positions
                    .reserve(element.count.min(bytes.len() as u64 / 3) as usize);
                row.clear();
                row.resize(element.properties.len(), 0.0);
                for index in 0..element.count {
                    r.begin_entry("vertex", index)?;
                    let mut p = [0f32; 3];
                    let mut n = [0f32; 3];
                    let mut t = [0f32; 2];
                    for (k, prop) in element.properties.iter().enumerate() {
                        match &prop.ty {
                            PropertyType::Scalar(ty) => {
                                let v = r.value(*ty)? as f32;
                                row[k] = v;
                                if let Some(axis) = xyz.iter().position(|&i| i == Some(k)) {
                                    p[axis] = v;
                                } else if let Some(axis) = nxyz.iter().position(|&i| i == Some(k)) {
                                    n[axis] = v;
                                } else if let Some(axis) = uv.iter().position(|&i| i == Some(k)) {
                                    t[axis] = v;
                                }
                            }
                            PropertyType::List { count, item } => {
                                r.list(*count, *item, &mut list)?
                            }
                        }
                    }
                    let p = Vec3::from(p);
                    let n = Vec3::from(n);
                    if !p.is_finite() || (has_normals && !n.is_finite()) {
                        return Err(r.error(
                            ErrorKind::NonFinite,
                            format!("vertex #{index} has a NaN or infinite coordinate"),
                        ));
                    }
                    r.end_entry()?;
                    mesh.positions.push(p);
                    if has_normals {
                        normals.push(n);
                    }
                    if has_uvs {
                        uvs.push(glam::Vec2::from(t));
                    }
                    push_attribute_values(&attributes, &row, &mut mesh.attributes, 1);
                }
                if has_normals {
                    mesh.normals = Some(std::mem::take(&mut normals));
                }
                if has_uvs {
                    mesh.uvs = Some(std::mem::take(&mut uvs));
                }
            }
            "face" | "tristrips" => {
                let strips = element.name == "tristrips";
                let Some(target) = find(&["vertex_indices", "vertex_index"]) else {
                    return Err(syntax(
                        file,
                        element.line,
                        format!("element '{}' has no 'vertex_indices' list", element.name),
                    ));
                };
                // Mitsuba reads face attributes (it does not read strips at all).
                let attributes = if strips {
                    Vec::new()
                } else {
                    mesh_attributes(file, element, "face_", &[], warnings)
                };
                row.clear();
                row.resize(element.properties.len(), 0.0);
                for index in 0..element.count {
                    r.begin_entry(&element.name, index)?;
                    let mut polygon = Vec::new();
                    for (k, prop) in element.properties.iter().enumerate() {
                        match &prop.ty {
                            PropertyType::Scalar(ty) => {
                                row[k] = r.value(*ty)? as f32;
                            }
                            PropertyType::List { count, item } => {
                                r.list(*count, *item, &mut list)?;
                                if k == target {
                                    polygon.clear();
                                    for &v in &list {
                                        // -1 separates strips; anything else must be a vertex.
                                        if strips && v == -1.0 {
                                            polygon.push(u32::MAX);
                                        } else if v < 0.0
                                            || v >= vertex_count as f64
                                            || v.fract() != 0.0
                                        {
                                            return Err(r.error(
                                                ErrorKind::IndexOutOfRange,
                                                format!(
                                                    "{} #{index} refers to vertex {v}, the file has {vertex_count}",
                                                    element.name
                                                ),
                                            ));
                                        } else {
                                            polygon.push(v as u32);
                                        }
                                    }
                                }
                            }
                        }
                    }
                    r.end_entry()?;
                    if strips {
                        push_strips(&polygon, &mut mesh.indices);
                    } else if polygon.len() < 3 {
                        short_faces += 1;
                    } else {
                        for i in 1..polygon.len() - 1 {
                            mesh.indices.push([polygon[0], polygon[i], polygon[i + 1]]);
                        }
                        // A polygon's attribute values hold for each triangle of its fan.
                        let triangles = polygon.len() - 2;
                        push_attribute_values(&attributes, &row, &mut mesh.attributes, triangles);
                    }
                }
            }
            _ => {
                for index in 0..element.count {
                    r.begin_entry(&element.name, index)?;
                    for prop in &element.properties {
                        match &prop.ty {
                            PropertyType::Scalar(ty) => {
                                r.value(*ty)?;
                            }
                            PropertyType::List { count, item } => {
                                r.list(*count, *item, &mut list)?
                            }
                        }
                    }
                    r.end_entry()?;
                }
            }
        }
    }
    if short_faces > 0 {
        warnings.push(Warning::new(
            Location::file(file),
            format!("{short_faces} faces with fewer than 3 vertices skipped"),
        ));
    }
    Ok(mesh)
}

/// Mitsuba's mesh attributes among `element`'s properties (`crate::ply_attributes`), with
/// its warnings located at the element's header line. Integer colour channels are read as
/// they are, as Mitsuba reads them, with its warning.
fn mesh_attributes(
    file: &Path,
    element: &Element,
    kind: &str,
    reserved: &[&str],
    warnings: &mut Vec<Warning>,
) -> Vec<AttributeFields> {
    let names: Vec<Option<&str>> = element
        .properties
        .iter()
        .map(|p| match p.ty {
            PropertyType::Scalar(_) => Some(p.name.as_str()),
            PropertyType::List { .. } => None,
        })
        .collect();
    let at = Location::line(file, element.line);
    let attributes = group_attributes(kind, &names, reserved, |w| {
        warnings.push(Warning::new(at.clone(), w))
    });
    for a in &attributes {
        let integer = a.fields.iter().any(
            |&k| matches!(element.properties[k].ty, PropertyType::Scalar(t) if t.is_integer()),
        );
        if integer && a.fields.len() >= 3 {
            warnings.push(Warning::new(
                at.clone(),
                format!(
                    "mesh attribute '{}' has integer fields: Mitsuba reads them as they are \
                     (colour attributes are expected to be in [0, 1])",
                    a.name
                ),
            ));
        }
    }
    attributes
}

/// Appends one entry's values (`row`, by property index) of each of `attributes` to the
/// mesh's attributes, `times` times, creating those the mesh does not have yet.
fn push_attribute_values(
    attributes: &[AttributeFields],
    row: &[f32],
    out: &mut Vec<MeshAttribute>,
    times: usize,
) {
    for a in attributes {
        let i = match out.iter().position(|m| m.name == a.name) {
            Some(i) => i,
            None => {
                out.push(MeshAttribute {
                    name: a.name.clone(),
                    channels: a.fields.len() as u32,
                    values: Vec::new(),
                });
                out.len() - 1
            }
        };
        let mut v = Vec3::ZERO;
        for (c, &k) in a.fields.iter().take(3).enumerate() {
            v[c] = row[k];
        }
        out[i].values.extend(std::iter::repeat_n(v, times));
    }
}

/// Triangle strips, `u32::MAX` = restart. Odd triangles swap their first two vertices so all keep
/// the winding of the first; triangles that repeat a vertex are the strip's own stitching and are
/// not real faces, so they are skipped here rather than reported as degenerate.
fn push_strips(list: &[u32], out: &mut Vec<[u32; 3]>) {
    for strip in list.split(|&v| v == u32::MAX) {
        for i in 0..strip.len().saturating_sub(2) {
            let (a, b, c) = (strip[i], strip[i + 1], strip[i + 2]);
            if a == b || b == c || a == c {
                continue;
            }
            out.push(if i % 2 == 0 { [a, b, c] } else { [b, a, c] });
        }
    }
}
