//! Traversal work, item 3: where the 8-wide traversal keeps its stack, against the renderer's
//! `traverse8` (a 64-entry local array, one entry per pushed child), in one run on the
//! renderer's tree, 2^20 primary and 2^20 unsorted diffuse rays of each scene (those of
//! `kernel_bench`):
//! - **workgroup stack** (`stack_wg`): the same entries in workgroup memory, interleaved by
//!   invocation (`sp * 64 + local_index`, so that a warp's pushes hit 32 banks), 16 KB per
//!   workgroup of 64;
//! - **group entries** (`stack_groups`): one entry per visited node that has more than one
//!   interior child to visit, (node's first record << 8 | the children still to visit, in
//!   octant order), instead of one push per child. A pop takes the next child of the entry
//!   and reads its reference from the parent's record again (16 bytes, one more dependent
//!   load); the entry stays until its last child is taken. The visiting order, and so every
//!   hit, is `traverse8`'s. Up to 7x fewer stack writes;
//! - **group entries in workgroup memory** (`stack_groups_wg`): at most one entry per tree
//!   level, so 32 entries per invocation (8 KB per workgroup) bound any tree of depth <= 33.
//!
//! Every variant's hits are compared with `traverse8`'s (bit for bit). Timings are GPU
//! timestamps (median of 10 dispatches after 0.3 s of the same kernel); `traverse8` runs
//! first and last and ratios are to the faster of its two runs.
//!
//! `cargo run --release -p cohort-render --example traversal_stacks -- [scene[,scene...]] [backend]`

mod common;

use cohort::prelude::*;
use cohort::runtime::{BackendKind, Device, GpuBuffer};
use cohort_kernels::layout::{Frame, Triangle, MISS};
use cohort_kernels::traverse::{dominant_axis, leaf_hits, rotate};
use cohort_kernels::traverse_wide::{
    hit4, permute8, pick, traverse8, Closest, WideNode, STACK_SIZE,
};
use cohort_scenes::{embedded, GpuBvh8};
use common::{differ, median_ns, primary_rays};

/// Workgroup size of the variants (the renderer's).
const WG: usize = 64;
/// Group entries per invocation of the workgroup-memory group stack.
const GROUP_ENTRIES: usize = 32;

/// `traverse8`'s loop with its stack in workgroup memory.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn stack_wg(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[workgroup] stack: &mut [u32; 4096],
    f: &Frame,
    count: &[u32],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    if gi < count[0] {
        let i = gi as usize;
        let o4 = ray_o[i];
        let org = o4.truncate();
        let dir = ray_d[i].truncate();
        let tmin = o4.w;
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
        let meta_shift = (oct & 3) * 8;
        let mut best = Vec4::new(3.0e38, 0.0, 0.0, f32::from_bits(MISS));
        let mut best_t = best.x;
        let base = li as usize;
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
        while go {
            let a = nodes[node as usize];
            let b = nodes[node as usize + 1];
            let hits8 = hit4(org, inv, neg, a, best_t) | (hit4(org, inv, neg, b, best_t) << 4);
            let ordered = permute8(hits8, oct);
            let leaf_mask = ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> meta_shift) & 0xff;
            let mut leaves = ordered & leaf_mask;
            let mut inner = ordered & !leaf_mask;
            while leaves != 0 {
                let p = leaves.trailing_zeros();
                leaves &= leaves - 1;
                let child = pick(a.child, b.child, p ^ oct);
                let first = child & 0x0fff_ffff;
                let cnt = ((child >> 28) & 7) + 1;
                best = leaf_hits::<Closest>(org_r, kz, shear, first, cnt, tmin, best, tris);
                best_t = best.x;
            }
            if inner != 0 {
                let p = inner.trailing_zeros();
                inner &= inner - 1;
                node = pick(a.child, b.child, p ^ oct);
                while inner != 0 {
                    let q = 31 - inner.leading_zeros();
                    inner ^= 1u32 << q;
                    stack[sp * WG + base] = pick(a.child, b.child, q ^ oct);
                    sp += 1;
                }
            } else if sp > 0 {
                sp -= 1;
                node = stack[sp * WG + base];
            } else {
                go = false;
            }
        }
        hits[i] = best;
    }
}

/// The closest hit of ray `i` with group entries on a local stack.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn stack_groups(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    if gi < count[0] {
        let i = gi as usize;
        let o4 = ray_o[i];
        let org = o4.truncate();
        let dir = ray_d[i].truncate();
        let tmin = o4.w;
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
        let meta_shift = (oct & 3) * 8;
        let mut best = Vec4::new(3.0e38, 0.0, 0.0, f32::from_bits(MISS));
        let mut best_t = best.x;
        let mut stack: [u32; STACK_SIZE] = uninit();
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
        while go {
            let a = nodes[node as usize];
            let b = nodes[node as usize + 1];
            let hits8 = hit4(org, inv, neg, a, best_t) | (hit4(org, inv, neg, b, best_t) << 4);
            let ordered = permute8(hits8, oct);
            let leaf_mask = ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> meta_shift) & 0xff;
            let mut leaves = ordered & leaf_mask;
            let mut inner = ordered & !leaf_mask;
            while leaves != 0 {
                let p = leaves.trailing_zeros();
                leaves &= leaves - 1;
                let child = pick(a.child, b.child, p ^ oct);
                let first = child & 0x0fff_ffff;
                let cnt = ((child >> 28) & 7) + 1;
                best = leaf_hits::<Closest>(org_r, kz, shear, first, cnt, tmin, best, tris);
                best_t = best.x;
            }
            if inner != 0 {
                let p = inner.trailing_zeros();
                inner &= inner - 1;
                if inner != 0 {
                    stack[sp] = (node << 8) | inner;
                    sp += 1;
                }
                node = pick(a.child, b.child, p ^ oct);
            } else if sp > 0 {
                let e = stack[sp - 1];
                let parent = e >> 8;
                let rest = e & 0xff;
                let s = rest.trailing_zeros() ^ oct;
                let c = nodes[(parent + (s >> 2)) as usize].child;
                node = pick(c, c, s & 3);
                let left = rest & (rest - 1);
                if left != 0 {
                    stack[sp - 1] = (parent << 8) | left;
                } else {
                    sp -= 1;
                }
            } else {
                go = false;
            }
        }
        hits[i] = best;
    }
}

/// [`stack_groups`] with the group entries in workgroup memory.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn stack_groups_wg(
    #[builtin(global_index)] gi: u32,
    #[builtin(local_index)] li: u32,
    #[workgroup] stack: &mut [u32; 2048],
    f: &Frame,
    count: &[u32],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    if gi < count[0] {
        let i = gi as usize;
        let o4 = ray_o[i];
        let org = o4.truncate();
        let dir = ray_d[i].truncate();
        let tmin = o4.w;
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
        let meta_shift = (oct & 3) * 8;
        let mut best = Vec4::new(3.0e38, 0.0, 0.0, f32::from_bits(MISS));
        let mut best_t = best.x;
        let base = li as usize;
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
        while go {
            let a = nodes[node as usize];
            let b = nodes[node as usize + 1];
            let hits8 = hit4(org, inv, neg, a, best_t) | (hit4(org, inv, neg, b, best_t) << 4);
            let ordered = permute8(hits8, oct);
            let leaf_mask = ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> meta_shift) & 0xff;
            let mut leaves = ordered & leaf_mask;
            let mut inner = ordered & !leaf_mask;
            while leaves != 0 {
                let p = leaves.trailing_zeros();
                leaves &= leaves - 1;
                let child = pick(a.child, b.child, p ^ oct);
                let first = child & 0x0fff_ffff;
                let cnt = ((child >> 28) & 7) + 1;
                best = leaf_hits::<Closest>(org_r, kz, shear, first, cnt, tmin, best, tris);
                best_t = best.x;
            }
            if inner != 0 {
                let p = inner.trailing_zeros();
                inner &= inner - 1;
                if inner != 0 {
                    stack[sp * WG + base] = (node << 8) | inner;
                    sp += 1;
                }
                node = pick(a.child, b.child, p ^ oct);
            } else if sp > 0 {
                let e = stack[(sp - 1) * WG + base];
                let parent = e >> 8;
                let rest = e & 0xff;
                let s = rest.trailing_zeros() ^ oct;
                let c = nodes[(parent + (s >> 2)) as usize].child;
                node = pick(c, c, s & 3);
                let left = rest & (rest - 1);
                if left != 0 {
                    stack[(sp - 1) * WG + base] = (parent << 8) | left;
                } else {
                    sp -= 1;
                }
            } else {
                go = false;
            }
        }
        hits[i] = best;
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scenes = args.get(1).map(String::as_str).unwrap_or("confroom");
    let backend = args
        .get(2)
        .and_then(|b| BackendKind::parse(b))
        .unwrap_or(BackendKind::Vulkan);
    let d = Device::new(backend).expect("device");
    println!(
        "device: {} [{}]",
        d.info().adapter_name,
        d.info().backend.name()
    );
    for name in scenes.split(',') {
        bench_scene(&d, name);
    }
}

fn bench_scene(d: &Device, name: &str) {
    let reps = 10;
    let scene = embedded::load(name).expect("unknown scene");
    let (b2, w) = GpuBvh8::build_scene(&scene).expect("bvh");
    let w = w.expect("an 8-wide BVH");
    // Group entries hold a record index in 24 bits, and the workgroup group stack one
    // entry per level below the root.
    assert!(
        w.nodes.len() < 1 << 24,
        "{name}: too many records for group entries"
    );
    assert!(
        (w.depth as usize) <= GROUP_ENTRIES + 1,
        "{name}: depth {} exceeds the workgroup group stack",
        w.depth
    );
    let nodes = d
        .upload::<WideNode>(bytemuck::cast_slice(&w.nodes))
        .unwrap();
    let tris_host: &[Triangle] = bytemuck::cast_slice(&b2.triangles);
    let tris = d.upload(tris_host).unwrap();
    let (o, dirs) = primary_rays(&scene);
    let n = o.len() as u32;
    let frame = Frame {
        has_geometry: 1,
        slots: n,
        ..Default::default()
    };
    let count = d.upload(&[n]).unwrap();
    let ids = d.upload(&(0..n).collect::<Vec<u32>>()).unwrap();
    let state = d.alloc::<UVec4>(n as usize).unwrap();
    let hits = d.alloc::<Vec4>(n as usize).unwrap();
    let gr = |t: f64| n as f64 / t;
    type Buf<T> = GpuBuffer<T>;
    let spec8 = traverse8::spec(d, None);
    let t8 = |ob: &Buf<Vec4>, db: &Buf<Vec4>| -> (f64, Vec<Vec4>) {
        traverse8::launch_spec(
            d, &spec8, n, &frame, &count, &ids, &state, ob, db, &nodes, &tris, &hits,
        )
        .unwrap();
        let t = median_ns(d, reps, |b| {
            traverse8::record(
                b, &spec8, n, &frame, &count, &ids, &state, ob, db, &nodes, &tris, &hits,
            )
            .unwrap()
        });
        (t, d.read(&hits).unwrap())
    };
    let (ws, gs, gws) = (
        stack_wg::spec(d, None),
        stack_groups::spec(d, None),
        stack_groups_wg::spec(d, None),
    );
    let run = |label: &str, o: &[Vec4], dirs: &[Vec4]| -> Vec<Vec4> {
        let ob = d.upload(o).unwrap();
        let db = d.upload(dirs).unwrap();
        let (ta, reference) = t8(&ob, &db);
        let mut rows = Vec::new();
        let mut variant = |label: &str, record: &dyn Fn(&mut cohort::runtime::Batch)| {
            d.write(&hits, 0, &vec![Vec4::ZERO; n as usize]).unwrap();
            let t = median_ns(d, reps, record);
            let h = d.read(&hits).unwrap();
            let bits = h
                .iter()
                .zip(&reference)
                .filter(|(a, b)| a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits))
                .count();
            rows.push((label.to_string(), t, differ(&reference, &h), bits));
        };
        variant("workgroup stack", &|b| {
            stack_wg::record(b, &ws, n, &frame, &count, &ob, &db, &nodes, &tris, &hits).unwrap()
        });
        variant("group entries", &|b| {
            stack_groups::record(b, &gs, n, &frame, &count, &ob, &db, &nodes, &tris, &hits).unwrap()
        });
        variant("group entries in workgroup memory", &|b| {
            stack_groups_wg::record(b, &gws, n, &frame, &count, &ob, &db, &nodes, &tris, &hits)
                .unwrap()
        });
        let (tb, _) = t8(&ob, &db);
        let t0 = ta.min(tb);
        println!(
            "{name} {label} traverse8: {:.3} ms = {:.2} Grays/s (two runs: {:.3}, {:.3} ms)",
            t0 / 1e6,
            gr(t0),
            ta / 1e6,
            tb / 1e6
        );
        for (v, t, diff, bits) in rows {
            println!("{name} {label} {v}: {:.3} ms = {:.2} Grays/s = {:.2}x traverse8; {diff} of {n} hits differ, {bits} not bit-identical", t / 1e6, gr(t), t0 / t);
        }
        reference
    };
    let primary_hits = run("primary", &o, &dirs);
    let (o2, d2, _) = common::diffuse_rays(&o, &dirs, &primary_hits, tris_host);
    run("diffuse", &o2, &d2);
}
