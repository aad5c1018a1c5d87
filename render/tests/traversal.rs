//! The traversal kernels (BVH2 `traverse`, its persistent-threads form, and the 8-wide
//! `traverse8`) return the same closest hits as the host traversal of the BVH2
//! (cohort-scenes), on random rays over every embedded scene.

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::layout::{BvhNode, Frame, Triangle, MISS};
use cohort_kernels::traverse::{traverse, traverse_persistent};
use cohort_kernels::traverse_cw::{traverse_cw, CwNode};
use cohort_kernels::traverse_wide::{traverse8, WideNode};
use cohort_scenes::{closest_hit, embedded, GpuBvh, GpuBvh8, GpuCwBvh};
use glam::{UVec4, Vec3, Vec4};

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

#[test]
fn gpu_traversal_matches_host() {
    let devices: Vec<Device> = [BackendKind::Vulkan, BackendKind::Wgpu, BackendKind::Cpu]
        .into_iter()
        .filter_map(Device::for_tests)
        .collect();
    let per_scene = 100_000 / embedded::names().len();
    let mut rng = Rng(0x9e3779b97f4a7c15);
    for name in embedded::names() {
        let scene = embedded::load(name).unwrap();
        let default_bvh = GpuBvh::build(&scene).unwrap();
        let lo = default_bvh.bounds_min;
        let hi = default_bvh.bounds_max;
        let mut o = Vec::new();
        let mut dir = Vec::new();
        for k in 0..per_scene {
            // Half the rays from the camera, half from random points in the bounds.
            let origin = if k % 2 == 0 {
                scene.camera.origin()
            } else {
                lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f())
            };
            let d = Vec3::new(
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
            )
            .normalize_or(Vec3::Y);
            o.push(origin.extend(0.0));
            dir.push(d.extend(0.0));
        }
        let n = o.len() as u32;
        // The default BVH2 and the renderer's (smaller leaves where the 8-wide stack allows).
        let default_wide = GpuBvh8::build(&default_bvh).unwrap();
        let (scene_bvh, scene_wide) = GpuBvh8::build_scene(&scene).unwrap();
        let scene_wide = scene_wide.expect("every embedded scene fits the 8-wide kernel's stack");
        for (bvh, wide) in [(&default_bvh, &default_wide), (&scene_bvh, &scene_wide)] {
            let nodes8: &[WideNode] = bytemuck::cast_slice(&wide.nodes);
            let nodes: &[BvhNode] = bytemuck::cast_slice(&bvh.nodes);
            let tris: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
            let frame = Frame {
                has_geometry: 1,
                slots: n,
                ..Default::default()
            };
            let host: Vec<Option<cohort_scenes::Hit>> = o
                .iter()
                .zip(&dir)
                .map(|(a, b)| closest_hit(bvh, a.truncate(), b.truncate(), 0.0, 3.0e38))
                .collect();
            for d in &devices {
                let ids: Vec<u32> = (0..n).collect();
                let hits = d.alloc::<Vec4>(n as usize).unwrap();
                traverse::launch(
                    d,
                    n,
                    &frame,
                    &d.upload(&[n]).unwrap(),
                    &d.upload(&ids).unwrap(),
                    &d.alloc::<UVec4>(n as usize).unwrap(),
                    &d.upload(&o).unwrap(),
                    &d.upload(&dir).unwrap(),
                    &d.upload(nodes).unwrap(),
                    &d.upload(tris).unwrap(),
                    &hits,
                )
                .unwrap();
                let plain = d.read(&hits).unwrap();
                // The persistent-threads variant, with far fewer invocations than rays.
                let hits2 = d.alloc::<Vec4>(n as usize).unwrap();
                let next = d.alloc::<u32>(1).unwrap();
                traverse_persistent::launch(
                    d,
                    4096u32,
                    &frame,
                    &d.upload(&[n]).unwrap(),
                    &next,
                    &d.upload(&ids).unwrap(),
                    &d.alloc::<UVec4>(n as usize).unwrap(),
                    &d.upload(&o).unwrap(),
                    &d.upload(&dir).unwrap(),
                    &d.upload(nodes).unwrap(),
                    &d.upload(tris).unwrap(),
                    &hits2,
                )
                .unwrap();
                let persistent = d.read(&hits2).unwrap();
                assert!(
                    d.read(&next).unwrap()[0] >= n,
                    "the counter covers every ray"
                );
                // Same triangle everywhere; t to rounding (the two kernels are compiled
                // separately, and drivers may contract floating-point operations differently).
                let differ = plain
                    .iter()
                    .zip(&persistent)
                    .filter(|(a, b)| {
                        a.w.to_bits() != b.w.to_bits()
                            || (a.x - b.x).abs() > 1e-5 * a.x.abs().max(1.0)
                    })
                    .count();
                // lavapipe (llvmpipe) mistraces a few rays of any loop that wraps the traversal
                // (also with a per-invocation atomic counter; the same symptom is known from
                // other kernels on that driver, cause unknown): there, bound the damage and say
                // so; everywhere else the persistent kernel must agree exactly.
                if d.info().adapter_name.contains("llvmpipe") {
                    assert!(
                        differ * 100 <= n as usize,
                        "{name}: persistent traversal differs on {differ} of {n} rays on lavapipe"
                    );
                    if differ > 0 {
                        eprintln!("known lavapipe defect: persistent traversal differs on {differ} of {n} rays ({name})");
                    }
                } else {
                    assert_eq!(differ, 0, "{name} on {:?}: persistent traversal differs from the plain one on {differ} rays", d.info().backend);
                }
                // The 8-wide kernel: same triangles and triangle test, another tree and order.
                let hits8 = d.alloc::<Vec4>(n as usize).unwrap();
                traverse8::launch(
                    d,
                    n,
                    &frame,
                    &d.upload(&[n]).unwrap(),
                    &d.upload(&ids).unwrap(),
                    &d.alloc::<UVec4>(n as usize).unwrap(),
                    &d.upload(&o).unwrap(),
                    &d.upload(&dir).unwrap(),
                    &d.upload(nodes8).unwrap(),
                    &d.upload(tris).unwrap(),
                    &hits8,
                )
                .unwrap();
                let wide_hits = d.read(&hits8).unwrap();
                // Against the BVH2 kernel: the same closest hit (another triangle only at the
                // same t, a tie that the two traversal orders may break differently).
                let differ8 = plain
                    .iter()
                    .zip(&wide_hits)
                    .filter(|(a, b)| {
                        a.w.to_bits() != b.w.to_bits()
                            && (a.w.to_bits() == MISS
                                || b.w.to_bits() == MISS
                                || (a.x - b.x).abs() > 1e-5 * a.x.abs().max(1.0))
                    })
                    .count();
                assert_eq!(
                    differ8,
                    0,
                    "{name} on {:?}: traverse8 differs from traverse on {differ8} rays",
                    d.info().backend
                );
                for (kernel, gpu) in [("traverse", plain), ("traverse8", wide_hits)] {
                    let mismatches = mismatches(&gpu, &host, tris);
                    // The GPU test runs in f32 without the host's f64 fallback for rays that
                    // graze an edge exactly: allow 1 in 10^4 such rays, no more.
                    assert!(
                        mismatches * 10_000 <= n as usize,
                        "{name} on {:?}: {kernel}: {mismatches} of {n} rays differ from the host",
                        d.info().backend
                    );
                    if mismatches > 0 {
                        eprintln!("{name} on {:?}: {kernel}: {mismatches} of {n} rays differ from the host", d.info().backend);
                    }
                }
            }
        }
    }
}

/// Rays whose GPU hit is neither the host's triangle nor at the host's t.
fn mismatches(gpu: &[Vec4], host: &[Option<cohort_scenes::Hit>], tris: &[Triangle]) -> usize {
    let mut mismatches = 0;
    for (g, h) in gpu.iter().zip(host) {
        let gi = g.w.to_bits();
        match h {
            None => {
                if gi != MISS {
                    mismatches += 1;
                }
            }
            Some(h) => {
                let same_tri = gi != MISS && tris[gi as usize].original == h.triangle_index;
                let same_t = gi != MISS && (g.x - h.t).abs() <= 1e-4 * h.t.max(1.0);
                if !(same_tri || same_t) {
                    mismatches += 1;
                }
            }
        }
    }
    mismatches
}

/// The compressed 8-wide kernel (`traverse_cw`) finds the same closest hits as `traverse8` on
/// the renderer's tree of every embedded scene, and the host's.
#[test]
fn compressed_traversal_matches_8_wide() {
    let devices: Vec<Device> = [BackendKind::Vulkan, BackendKind::Wgpu, BackendKind::Cpu]
        .into_iter()
        .filter_map(Device::for_tests)
        .collect();
    let mut rng = Rng(0x2545f4914f6cdd1d);
    for name in embedded::names() {
        let scene = embedded::load(name).unwrap();
        let (mut bvh, wide) = GpuBvh8::build_scene(&scene).unwrap();
        let mut wide = wide.expect("an 8-wide BVH");
        let cw = GpuCwBvh::from_wide(&mut bvh, &mut wide);
        let (lo, hi) = (bvh.bounds_min, bvh.bounds_max);
        let n = 20_000u32;
        let (mut o, mut dir) = (Vec::new(), Vec::new());
        for k in 0..n {
            let origin = if k % 2 == 0 {
                scene.camera.origin()
            } else {
                lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f())
            };
            // Some rays along an axis: zero direction components take the kernel's guard.
            let mut d = Vec3::new(
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
                rng.f() * 2.0 - 1.0,
            );
            if k % 7 == 0 {
                d.x = 0.0;
            }
            if k % 11 == 0 {
                d.z = 0.0;
            }
            o.push(origin.extend(0.0));
            dir.push(d.normalize_or(Vec3::Y).extend(0.0));
        }
        let tris: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
        let host: Vec<Option<cohort_scenes::Hit>> = o
            .iter()
            .zip(&dir)
            .map(|(a, b)| closest_hit(&bvh, a.truncate(), b.truncate(), 0.0, 3.0e38))
            .collect();
        let frame = Frame {
            has_geometry: 1,
            slots: n,
            ..Default::default()
        };
        for d in &devices {
            let ids: Vec<u32> = (0..n).collect();
            let (count, ids) = (d.upload(&[n]).unwrap(), d.upload(&ids).unwrap());
            let state = d.alloc::<UVec4>(n as usize).unwrap();
            let (ob, db, tb) = (
                d.upload(&o).unwrap(),
                d.upload(&dir).unwrap(),
                d.upload(tris).unwrap(),
            );
            let hits8 = d.alloc::<Vec4>(n as usize).unwrap();
            let nodes8: &[WideNode] = bytemuck::cast_slice(&wide.nodes);
            traverse8::launch(
                d,
                n,
                &frame,
                &count,
                &ids,
                &state,
                &ob,
                &db,
                &d.upload(nodes8).unwrap(),
                &tb,
                &hits8,
            )
            .unwrap();
            let hits_cw = d.alloc::<Vec4>(n as usize).unwrap();
            let nodes_cw: &[CwNode] = bytemuck::cast_slice(&cw.nodes);
            traverse_cw::launch(
                d,
                n,
                &frame,
                &count,
                &ids,
                &state,
                &ob,
                &db,
                &d.upload(nodes_cw).unwrap(),
                &tb,
                &hits_cw,
            )
            .unwrap();
            let (a, b) = (d.read(&hits8).unwrap(), d.read(&hits_cw).unwrap());
            let differ = a
                .iter()
                .zip(&b)
                .filter(|(a, b)| {
                    a.w.to_bits() != b.w.to_bits()
                        && (a.w.to_bits() == MISS
                            || b.w.to_bits() == MISS
                            || (a.x - b.x).abs() > 1e-5 * a.x.abs().max(1.0))
                })
                .count();
            assert_eq!(
                differ,
                0,
                "{name} on {:?}: traverse_cw differs from traverse8 on {differ} of {n} rays",
                d.info().backend
            );
            // Against the host BVH2 traversal only on rays without a zero direction component:
            // on fairyforest the host disagrees with both GPU kernels on ~20 % of the rays that
            // have one, and the brute-force host test sides with the GPU kernels (a defect of
            // the host traversal, not yet found).
            let oblique: Vec<usize> = (0..n as usize)
                .filter(|&k| k % 7 != 0 && k % 11 != 0)
                .collect();
            let pick = |v: &[Vec4]| oblique.iter().map(|&k| v[k]).collect::<Vec<_>>();
            let host_oblique: Vec<_> = oblique.iter().map(|&k| host[k]).collect();
            let mismatches = mismatches(&pick(&b), &host_oblique, tris);
            assert!(
                mismatches * 10_000 <= n as usize,
                "{name} on {:?}: traverse_cw: {mismatches} of {n} rays differ from the host",
                d.info().backend
            );
        }
    }
}
