//! Mitsuba's `.serialized` meshes: one file holds several shapes, each a header (format id
//! 0x041C, version 3 or 4) followed by a zlib stream with the shape's flags, (version 4) its
//! name, vertex and triangle counts, positions, optional normals, texture coordinates and
//! colours, and the triangles; a table at the end of the file gives each shape's offset
//! (u32 in version 3, u64 in version 4) and the shape count. Positions and normals are f32 or
//! f64; indices u32, or u64 beyond 2^32 vertices.
//!
//! Errors name the file, the shape and the byte offset of the shape's header.

use std::io::Read;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::error::{ErrorKind, Location, SceneError};
use crate::mesh::TriMesh;

const FORMAT_ID: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const SINGLE_PRECISION: u32 = 0x1000;
const DOUBLE_PRECISION: u32 = 0x2000;

/// Shape `index` of the `.serialized` file at `path`.
pub fn read_serialized(path: &Path, index: u32) -> Result<TriMesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| {
        SceneError::new(
            ErrorKind::Io,
            Location::file(path),
            format!("cannot read serialized mesh file: {e}"),
        )
    })?;
    parse_serialized(&bytes, path, index)
}

fn err(
    path: &Path,
    offset: u64,
    index: u32,
    kind: ErrorKind,
    msg: impl Into<String>,
) -> SceneError {
    SceneError::new(
        kind,
        Location::byte(path, offset, "shape", index as u64),
        msg,
    )
}

fn header(bytes: &[u8], at: usize) -> Option<(u16, u16)> {
    let h = bytes.get(at..at + 4)?;
    Some((
        u16::from_le_bytes([h[0], h[1]]),
        u16::from_le_bytes([h[2], h[3]]),
    ))
}

/// The byte offset of shape `index`: 0 for the first, else from the table at the end.
fn shape_offset(bytes: &[u8], path: &Path, index: u32, version: u16) -> Result<usize, SceneError> {
    if index == 0 {
        return Ok(0);
    }
    let n = bytes.len();
    let bad = |msg: String| err(path, n as u64, index, ErrorKind::Truncated, msg);
    let count = bytes
        .get(n.saturating_sub(4)..)
        .filter(|_| n >= 4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .ok_or_else(|| bad("file too short for its shape table".into()))?;
    if index >= count {
        return Err(err(
            path,
            0,
            index,
            ErrorKind::Syntax,
            format!("shape_index {index} is out of range: the file holds {count} shapes"),
        ));
    }
    let width = if version == 3 { 4 } else { 8 };
    let table = (count as usize)
        .checked_mul(width)
        .and_then(|t| n.checked_sub(4 + t))
        .ok_or_else(|| bad(format!("file too short for a table of {count} shapes")))?;
    let entry = table + index as usize * width;
    let e = &bytes[entry..entry + width];
    let offset = if width == 4 {
        u32::from_le_bytes([e[0], e[1], e[2], e[3]]) as u64
    } else {
        u64::from_le_bytes(e.try_into().unwrap())
    };
    usize::try_from(offset)
        .ok()
        .filter(|&o| o < table)
        .ok_or_else(|| {
            bad(format!(
                "shape {index}'s offset {offset} is past the file's data"
            ))
        })
}

/// Reads little-endian values from the decompressed stream.
struct Cursor<'a> {
    data: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.data.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
    }
    fn real(&mut self, double: bool) -> Option<f32> {
        if double {
            self.take(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap()) as f32)
        } else {
            self.take(4)
                .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        }
    }
    fn vec3s(&mut self, n: usize, double: bool) -> Option<Vec<Vec3>> {
        (0..n)
            .map(|_| {
                Some(Vec3::new(
                    self.real(double)?,
                    self.real(double)?,
                    self.real(double)?,
                ))
            })
            .collect()
    }
}

fn parse_serialized(bytes: &[u8], path: &Path, index: u32) -> Result<TriMesh, SceneError> {
    let (id, version) = header(bytes, 0).ok_or_else(|| {
        err(
            path,
            0,
            index,
            ErrorKind::Truncated,
            "file too short for a header",
        )
    })?;
    let check = |at: usize, id: u16, version: u16| -> Result<(), SceneError> {
        if id != FORMAT_ID {
            return Err(err(
                path,
                at as u64,
                index,
                ErrorKind::Syntax,
                format!("not a Mitsuba serialized mesh (format id {id:#06x}, expected 0x041c)"),
            ));
        }
        if !(3..=4).contains(&version) {
            return Err(err(
                path,
                at as u64,
                index,
                ErrorKind::Unsupported,
                format!("serialized format version {version} is not supported (3 and 4 are)"),
            ));
        }
        Ok(())
    };
    check(0, id, version)?;
    let at = shape_offset(bytes, path, index, version)?;
    let (id, version) = header(bytes, at).ok_or_else(|| {
        err(
            path,
            at as u64,
            index,
            ErrorKind::Truncated,
            "file ends in a header",
        )
    })?;
    check(at, id, version)?;

    let mut data = Vec::new();
    flate2::read::ZlibDecoder::new(&bytes[at + 4..])
        .read_to_end(&mut data)
        .map_err(|e| {
            err(
                path,
                at as u64,
                index,
                ErrorKind::Syntax,
                format!("shape {index}'s compressed data cannot be read: {e}"),
            )
        })?;
    let truncated = || {
        err(
            path,
            at as u64,
            index,
            ErrorKind::Truncated,
            format!("shape {index}'s data ends before what its counts announce"),
        )
    };
    let mut c = Cursor { data: &data, at: 0 };
    let flags = c.u32().ok_or_else(truncated)?;
    if version >= 4 {
        // The shape's name, NUL-terminated.
        let end = data[c.at..]
            .iter()
            .position(|&b| b == 0)
            .ok_or_else(truncated)?;
        c.at += end + 1;
    }
    let double = match flags & (SINGLE_PRECISION | DOUBLE_PRECISION) {
        SINGLE_PRECISION => false,
        DOUBLE_PRECISION => true,
        _ => {
            return Err(err(
                path,
                at as u64,
                index,
                ErrorKind::Syntax,
                format!("shape {index}: flags {flags:#x} give neither single nor double precision"),
            ))
        }
    };
    let vertices = c.u64().ok_or_else(truncated)?;
    let triangles = c.u64().ok_or_else(truncated)?;
    let real = if double { 8 } else { 4 };
    // Counts bounded by the data before anything is allocated for them.
    let per_vertex = 3 * real
        + if flags & HAS_NORMALS != 0 {
            3 * real
        } else {
            0
        }
        + if flags & HAS_TEXCOORDS != 0 {
            2 * real
        } else {
            0
        }
        + if flags & HAS_COLORS != 0 { 3 * real } else { 0 };
    let wide = vertices > u32::MAX as u64;
    let per_triangle = if wide { 24 } else { 12 };
    let needed = (vertices as u128) * per_vertex as u128 + (triangles as u128) * per_triangle;
    if needed > (data.len() - c.at) as u128 {
        return Err(truncated());
    }
    let (nv, nt) = (vertices as usize, triangles as usize);
    let positions = c.vec3s(nv, double).ok_or_else(truncated)?;
    let normals = if flags & HAS_NORMALS != 0 {
        Some(c.vec3s(nv, double).ok_or_else(truncated)?)
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        let uv: Option<Vec<Vec2>> = (0..nv)
            .map(|_| Some(Vec2::new(c.real(double)?, c.real(double)?)))
            .collect();
        Some(uv.ok_or_else(truncated)?)
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        c.take(nv * 3 * real).ok_or_else(truncated)?;
    }
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(err(
            path,
            at as u64,
            index,
            ErrorKind::NonFinite,
            format!("shape {index}: vertex {i} is not finite ({})", positions[i]),
        ));
    }
    let mut indices = Vec::with_capacity(nt);
    for t in 0..nt {
        let mut tri = [0u32; 3];
        for v in &mut tri {
            let i = if wide {
                c.u64().ok_or_else(truncated)?
            } else {
                c.u32().ok_or_else(truncated)? as u64
            };
            if i >= vertices {
                return Err(err(
                    path,
                    at as u64,
                    index,
                    ErrorKind::IndexOutOfRange,
                    format!("shape {index}: triangle {t} refers to vertex {i} of {vertices}"),
                ));
            }
            *v = i as u32;
        }
        indices.push(tri);
    }
    Ok(TriMesh {
        positions,
        normals,
        uvs,
        attributes: Vec::new(),
        indices,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// One shape: positions, triangles, whether it has (constant +z) vertex normals.
    type Shape<'a> = (&'a [[f32; 3]], &'a [[u32; 3]], bool);

    /// A version-4 file in Mitsuba's layout (the layout `mitsuba` 3.9.1 loads, see
    /// scripts/mitsuba_references.py), single precision.
    fn file(shapes: &[Shape]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for (v, f, normals) in shapes {
            offsets.push(out.len() as u64);
            let mut body = Vec::new();
            let flags = SINGLE_PRECISION | if *normals { HAS_NORMALS } else { 0 };
            body.extend(flags.to_le_bytes());
            body.extend(b"shape\0");
            body.extend((v.len() as u64).to_le_bytes());
            body.extend((f.len() as u64).to_le_bytes());
            for p in v.iter() {
                body.extend(p.iter().flat_map(|x| x.to_le_bytes()));
            }
            if *normals {
                for _ in v.iter() {
                    body.extend([0f32, 0.0, 1.0].iter().flat_map(|x| x.to_le_bytes()));
                }
            }
            for t in f.iter() {
                body.extend(t.iter().flat_map(|x| x.to_le_bytes()));
            }
            out.extend(FORMAT_ID.to_le_bytes());
            out.extend(4u16.to_le_bytes());
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&body).unwrap();
            out.extend(z.finish().unwrap());
        }
        for o in &offsets {
            out.extend(o.to_le_bytes());
        }
        out.extend((offsets.len() as u32).to_le_bytes());
        out
    }

    const TRI: &[[f32; 3]] = &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    const QUAD: &[[f32; 3]] = &[
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ];

    #[test]
    fn reads_each_shape_of_a_file() {
        let bytes = file(&[
            (TRI, &[[0, 1, 2]], false),
            (QUAD, &[[0, 1, 2], [0, 2, 3]], true),
        ]);
        let p = Path::new("two.serialized");
        let a = parse_serialized(&bytes, p, 0).unwrap();
        assert_eq!(
            (a.positions.len(), a.indices.len(), a.normals.is_some()),
            (3, 1, false)
        );
        let b = parse_serialized(&bytes, p, 1).unwrap();
        assert_eq!(
            (b.positions.len(), b.indices, b.normals.map(|n| n[0])),
            (4, vec![[0, 1, 2], [0, 2, 3]], Some(Vec3::Z))
        );
        assert_eq!(b.positions[2], Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn bad_files_are_located_errors() {
        let p = Path::new("bad.serialized");
        let good = file(&[(TRI, &[[0, 1, 2]], false)]);
        let e = parse_serialized(&good, p, 3).unwrap_err();
        assert!(
            e.to_string().contains("out of range") && e.to_string().contains("holds 1 shapes"),
            "{e}"
        );
        let e = parse_serialized(&file(&[(TRI, &[[0, 1, 7]], false)]), p, 0).unwrap_err();
        assert_eq!(e.kind, ErrorKind::IndexOutOfRange, "{e}");
        let e = parse_serialized(b"PLY!", p, 0).unwrap_err();
        assert!(
            e.to_string().contains("not a Mitsuba serialized mesh"),
            "{e}"
        );
        let e = parse_serialized(&good[..good.len() - 30], p, 0).unwrap_err();
        assert!(
            matches!(e.kind, ErrorKind::Syntax | ErrorKind::Truncated),
            "{e}"
        );
    }
}
