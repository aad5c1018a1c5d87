//! Embedded scenes: every name loads, triangle counts are within 15 % of the stated targets,
//! generation is deterministic, and the scenes are well formed (materials in range, an emitter or a
//! sky, finite geometry, the camera inside the scene bounds).

use cohort_scenes::embedded;

#[test]
fn every_embedded_scene_loads_with_its_stated_triangle_count() {
    assert_eq!(embedded::names().len(), 5);
    for &name in embedded::names() {
        let t = std::time::Instant::now();
        let scene = embedded::load(name).expect(name);
        let stats = scene.stats();
        let target = embedded::target_triangles(name).unwrap();
        println!(
            "{name}: {stats} [{:?}] - {}",
            t.elapsed(),
            embedded::description(name).unwrap()
        );
        let ratio = stats.triangles as f64 / target as f64;
        assert!(
            (0.85..=1.15).contains(&ratio),
            "{name}: {} triangles, target {target}",
            stats.triangles
        );
    }
    assert!(embedded::load("no such scene").is_none());
}

#[test]
fn embedded_scenes_are_deterministic_and_well_formed() {
    use cohort_scenes::Bsdf;
    for &name in embedded::names() {
        let a = embedded::load(name).unwrap();
        assert!(
            a == embedded::load(name).unwrap(),
            "{name} is not deterministic"
        );
        let stats = a.stats();
        assert!(
            stats.emitters > 0 || stats.has_environment,
            "{name} has no light"
        );
        assert!(a.triangles.positions.iter().all(|p| p.is_finite()));
        assert!(a
            .triangles
            .materials
            .iter()
            .all(|&m| (m as usize) < a.materials.len()));
        assert_eq!(a.triangles.positions.len(), 3 * a.triangles.len());
        if let Some(n) = &a.triangles.normals {
            assert_eq!(n.len(), a.triangles.positions.len());
            assert!(n.iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
        }
        // The paper's albedo: 0.8 grey, or a colour whose largest component is 0.8.
        for m in &a.materials {
            if let Bsdf::Diffuse { reflectance } = m.bsdf {
                let max = reflectance.max_element();
                assert!(
                    max == 0.8 || (max == 0.0 && m.emission.is_some()),
                    "{name}: albedo {reflectance}"
                );
            }
        }
        // Interiors: the camera stands inside (the boxes are open towards their cameras).
        if ["confroom", "sponza", "fairyforest"].contains(&name) {
            let o = a.camera.origin();
            assert!(
                o.cmpge(stats.bounds_min).all() && o.cmple(stats.bounds_max).all(),
                "{name}: camera outside"
            );
        }
        assert_eq!((a.camera.width, a.camera.height), (1024, 1024));
    }
}

/// The embedded Cornell box is the reference file scene, generated.
#[test]
fn embedded_cornell_matches_the_reference_file() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/scenes/cornell-box/scene.xml");
    let file = cohort_scenes::load_mitsuba(path).unwrap().scene;
    let gen = embedded::load("cornell").unwrap();
    assert_eq!(file.stats().triangles, gen.stats().triangles);
    assert_eq!(file.stats().bounds_min, gen.stats().bounds_min);
    assert_eq!(file.stats().bounds_max, gen.stats().bounds_max);
    assert!((file.stats().emissive_area - gen.stats().emissive_area).abs() < 1e-6);
    assert_eq!(file.camera.origin(), gen.camera.origin());
    assert_eq!(file.camera.tan_half_fov(), gen.camera.tan_half_fov());
    let mut a = file.materials.clone();
    let mut b = gen.materials.clone();
    let key = |m: &cohort_scenes::Material| format!("{m:?}");
    a.sort_by_key(key);
    b.sort_by_key(key);
    assert_eq!(a, b);
    // Same surfaces: every generated triangle's centroid lies on a file triangle's plane with the
    // same facing.
    for i in 0..gen.triangles.len() {
        let [a0, b0, c0] = gen.triangles.vertices(i);
        let centroid = (a0 + b0 + c0) / 3.0;
        let n = gen.triangles.face_normal(i);
        let found = (0..file.triangles.len()).any(|j| {
            let m = file.triangles.face_normal(j);
            let p = file.triangles.vertices(j)[0];
            m.dot(n) > 0.9999 && (centroid - p).dot(m).abs() < 1e-5
        });
        assert!(found, "generated triangle {i} has no counterpart");
    }
}
