//! Assembly of a [`Scene`] from object-space meshes: the one place where both the Mitsuba loader and
//! the embedded generators turn `TriMesh` + transform + material into world-space triangles. Keeping
//! it single means degenerate-triangle policy, normal handling and material de-duplication cannot
//! drift between file scenes and generated ones.
//!
//! Degenerate policy: a triangle whose world-space `cross(v1 - v0, v2 - v0)` is zero or not finite
//! is DROPPED and counted (the caller turns the count into a warning). Scanned meshes routinely
//! contain a few; they can never be hit by a watertight test (determinant 0) and their face normal
//! is undefined, so keeping them buys nothing and rejecting the file would be hostile.

use glam::{Mat4, Vec3};

use crate::camera::Camera;
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::scene::{Object, Scene};

/// How a mesh shades.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shading {
    /// Face (geometric) normal everywhere: Mitsuba `face_normals = true`.
    Flat,
    /// Per-vertex normals: the mesh's own, or angle-weighted ones computed in world space when it
    /// has none (Mitsuba `face_normals = false`).
    Smooth,
}

/// What [`SceneBuilder::add_mesh`] did with a mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Added {
    pub triangles: usize,
    pub dropped_degenerate: usize,
}

pub struct SceneBuilder {
    scene: Scene,
}

impl SceneBuilder {
    pub fn new(camera: Camera) -> Self {
        SceneBuilder {
            scene: Scene::new(camera),
        }
    }

    /// Settings other than geometry and materials (camera, environment, integrator...).
    pub fn scene_mut(&mut self) -> &mut Scene {
        &mut self.scene
    }

    /// Index of `m`, reusing an identical existing material so the GPU material table stays small.
    pub fn material(&mut self, m: Material) -> u32 {
        if let Some(i) = self.scene.materials.iter().position(|x| *x == m) {
            return i as u32;
        }
        self.scene.materials.push(m);
        (self.scene.materials.len() - 1) as u32
    }

    /// Adds `mesh` (object space) transformed by `to_world`, as one [`Object`].
    pub fn add_mesh(
        &mut self,
        name: &str,
        mesh: &TriMesh,
        to_world: &Mat4,
        material: u32,
        shading: Shading,
    ) -> Added {
        let world = mesh.clone().transformed(to_world);
        self.add_world_mesh(name, &world, material, shading)
    }

    /// Adds a mesh that is already in world space.
    pub fn add_world_mesh(
        &mut self,
        name: &str,
        mesh: &TriMesh,
        material: u32,
        shading: Shading,
    ) -> Added {
        let vertex_normals = match shading {
            Shading::Flat => None,
            Shading::Smooth => Some(
                mesh.normals
                    .clone()
                    .unwrap_or_else(|| mesh.angle_weighted_normals()),
            ),
        };
        if vertex_normals.is_some() && self.scene.triangles.normals.is_none() {
            self.backfill_face_normals();
        }
        if mesh.uvs.is_some() && self.scene.triangles.uvs.is_none() {
            self.scene.triangles.uvs = Some(BARYCENTRIC_UVS.repeat(self.scene.triangles.len()));
        }
        for a in &mesh.attributes {
            let tris = &mut self.scene.triangles;
            if !tris.attributes.iter().any(|(n, _)| *n == a.name) {
                tris.attributes
                    .push((a.name.clone(), vec![Vec3::ZERO; 3 * tris.len()]));
            }
        }

        let tris = &mut self.scene.triangles;
        let first = tris.len() as u32;
        let mut added = Added::default();
        for (index, t) in mesh.indices.iter().enumerate() {
            let p = t.map(|i| mesh.positions[i as usize]);
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let area2 = cross.length_squared();
            if !(area2 > 0.0 && area2.is_finite()) {
                added.dropped_degenerate += 1;
                continue;
            }
            let face = cross / area2.sqrt();
            tris.positions.extend_from_slice(&p);
            tris.materials.push(material);
            if let Some(uvs) = &mut tris.uvs {
                match &mesh.uvs {
                    Some(m) => uvs.extend(t.map(|i| m[i as usize])),
                    None => uvs.extend(BARYCENTRIC_UVS),
                }
            }
            for (name, corners) in &mut tris.attributes {
                match mesh.attributes.iter().find(|a| a.name == *name) {
                    Some(a) => corners.extend((0..3).map(|k| a.corner(index, *t, k))),
                    None => corners.extend([Vec3::ZERO; 3]),
                }
            }
            if let Some(normals) = &mut tris.normals {
                match &vertex_normals {
                    Some(vn) => normals.extend(t.map(|i| {
                        let n = vn[i as usize];
                        // A zero or broken file normal would poison interpolation: fall back.
                        n.try_normalize().unwrap_or(face)
                    })),
                    None => normals.extend([face; 3]),
                }
            }
            added.triangles += 1;
        }
        if added.triangles > 0 {
            self.scene.objects.push(Object {
                name: name.to_string(),
                triangles: first..first + added.triangles as u32,
                material,
            });
        }
        added
    }

    pub fn set_environment(&mut self, radiance: Vec3) {
        self.scene.environment = radiance;
    }

    pub fn finish(self) -> Scene {
        self.scene
    }

    fn backfill_face_normals(&mut self) {
        let tris = &self.scene.triangles;
        let normals = (0..tris.len())
            .flat_map(|i| [tris.face_normal(i); 3])
            .collect();
        self.scene.triangles.normals = Some(normals);
    }
}

/// Texture coordinates of a triangle of a mesh without any: interpolated, they are the
/// barycentric coordinates of the second and third vertex, Mitsuba's.
const BARYCENTRIC_UVS: [glam::Vec2; 3] = [glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y];
