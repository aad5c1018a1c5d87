//! The traversal work's experiments against the renderer's `traverse8`, in one run on the
//! renderer's tree (`GpuBvh8::build_scene`), 2^20 primary and 2^20 unsorted diffuse rays
//! of each scene (those of `kernel_bench`):
//! - **any-hit** (`trace8::<AnyHit>`, the shadow rays' traversal) over the same rays,
//!   unbounded (stops at the first hit) and up to just before the closest hit (no hit
//!   exists: the traversal proves it, the worst case of a visible light);
//! - **dynamic fetch** (`traverse8_dynamic`): persistent threads that flatten ray and node
//!   loops into one, taking a new ray as soon as theirs finishes (Aila & Laine 2009's
//!   while-while with replacement), rays claimed in batches of `BATCH`;
//! - **reordered rays**: the diffuse rays sorted on the host by a key of direction octant
//!   and origin cell (Morton order of a 2^10 grid per axis over the scene's bounds), both
//!   key orders: what sorting can gain traversal at most (the sort itself not counted);
//! - **binned on the GPU**: the same rays binned by a 12-bit key (octant, then the Morton
//!   code of an 8x8x8 grid of origin cells) with the renderer's counting sort
//!   (`cohort_kernels::reorder`: `bin_clear`, `bin_count`: key and histogram by atomics,
//!   `bin_offsets`: one workgroup's exclusive scan, `bin_scatter`), which permutes the ray
//!   ids `traverse8` reads (`idrays`, as in the renderer), against `traverse8` over the
//!   identity ids: what reordering gains with its own cost paid.
//!
//! Every variant's hits are compared with `traverse8`'s. Timings are GPU timestamps
//! (median of 10 dispatches after 0.3 s of the same kernel); `traverse8` runs first and
//! last and ratios are to the faster of its two runs.
//!
//! `cargo run --release -p cohort-render --example traversal_variants -- [scene[,scene...]] [backend]`

mod common;

use cohort::prelude::*;
use cohort::runtime::{BackendKind, Device, GpuBuffer};
use cohort_kernels::layout::{Frame, Triangle, MISS};
use cohort_kernels::reorder;
use cohort_kernels::traverse::{dominant_axis, leaf_hits, rotate};
use cohort_kernels::traverse_wide::{
    hit4, permute8, pick, trace8, traverse8, AnyHit, Closest, WideNode, STACK_SIZE,
};
use cohort_scenes::{embedded, GpuBvh8};
use common::{differ, median_ns, primary_rays};

/// Rays one invocation of `traverse8_dynamic` claims at a time.
const BATCH: u32 = 4;

/// Any-hit traversal of ray `gi` over (tmin in `ray_o.w`, `tmax[gi]`).
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn occlude8(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    tmax: &[f32],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    if gi < count[0] {
        let i = gi as usize;
        let o4 = ray_o[i];
        hits[i] = trace8::<AnyHit>(
            o4.truncate(),
            ray_d[i].truncate(),
            o4.w,
            tmax[i],
            f,
            nodes,
            tris,
        );
    }
}

/// `traverse8` as persistent threads: one loop whose every iteration visits one node of
/// the invocation's ray, and which first takes the next ray (claimed `BATCH` at a time
/// from `next`) when the last one finished, so that a warp's invocations are not held by
/// its slowest ray. Same hits as `traverse8`.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn traverse8_dynamic(
    f: &Frame,
    count: &[u32],
    next: &[AtomicU32],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let n = count[0];
    let mut r = 0u32;
    let mut end = 0u32;
    let mut active = false;
    let mut run = true;
    let mut org = Vec3::ZERO;
    let mut inv = Vec3::ZERO;
    let mut org_r = Vec3::ZERO;
    let mut shear = Vec3::ZERO;
    let mut neg = UVec3::ZERO;
    let mut kz = 0u32;
    let mut oct = 0u32;
    let mut tmin = 0.0f32;
    let mut best = Vec4::ZERO;
    let mut best_t = 0.0f32;
    // Every entry is pushed before it is popped: no zero fill (`uninit`).
    let mut stack: [u32; STACK_SIZE] = uninit();
    let mut sp = 0usize;
    let mut node = 0u32;
    while run {
        if !active {
            if r >= end {
                let i = next[0].fetch_add(BATCH, Ordering::Relaxed);
                r = i;
                end = (i + BATCH).min(n);
            }
            if r >= end {
                run = false;
            } else {
                let o4 = ray_o[r as usize];
                let dir = ray_d[r as usize].truncate();
                org = o4.truncate();
                tmin = o4.w;
                inv = dir.recip();
                kz = dominant_axis(dir);
                let d_r = rotate(dir, kz);
                org_r = rotate(org, kz);
                shear = Vec3::new(d_r.x / d_r.z, d_r.y / d_r.z, 1.0 / d_r.z);
                neg = UVec3::new(
                    (inv.x < 0.0) as u32,
                    (inv.y < 0.0) as u32,
                    (inv.z < 0.0) as u32,
                );
                oct = neg.x | (neg.y << 1) | (neg.z << 2);
                best_t = 3.0e38;
                best = Vec4::new(best_t, 0.0, 0.0, f32::from_bits(MISS));
                sp = 0;
                node = 0;
                active = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
                if !active {
                    hits[r as usize] = best;
                    r += 1;
                }
            }
        }
        if active {
            let a = nodes[node as usize];
            let b = nodes[node as usize + 1];
            let hits8 = hit4(org, inv, neg, a, best_t) | (hit4(org, inv, neg, b, best_t) << 4);
            let ordered = permute8(hits8, oct);
            let leaf_mask =
                ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> ((oct & 3) * 8)) & 0xff;
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
                    stack[sp] = pick(a.child, b.child, q ^ oct);
                    sp += 1;
                }
            } else if sp > 0 {
                sp -= 1;
                node = stack[sp];
            } else {
                hits[r as usize] = best;
                r += 1;
                active = false;
            }
        }
    }
}

/// Spreads the low 10 bits of `v` to every third bit.
fn spread3(v: u32) -> u64 {
    let mut x = v as u64 & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// The order that sorts rays by (octant, origin cell) or (origin cell, octant).
fn sorted_order(o: &[Vec4], d: &[Vec4], octant_first: bool) -> Vec<u32> {
    let lo = o
        .iter()
        .fold(Vec3::splat(f32::MAX), |a, p| a.min(p.truncate()));
    let hi = o
        .iter()
        .fold(Vec3::splat(f32::MIN), |a, p| a.max(p.truncate()));
    let scale = 1023.0 / (hi - lo).max(Vec3::splat(1e-20));
    let key = |i: usize| -> u64 {
        let c = ((o[i].truncate() - lo) * scale).as_uvec3();
        let cell = spread3(c.x) | (spread3(c.y) << 1) | (spread3(c.z) << 2);
        let v = d[i];
        let oct = (v.x < 0.0) as u64 | ((v.y < 0.0) as u64) << 1 | ((v.z < 0.0) as u64) << 2;
        if octant_first {
            (oct << 30) | cell
        } else {
            (cell << 3) | oct
        }
    };
    let mut order: Vec<u32> = (0..o.len() as u32).collect();
    order.sort_by_key(|&i| key(i as usize));
    order
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
        "device: {} [{}], COHORT_EXP={:?}",
        d.info().adapter_name,
        d.info().backend.name(),
        std::env::var("COHORT_EXP").unwrap_or_default()
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
    let next = d.alloc::<u32>(1).unwrap();
    let tmax = d.alloc::<f32>(n as usize).unwrap();
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
    let ospec = occlude8::spec(d, None);
    let occ = |ob: &Buf<Vec4>, db: &Buf<Vec4>| -> (f64, Vec<Vec4>) {
        occlude8::launch_spec(
            d, &ospec, n, &frame, &count, ob, db, &tmax, &nodes, &tris, &hits,
        )
        .unwrap();
        let t = median_ns(d, reps, |b| {
            occlude8::record(
                b, &ospec, n, &frame, &count, ob, db, &tmax, &nodes, &tris, &hits,
            )
            .unwrap()
        });
        (t, d.read(&hits).unwrap())
    };
    let dspec = traverse8_dynamic::spec(d, None);
    let sms = 132 * 2048;
    let dynamic = |threads: u32, ob: &Buf<Vec4>, db: &Buf<Vec4>| -> (f64, Vec<Vec4>) {
        let mut times = Vec::new();
        for _ in 0..reps {
            d.write(&next, 0, &[0]).unwrap();
            let st = traverse8_dynamic::launch_spec(
                d, &dspec, threads, &frame, &count, &next, ob, db, &nodes, &tris, &hits,
            )
            .unwrap();
            times.push(common::ns(&st));
        }
        (common::median(times), d.read(&hits).unwrap())
    };
    let run = |label: &str, o: &[Vec4], dirs: &[Vec4]| -> Vec<Vec4> {
        let ob = d.upload(o).unwrap();
        let db = d.upload(dirs).unwrap();
        let (ta, reference) = t8(&ob, &db);
        // Any hit, unbounded, and up to just before the closest hit.
        d.write(&tmax, 0, &vec![3.0e38f32; n as usize]).unwrap();
        let (t_any, any) = occ(&ob, &db);
        let wrong_any = any
            .iter()
            .zip(&reference)
            .filter(|(a, r)| (a.w.to_bits() == MISS) != (r.w.to_bits() == MISS))
            .count();
        let before: Vec<f32> = reference
            .iter()
            .map(|h| {
                if h.w.to_bits() == MISS {
                    3.0e38
                } else {
                    h.x * 0.999
                }
            })
            .collect();
        d.write(&tmax, 0, &before).unwrap();
        let (t_before, none) = occ(&ob, &db);
        let wrong_before = none.iter().filter(|h| h.w.to_bits() != MISS).count();
        let mut dyn_rows = Vec::new();
        for threads in [sms / 4, sms / 2, sms] {
            let (t, h) = dynamic(threads, &ob, &db);
            dyn_rows.push((threads, t, differ(&reference, &h)));
        }
        let (tb, _) = t8(&ob, &db);
        let t0 = ta.min(tb);
        println!(
            "{name} {label} traverse8: {:.3} ms = {:.2} Grays/s (two runs: {:.3}, {:.3} ms)",
            t0 / 1e6,
            gr(t0),
            ta / 1e6,
            tb / 1e6
        );
        println!("{name} {label} any-hit unbounded: {:.2} Grays/s = {:.2}x traverse8; occlusion differs from the closest hit's on {wrong_any} rays", gr(t_any), t0 / t_any);
        println!("{name} {label} any-hit up to 0.999 t of the closest hit: {:.2} Grays/s = {:.2}x traverse8; {wrong_before} rays found a hit (must be 0 but for grazing ties)", gr(t_before), t0 / t_before);
        for (threads, t, diff) in dyn_rows {
            println!("{name} {label} dynamic fetch, {threads} invocations, batch {BATCH}: {:.2} Grays/s = {:.2}x traverse8; {diff} of {n} hits differ", gr(t), t0 / t);
        }
        reference
    };
    let primary_hits = run("primary", &o, &dirs);
    let (o2, d2, _) = common::diffuse_rays(&o, &dirs, &primary_hits, tris_host);
    let diffuse_hits = run("diffuse", &o2, &d2);
    // Binned on the GPU: the sort's kernels plus traverse8 over the sorted ids, against
    // traverse8 over the identity ids.
    {
        let lo = o2
            .iter()
            .fold(Vec3::splat(f32::MAX), |a, p| a.min(p.truncate()));
        let hi = o2
            .iter()
            .fold(Vec3::splat(f32::MIN), |a, p| a.max(p.truncate()));
        let grid = d.upload(&reorder::cells(lo, hi)).unwrap();
        let ob = d.upload(&o2).unwrap();
        let db = d.upload(&d2).unwrap();
        let keys = d.alloc::<u32>(n as usize).unwrap();
        let bins = d.alloc::<u32>(reorder::HISTOGRAM_LEN).unwrap();
        let sorted = d.alloc::<u32>(n as usize).unwrap();
        let specs = reorder::specs(d);
        let buffers = reorder::SortBuffers {
            cells: &grid,
            keys: &keys,
            bins: &bins,
            sorted: &sorted,
        };
        let record_sort = |b: &mut cohort::runtime::Batch| {
            reorder::record(b, &specs, n, &count, &ids, &state, &ob, &db, &buffers).unwrap();
        };
        let t_id = |ids: &Buf<u32>| -> f64 {
            median_ns(d, reps, |b| {
                traverse8::record(
                    b, &spec8, n, &frame, &count, ids, &state, &ob, &db, &nodes, &tris, &hits,
                )
                .unwrap()
            })
        };
        let ta = t_id(&ids);
        // The sort's four dispatches, timed together (median over batches of the sum).
        let st = common::timed(d, reps, |b| record_sort(b));
        let t_sort = common::median(
            st.chunks(4)
                .map(|c| c.iter().map(common::ns).sum())
                .collect(),
        );
        let parts: Vec<f64> = (0..4)
            .map(|k| common::median(st.iter().skip(k).step_by(4).map(common::ns).collect()))
            .collect();
        let ts = t_id(&sorted);
        let binned = d.read(&hits).unwrap();
        let perm = d.read(&sorted).unwrap();
        let mut seen = vec![false; n as usize];
        let is_perm = perm
            .iter()
            .all(|&i| !std::mem::replace(&mut seen[i as usize], true));
        let tb = t_id(&ids);
        let t0 = ta.min(tb);
        println!("{name} diffuse binned on the GPU (12-bit key): sort {:.3} ms (clear {:.3}, count {:.3}, offsets {:.3}, scatter {:.3}) + traverse8 {:.3} ms = {:.2}x traverse8 over unsorted ids ({:.3} ms); traverse8 alone {:.2}x; ids a permutation: {is_perm}; {} of {n} hits differ",
            t_sort / 1e6, parts[0] / 1e6, parts[1] / 1e6, parts[2] / 1e6, parts[3] / 1e6, ts / 1e6, t0 / (t_sort + ts), t0 / 1e6, t0 / ts, differ(&diffuse_hits, &binned));
    }
    for octant_first in [true, false] {
        let order = sorted_order(&o2, &d2, octant_first);
        let so: Vec<Vec4> = order.iter().map(|&i| o2[i as usize]).collect();
        let sd: Vec<Vec4> = order.iter().map(|&i| d2[i as usize]).collect();
        let ob = d.upload(&so).unwrap();
        let db = d.upload(&sd).unwrap();
        let ub = d.upload(&o2).unwrap();
        let udb = d.upload(&d2).unwrap();
        let (ta, _) = t8(&ub, &udb);
        let (ts, sorted_hits) = t8(&ob, &db);
        let (tb, _) = t8(&ub, &udb);
        let back: Vec<Vec4> = {
            let mut v = vec![Vec4::ZERO; n as usize];
            for (k, &i) in order.iter().enumerate() {
                v[i as usize] = sorted_hits[k];
            }
            v
        };
        let key = if octant_first {
            "octant, origin cell"
        } else {
            "origin cell, octant"
        };
        let t0 = ta.min(tb);
        println!("{name} diffuse sorted by ({key}): traverse8 {:.2} Grays/s = {:.2}x unsorted ({:.2} Grays/s); {} of {n} hits differ", gr(ts), t0 / ts, gr(t0), differ(&diffuse_hits, &back));
    }
}
