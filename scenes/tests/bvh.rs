//! The flattened GPU BVH against brute force: on thousands of random rays per embedded scene the
//! reference traversal must find the same closest triangle (or one at the same distance) at the
//! same t. Also checks the layout invariants a kernel relies on.

use cohort_scenes::bvh::{decode_leaf, is_leaf, MAX_LEAF_TRIANGLES};
use cohort_scenes::embedded::{self, Rng};
use cohort_scenes::{brute_force_closest_hit, closest_hit, BruteForce, GpuBvh, Hit, Scene};
use glam::Vec3;

fn random_unit(rng: &mut Rng) -> Vec3 {
    let z = rng.range(-1.0, 1.0);
    let phi = rng.range(0.0, std::f32::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn same_hit(a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.triangle_index == b.triangle_index
                || (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(b.t.abs())
        }
        _ => false,
    }
}

/// Half the rays start at the camera through random pixels, half at random points of the scene's
/// bounds in random directions.
fn random_rays(scene: &Scene, n: usize) -> Vec<(Vec3, Vec3)> {
    let stats = scene.stats();
    let mut rng = Rng::new(0xb0b + n as u64);
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                (
                    scene.camera.origin(),
                    scene.camera.ray_direction(rng.f32(), rng.f32()),
                )
            } else {
                let s = Vec3::new(rng.f32(), rng.f32(), rng.f32());
                (
                    stats.bounds_min + s * (stats.bounds_max - stats.bounds_min),
                    random_unit(&mut rng),
                )
            }
        })
        .collect()
}

fn check_scene(name: &str, scene: &Scene, rays: usize) {
    let t0 = std::time::Instant::now();
    let bvh = GpuBvh::build(scene).unwrap();
    let built = t0.elapsed();
    check_layout(scene, &bvh);
    let stats = scene.stats();
    let truth = BruteForce::new(&scene.triangles);
    let mut hits = 0;
    let t1 = std::time::Instant::now();
    for (i, (o, d)) in random_rays(scene, rays).into_iter().enumerate() {
        let a = closest_hit(&bvh, o, d, 0.0, f32::INFINITY);
        let b = truth.closest_hit(o, d, 0.0, f32::INFINITY);
        assert!(
            same_hit(a, b),
            "{name}: ray {i} o={o} d={d}: bvh {a:?} vs brute force {b:?}"
        );
        if let Some(a) = a {
            let b = b.unwrap();
            assert!(
                (a.t - b.t).abs() <= 1e-4 * a.t.max(b.t),
                "{name}: ray {i}: t {} vs {}",
                a.t,
                b.t
            );
            hits += 1;
        }
    }
    println!(
        "{name}: {} triangles, {} nodes, depth {}, built in {built:?}; {rays} rays ({hits} hits) checked in {:?}",
        stats.triangles,
        bvh.nodes.len(),
        bvh.depth,
        t1.elapsed()
    );
    assert!(
        hits > rays / 4,
        "{name}: too few hits ({hits}) for a meaningful check"
    );
}

/// Every triangle appears exactly once, leaves are within bounds, child boxes contain their
/// triangles.
fn check_layout(scene: &Scene, bvh: &GpuBvh) {
    assert_eq!(bvh.triangles.len(), scene.triangles.len());
    let mut seen = vec![false; scene.triangles.len()];
    for t in &bvh.triangles {
        assert!(!std::mem::replace(&mut seen[t.original as usize], true));
        assert_eq!(t.material, scene.triangles.materials[t.original as usize]);
        assert_eq!(t.light_pdf, 0.0);
        let v = scene.triangles.vertices(t.original as usize);
        assert_eq!([t.v0, t.v1, t.v2], v);
    }
    let mut stack = vec![(0u32, 0u32)];
    while let Some((node, depth)) = stack.pop() {
        assert!(depth < bvh.depth);
        let n = &bvh.nodes[node as usize];
        assert_eq!((n.pad0, n.pad1), (0, 0));
        for (child, lo, hi) in [(n.left, n.lmin, n.lmax), (n.right, n.rmin, n.rmax)] {
            if is_leaf(child) {
                let (first, count) = decode_leaf(child);
                assert!((1..=MAX_LEAF_TRIANGLES).contains(&count));
                assert!((first + count) as usize <= bvh.triangles.len());
                for t in &bvh.triangles[first as usize..(first + count) as usize] {
                    for v in [t.v0, t.v1, t.v2] {
                        assert!(v.cmpge(lo).all() && v.cmple(hi).all());
                    }
                }
            } else {
                assert!((child as usize) < bvh.nodes.len() && child != 0);
                stack.push((child, depth + 1));
            }
        }
    }
}

/// The culled exhaustive search is only a speed-up: it must return exactly the plain brute force.
#[test]
fn culled_brute_force_equals_plain_brute_force() {
    for (name, rays) in [("cornell", 2000), ("stanford", 60)] {
        let scene = embedded::load(name).unwrap();
        let culled = BruteForce::new(&scene.triangles);
        for (o, d) in random_rays(&scene, rays) {
            let plain = brute_force_closest_hit(&scene.triangles, o, d, 0.0, f32::INFINITY);
            assert_eq!(
                culled.closest_hit(o, d, 0.0, f32::INFINITY),
                plain,
                "{name}: o={o} d={d}"
            );
        }
    }
}

#[test]
fn empty_and_single_triangle_scenes() {
    let mut scene = embedded::load("cornell").unwrap();
    scene.triangles = Default::default();
    let bvh = GpuBvh::build(&scene).unwrap();
    assert!(bvh.nodes.is_empty() && bvh.triangles.is_empty());
    assert_eq!(
        closest_hit(&bvh, Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY),
        None
    );

    scene.triangles.positions = vec![
        Vec3::new(-1.0, -1.0, 2.0),
        Vec3::new(1.0, -1.0, 2.0),
        Vec3::new(0.0, 1.0, 2.0),
    ];
    scene.triangles.materials = vec![0];
    let bvh = GpuBvh::build(&scene).unwrap();
    assert_eq!(bvh.nodes.len(), 1);
    let hit = closest_hit(&bvh, Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY).unwrap();
    assert_eq!((hit.triangle_index, hit.t), (0, 2.0));
    // Barycentrics: hit point = (1 - u - v) v0 + u v1 + v v2 = origin projected onto the plane.
    let p = (1.0 - hit.u - hit.v) * scene.triangles.positions[0]
        + hit.u * scene.triangles.positions[1]
        + hit.v * scene.triangles.positions[2];
    assert!(p.distance(Vec3::new(0.0, 0.0, 2.0)) < 1e-6);
    assert_eq!(closest_hit(&bvh, Vec3::ZERO, Vec3::Z, 0.0, 1.5), None);
    assert_eq!(
        closest_hit(&bvh, Vec3::ZERO, -Vec3::Z, 0.0, f32::INFINITY),
        None
    );
}

/// Rays aimed exactly at shared edges and vertices of a subdivided quad must hit something: the
/// watertight test leaves no cracks.
#[test]
fn watertight_on_shared_edges_and_vertices() {
    let mut scene = embedded::load("cornell").unwrap();
    let grid = cohort_scenes::shapes::grid(8, 8);
    scene.triangles = Default::default();
    for t in &grid.indices {
        scene
            .triangles
            .positions
            .extend(t.map(|i| grid.positions[i as usize] * 1.7 + Vec3::new(0.1, 0.3, 0.0)));
        scene.triangles.materials.push(0);
    }
    let bvh = GpuBvh::build(&scene).unwrap();
    let eye = Vec3::new(0.37, -0.21, 5.0);
    for p in &grid.positions {
        let p = *p * 1.7 + Vec3::new(0.1, 0.3, 0.0);
        if p.x.abs() > 1.7 || p.y.abs() > 1.9 {
            continue;
        }
        // At the vertex, and halfway to the neighbours (edge midpoints).
        for q in [
            p,
            p + Vec3::new(0.2125, 0.0, 0.0),
            p + Vec3::new(0.0, 0.2125, 0.0),
            p + Vec3::new(0.2125, 0.2125, 0.0),
        ] {
            if q.x >= 1.8 || q.y >= 2.0 || q.x <= -1.6 || q.y <= -1.4 {
                continue;
            }
            assert!(
                closest_hit(&bvh, eye, q - eye, 0.0, f32::INFINITY).is_some(),
                "crack at {q}"
            );
        }
    }
}

#[test]
fn bvh_matches_brute_force_on_small_scenes() {
    for name in ["cornell", "stanford"] {
        check_scene(name, &embedded::load(name).unwrap(), 2000);
    }
}

#[test]
fn bvh_matches_brute_force_on_confroom() {
    check_scene("confroom", &embedded::load("confroom").unwrap(), 2000);
}

#[test]
fn bvh_matches_brute_force_on_fairyforest() {
    check_scene("fairyforest", &embedded::load("fairyforest").unwrap(), 2000);
}

#[test]
fn bvh_matches_brute_force_on_sponza() {
    check_scene("sponza", &embedded::load("sponza").unwrap(), 2000);
}
