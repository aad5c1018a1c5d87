//! Scenes generated in code, no files: stand-ins for the paper's four test scenes (§4) and
//! the classic Cornell box, built from [`crate::shapes`] through the same [`SceneBuilder`] as file
//! scenes, so they flow into the BVH and the renderer exactly like loaded ones.
//!
//! Common to all: 1024 x 1024 film (the paper's resolution; the renderer may override it), box
//! filter, `path` integrator with unlimited depth and Russian roulette from the first bounce,
//! diffuse albedo 0.8 (grey, or coloured with 0.8 as the largest component), one-sided surfaces
//! wound to face where the camera and the light are, and fixed seeds so that a name always yields
//! the same triangles in the same order.

mod confroom;
mod cornell;
mod fairyforest;
mod rng;
mod sponza;
mod stanford;

use glam::{Mat4, Quat, Vec3};

use crate::builder::{SceneBuilder, Shading};
use crate::camera::{Camera, FovAxis};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::scene::{Integrator, Scene};

pub use rng::Rng;

/// The default scene when none is named: small and fast to build.
pub const DEFAULT: &str = "cornell";

struct Entry {
    name: &'static str,
    description: &'static str,
    /// Triangle count the generator aims at (tests hold it to +-15 %).
    target_triangles: usize,
    build: fn() -> Scene,
}

const SCENES: &[Entry] = &[
    Entry {
        name: "cornell",
        description: "classic Cornell box: white/red/green walls, two boxes, area light on the ceiling (36 triangles)",
        target_triangles: 36,
        build: cornell::build,
    },
    Entry {
        name: "confroom",
        description: "conference room whose whole ceiling is an area light, rows of tables and chairs (~250k triangles)",
        target_triangles: 250_000,
        build: confroom::build,
    },
    Entry {
        name: "fairyforest",
        description: "forest glade open to a constant sky: rolling ground, grass blades, trees, mushrooms (~170k triangles)",
        target_triangles: 170_000,
        build: fairyforest::build,
    },
    Entry {
        name: "sponza",
        description: "atrium with two storeys of columns and arches, area light above it, camera in the indirectly lit gallery (~260k triangles)",
        target_triangles: 260_000,
        build: sponza::build,
    },
    Entry {
        name: "stanford",
        description: "diffuse box with a glossy blob, a mirror torus and a glass sphere, area light on top (~130k triangles)",
        target_triangles: 130_000,
        build: stanford::build,
    },
];

const NAMES: &[&str] = &["cornell", "confroom", "fairyforest", "sponza", "stanford"];

/// Names of the embedded scenes, in a fixed order.
pub fn names() -> &'static [&'static str] {
    NAMES
}

/// One-line description of a scene.
pub fn description(name: &str) -> Option<&'static str> {
    entry(name).map(|e| e.description)
}

/// Triangle count the generator aims at.
pub fn target_triangles(name: &str) -> Option<usize> {
    entry(name).map(|e| e.target_triangles)
}

/// Generates the named scene; `None` for an unknown name.
pub fn load(name: &str) -> Option<Scene> {
    entry(name).map(|e| (e.build)())
}

fn entry(name: &str) -> Option<&'static Entry> {
    SCENES.iter().find(|e| e.name == name)
}

/// Shared scaffolding of the generators.
struct Gen {
    b: SceneBuilder,
}

impl Gen {
    fn new(origin: Vec3, target: Vec3, fov: f32) -> Gen {
        let camera = Camera::look_at(origin, target, Vec3::Y, fov, FovAxis::X, 1024, 1024)
            .expect("embedded cameras are constant and valid");
        let mut b = SceneBuilder::new(camera);
        let s = b.scene_mut();
        s.integrator = Integrator {
            max_depth: -1,
            rr_depth: 1,
            hide_emitters: false,
        };
        s.sample_count = 1;
        Gen { b }
    }

    fn material(&mut self, m: Material) -> u32 {
        self.b.material(m)
    }

    fn add(&mut self, name: &str, mesh: &TriMesh, to_world: Mat4, material: u32) {
        self.b
            .add_mesh(name, mesh, &to_world, material, Shading::Flat);
    }

    fn add_smooth(&mut self, name: &str, mesh: &TriMesh, to_world: Mat4, material: u32) {
        self.b
            .add_mesh(name, mesh, &to_world, material, Shading::Smooth);
    }

    fn finish(self) -> Scene {
        self.b.finish()
    }
}

/// Scale, then rotate about +y by `yaw` degrees, then translate (Mitsuba's usual order).
fn place(translation: Vec3, yaw_degrees: f32, scale: Vec3) -> Mat4 {
    Mat4::from_scale_rotation_translation(
        scale,
        Quat::from_rotation_y(yaw_degrees.to_radians()),
        translation,
    )
}

/// Grey diffuse of albedo 0.8.
fn grey() -> Material {
    Material::diffuse(Vec3::splat(0.8))
}

/// Transform taking Mitsuba's rectangle ([-1,1]^2, facing +z) to an axis-aligned wall facing
/// `normal` (an axis direction), centred at `center`, with half extents `half` along its two in-plane
/// world axes taken in x, y, z order. Built from exact axis columns rather than a rotation so that
/// walls meet without round-off gaps.
fn wall(center: Vec3, normal: Vec3, half: (f32, f32)) -> Mat4 {
    let mut axes = [Vec3::X, Vec3::Y, Vec3::Z]
        .into_iter()
        .filter(|a| a.dot(normal) == 0.0);
    let (u, v) = (
        axes.next().unwrap_or(Vec3::X),
        axes.next().unwrap_or(Vec3::Y),
    );
    // Right-handed (u x v = normal) keeps the rectangle's counter-clockwise front facing `normal`.
    let v = if u.cross(v).dot(normal) > 0.0 { v } else { -v };
    Mat4::from_cols(
        (u * half.0).extend(0.0),
        (v * half.1).extend(0.0),
        normal.extend(0.0),
        center.extend(1.0),
    )
}
