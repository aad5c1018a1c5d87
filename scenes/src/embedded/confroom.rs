//! `confroom`: stand-in for the paper's ConfRoom. A 14 x 3 x 16 m room whose entire ceiling is one
//! area light facing down (so most paths end after a single bounce, as in the paper), with six rows
//! of six tables, three cushioned chairs behind each, a lectern and a screen wall at the front.
//! About 250k triangles, most of them in the rounded cushions and table tops.

use glam::{Mat4, Quat, Vec3};

use super::rng::Rng;
use super::{grey, place, wall, Gen};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::scene::Scene;
use crate::shapes;

const HALF_X: f32 = 7.0;
const HALF_Z: f32 = 8.0;
const HEIGHT: f32 = 3.0;

/// Leg of radius `r` and height `h` standing on y = 0 at (x, z).
fn leg(x: f32, z: f32, r: f32, h: f32) -> Mat4 {
    Mat4::from_translation(Vec3::new(x, 0.0, z)) * Mat4::from_scale(Vec3::new(r, h, r))
}

/// Chair facing -z (towards the front), origin at the floor below the seat centre.
/// 2 x 768 cushion triangles + 4 x 48 leg triangles = 1,728.
fn chair() -> (TriMesh, TriMesh) {
    let mut cushions = shapes::rounded_box(Vec3::new(0.23, 0.04, 0.22), 0.035, 8)
        .transformed(&Mat4::from_translation(Vec3::new(0.0, 0.46, 0.0)));
    let back = shapes::rounded_box(Vec3::new(0.22, 0.22, 0.035), 0.03, 8).transformed(
        &(Mat4::from_translation(Vec3::new(0.0, 0.78, 0.21))
            * Mat4::from_quat(Quat::from_rotation_x(-0.12))),
    );
    cushions.append(&back);
    let mut frame = TriMesh::new();
    let post = shapes::cylinder(12, 1);
    for (x, z) in [(-0.19, -0.18), (0.19, -0.18), (-0.19, 0.18), (0.19, 0.18)] {
        frame.append(&post.clone().transformed(&leg(x, z, 0.015, 0.43)));
    }
    (cushions, frame)
}

/// Table 1.6 x 0.7 m, 0.74 m high: rounded top (1,200 triangles) and four legs (4 x 96).
fn table() -> TriMesh {
    let mut t = shapes::rounded_box(Vec3::new(0.8, 0.02, 0.35), 0.015, 10)
        .transformed(&Mat4::from_translation(Vec3::new(0.0, 0.72, 0.0)));
    let post = shapes::cylinder(16, 2);
    for (x, z) in [(-0.74, -0.29), (0.74, -0.29), (-0.74, 0.29), (0.74, 0.29)] {
        t.append(&post.clone().transformed(&leg(x, z, 0.025, 0.70)));
    }
    t
}

pub fn build() -> Scene {
    let mut g = Gen::new(Vec3::new(6.2, 1.75, 7.4), Vec3::new(-1.5, 0.7, -3.0), 65.0);
    let white = g.material(grey());
    let carpet = g.material(Material::diffuse(Vec3::new(0.5, 0.55, 0.8)));
    let wood = g.material(Material::diffuse(Vec3::new(0.8, 0.6, 0.4)));
    let fabric = g.material(Material::diffuse(Vec3::new(0.8, 0.25, 0.2)));
    let light = g.material(Material::emitter(Vec3::splat(1.5)));

    let quad = shapes::rectangle();
    g.add(
        "floor",
        &quad,
        wall(Vec3::ZERO, Vec3::Y, (HALF_X, HALF_Z)),
        carpet,
    );
    g.add(
        "front wall",
        &quad,
        wall(
            Vec3::new(0.0, HEIGHT / 2.0, -HALF_Z),
            Vec3::Z,
            (HALF_X, HEIGHT / 2.0),
        ),
        white,
    );
    g.add(
        "back wall",
        &quad,
        wall(
            Vec3::new(0.0, HEIGHT / 2.0, HALF_Z),
            Vec3::NEG_Z,
            (HALF_X, HEIGHT / 2.0),
        ),
        white,
    );
    g.add(
        "left wall",
        &quad,
        wall(
            Vec3::new(-HALF_X, HEIGHT / 2.0, 0.0),
            Vec3::X,
            (HEIGHT / 2.0, HALF_Z),
        ),
        white,
    );
    g.add(
        "right wall",
        &quad,
        wall(
            Vec3::new(HALF_X, HEIGHT / 2.0, 0.0),
            Vec3::NEG_X,
            (HEIGHT / 2.0, HALF_Z),
        ),
        white,
    );
    // The whole ceiling emits downwards; its black BSDF ends the paths that reach it.
    g.add(
        "ceiling light",
        &quad,
        wall(Vec3::new(0.0, HEIGHT, 0.0), Vec3::NEG_Y, (HALF_X, HALF_Z)),
        light,
    );

    // Front: a projection screen panel and a lectern.
    g.add(
        "screen",
        &shapes::rounded_box(Vec3::new(2.5, 1.0, 0.03), 0.02, 6),
        Mat4::from_translation(Vec3::new(0.0, 1.6, -HALF_Z + 0.05)),
        white,
    );
    let lectern = shapes::rounded_box(Vec3::new(0.35, 0.55, 0.3), 0.04, 10);
    g.add(
        "lectern",
        &lectern,
        place(Vec3::new(-4.0, 0.55, -6.5), 20.0, Vec3::ONE),
        wood,
    );

    let table = table();
    let (cushions, frame) = chair();
    let mut rng = Rng::new(0x00c0_ffee);
    for row in 0..6 {
        let z = -4.6 + 2.1 * row as f32;
        for col in 0..6 {
            let x = -5.5 + 2.2 * col as f32;
            g.add(
                &format!("table {row}.{col}"),
                &table,
                place(Vec3::new(x, 0.0, z), 0.0, Vec3::ONE),
                wood,
            );
            for seat in 0..3 {
                // Chairs pulled back by slightly different amounts and turned a little: people left.
                let cx = x - 0.53 + 0.53 * seat as f32 + rng.range(-0.05, 0.05);
                let cz = z + 0.55 + rng.range(0.0, 0.25);
                let yaw = rng.range(-15.0, 15.0);
                let xf = place(Vec3::new(cx, 0.0, cz), yaw, Vec3::ONE);
                g.add(&format!("chair {row}.{col}.{seat}"), &cushions, xf, fabric);
                g.add(
                    &format!("chair frame {row}.{col}.{seat}"),
                    &frame,
                    xf,
                    white,
                );
            }
        }
    }
    g.finish()
}
