//! `stanford`: stand-in for the paper's Stanford scene (diffuse box, glossy Buddha, mirror Dragon,
//! glass Bunny, area light on top) with procedural objects in the layout of
//! shared/scenes/stanford-like: a lumpy glossy blob (roughconductor, GGX alpha 0.2), a mirror torus
//! and a glass blob (dielectric 1.5 / 1.0), all reflectances 0.8. Denser than the file version so
//! that traversal cost matters: about 130k triangles.

use glam::{Mat4, Quat, Vec3};

use super::rng::value_noise;
use super::{grey, wall, Gen};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::scene::Scene;
use crate::shapes;

/// Icosphere pushed in and out along the radius by smooth noise: a "scanned statue" stand-in whose
/// many small facets give the traversal real work. Normals are recomputed by the builder.
fn blob(level: u32, amplitude: f32, frequency: f32, seed: u64) -> TriMesh {
    let mut m = shapes::icosphere(level);
    for p in &mut m.positions {
        let d = *p;
        // Two noise planes, blended by the direction, avoid a visible seam or pole.
        let n = value_noise(d.x * frequency + 7.1, d.y * frequency - 3.3, seed)
            + value_noise(d.z * frequency + 1.7, d.y * frequency + 5.9, seed ^ 0x55)
            - 1.0;
        *p = d * (1.0 + amplitude * n);
    }
    m.normals = None;
    m
}

pub fn build() -> Scene {
    let mut g = Gen::new(Vec3::new(0.0, 0.0, 2.8), Vec3::new(0.0, -0.27, 0.0), 40.0);
    let white = g.material(grey());
    let glossy = g.material(Material::rough_conductor(0.2, Vec3::splat(0.8)));
    let mirror = g.material(Material::mirror(Vec3::splat(0.8)));
    let glass = g.material(Material::glass(1.5, 1.0, Vec3::splat(0.8)));
    let light = g.material(Material::emitter(Vec3::splat(12.0)));

    let quad = shapes::rectangle();
    g.add(
        "floor",
        &quad,
        wall(Vec3::new(0.0, -1.0, 0.0), Vec3::Y, (1.0, 1.0)),
        white,
    );
    g.add(
        "ceiling",
        &quad,
        wall(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y, (1.0, 1.0)),
        white,
    );
    g.add(
        "back",
        &quad,
        wall(Vec3::new(0.0, 0.0, -1.0), Vec3::Z, (1.0, 1.0)),
        white,
    );
    g.add(
        "left",
        &quad,
        wall(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, (1.0, 1.0)),
        white,
    );
    g.add(
        "right",
        &quad,
        wall(Vec3::new(1.0, 0.0, 0.0), Vec3::NEG_X, (1.0, 1.0)),
        white,
    );

    // 'Buddha': 81,920 triangles, an ellipsoid 0.28 x 0.55 x 0.28 standing on the floor.
    let buddha = blob(6, 0.06, 3.0, 11);
    g.add_smooth(
        "glossy blob",
        &buddha,
        Mat4::from_translation(Vec3::new(-0.5, -0.43, -0.3))
            * Mat4::from_scale(Vec3::new(0.27, 0.53, 0.27)),
        glossy,
    );
    // 'Dragon': 2 x 128 x 96 = 24,576 triangles, upright ring turned -40 deg about y.
    let torus = shapes::torus(1.0, 0.35, 128, 96);
    g.add_smooth(
        "mirror torus",
        &torus,
        Mat4::from_translation(Vec3::new(0.5, -0.621, -0.3))
            * Mat4::from_quat(Quat::from_rotation_y((-40f32).to_radians()))
            * Mat4::from_scale(Vec3::splat(0.28)),
        mirror,
    );
    // 'Bunny': 20,480 triangles, a gently lumpy glass ball.
    let bunny = blob(5, 0.03, 2.0, 23);
    g.add_smooth(
        "glass blob",
        &bunny,
        Mat4::from_translation(Vec3::new(-0.05, -0.74, 0.4)) * Mat4::from_scale(Vec3::splat(0.25)),
        glass,
    );

    let light_xf = Mat4::from_translation(Vec3::new(0.0, 0.998, 0.0))
        * Mat4::from_quat(Quat::from_rotation_x(90f32.to_radians()))
        * Mat4::from_scale(Vec3::new(0.3, 0.3, 1.0));
    g.add("light", &quad, light_xf, light);
    g.finish()
}
