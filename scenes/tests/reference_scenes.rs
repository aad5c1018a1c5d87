//! The two reference scenes in shared/scenes load as their READMEs describe them: camera, film,
//! triangle counts, materials, emitters, integrator, and no warnings (they use only supported
//! features).

use std::path::PathBuf;

use cohort_scenes::{load_mitsuba, Bsdf, FovAxis, Material};
use glam::Vec3;

fn shared(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/scenes")
        .join(path)
}

fn close(a: Vec3, b: Vec3) -> bool {
    a.distance(b) < 1e-5
}

#[test]
fn cornell_box() {
    let loaded = load_mitsuba(shared("cornell-box/scene.xml")).unwrap_or_else(|e| panic!("{e}"));
    for w in &loaded.warnings {
        println!("{w}");
    }
    assert!(loaded.warnings.is_empty());
    let s = &loaded.scene;

    let c = &s.camera;
    assert!(close(c.origin(), Vec3::new(0.0, 0.0, 3.7)));
    assert!(close((c.target() - c.origin()).normalize(), Vec3::NEG_Z));
    assert!(close(c.up(), Vec3::Y));
    assert_eq!(
        (c.fov, c.fov_axis, c.width, c.height),
        (40.0, FovAxis::X, 128, 128)
    );
    // Image x runs along cross(dir, up) = +x; image y top to bottom.
    let f = c.frame();
    assert!(f.right.x > 0.0 && f.up.y > 0.0);
    assert!((f.right.length() - 20f32.to_radians().tan()).abs() < 1e-6);
    assert_eq!(
        (
            s.integrator.max_depth,
            s.integrator.rr_depth,
            s.sample_count
        ),
        (-1, 1, 64)
    );

    let st = s.stats();
    // 5 walls x 2 + 2 cubes x 12 + light 2.
    assert_eq!(st.triangles, 36);
    assert_eq!(st.objects, 8);
    assert_eq!(st.emitters, 1);
    assert_eq!(st.emissive_triangles, 2);
    assert!((st.emissive_area - 0.25).abs() < 1e-5);
    assert!(!st.has_environment && !st.has_vertex_normals);
    assert_eq!(s.environment, Vec3::ZERO);
    assert!(close(st.bounds_min, Vec3::splat(-1.0)) && close(st.bounds_max, Vec3::ONE));

    // White walls and boxes share one material.
    assert_eq!(s.materials.len(), 4);
    let diffuse = |r: Vec3| Material::diffuse(r);
    assert!(s.materials.contains(&diffuse(Vec3::splat(0.8))));
    assert!(s.materials.contains(&diffuse(Vec3::new(0.8, 0.1, 0.1))));
    assert!(s.materials.contains(&diffuse(Vec3::new(0.1, 0.8, 0.1))));
    assert!(s
        .materials
        .contains(&Material::emitter(Vec3::new(17.0, 12.0, 4.0))));

    // Every wall faces into the box, the light faces down at y = 0.998, and the red wall is at x = -1.
    for i in 0..st.triangles {
        let m = s.material_of(i);
        let n = s.triangles.face_normal(i);
        let [a, b, c] = s.triangles.vertices(i);
        let centroid = (a + b + c) / 3.0;
        if m.emission.is_some() {
            assert!(close(n, Vec3::NEG_Y) && (centroid.y - 0.998).abs() < 1e-6);
        }
        if *m == diffuse(Vec3::new(0.8, 0.1, 0.1)) {
            assert!(close(n, Vec3::X) && (centroid.x + 1.0).abs() < 1e-6);
        }
    }
    // The boxes rest on the floor: lowest box vertex at y = -0.999.
    let box_min_y = s
        .objects
        .iter()
        .filter(|o| o.name.starts_with("cube"))
        .flat_map(|o| {
            (o.triangles.start..o.triangles.end).flat_map(|i| s.triangles.vertices(i as usize))
        });
    let lowest = box_min_y.map(|v| v.y).fold(f32::INFINITY, f32::min);
    assert!((lowest + 0.999).abs() < 1e-5, "{lowest}");
}

#[test]
fn stanford_like() {
    let loaded = load_mitsuba(shared("stanford-like/scene.xml")).unwrap_or_else(|e| panic!("{e}"));
    for w in &loaded.warnings {
        println!("{w}");
    }
    assert!(loaded.warnings.is_empty());
    let s = &loaded.scene;
    let c = &s.camera;
    assert!(close(c.origin(), Vec3::new(0.0, 0.0, 2.8)));
    assert!(close(
        (c.target() - c.origin()).normalize(),
        Vec3::new(0.0, -0.27, -2.8).normalize()
    ));
    assert_eq!(
        (c.fov, c.fov_axis, c.width, c.height),
        (40.0, FovAxis::X, 128, 128)
    );

    let st = s.stats();
    assert_eq!(st.triangles, 5120 + 4096 + 1280 + 5 * 2 + 2);
    assert_eq!((st.objects, st.emitters, st.emissive_triangles), (9, 1, 2));
    assert!((st.emissive_area - 0.36).abs() < 1e-5);

    assert_eq!(s.materials.len(), 5);
    let by_kind = |f: fn(&Bsdf) -> bool| s.materials.iter().filter(|m| f(&m.bsdf)).count();
    assert_eq!(by_kind(|b| matches!(b, Bsdf::Diffuse { .. })), 2);
    assert!(s
        .materials
        .contains(&Material::rough_conductor(0.2, Vec3::splat(0.8))));
    assert!(s.materials.contains(&Material::mirror(Vec3::splat(0.8))));
    assert!(s
        .materials
        .contains(&Material::glass(1.5, 1.0, Vec3::splat(0.8))));
    assert!(s.materials.contains(&Material::emitter(Vec3::splat(12.0))));

    // The glass sphere: 1280 triangles, radius 0.26 around (-0.05, -0.739, 0.4), normals outward.
    let glass = s
        .objects
        .iter()
        .find(|o| {
            s.materials[o.material as usize].bsdf
                == Material::glass(1.5, 1.0, Vec3::splat(0.8)).bsdf
        })
        .unwrap();
    assert_eq!(glass.triangles.len(), 1280);
    let center = Vec3::new(-0.05, -0.739, 0.4);
    for i in glass.triangles.clone() {
        let [a, b, c] = s.triangles.vertices(i as usize);
        assert!(((a - center).length() - 0.26).abs() < 1e-3);
        assert!(
            s.triangles
                .face_normal(i as usize)
                .dot((a + b + c) / 3.0 - center)
                > 0.0
        );
    }
}
