//! What one ray costs the 8-wide traversal (`traverse_wide::trace8`) on the host, for a
//! Mitsuba XML scene: nodes visited, leaves and triangles tested per ray, stack pops and
//! how many of them a stored entry distance would have skipped (the node's box starts
//! beyond the closest hit found by then), and nanoseconds per ray on one thread, for 2^20
//! primary rays (1024x1024, pixels in Morton order) and 2^20 diffuse rays from their hits
//! (`common::diffuse_rays`), closest and any hit.
//!
//! The counts hold for any ray order. The times of rays in Morton order do not carry over
//! to the renderer: consecutive rays take the same branches, where the renderer's bounces
//! do not (BENCHMARKS.md, "where the CPU traversal's time goes": a change that saved 18 %
//! here saved nothing there). So each set is timed again shuffled (a fixed permutation),
//! which is the renderer's order after the first bounce. Compare builds on `cohort render`.
//!
//! With `--dump DIR` the four ray sets (primary and diffuse, each in Morton order and
//! shuffled) are written to DIR as `NAME.o.f32` and `NAME.d.f32` (origins and directions,
//! four little-endian f32 per ray, w unused), so that another renderer can trace the same
//! rays: `scripts/traversal_vs_embree.py` times Mitsuba's (Embree's) traversal on them.
//!
//! `cargo run --release -p cohort-render --example traversal_counts -- SCENE.xml [--dump DIR]`

mod common;

use cohort_kernels::layout::{Frame, Triangle, MISS};
use cohort_kernels::traverse::{dominant_axis, leaf_hits, rotate};
use cohort_kernels::traverse_wide::{
    hit4, permute8, pick, trace8, AnyHit, Closest, HitQuery, WideNode,
};
use cohort_scenes::GpuBvh8;
use common::{diffuse_rays, load_or_exit, primary_rays, shuffled};
use glam::{UVec3, Vec3, Vec4};
use std::time::Instant;

/// Work of one closest-hit traversal, step for step as `trace8::<Closest>`.
#[derive(Default)]
struct Counts {
    rays: u64,
    nodes: u64,
    leaves: u64,
    triangles: u64,
    pops: u64,
    /// Pops of a node whose box's entry distance exceeds the closest hit found by then.
    skippable: u64,
    /// Rays that hit nothing (to compare with another renderer on the same rays).
    misses: u64,
}

/// Entry distance of the ray into child slot `s`'s box (as `traverse::slab`, unclipped).
fn entry(org: Vec3, inv: Vec3, a: &WideNode, b: &WideNode, s: u32) -> f32 {
    let n = if s >= 4 { b } else { a };
    let k = (s & 3) as usize;
    let lo = Vec3::new(n.lo_x[k], n.lo_y[k], n.lo_z[k]);
    let hi = Vec3::new(n.hi_x[k], n.hi_y[k], n.hi_z[k]);
    let (t0, t1) = ((lo - org) * inv, (hi - org) * inv);
    t0.min(t1).max_element().max(0.0)
}

fn count(org: Vec3, dir: Vec3, nodes: &[WideNode], tris: &[Triangle], c: &mut Counts) {
    c.rays += 1;
    // `trace8` stops such a ray before its first node.
    if dir == Vec3::ZERO || dir.is_nan() {
        c.misses += 1;
        return;
    }
    let inv = dir.recip();
    let kz = dominant_axis(dir);
    let d_r = rotate(dir, kz);
    let org_r = rotate(org, kz);
    let shear = Vec3::new(d_r.x / d_r.z, d_r.y / d_r.z, 1.0 / d_r.z);
    let neg = UVec3::new(
        (inv.x < 0.0) as u32,
        (inv.y < 0.0) as u32,
        (inv.z < 0.0) as u32,
    );
    let oct = neg.x | (neg.y << 1) | (neg.z << 2);
    let mut best = Vec4::new(3.0e38, 0.0, 0.0, f32::from_bits(MISS));
    let mut stack: Vec<(u32, f32)> = Vec::new();
    let mut node = 0u32;
    loop {
        c.nodes += 1;
        let (a, b) = (nodes[node as usize], nodes[node as usize + 1]);
        let hits8 = hit4(org, inv, neg, a, best.x) | (hit4(org, inv, neg, b, best.x) << 4);
        let ordered = permute8(hits8, oct);
        let leaf_mask = ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> ((oct & 3) * 8)) & 0xff;
        let mut leaves = ordered & leaf_mask;
        let mut inner = ordered & !leaf_mask;
        while leaves != 0 {
            let p = leaves.trailing_zeros();
            leaves &= leaves - 1;
            let child = pick(a.child, b.child, p ^ oct);
            let cnt = ((child >> 28) & 7) + 1;
            c.leaves += 1;
            c.triangles += u64::from(cnt);
            best =
                leaf_hits::<Closest>(org_r, kz, shear, child & 0x0fff_ffff, cnt, 0.0, best, tris);
        }
        if inner != 0 {
            let p = inner.trailing_zeros();
            inner &= inner - 1;
            node = pick(a.child, b.child, p ^ oct);
            while inner != 0 {
                let q = 31 - inner.leading_zeros();
                inner ^= 1u32 << q;
                stack.push((
                    pick(a.child, b.child, q ^ oct),
                    entry(org, inv, &a, &b, q ^ oct),
                ));
            }
        } else if let Some((n, near)) = stack.pop() {
            c.pops += 1;
            c.skippable += u64::from(near > best.x);
            node = n;
        } else {
            break;
        }
    }
    c.misses += u64::from(best.w.to_bits() == MISS);
}

/// Nanoseconds per ray of `trace8::<Q>` over the rays, on this thread (best of three).
fn time<Q: HitQuery>(
    o: &[Vec4],
    d: &[Vec4],
    f: &Frame,
    nodes: &[WideNode],
    tris: &[Triangle],
) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        let mut acc = 0u32;
        for (o, d) in o.iter().zip(d) {
            acc ^= trace8::<Q>(o.truncate(), d.truncate(), 0.0, 3.0e38, f, nodes, tris)
                .w
                .to_bits();
        }
        std::hint::black_box(acc);
        best = best.min(start.elapsed().as_nanos() as f64 / o.len() as f64);
    }
    best
}

/// Writes `v` to `path` as little-endian f32, four per ray.
fn dump(path: &std::path::Path, v: &[Vec4]) {
    let bytes: Vec<u8> = v
        .iter()
        .flat_map(|x| x.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    if let Err(e) = std::fs::write(path, bytes) {
        eprintln!("{}: {e}", path.display());
        std::process::exit(1);
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (path, dump_dir) = match args.as_slice() {
        [p] => (p.clone(), None),
        [p, flag, dir] if flag == "--dump" => (p.clone(), Some(std::path::PathBuf::from(dir))),
        _ => {
            eprintln!("usage: traversal_counts SCENE.xml [--dump DIR]");
            std::process::exit(2);
        }
    };
    let scene = load_or_exit(&path);
    let (bvh, wide) = GpuBvh8::build_scene(&scene).expect("bvh");
    let wide = wide.expect("the scene's tree has an 8-wide form");
    let tris: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
    println!(
        "{path}: {} triangles, {} 8-wide nodes, depth {}",
        tris.len(),
        wide.nodes.len() / 2,
        wide.depth
    );
    let f = Frame {
        has_geometry: 1,
        ..Default::default()
    };
    let (o, d) = primary_rays(&scene);
    let hits: Vec<Vec4> = o
        .iter()
        .zip(&d)
        .map(|(o, d)| {
            trace8::<Closest>(
                o.truncate(),
                d.truncate(),
                0.0,
                3.0e38,
                &f,
                &wide.nodes,
                tris,
            )
        })
        .collect();
    let (o2, d2, _) = diffuse_rays(&o, &d, &hits, tris);
    let (o3, d3) = shuffled(&o, &d);
    let (o4, d4) = shuffled(&o2, &d2);
    let sets = [
        ("primary", &o, &d),
        ("diffuse", &o2, &d2),
        ("primary_shuffled", &o3, &d3),
        ("diffuse_shuffled", &o4, &d4),
    ];
    if let Some(dir) = &dump_dir {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("{}: {e}", dir.display());
            std::process::exit(1);
        }
        for (name, o, d) in sets {
            dump(&dir.join(format!("{name}.o.f32")), o);
            dump(&dir.join(format!("{name}.d.f32")), d);
        }
    }
    println!(
        "rays              nodes leaves triangles  pops skippable  closest ns  any ns   misses"
    );
    for (name, o, d) in sets {
        let mut c = Counts::default();
        for (o, d) in o.iter().zip(d.iter()) {
            count(o.truncate(), d.truncate(), &wide.nodes, tris, &mut c);
        }
        let per = |x: u64| x as f64 / c.rays as f64;
        println!(
            "{name:17} {:5.2} {:6.2} {:9.2} {:5.2} {:9.2} {:11.1} {:7.1} {:8}",
            per(c.nodes),
            per(c.leaves),
            per(c.triangles),
            per(c.pops),
            per(c.skippable),
            time::<Closest>(o, d, &f, &wide.nodes, tris),
            time::<AnyHit>(o, d, &f, &wide.nodes, tris),
            c.misses,
        );
    }
}
