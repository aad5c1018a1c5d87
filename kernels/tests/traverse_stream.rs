//! The CPU backend's ray-stream traversal (`traverse_stream`) against `trace8`, ray by
//! ray, on two test scenes: random rays inside and around the scene, rays along the axes
//! (infinite inverse directions), rays that start on a box's face, rays with tmin > 0,
//! shadow segments, and the rays `trace8` refuses (NaN or zero direction, huge origin).
//! Closest hits: the same t, bit for bit, and the same triangle except at an exact tie in
//! t, where the stream's triangle must itself be hit at that t. Any hits: the same answer.

use cohort_kernels::layout::{Frame, Triangle, MISS};
use cohort_kernels::traverse::{dominant_axis, intersect, rotate};
use cohort_kernels::traverse_stream::trace_stream;
use cohort_kernels::traverse_wide::{trace8, AnyHit, Closest, WideNode};
use cohort_scenes::GpuBvh8;
use glam::{Vec3, Vec4};

fn scene(name: &str) -> (Vec<WideNode>, Vec<Triangle>, Vec3, Vec3) {
    let path = format!(
        "{}/../render/tests/scenes/{name}/scene.xml",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = cohort_scenes::mitsuba::load_mitsuba(&path)
        .expect("scene")
        .scene;
    let stats = scene.stats();
    let (bvh, wide) = GpuBvh8::build_scene(&scene).expect("bvh");
    let tris: Vec<Triangle> = bytemuck::cast_slice(&bvh.triangles).to_vec();
    (
        wide.expect("8-wide tree").nodes,
        tris,
        stats.bounds_min,
        stats.bounds_max,
    )
}

/// xorshift64: the same rays on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn dir(&mut self) -> Vec3 {
        Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5)
    }
}

/// Rays (origin with w, direction) of every kind the module docs list.
fn rays(lo: Vec3, hi: Vec3, nodes: &[WideNode]) -> Vec<(Vec4, Vec4)> {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let ext = hi - lo;
    let mut v = Vec::new();
    for i in 0..20000 {
        // Inside and a little around the scene's bounds.
        let o = lo - 0.1 * ext + 1.2 * ext * Vec3::new(rng.next(), rng.next(), rng.next());
        let mut d = rng.dir();
        match i % 10 {
            // Along an axis, or in an axis plane: infinite inverse components.
            0 => d = Vec3::new(0.0, 0.0, if rng.next() < 0.5 { -1.0 } else { 1.0 }),
            1 => d.y = 0.0,
            2 => d = Vec3::new(-0.0, 1.0, 0.0),
            _ => {}
        }
        let w = if i % 7 == 0 { 0.05 * rng.next() } else { 0.0 };
        v.push((o.extend(w), d.extend(0.0)));
    }
    // From a face of the root's first child box, into and along it.
    let a = nodes[0];
    let face = Vec3::new(a.lo_x.x, a.lo_y.x, a.lo_z.x);
    for _ in 0..200 {
        v.push((face.extend(0.0), rng.dir().extend(0.0)));
        v.push((face.extend(0.0), Vec3::X.extend(0.0)));
    }
    // What trace8 refuses: every one misses.
    for d in [
        Vec3::ZERO,
        Vec3::splat(f32::NAN),
        Vec3::new(1.0, f32::NAN, 0.0),
    ] {
        v.push((lo.extend(0.0), d.extend(0.0)));
    }
    v.push((Vec3::splat(1.0e20).extend(0.0), Vec3::X.extend(0.0)));
    v.push((
        Vec3::splat(f32::INFINITY).extend(0.0),
        (-Vec3::ONE).extend(0.0),
    ));
    v
}

fn frame() -> Frame {
    Frame {
        has_geometry: 1,
        ..Default::default()
    }
}

#[test]
fn stream_finds_trace8s_closest_hits() {
    for name in ["cornell-box", "stanford-like"] {
        let (nodes, tris, lo, hi) = scene(name);
        let rays = rays(lo, hi, &nodes);
        let (o, d): (Vec<Vec4>, Vec<Vec4>) = rays.iter().copied().unzip();
        let Some(got) = trace_stream(&o, &d, true, false, &nodes, &tris) else {
            assert!(
                !std::arch::is_x86_feature_detected!("avx512f"),
                "the stream declined on a CPU with AVX-512"
            );
            eprintln!("no AVX-512 here: the CPU backend runs trace8 (the stream declines)");
            return;
        };
        let f = frame();
        let mut ties = 0;
        let mut hits = 0;
        for (i, (&(o, d), g)) in rays.iter().zip(&got).enumerate() {
            let h = trace8::<Closest>(o.truncate(), d.truncate(), o.w, 3.0e38, &f, &nodes, &tris);
            hits += usize::from(h.w.to_bits() != MISS);
            assert_eq!(
                g.x.to_bits(),
                h.x.to_bits(),
                "{name} ray {i} ({o}, {d}): t {g} against {h}"
            );
            if g.w.to_bits() != h.w.to_bits() {
                // A tie: the stream's triangle is hit at the same t.
                assert!(
                    g.w.to_bits() != MISS && h.w.to_bits() != MISS,
                    "{name} ray {i}: {g} against {h}"
                );
                let t = tris[g.w.to_bits() as usize];
                let dir = d.truncate();
                let kz = dominant_axis(dir);
                let d_r = rotate(dir, kz);
                let shear = Vec3::new(d_r.x / d_r.z, d_r.y / d_r.z, 1.0 / d_r.z);
                let again = intersect(
                    rotate(o.truncate(), kz),
                    kz,
                    shear,
                    t.v0,
                    t.v1,
                    t.v2,
                    o.w,
                    3.0e38,
                );
                assert_eq!(
                    again.x.to_bits(),
                    g.x.to_bits(),
                    "{name} ray {i}: the tie's triangle"
                );
                ties += 1;
            } else {
                assert_eq!(
                    (g.y.to_bits(), g.z.to_bits()),
                    (h.y.to_bits(), h.z.to_bits()),
                    "{name} ray {i}: barycentrics"
                );
            }
        }
        eprintln!("{name}: {} rays, {hits} hits, {ties} ties", rays.len());
        // The rays are not all misses or all ties, or the test would test little.
        assert!(
            hits > rays.len() / 4,
            "{name}: {hits} hits of {}",
            rays.len()
        );
        assert!(ties < rays.len() / 100, "{name}: {ties} ties");
    }
}

#[test]
fn stream_answers_shadow_rays_as_trace8() {
    for name in ["cornell-box", "stanford-like"] {
        let (nodes, tris, lo, hi) = scene(name);
        let mut rng = Rng(7);
        // Segments between two points of the bounds (tmax in w, as the shadow pass has it),
        // and the refused rays.
        let mut rays: Vec<(Vec4, Vec4)> = (0..20000)
            .map(|_| {
                let p = |r: &mut Rng| lo + (hi - lo) * Vec3::new(r.next(), r.next(), r.next());
                let (a, b) = (p(&mut rng), p(&mut rng));
                let len = (b - a).length();
                (a.extend(len * 0.999), ((b - a) / len).extend(1.0))
            })
            .collect();
        rays.extend(refused_shadow_rays(lo));
        let (o, d): (Vec<Vec4>, Vec<Vec4>) = rays.iter().copied().unzip();
        let Some(got) = trace_stream(&o, &d, false, true, &nodes, &tris) else {
            assert!(!std::arch::is_x86_feature_detected!("avx512f"));
            return;
        };
        let f = frame();
        let mut blocked = 0;
        for (i, (&(o, d), g)) in rays.iter().zip(&got).enumerate() {
            let h = trace8::<AnyHit>(o.truncate(), d.truncate(), 0.0, o.w, &f, &nodes, &tris);
            let occluded = h.w.to_bits() != MISS;
            blocked += usize::from(occluded);
            assert_eq!(
                g.w.to_bits() != MISS,
                occluded,
                "{name} ray {i}: ({o}, {d})"
            );
        }
        eprintln!("{name}: {} shadow rays, {blocked} blocked", rays.len());
        assert!(
            blocked > 0 && blocked < rays.len(),
            "{name}: {blocked} of {} blocked",
            rays.len()
        );
    }
}

/// Shadow rays `trace8` refuses: every one is visible.
fn refused_shadow_rays(lo: Vec3) -> Vec<(Vec4, Vec4)> {
    [Vec3::ZERO, Vec3::splat(f32::NAN)]
        .into_iter()
        .map(|d| (lo.extend(10.0), d.extend(1.0)))
        .collect()
}
