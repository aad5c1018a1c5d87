//! Indexed triangle meshes in object space: what the OBJ/PLY readers and the procedural shape
//! generators hand to [`crate::SceneBuilder`], which transforms them to world space and flattens
//! them into the scene's triangle soup. Indices are already validated here; readers reject bad
//! ones with a file location before a `TriMesh` exists.

use glam::{Mat3, Mat4, Vec3};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex normals (same length as `positions`) when the source had them.
    pub normals: Option<Vec<Vec3>>,
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

    /// Appends `other`. Normals survive only if both meshes have them.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        let had_positions = !self.positions.is_empty();
        match (&mut self.normals, &other.normals) {
            (Some(a), Some(b)) => a.extend_from_slice(b),
            (None, Some(b)) if !had_positions => self.normals = Some(b.clone()),
            _ => self.normals = None,
        }
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(
            other
                .indices
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
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
