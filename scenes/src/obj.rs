//! Wavefront OBJ → [`TriMesh`], for Mitsuba `obj` shapes. Parsing is tobj's (triangulated as fans,
//! single index); this module adds what tobj does not report: the LINE of a failure, and checks for
//! non-finite coordinates. tobj resolves face indices only when an object ends, so for index errors
//! the offending `f` line is found by a separate scan that runs only after tobj has failed.

use std::io::{BufRead, Read};
use std::path::Path;

use glam::Vec3;

use crate::error::{ErrorKind, Location, SceneError};
use crate::mesh::TriMesh;

pub fn read_obj(path: &Path) -> Result<TriMesh, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| {
        SceneError::new(
            ErrorKind::Io,
            Location::file(path),
            format!("cannot read OBJ file: {e}"),
        )
    })?;
    parse_obj(&bytes, path)
}

/// Parses OBJ text; `file` is used only to name locations.
pub fn parse_obj(bytes: &[u8], file: &Path) -> Result<TriMesh, SceneError> {
    // The struct update covers the fields that tobj's optional features add, in case another
    // crate of the build turns them on (features unify across the workspace).
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = Tracker {
        data: bytes,
        pos: 0,
    };
    // Materials are not used (BSDFs come from the scene file), so `mtllib` resolves to nothing.
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| {
        Ok((Vec::new(), Default::default()))
    });
    let models = match loaded {
        Ok((models, _)) => models,
        Err(e) => return Err(locate_tobj_error(e, bytes, reader.current_line(), file)),
    };

    let mut mesh = TriMesh::new();
    for model in &models {
        let m = &model.mesh;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
        let normals = (m.normals.len() == m.positions.len() && !m.normals.is_empty())
            .then(|| m.normals.chunks_exact(3).map(Vec3::from_slice).collect());
        // As in the file (Mitsuba's `flip_tex_coords` is applied by the scene loader).
        let uvs =
            (m.texcoords.len() / 2 == positions.len() && !m.texcoords.is_empty()).then(|| {
                m.texcoords
                    .chunks_exact(2)
                    .map(|t| glam::Vec2::new(t[0], t[1]))
                    .collect()
            });
        let indices = m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        mesh.append(&TriMesh {
            positions,
            normals,
            uvs,
            attributes: Vec::new(),
            indices,
        });
    }
    let bad_position = mesh.positions.iter().any(|p| !p.is_finite());
    let bad_normal = mesh
        .normals
        .as_ref()
        .is_some_and(|n| n.iter().any(|p| !p.is_finite()));
    if bad_position || bad_normal {
        let (line, what) = find_non_finite(bytes).unwrap_or((0, "vertex"));
        return Err(SceneError::new(
            ErrorKind::NonFinite,
            Location::line(file, line),
            format!("{what} has a NaN or infinite coordinate"),
        ));
    }
    Ok(mesh)
}

/// A `BufRead` over the whole file that remembers how far tobj has read, so that a per-line parse
/// error can be pinned to its line.
struct Tracker<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Tracker<'_> {
    /// Line number of the last line handed out.
    fn current_line(&self) -> u32 {
        let mut end = self.pos;
        if end > 0 && self.data[end - 1] == b'\n' {
            end -= 1;
        }
        1 + self.data[..end].iter().filter(|&&b| b == b'\n').count() as u32
    }
}

impl Read for Tracker<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = buf.len().min(self.data.len() - self.pos);
        buf[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

impl BufRead for Tracker<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(&self.data[self.pos..])
    }

    fn consume(&mut self, amt: usize) {
        self.pos = (self.pos + amt).min(self.data.len());
    }
}

fn locate_tobj_error(e: tobj::LoadError, bytes: &[u8], line: u32, file: &Path) -> SceneError {
    use tobj::LoadError as E;
    match e {
        E::FaceVertexOutOfBounds
        | E::FaceNormalOutOfBounds
        | E::FaceTexCoordOutOfBounds
        | E::FaceColorOutOfBounds => {
            let (line, msg) = find_bad_index(bytes).unwrap_or((
                line,
                format!("{e} (the offending face could not be pinned down)"),
            ));
            SceneError::new(ErrorKind::IndexOutOfRange, Location::line(file, line), msg)
        }
        E::ReadError => SceneError::new(
            ErrorKind::Syntax,
            Location::line(file, line),
            "cannot read line (not UTF-8?)",
        ),
        other => SceneError::new(
            ErrorKind::Syntax,
            Location::line(file, line),
            other.to_string(),
        ),
    }
}

fn lines(bytes: &[u8]) -> impl Iterator<Item = (u32, &str)> {
    bytes
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (i as u32 + 1, std::str::from_utf8(l).unwrap_or("")))
}

/// First `f` line with an index that tobj cannot resolve, using tobj's rules: positive indices are
/// checked against the file's final counts, negative ones against the counts so far.
fn find_bad_index(bytes: &[u8]) -> Option<(u32, String)> {
    let mut totals = [0isize; 3];
    for (_, l) in lines(bytes) {
        match l.split_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let names = ["vertex", "texture coordinate", "normal"];
    let plural = ["vertices", "texture coordinates", "normals"];
    let mut so_far = [0isize; 3];
    for (line, l) in lines(bytes) {
        let mut words = l.split_whitespace();
        match words.next() {
            Some("v") => so_far[0] += 1,
            Some("vt") => so_far[1] += 1,
            Some("vn") => so_far[2] += 1,
            Some("f") => {
                for word in words {
                    for (k, part) in word.split('/').enumerate().take(3) {
                        let Ok(i) = part.parse::<isize>() else {
                            continue;
                        };
                        let resolved = if i < 0 { so_far[k] + i } else { i - 1 };
                        if resolved < 0 || resolved >= totals[k] {
                            return Some((
                                line,
                                format!(
                                    "face {} index {i} out of range (the file has {} {})",
                                    names[k], totals[k], plural[k]
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

fn find_non_finite(bytes: &[u8]) -> Option<(u32, &'static str)> {
    lines(bytes).find_map(|(line, l)| {
        let mut words = l.split_whitespace();
        let what = match words.next() {
            Some("v") => "vertex",
            Some("vn") => "normal",
            _ => return None,
        };
        words
            .take(3)
            .any(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite()))
            .then_some((line, what))
    })
}
