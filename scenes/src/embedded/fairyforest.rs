//! `fairyforest`: stand-in for the paper's FairyForest, a scene open at the top and lit only by a
//! constant sky (the `environment`). Rolling ground 40 x 40 m, a clearing of dense grass blades
//! around the camera, a ring of trees (tapered trunks, lumpy foliage) and mushrooms. Grass and
//! leaves are thin sheets, so their materials are two-sided. About 170k triangles.

use std::f32::consts::TAU;

use glam::{Mat4, Quat, Vec2, Vec3};

use super::rng::{value_noise, Rng};
use super::{place, Gen};
use crate::material::Material;
use crate::mesh::TriMesh;
use crate::morton::morton2d_encode;
use crate::scene::Scene;
use crate::shapes;

const HALF: f32 = 20.0;
const GROUND_CELLS: u32 = 96;
const BLADES: u32 = 13_000;
const TREES: u32 = 56;
const MUSHROOMS: u32 = 40;

/// Ground height: gentle hills from two octaves of value noise, flattened in the clearing.
fn height(x: f32, z: f32) -> f32 {
    let hills =
        1.2 * value_noise(x * 0.12, z * 0.12, 3) + 0.4 * value_noise(x * 0.4, z * 0.4, 5) - 0.8;
    let clearing = ((x * x + z * z).sqrt() / 8.0).min(1.0);
    hills * clearing
}

fn ground() -> TriMesh {
    // The grid lies in z = 0 facing +z; turn it to face +y, then lift each vertex to the terrain.
    let mut m = shapes::grid(GROUND_CELLS, GROUND_CELLS).transformed(
        &(Mat4::from_quat(Quat::from_rotation_x(-90f32.to_radians()))
            * Mat4::from_scale(Vec3::new(HALF, HALF, 1.0))),
    );
    for p in &mut m.positions {
        p.y = height(p.x, p.z);
    }
    m
}

/// One curved, tapering grass blade on the ground at the origin, bending towards +x: 3 quads
/// narrowing to a tip, 5 triangles. Faces +z; the material is two-sided.
fn blade(rng: &mut Rng) -> TriMesh {
    let h = rng.range(0.25, 0.6);
    let w = rng.range(0.015, 0.03);
    let bend = rng.range(0.05, 0.25);
    let mut m = TriMesh::new();
    let rows: Vec<(f32, f32)> = (0..3)
        .map(|i| i as f32 / 3.0)
        .map(|s| (s, w * (1.0 - s)))
        .collect();
    for &(s, half) in &rows {
        let x = bend * h * s * s;
        m.push_vertex(Vec3::new(x - half, h * s, 0.0));
        m.push_vertex(Vec3::new(x + half, h * s, 0.0));
    }
    let tip = m.push_vertex(Vec3::new(bend * h, h, 0.0));
    for i in 0..2 {
        let (a, b) = (2 * i, 2 * i + 1);
        m.push_quad(a, b, b + 2, a + 2);
    }
    m.push_triangle(4, 5, tip);
    m
}

/// Tree about 6 m tall before scaling: trunk (lathe, 16 around, 256 triangles) and three foliage
/// blobs (icospheres of level 2, 320 triangles each, pushed around by noise).
fn tree(rng: &mut Rng, seed: u64) -> (TriMesh, TriMesh) {
    let trunk_profile: Vec<Vec2> = [
        (0.0, 0.0),
        (0.35, 0.0),
        (0.28, 0.4),
        (0.22, 1.2),
        (0.19, 2.0),
        (0.16, 2.8),
        (0.13, 3.6),
        (0.1, 4.2),
        (0.07, 4.6),
        (0.0, 4.7),
    ]
    .iter()
    .map(|&(r, y)| Vec2::new(r, y))
    .collect();
    let trunk = shapes::lathe(&trunk_profile, 16);
    let mut foliage = TriMesh::new();
    for k in 0..3 {
        let mut blob = shapes::icosphere(2);
        let s = seed.wrapping_add(k);
        for p in &mut blob.positions {
            let d = *p;
            let n = value_noise(d.x * 2.5 + 3.0, d.z * 2.5 + d.y, s) - 0.5;
            *p = d * (1.0 + 0.35 * n);
        }
        blob.normals = None;
        let r = rng.range(1.1, 1.6) * (1.0 - 0.2 * k as f32);
        let c = Vec3::new(
            rng.range(-0.3, 0.3),
            3.2 + 1.1 * k as f32,
            rng.range(-0.3, 0.3),
        );
        foliage.append(&blob.transformed(
            &(Mat4::from_translation(c) * Mat4::from_scale(Vec3::new(r, 0.8 * r, r))),
        ));
    }
    (trunk, foliage)
}

/// Mushroom about 0.3 m tall: stem and domed cap as one closed lathe, 24 around.
fn mushroom() -> (TriMesh, TriMesh) {
    let stem = shapes::lathe(
        &[
            Vec2::new(0.0, 0.0),
            Vec2::new(0.05, 0.0),
            Vec2::new(0.04, 0.1),
            Vec2::new(0.035, 0.2),
            Vec2::new(0.0, 0.2),
        ],
        24,
    );
    let cap_profile: Vec<Vec2> = (0..=8)
        .map(|i| {
            let a = i as f32 / 8.0 * std::f32::consts::FRAC_PI_2;
            // The last point closes the dome exactly on the axis (cos(pi/2) is not 0 in f32).
            Vec2::new(
                if i == 8 { 0.0 } else { 0.14 * a.cos() },
                0.19 + 0.1 * a.sin(),
            )
        })
        .collect();
    let mut profile = vec![Vec2::new(0.0, 0.18)];
    profile.extend(cap_profile);
    (stem, shapes::lathe(&profile, 24))
}

pub fn build() -> Scene {
    let eye = Vec3::new(0.0, height(0.0, 9.0) + 1.6, 9.0);
    let mut g = Gen::new(eye, Vec3::new(0.0, height(0.0, 0.0) + 1.8, 0.0), 60.0);
    g.b.set_environment(Vec3::new(0.9, 0.95, 1.0));
    let soil = g.material(Material::diffuse(Vec3::new(0.8, 0.6, 0.4)));
    let grass = g.material(Material::diffuse_two_sided(Vec3::new(0.35, 0.8, 0.2)));
    let bark = g.material(Material::diffuse(Vec3::new(0.8, 0.55, 0.35)));
    let leaves = g.material(Material::diffuse_two_sided(Vec3::new(0.25, 0.8, 0.3)));
    let stem_mat = g.material(Material::diffuse(Vec3::splat(0.8)));
    let cap_mat = g.material(Material::diffuse(Vec3::new(0.8, 0.15, 0.1)));

    g.add("ground", &ground(), Mat4::IDENTITY, soil);

    let mut rng = Rng::new(0xf0_4e57);
    let mut placed: Vec<(u32, TriMesh)> = (0..BLADES)
        .map(|_| {
            // r = 12 u^0.8 instead of the area-uniform 12 u^0.5: denser towards the clearing's centre.
            let r = 12.0 * rng.f32().powf(0.8);
            let a = rng.range(0.0, TAU);
            let (x, z) = (r * a.cos(), r * a.sin());
            let b = blade(&mut rng);
            let xf = place(
                Vec3::new(x, height(x, z) - 0.01, z),
                rng.range(0.0, 360.0),
                Vec3::ONE,
            );
            // Z-order of a 5 cm cell: neighbouring blades end up neighbouring in the triangle list.
            let cell = |v: f32| ((v + HALF) * 20.0) as u32;
            (morton2d_encode(cell(x), cell(z)), b.transformed(&xf))
        })
        .collect();
    placed.sort_by_key(|(key, _)| *key);
    let mut blades = TriMesh::new();
    for (_, b) in &placed {
        blades.append(b);
    }
    g.add("grass", &blades, Mat4::IDENTITY, grass);

    for i in 0..TREES {
        // A ring around the clearing, shifted away from the camera, never right in front of it.
        let (x, z) = loop {
            let a = rng.range(0.0, TAU);
            let r = rng.range(7.0, 18.0);
            let (x, z) = (r * a.cos(), r * a.sin() - 3.0);
            if Vec2::new(x - eye.x, z - eye.z).length() > 5.0 {
                break (x, z);
            }
        };
        let s = rng.range(0.8, 1.3);
        let (trunk, foliage) = tree(&mut rng, 100 + i as u64);
        let xf = place(
            Vec3::new(x, height(x, z) - 0.05, z),
            rng.range(0.0, 360.0),
            Vec3::splat(s),
        );
        g.add(&format!("trunk {i}"), &trunk, xf, bark);
        g.add_smooth(&format!("foliage {i}"), &foliage, xf, leaves);
    }

    let (stem, cap) = mushroom();
    for i in 0..MUSHROOMS {
        let a = rng.range(0.0, TAU);
        let r = rng.range(1.5, 7.0);
        let (x, z) = (r * a.cos(), r * a.sin());
        let xf = place(
            Vec3::new(x, height(x, z) - 0.01, z),
            0.0,
            Vec3::splat(rng.range(0.7, 1.6)),
        );
        g.add(&format!("mushroom stem {i}"), &stem, xf, stem_mat);
        g.add_smooth(&format!("mushroom cap {i}"), &cap, xf, cap_mat);
    }
    g.finish()
}
