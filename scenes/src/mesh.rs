//! Indexed triangle meshes in object space: what the OBJ/PLY readers and the procedural shape
//! generators hand to [`crate::SceneBuilder`], which transforms them to world space and flattens
//! them into the scene's triangle soup. Indices are already validated here; readers reject bad
//! ones with a file location before a `TriMesh` exists.

use glam::{Mat3, Mat4, Vec2, Vec3};

/// One of Mitsuba's mesh attributes: a value per vertex (a name starting with `vertex_`) or
/// per triangle (`face_`; a polygon's value repeated for each triangle of its fan).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    pub name: String,
    /// 1 (a number, held in `x`), 3 (a colour or vector) or 4 (r, g, b, a: Mitsuba keeps it,
    /// but no texture can read it).
    pub channels: u32,
    pub values: Vec<Vec3>,
}

impl MeshAttribute {
    /// Whether it holds a value per triangle rather than per vertex.
    pub fn per_face(&self) -> bool {
        self.name.starts_with("face_")
    }

    /// The attribute's value at corner `k` (0..3) of triangle `face`, whose vertices are
    /// `t`: a number as grey, as Mitsuba evaluates a one-channel attribute as a colour.
    pub fn corner(&self, face: usize, t: [u32; 3], k: usize) -> Vec3 {
        let v = if self.per_face() {
            self.values[face]
        } else {
            self.values[t[k] as usize]
        };
        if self.channels == 1 {
            Vec3::splat(v.x)
        } else {
            v
        }
    }
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals (same length as `positions`) when the source had them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates (same length as `positions`) when the source had them.
    pub uvs: Option<Vec<Vec2>>,
    /// Mitsuba's mesh attributes (a PLY's extra properties: `vertex_color` from its r, g, b,
    /// `face_color`, `vertex_weight`, ...), what a `mesh_attribute` texture reads.
    pub attributes: Vec<MeshAttribute>,
    /// Counter-clockwise = front.
    pub indices: Vec<[u32; 3]>,
}

impl TriMesh {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Applies `m` to positions, and its inverse transpose to normals (so non-uniform scales keep
    /// normals perpendicular to the surface).
    pub fn transform(&mut self, m: &Mat4) {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if let Some(normals) = &mut self.normals {
            let nm = normal_matrix(m);
            for n in normals {
                *n = (nm * *n).normalize_or_zero();
            }
        }
    }

    pub fn transformed(mut self, m: &Mat4) -> Self {
        self.transform(m);
        self
    }

    /// Mitsuba's `flip_normals`: the back becomes the front, for both face and vertex normals.
    pub fn flip(&mut self) {
        for t in &mut self.indices {
            t.swap(1, 2);
        }
        if let Some(normals) = &mut self.normals {
            for n in normals {
                *n = -*n;
            }
        }
    }

    /// Appends `other`. Normals and texture coordinates survive only if both meshes have them.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        let had_positions = !self.positions.is_empty();
        match (&mut self.normals, &other.normals) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (None, Some(b)) if !had_positions => self.normals = Some(b.clone()),
            _ => self.normals = None,
        }
        match (&mut self.uvs, &other.uvs) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (None, Some(b)) if !had_positions => self.uvs = Some(b.clone()),
            _ => self.uvs = None,
        }
        if !had_positions {
            self.attributes = other.attributes.clone();
        } else {
            // An attribute survives only if both meshes have it with the same channels.
            self.attributes.retain_mut(|a| {
                match other
                    .attributes
                    .iter()
                    .find(|b| b.name == a.name && b.channels == a.channels)
                {
                    Some(b) => {
                        a.values.extend_from_slice(&b.values);
                        true
                    }
                    None => false,
                }
            });
        }
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(
            other
                .indices
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// The mesh with texture coordinates `uv(p)` of each (object-space) vertex position, each
    /// triangle given its own three vertices so that a coordinate that wraps around (the
    /// `periodic` component, in [0, 1)) can be continued across the seam within a triangle. A
    /// vertex where `uv` is undefined (a pole or an axis: `singular(p)`) takes the mean
    /// periodic coordinate of the triangle's other vertices.
    pub fn with_corner_uvs(
        &self,
        uv: impl Fn(Vec3) -> Vec2,
        periodic: usize,
        singular: impl Fn(Vec3) -> bool,
    ) -> TriMesh {
        // Shading normals of the welded mesh: unwelded, each triangle would see only itself.
        let normals = self
            .normals
            .clone()
            .unwrap_or_else(|| self.angle_weighted_normals());
        let mut out = TriMesh {
            normals: Some(Vec::new()),
            uvs: Some(Vec::new()),
            attributes: self
                .attributes
                .iter()
                .map(|a| MeshAttribute {
                    values: Vec::new(),
                    ..a.clone()
                })
                .collect(),
            ..TriMesh::default()
        };
        for (face, t) in self.indices.iter().enumerate() {
            let p = t.map(|i| self.positions[i as usize]);
            let mut c = p.map(&uv);
            let regular: Vec<usize> = (0..3).filter(|&k| !singular(p[k])).collect();
            let lo = regular
                .iter()
                .map(|&k| c[k][periodic])
                .fold(f32::INFINITY, f32::min);
            let hi = regular
                .iter()
                .map(|&k| c[k][periodic])
                .fold(f32::NEG_INFINITY, f32::max);
            if hi - lo > 0.5 {
                for &k in &regular {
                    if c[k][periodic] < 0.5 {
                        c[k][periodic] += 1.0;
                    }
                }
            }
            if !regular.is_empty() {
                let mean =
                    regular.iter().map(|&k| c[k][periodic]).sum::<f32>() / regular.len() as f32;
                for k in 0..3 {
                    if singular(p[k]) {
                        c[k][periodic] = mean;
                    }
                }
            }
            let base = out.positions.len() as u32;
            for k in 0..3 {
                out.positions.push(p[k]);
                out.normals.as_mut().unwrap().push(normals[t[k] as usize]);
                out.uvs.as_mut().unwrap().push(c[k]);
            }
            for (a, o) in self.attributes.iter().zip(&mut out.attributes) {
                if a.per_face() {
                    o.values.push(a.values[face]);
                } else {
                    o.values.extend(t.map(|i| a.values[i as usize]));
                }
            }
            out.indices.push([base, base + 1, base + 2]);
        }
        out
    }

    /// Angle-weighted vertex normals (Thürmer & Wüthrich), what Mitsuba computes for a mesh without
    /// normals when `face_normals` is false. Vertices with no usable face get +x, as in Mitsuba.
    pub fn angle_weighted_normals(&self) -> Vec<Vec3> {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.indices {
            let p = t.map(|i| self.positions[i as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let Some(n) = n.try_normalize() else { continue };
            for k in 0..3 {
                let d0 = (p[(k + 1) % 3] - p[k]).normalize_or_zero();
                let d1 = (p[(k + 2) % 3] - p[k]).normalize_or_zero();
                let angle = d0.dot(d1).clamp(-1.0, 1.0).acos();
                acc[t[k] as usize] += n * angle;
            }
        }
        acc.into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::X))
            .collect()
    }
}

/// Inverse transpose of the linear part: the matrix that maps normals.
pub fn normal_matrix(m: &Mat4) -> Mat3 {
    Mat3::from_mat4(*m).inverse().transpose()
}
