//! `cornell`: the geometry, materials, light and camera of shared/scenes/cornell-box/scene.xml
//! (box [-1,1]^3 open towards the camera, y up), generated instead of loaded, so the renderer has a
//! tiny scene with a Mitsuba reference and no files.

use glam::{Mat4, Quat, Vec3};

use super::{grey, place, wall, Gen};
use crate::material::Material;
use crate::scene::Scene;
use crate::shapes;

pub fn build() -> Scene {
    let mut g = Gen::new(Vec3::new(0.0, 0.0, 3.7), Vec3::ZERO, 40.0);
    let white = g.material(grey());
    let red = g.material(Material::diffuse(Vec3::new(0.8, 0.1, 0.1)));
    let green = g.material(Material::diffuse(Vec3::new(0.1, 0.8, 0.1)));
    let light = g.material(Material::emitter(Vec3::new(17.0, 12.0, 4.0)));

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
        red,
    );
    g.add(
        "right",
        &quad,
        wall(Vec3::new(1.0, 0.0, 0.0), Vec3::NEG_X, (1.0, 1.0)),
        green,
    );

    let cube = shapes::cube();
    g.add(
        "short box",
        &cube,
        place(Vec3::new(0.35, -0.699, 0.3), -17.0, Vec3::splat(0.3)),
        white,
    );
    g.add(
        "tall box",
        &cube,
        place(
            Vec3::new(-0.35, -0.399, -0.35),
            17.0,
            Vec3::new(0.3, 0.6, 0.3),
        ),
        white,
    );

    // 0.5 x 0.5, facing down, just below the ceiling: scale, rotate +90 deg about x, translate.
    let light_xf = Mat4::from_translation(Vec3::new(0.0, 0.998, 0.0))
        * Mat4::from_quat(Quat::from_rotation_x(90f32.to_radians()))
        * Mat4::from_scale(Vec3::new(0.25, 0.25, 1.0));
    g.add("light", &quad, light_xf, light);
    g.finish()
}
