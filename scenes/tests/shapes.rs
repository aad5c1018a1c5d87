//! Procedural shapes: closed solids wind outward (every face normal points away from the centre),
//! counts match their documentation, Mitsuba's rectangle and cube conventions hold.

use cohort_scenes::shapes;
use cohort_scenes::TriMesh;
use glam::{Vec2, Vec3};

fn face_normals_point_away_from(m: &TriMesh, center: impl Fn(Vec3) -> Vec3) -> usize {
    m.indices
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            n.length_squared() > 0.0 && n.dot(centroid - center(centroid)) <= 0.0
        })
        .count()
}

#[test]
fn closed_shapes_wind_outward() {
    let origin = |_| Vec3::ZERO;
    assert_eq!(face_normals_point_away_from(&shapes::cube(), origin), 0);
    assert_eq!(
        face_normals_point_away_from(&shapes::subdivided_cube(3), origin),
        0
    );
    assert_eq!(
        face_normals_point_away_from(
            &shapes::rounded_box(Vec3::new(1.0, 0.5, 0.3), 0.1, 5),
            origin
        ),
        0
    );
    for level in 0..4 {
        let s = shapes::icosphere(level);
        assert_eq!(s.indices.len(), 20 * 4usize.pow(level));
        assert_eq!(
            face_normals_point_away_from(&s, origin),
            0,
            "icosphere {level}"
        );
    }
    // Lathe-based solids: "away" from the axis point at the same height, or from the axis itself
    // for the caps (checked separately through the signed volume below).
    let cyl = shapes::cylinder(16, 3);
    assert_eq!(cyl.indices.len(), 2 * 16 * 4);
    assert!(signed_volume(&cyl) > 0.0);
    assert!((signed_volume(&cyl) - std::f32::consts::PI).abs() < 0.1);
    let cone = shapes::cone(32);
    assert!((signed_volume(&cone) - std::f32::consts::PI / 3.0).abs() < 0.02);
    let torus = shapes::torus(1.0, 0.35, 64, 32);
    assert_eq!(torus.indices.len(), 2 * 64 * 32);
    let expected = 2.0 * std::f32::consts::PI.powi(2) * 0.35f32.powi(2);
    assert!((signed_volume(&torus) - expected).abs() / expected < 0.02);
    let profile = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 2.0),
        Vec2::new(0.0, 2.0),
    ];
    assert!(signed_volume(&shapes::fluted_lathe(&profile, 48, 12, 0.1)) > 0.0);
}

/// Divergence theorem: positive for an outward-wound closed mesh.
fn signed_volume(m: &TriMesh) -> f32 {
    m.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn mitsuba_rectangle_and_cube_conventions() {
    let r = shapes::rectangle();
    assert_eq!(r.indices.len(), 2);
    for t in &r.indices {
        let [a, b, c] = t.map(|i| r.positions[i as usize]);
        assert_eq!((b - a).cross(c - a).normalize(), Vec3::Z);
    }
    assert!(r
        .positions
        .iter()
        .all(|p| p.z == 0.0 && p.x.abs() == 1.0 && p.y.abs() == 1.0));
    let c = shapes::cube();
    assert_eq!(c.indices.len(), 12);
    assert!(c.positions.iter().all(|p| p.abs() == Vec3::ONE));
    assert!((signed_volume(&c) - 8.0).abs() < 1e-5);
}

#[test]
fn arch_panel_faces_out_and_soffit_faces_the_opening() {
    let m = shapes::arch_panel(1.5, 1.0, 2.0, 0.5, 16);
    assert_eq!(m.indices.len(), 6 * 18);
    let mut front = 0;
    let mut back = 0;
    let mut soffit = 0;
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        let n = (b - a).cross(c - a);
        if n.length_squared() == 0.0 {
            continue;
        }
        let n = n.normalize();
        let centroid = (a + b + c) / 3.0;
        if n.z > 0.99 {
            front += 1;
            assert!(centroid.z > 0.0);
        } else if n.z < -0.99 {
            back += 1;
            assert!(centroid.z < 0.0);
        } else {
            soffit += 1;
            let to_axis = -Vec3::new(centroid.x, centroid.y, 0.0);
            assert!(n.dot(to_axis) > 0.0, "soffit normal {n} at {centroid}");
        }
    }
    assert!(front > 0 && back == front && soffit > 0);
}
