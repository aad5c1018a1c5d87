//! What the CPU backend's ray-stream traversal (`cohort_kernels::traverse_stream`) costs
//! against `traverse_wide::trace8` one ray at a time, on the rays of `traversal_counts`
//! (shuffled, the renderer's order after the first bounce) and on shadow segments from
//! the primary hits to points on the emitters, on one thread: nanoseconds per ray of each, with streams of 4096, 16384 and 65536 rays, closest and any hit, and how
//! many rays' results differ (t or triangle for closest hits: the two may pick different
//! triangles at exact ties in t; hit or miss for any hits). The stream's time includes
//! setting its rays up.
//!
//! `cargo run --release -p cohort-render --example stream_traversal -- SCENE.xml`

mod common;

use cohort_kernels::layout::{Frame, Triangle, MISS};
use cohort_kernels::traverse_stream::trace_stream;
use cohort_kernels::traverse_wide::{trace8, AnyHit, Closest};
use cohort_scenes::GpuBvh8;
use common::{diffuse_rays, load_or_exit, primary_rays, shuffled};
use glam::Vec4;
use std::time::Instant;

/// Best of three of `f`, in nanoseconds per ray over `n` rays.
fn best_ns(n: usize, mut f: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_nanos() as f64 / n as f64
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let path = match std::env::args().nth(1) {
        Some(p) => p,
        None => {
            eprintln!("usage: stream_traversal SCENE.xml");
            std::process::exit(2);
        }
    };
    let scene = load_or_exit(&path);
    let (bvh, wide) = GpuBvh8::build_scene(&scene).expect("bvh");
    let wide = wide.expect("the scene's tree has an 8-wide form");
    let tris: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
    let nodes = &wide.nodes;
    let f = Frame {
        has_geometry: 1,
        ..Default::default()
    };
    let (o, d) = primary_rays(&scene);
    let hits: Vec<Vec4> = o
        .iter()
        .zip(&d)
        .map(|(o, d)| trace8::<Closest>(o.truncate(), d.truncate(), 0.0, 3.0e38, &f, nodes, tris))
        .collect();
    let (o2, d2, _) = diffuse_rays(&o, &d, &hits, tris);
    // Origins' w is the ray's tmin (0 here), as the renderer's path rays carry it.
    let zero_w = |v: Vec<Vec4>| {
        v.into_iter()
            .map(|x| x.truncate().extend(0.0))
            .collect::<Vec<_>>()
    };
    let (o3, d3) = shuffled(&o, &d);
    let (o4, d4) = shuffled(&o2, &d2);
    let (o3, o4) = (zero_w(o3), zero_w(o4));
    // Shadow segments as next-event estimation traces them: from each primary hit to a
    // point on an emitter, tmax (in the origin's w) just short of it.
    let lights: Vec<[glam::Vec3; 3]> = (0..scene.triangles.len())
        .filter(|&i| scene.material_of(i).emission.is_some())
        .map(|i| scene.triangles.vertices(i))
        .collect();
    let mut seed = 0x0005_DEEC_E66D_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    let (mut o5, mut d5) = (Vec::new(), Vec::new());
    for ((o, d), h) in o.iter().zip(&d).zip(&hits) {
        if h.w.to_bits() == MISS || lights.is_empty() {
            continue;
        }
        let p = o.truncate() + h.x * d.truncate();
        let [a, b, c] = lights[(next() * lights.len() as f32) as usize % lights.len()];
        let (u, v) = (next().sqrt(), next());
        let to = a * (1.0 - u) + b * (u * (1.0 - v)) + c * (u * v) - p;
        let len = to.length();
        let dir = to / len;
        // Off the surface by a little, as the renderer's shadow rays start.
        o5.push((p + dir * 1.0e-4).extend(len * 0.999));
        d5.push(dir.extend(1.0));
    }
    let (o5, d5) = shuffled(&o5, &d5);
    println!(
        "{path}: {} triangles, {} 8-wide nodes",
        tris.len(),
        nodes.len() / 2
    );
    println!("rays              query    stream  trace8 ns  stream ns  ratio  differ");
    let sets = [
        ("primary_shuffled", &o3, &d3, false),
        ("diffuse_shuffled", &o4, &d4, false),
        ("shadow_shuffled", &o5, &d5, true),
    ];
    for (name, o, d, segments) in sets {
        // Segments (shadow rays) carry tmax in the origin's w, the others tmin (0).
        let queries: &[bool] = if segments { &[true] } else { &[false, true] };
        for &any in queries {
            let one = |o: &Vec4, d: &Vec4| {
                let (tmin, tmax) = if segments { (0.0, o.w) } else { (o.w, 3.0e38) };
                let (o, d) = (o.truncate(), d.truncate());
                if any {
                    trace8::<AnyHit>(o, d, tmin, tmax, &f, nodes, tris)
                } else {
                    trace8::<Closest>(o, d, tmin, tmax, &f, nodes, tris)
                }
            };
            let reference: Vec<Vec4> = o.iter().zip(d.iter()).map(|(o, d)| one(o, d)).collect();
            let single = best_ns(o.len(), || {
                let acc = o
                    .iter()
                    .zip(d.iter())
                    .fold(0u32, |a, (o, d)| a ^ one(o, d).w.to_bits());
                std::hint::black_box(acc);
            });
            for stream in [4096usize, 16384, 65536] {
                let run = || -> Option<Vec<Vec4>> {
                    let mut all = Vec::with_capacity(o.len());
                    for (oc, dc) in o.chunks(stream).zip(d.chunks(stream)) {
                        all.extend(trace_stream(oc, dc, !segments, any, nodes, tris)?);
                    }
                    Some(all)
                };
                let Some(got) = run() else {
                    eprintln!("the stream traversal needs AVX-512, which this CPU lacks");
                    std::process::exit(1);
                };
                let ns = best_ns(o.len(), || {
                    std::hint::black_box(run());
                });
                let differ = got
                    .iter()
                    .zip(&reference)
                    .filter(|(g, h)| {
                        let (gm, hm) = (g.w.to_bits() == MISS, h.w.to_bits() == MISS);
                        gm != hm
                            || (!any
                                && !gm
                                && (g.x.to_bits() != h.x.to_bits()
                                    || g.w.to_bits() != h.w.to_bits()))
                    })
                    .count();
                println!(
                    "{name:17} {:7} {stream:6} {single:10.1} {ns:10.1} {:6.2} {differ:7}",
                    if any { "any" } else { "closest" },
                    ns / single,
                );
            }
        }
    }
}
