//! `sponza`: stand-in for the paper's Sponza atrium. A closed 24 x 13 m courtyard building: the
//! atrium (|z| < 2.7) rises to 14 m, where one area light covers its whole top, facing down; along
//! both long sides run two storeys of arcades (fluted columns, round arches, a balustrade upstairs)
//! with roofed galleries behind them. The camera stands in the ground-floor gallery, which the light
//! reaches only after bouncing off the atrium, the case the paper picked. Coloured drapes hang into
//! the atrium and potted plants stand on its floor. About 260k triangles, most in the columns.

use std::f32::consts::PI;

use glam::{Mat4, Vec2, Vec3};

use super::rng::value_noise;
use super::{grey, place, wall, Gen};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::scene::Scene;
use crate::shapes;

const HALF_X: f32 = 12.0;
const OUTER_Z: f32 = 6.5;
/// The atrium-side face of the arcades and slabs.
const ATRIUM_Z: f32 = 2.7;
const ARCADE_Z: f32 = 3.0;
const BAY: f32 = 3.0;
const BAYS: i32 = 8;
const SLAB_Y: f32 = 6.0;
const SLAB_TOP: f32 = 6.3;
const ROOF_Y: f32 = 11.3;
const TOP_Y: f32 = 14.0;

/// A column 4 m tall on y = 0: square plinth, moulded base, fluted shaft with entasis, echinus and
/// a rounded abacus. The lathe part has 96 segments (24 flutes) and 22 profile points.
fn column() -> TriMesh {
    let mut profile: Vec<Vec2> = [
        (0.0, 0.2),
        (0.3, 0.2),
        (0.3, 0.26),
        (0.26, 0.3),
        (0.27, 0.36),
        (0.23, 0.42),
    ]
    .iter()
    .map(|&(r, y)| Vec2::new(r, y))
    .collect();
    // Shaft: radius 0.22 tapering to 0.19 along a gentle curve (entasis).
    for i in 0..=11 {
        let s = i as f32 / 11.0;
        profile.push(Vec2::new(0.22 - 0.03 * s * s, 0.45 + 3.05 * s));
    }
    profile.extend(
        [(0.21, 3.55), (0.21, 3.6), (0.3, 3.75), (0.0, 3.8)]
            .iter()
            .map(|&(r, y)| Vec2::new(r, y)),
    );
    let mut m = shapes::fluted_lathe(&profile, 96, 24, 0.06);
    m.append(&shapes::aabb_box(
        Vec3::new(-0.32, 0.0, -0.32),
        Vec3::new(0.32, 0.2, 0.32),
    ));
    m.append(
        &shapes::rounded_box(Vec3::new(0.34, 0.1, 0.34), 0.03, 4)
            .transformed(&Mat4::from_translation(Vec3::new(0.0, 3.9, 0.0))),
    );
    m
}

/// Turned baluster 0.9 m tall, 20 segments, 480 triangles.
fn baluster() -> TriMesh {
    let profile: Vec<Vec2> = [
        (0.0, 0.0),
        (0.07, 0.0),
        (0.07, 0.06),
        (0.05, 0.1),
        (0.045, 0.2),
        (0.07, 0.35),
        (0.08, 0.45),
        (0.06, 0.55),
        (0.035, 0.65),
        (0.04, 0.72),
        (0.055, 0.78),
        (0.06, 0.84),
        (0.06, 0.9),
        (0.0, 0.9),
    ]
    .iter()
    .map(|&(r, y)| Vec2::new(r, y))
    .collect();
    shapes::lathe(&profile, 20)
}

/// Hanging cloth 2.2 x 5 m with vertical folds that deepen downwards, top edge at the origin,
/// facing +z (two-sided material). 24 x 48 quads.
fn drape() -> TriMesh {
    let mut m = shapes::grid(24, 48);
    for p in &mut m.positions {
        let (u, v) = (p.x, p.y);
        let depth = 0.06 + 0.1 * (1.0 - v) / 2.0;
        *p = Vec3::new(1.1 * u, 2.5 * v - 2.5, depth * (5.0 * PI * u).sin());
    }
    m
}

/// Flower pot with soil (one closed lathe, 448 triangles) and a round shrub (1,280 triangles).
fn planter() -> (TriMesh, TriMesh) {
    let profile: Vec<Vec2> = [
        (0.0, 0.0),
        (0.25, 0.0),
        (0.3, 0.1),
        (0.38, 0.5),
        (0.42, 0.6),
        (0.42, 0.65),
        (0.37, 0.65),
        (0.35, 0.55),
        (0.0, 0.55),
    ]
    .iter()
    .map(|&(r, y)| Vec2::new(r, y))
    .collect();
    let pot = shapes::lathe(&profile, 32);
    let mut shrub = shapes::icosphere(3);
    for p in &mut shrub.positions {
        let d = *p;
        *p = d * (1.0 + 0.3 * (value_noise(4.0 * d.x + 2.0, 4.0 * d.z + 3.0 * d.y, 77) - 0.5));
    }
    shrub.normals = None;
    let shrub = shrub.transformed(
        &(Mat4::from_translation(Vec3::new(0.0, 1.05, 0.0)) * Mat4::from_scale(Vec3::splat(0.55))),
    );
    (pot, shrub)
}

pub fn build() -> Scene {
    let mut g = Gen::new(Vec3::new(10.5, 1.8, 5.4), Vec3::new(-2.0, 2.8, 1.5), 70.0);
    let stone = g.material(grey());
    let sand = g.material(Material::diffuse(Vec3::new(0.8, 0.72, 0.55)));
    let light = g.material(Material::emitter(Vec3::splat(8.0)));
    let cloths = [
        g.material(Material::diffuse_two_sided(Vec3::new(0.8, 0.1, 0.1))),
        g.material(Material::diffuse_two_sided(Vec3::new(0.15, 0.8, 0.2))),
        g.material(Material::diffuse_two_sided(Vec3::new(0.2, 0.3, 0.8))),
    ];
    let terracotta = g.material(Material::diffuse(Vec3::new(0.8, 0.4, 0.25)));
    let leaves = g.material(Material::diffuse(Vec3::new(0.25, 0.8, 0.3)));

    // Shell: floor, end walls (full height), outer gallery walls, upper atrium walls, light.
    let quad = shapes::rectangle();
    let half_top = TOP_Y / 2.0;
    g.add(
        "floor",
        &quad,
        wall(Vec3::ZERO, Vec3::Y, (HALF_X, OUTER_Z)),
        sand,
    );
    g.add(
        "east wall",
        &quad,
        wall(
            Vec3::new(HALF_X, half_top, 0.0),
            Vec3::NEG_X,
            (half_top, OUTER_Z),
        ),
        stone,
    );
    g.add(
        "west wall",
        &quad,
        wall(
            Vec3::new(-HALF_X, half_top, 0.0),
            Vec3::X,
            (half_top, OUTER_Z),
        ),
        stone,
    );
    for side in [1.0f32, -1.0] {
        let n = Vec3::new(0.0, 0.0, -side);
        g.add(
            "gallery wall",
            &quad,
            wall(
                Vec3::new(0.0, ROOF_Y / 2.0, side * OUTER_Z),
                n,
                (HALF_X, ROOF_Y / 2.0),
            ),
            stone,
        );
        let upper = (ROOF_Y + 0.3 + TOP_Y) / 2.0;
        g.add(
            "atrium upper wall",
            &quad,
            wall(
                Vec3::new(0.0, upper, side * ATRIUM_Z),
                n,
                (HALF_X, TOP_Y - upper),
            ),
            stone,
        );
        // Slabs are boxes: their undersides are the gallery ceilings, their tops the floors above.
        let (z0, z1) = if side > 0.0 {
            (ATRIUM_Z, OUTER_Z)
        } else {
            (-OUTER_Z, -ATRIUM_Z)
        };
        g.add(
            "gallery slab",
            &shapes::aabb_box(
                Vec3::new(-HALF_X, SLAB_Y, z0),
                Vec3::new(HALF_X, SLAB_TOP, z1),
            ),
            Mat4::IDENTITY,
            stone,
        );
        g.add(
            "gallery roof",
            &shapes::aabb_box(
                Vec3::new(-HALF_X, ROOF_Y, z0),
                Vec3::new(HALF_X, ROOF_Y + 0.3, z1),
            ),
            Mat4::IDENTITY,
            stone,
        );
    }
    g.add(
        "skylight",
        &quad,
        wall(Vec3::new(0.0, TOP_Y, 0.0), Vec3::NEG_Y, (HALF_X, ATRIUM_Z)),
        light,
    );

    // Arcades: 9 columns and 8 arches per side and storey; the upper storey is 7/8 as tall.
    let column = column();
    let baluster = baluster();
    let rail = shapes::rounded_box(Vec3::new(1.25, 0.05, 0.1), 0.03, 6);
    let lower_arch = shapes::arch_panel(BAY / 2.0, 1.25, SLAB_Y - 4.0, 0.6, 24);
    let upper_arch = shapes::arch_panel(BAY / 2.0, 1.25, ROOF_Y - (SLAB_TOP + 3.5), 0.6, 24);
    for side in [1.0f32, -1.0] {
        let z = side * ARCADE_Z;
        for k in 0..=BAYS {
            let x = -HALF_X + BAY * k as f32;
            g.add(
                "column",
                &column,
                place(Vec3::new(x, 0.0, z), 0.0, Vec3::ONE),
                stone,
            );
            g.add(
                "upper column",
                &column,
                place(Vec3::new(x, SLAB_TOP, z), 0.0, Vec3::new(0.85, 0.875, 0.85)),
                stone,
            );
        }
        for k in 0..BAYS {
            let x = -HALF_X + BAY * (k as f32 + 0.5);
            g.add(
                "arch",
                &lower_arch,
                Mat4::from_translation(Vec3::new(x, 4.0, z)),
                stone,
            );
            g.add(
                "upper arch",
                &upper_arch,
                Mat4::from_translation(Vec3::new(x, SLAB_TOP + 3.5, z)),
                stone,
            );
            let mut balusters = TriMesh::new();
            for b in 0..9 {
                let bx = x - 1.2 + 0.3 * b as f32;
                balusters.append(
                    &baluster
                        .clone()
                        .transformed(&Mat4::from_translation(Vec3::new(bx, SLAB_TOP, z))),
                );
            }
            g.add("balustrade", &balusters, Mat4::IDENTITY, stone);
            g.add(
                "handrail",
                &rail,
                Mat4::from_translation(Vec3::new(x, SLAB_TOP + 0.95, z)),
                stone,
            );
            if k % 2 == 1 {
                let cloth = cloths[(k as usize / 2 + (side < 0.0) as usize) % cloths.len()];
                let zc = side * (ATRIUM_Z - 0.25);
                g.add(
                    "drape",
                    &drape(),
                    Mat4::from_translation(Vec3::new(x, 9.5, zc)),
                    cloth,
                );
            }
        }
    }

    let (pot, shrub) = planter();
    for (i, x) in [-8.0f32, -4.0, 0.0, 4.0, 8.0].iter().enumerate() {
        for side in [1.0f32, -1.0] {
            let xf = place(Vec3::new(*x, 0.0, side * 1.8), 37.0 * i as f32, Vec3::ONE);
            g.add("pot", &pot, xf, terracotta);
            g.add_smooth("shrub", &shrub, xf, leaves);
        }
    }
    g.finish()
}
