//! Benchmarks of single kernels on the GPU, timed with GPU timestamps (median of
//! repeated dispatches):
//! - BVH2 traversal of 2^20 primary rays and 2^20 unsorted diffuse rays over an
//!   embedded scene (default `confroom`, ~250k triangles), in Grays/s;
//! - stream compaction of 2^24 ray ids with random flags against a copy kernel of the
//!   same size, in GB/s of the minimal traffic.
//!
//! The 8-wide traversal (`traverse8`, `cohort_scenes::GpuBvh8`) runs beside the BVH2
//! kernel on the same rays in the same run (ratios within one run are what counts on a
//! shared GPU), at workgroup sizes 64 and 128, and both kernels again on BVHs with smaller
//! leaves (the renderer's `GpuScene` uses leaves <= 4 at cost 1.5); hits are compared with
//! the BVH2 kernel's. Several scenes: `confroom,fairyforest,sponza,stanford`.
//!
//! `cargo run --release -p cohort-render --example kernel_bench -- [scene[,scene...]] [backend]`
//! (`kernel_bench wgsl` prints the WGSL of `traverse8` and exits.)

use cohort::runtime::{BackendKind, Device};
use cohort_kernels::compact;
use cohort_kernels::copy::copy_u32;
use cohort_kernels::layout::{BvhNode, Frame, Triangle};
use cohort_kernels::traverse::{traverse, traverse_persistent};
use cohort_kernels::traverse_cw::{traverse_cw, CwNode};
use cohort_kernels::traverse_wide::{traverse8, WideNode};
use cohort_scenes::{embedded, GpuBvh, GpuBvh8, GpuCwBvh};
use glam::{UVec4, Vec4};

mod common;
use common::{differ, diffuse_rays, median, ns, primary_rays, timed};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("wgsl") {
        let built = traverse8::build(&cohort::Spec::portable(
            &traverse8::INFO,
            cohort::Group::Thread,
        ));
        println!("{}", cohort::emit::emit(&built).unwrap().wgsl);
        return;
    }
    let scenes = args.get(1).map(String::as_str).unwrap_or("confroom");
    let backend = args
        .get(2)
        .and_then(|b| BackendKind::parse(b))
        .unwrap_or(BackendKind::Vulkan);
    let d = Device::new(backend).expect("device");
    let info = d.info().clone();
    println!(
        "device: {} [{}], subgroup {}",
        info.adapter_name,
        info.backend.name(),
        info.subgroup_size
    );
    for scene_name in scenes.split(',') {
        bench_traversal(&d, scene_name);
    }
    bench_compaction(&d);
}

fn bench_traversal(d: &Device, scene_name: &str) {
    let reps = 10;
    let scene = embedded::load(scene_name).expect("unknown scene");
    let bvh = GpuBvh::build(&scene).expect("bvh");
    let wide = GpuBvh8::build(&bvh).expect("8-wide bvh");
    let nodes8 = d
        .upload::<WideNode>(bytemuck::cast_slice(&wide.nodes))
        .unwrap();
    let nodes = d
        .upload::<BvhNode>(bytemuck::cast_slice(&bvh.nodes))
        .unwrap();
    let tris_host: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
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
    type Buf<T> = cohort::runtime::GpuBuffer<T>;
    let spec = traverse::spec(d, None);
    let time_trace_on =
        |nodes: &Buf<BvhNode>, tris: &Buf<Triangle>, ob: &Buf<Vec4>, db: &Buf<Vec4>| {
            traverse::launch_spec(
                d, &spec, n, &frame, &count, &ids, &state, ob, db, nodes, tris, &hits,
            )
            .unwrap();
            median(
                timed(d, reps, |b| {
                    traverse::record(
                        b, &spec, n, &frame, &count, &ids, &state, ob, db, nodes, tris, &hits,
                    )
                    .unwrap();
                })
                .iter()
                .map(ns)
                .collect(),
            )
        };
    let hits8 = d.alloc::<Vec4>(n as usize).unwrap();
    let time_trace8_on =
        |wg: u32, nodes8: &Buf<WideNode>, tris: &Buf<Triangle>, ob: &Buf<Vec4>, db: &Buf<Vec4>| {
            let mut spec8 = traverse8::spec(d, None);
            spec8.workgroup_size = wg;
            traverse8::launch_spec(
                d, &spec8, n, &frame, &count, &ids, &state, ob, db, nodes8, tris, &hits8,
            )
            .unwrap();
            median(
                timed(d, reps, |b| {
                    traverse8::record(
                        b, &spec8, n, &frame, &count, &ids, &state, ob, db, nodes8, tris, &hits8,
                    )
                    .unwrap();
                })
                .iter()
                .map(ns)
                .collect(),
            )
        };
    // Other leaf sizes (SAH collapse of the BVH2 before widening): (max triangles, traversal
    // cost); both kernels run on each (their own BVH2 and triangle order).
    type LeafVariant = (String, Buf<BvhNode>, Buf<WideNode>, Buf<Triangle>);
    let leaf_variants: Vec<LeafVariant> = [(4u32, 1.5f32), (3, 1.0), (2, 1.0)]
        .iter()
        .filter_map(|&(m, c)| {
            let b2 = GpuBvh::build_with_leaves(&scene, m, c).expect("bvh");
            let w = match GpuBvh8::build(&b2) {
                Ok(w) => w,
                Err(e) => {
                    println!("{scene_name}: leaves<={m} cost {c}: {e}");
                    return None;
                }
            };
            let label = format!("leaves<={m} cost {c} ({} BVH2 nodes, {} 8-wide nodes, stack bound {}, {:.2} triangles/leaf)", b2.nodes.len(), w.nodes.len() / 2, w.stack_bound, b2.triangles.len() as f64 / (b2.nodes.len() + 1) as f64);
            Some((label, d.upload::<BvhNode>(bytemuck::cast_slice(&b2.nodes)).unwrap(), d.upload::<WideNode>(bytemuck::cast_slice(&w.nodes)).unwrap(), d.upload::<Triangle>(bytemuck::cast_slice(&b2.triangles)).unwrap()))
        })
        .collect();
    // The renderer's tree (`GpuBvh8::build_scene`) as 8-wide records and compressed, on one
    // (reordered) triangle array.
    let (mut rb2, rw) = GpuBvh8::build_scene(&scene).expect("bvh");
    let mut rw = rw.expect("an 8-wide BVH");
    let cw = GpuCwBvh::from_wide(&mut rb2, &mut rw);
    println!("{scene_name}: renderer tree: {} 8-wide nodes ({} bytes each) = {} compressed nodes ({} bytes each)", rw.nodes.len() / 2, 2 * std::mem::size_of::<WideNode>(), cw.nodes.len(), std::mem::size_of::<CwNode>());
    let r_nodes8 = d
        .upload::<WideNode>(bytemuck::cast_slice(&rw.nodes))
        .unwrap();
    let r_cw = d.upload::<CwNode>(bytemuck::cast_slice(&cw.nodes)).unwrap();
    let r_tris = d
        .upload::<Triangle>(bytemuck::cast_slice(&rb2.triangles))
        .unwrap();
    let hits_cw = d.alloc::<Vec4>(n as usize).unwrap();
    let time_cw = |wg: u32, ob: &Buf<Vec4>, db: &Buf<Vec4>| {
        let mut spec = traverse_cw::spec(d, None);
        spec.workgroup_size = wg;
        traverse_cw::launch_spec(
            d, &spec, n, &frame, &count, &ids, &state, ob, db, &r_cw, &r_tris, &hits_cw,
        )
        .unwrap();
        median(
            timed(d, reps, |b| {
                traverse_cw::record(
                    b, &spec, n, &frame, &count, &ids, &state, ob, db, &r_cw, &r_tris, &hits_cw,
                )
                .unwrap();
            })
            .iter()
            .map(ns)
            .collect(),
        )
    };
    // traverse8 and the compressed kernel alternate (8-wide first and last).
    let compare_cw = |label: &str, ob: &Buf<Vec4>, db: &Buf<Vec4>| {
        let t8a = time_trace8_on(64, &r_nodes8, &r_tris, ob, db);
        let h8 = d.read(&hits8).unwrap();
        let c64 = time_cw(64, ob, db);
        let hc = d.read(&hits_cw).unwrap();
        let c128 = time_cw(128, ob, db);
        let c32 = time_cw(32, ob, db);
        let t8b = time_trace8_on(64, &r_nodes8, &r_tris, ob, db);
        let t8 = t8a.min(t8b);
        let gr = |t: f64| n as f64 / t;
        println!("{scene_name} {label} renderer tree: traverse8 (wg64) {:.3} ms = {:.2} Grays/s (two runs: {:.3}, {:.3} ms)", t8 / 1e6, gr(t8), t8a / 1e6, t8b / 1e6);
        for (wg, t) in [(32, c32), (64, c64), (128, c128)] {
            println!("{scene_name} {label} renderer tree: traverse_cw (wg{wg}) {:.3} ms = {:.2} Grays/s = {:.2}x traverse8", t / 1e6, gr(t), t8 / t);
        }
        println!(
            "{scene_name} {label} renderer tree: traverse_cw vs traverse8 hits: {} of {n} differ",
            differ(&h8, &hc)
        );
    };
    // BVH2 and 8-wide alternate, the default BVH2 first and last, so that clock changes hit
    // both alike; ratios are to the faster of the two default BVH2 runs.
    let compare = |label: &str, ob: &Buf<Vec4>, db: &Buf<Vec4>| -> f64 {
        let t2a = time_trace_on(&nodes, &tris, ob, db);
        let h2 = d.read(&hits).unwrap();
        let t8 = [
            time_trace8_on(64, &nodes8, &tris, ob, db),
            time_trace8_on(128, &nodes8, &tris, ob, db),
        ];
        let h8 = d.read(&hits8).unwrap();
        let mut tv = Vec::new();
        for (vl, n2, n8, vt) in &leaf_variants {
            let t2v = time_trace_on(n2, vt, ob, db);
            let h2v = d.read(&hits).unwrap();
            let t8v = time_trace8_on(64, n8, vt, ob, db);
            let h8v = d.read(&hits8).unwrap();
            tv.push((vl, t2v, t8v, differ(&h2v, &h8v)));
        }
        let t2b = time_trace_on(&nodes, &tris, ob, db);
        let t2 = t2a.min(t2b);
        let gr = |t: f64| n as f64 / t;
        println!("{scene_name} {label} BVH2 traverse (wg64): {:.3} ms = {:.2} Grays/s (two runs: {:.3}, {:.3} ms)", t2 / 1e6, gr(t2), t2a / 1e6, t2b / 1e6);
        println!(
            "{scene_name} {label} BVH8 traverse8 (wg64): {:.3} ms = {:.2} Grays/s = {:.2}x BVH2",
            t8[0] / 1e6,
            gr(t8[0]),
            t2 / t8[0]
        );
        println!(
            "{scene_name} {label} BVH8 traverse8 (wg128): {:.3} ms = {:.2} Grays/s = {:.2}x BVH2",
            t8[1] / 1e6,
            gr(t8[1]),
            t2 / t8[1]
        );
        println!(
            "{scene_name} {label} BVH8 vs BVH2 hits: {} of {n} differ",
            differ(&h2, &h8)
        );
        for (vl, t2v, t8v, diff) in tv {
            println!("{scene_name} {label} {vl}: BVH2 traverse {:.2} Grays/s = {:.2}x, BVH8 traverse8 (wg64) {:.3} ms = {:.2} Grays/s = {:.2}x BVH2; {diff} hits differ", gr(t2v), t2 / t2v, t8v / 1e6, gr(t8v), t2 / t8v);
        }
        t2
    };
    let ob = d.upload(&o).unwrap();
    let db = d.upload(&dirs).unwrap();
    compare_cw("primary", &ob, &db);
    let t_primary = compare("primary", &ob, &db);
    let primary_hits = d.read(&hits).unwrap();

    let (o2, d2, hit_count) = diffuse_rays(&o, &dirs, &primary_hits, tris_host);
    let ob2 = d.upload(&o2).unwrap();
    let db2 = d.upload(&d2).unwrap();
    compare_cw("diffuse", &ob2, &db2);
    let t_diffuse = compare("diffuse", &ob2, &db2);
    // Persistent threads: a fixed number of invocations drain an atomic ray counter.
    let next = d.alloc::<u32>(1).unwrap();
    let pspec = traverse_persistent::spec(d, None);
    let mut persistent = Vec::new();
    for (label, ob, db) in [("primary", &ob, &db), ("diffuse", &ob2, &db2)] {
        for threads in [65536u32, 262144] {
            let mut times = Vec::new();
            for _ in 0..reps {
                d.write(&next, 0, &[0]).unwrap();
                times.push(ns(&traverse_persistent::launch_spec(
                    d, &pspec, threads, &frame, &count, &next, &ids, &state, ob, db, &nodes, &tris,
                    &hits,
                )
                .unwrap()));
            }
            persistent.push((label, threads, median(times)));
        }
    }
    println!(
        "scene {scene_name}: {} triangles, {} BVH nodes, {} 8-wide nodes (stack bound {}), {:.1}% primary rays hit",
        tris_host.len(),
        bvh.nodes.len(),
        wide.nodes.len() / 2,
        wide.stack_bound,
        100.0 * hit_count as f64 / n as f64
    );
    println!(
        "traversal primary: {:.3} ms = {:.2} Grays/s",
        t_primary / 1e6,
        n as f64 / t_primary
    );
    println!(
        "traversal diffuse: {:.3} ms = {:.2} Grays/s",
        t_diffuse / 1e6,
        n as f64 / t_diffuse
    );
    for (label, threads, t) in persistent {
        println!(
            "persistent traversal {label}, {threads} invocations: {:.3} ms = {:.2} Grays/s",
            t / 1e6,
            n as f64 / t
        );
    }
}

fn bench_compaction(d: &Device) {
    let reps = 10;
    // Compaction vs copy, 2^24 elements.
    let m = 1u32 << 24;
    let flags_host: Vec<u32> = (0..m)
        .map(|i| (i.wrapping_mul(2654435761) >> 16) & 1)
        .collect();
    let flags = d.upload(&flags_host).unwrap();
    let idr = d.upload(&(0..m).collect::<Vec<u32>>()).unwrap();
    let out = d.alloc::<u32>(m as usize).unwrap();
    let mcount = d.upload(&[m]).unwrap();
    let scratch = d.alloc::<u32>(compact::scratch_len(m as usize)).unwrap();
    let total = d.alloc::<u32>(1).unwrap();
    let cspecs = compact::specs(d);
    let st = timed(d, reps, |b| {
        compact::record(b, &cspecs, m, &mcount, &flags, &scratch, &total, &idr, &out).unwrap();
    });
    let k = compact::DISPATCHES;
    let per: Vec<f64> = st.chunks(k).map(|c| c.iter().map(ns).sum()).collect();
    let t_compact = median(per);
    let parts: Vec<f64> = (0..k)
        .map(|i| median(st.iter().skip(i).step_by(k).map(ns).collect()))
        .collect();
    let got = d.read(&out).unwrap();
    let alive = flags_host.iter().filter(|&&f| f == 1).count();
    assert!(
        got[..alive].windows(2).all(|w| w[0] < w[1])
            && got[alive..].windows(2).all(|w| w[0] < w[1]),
        "compaction is not a stable partition"
    );
    assert!(
        got[..alive].iter().all(|&i| flags_host[i as usize] == 1),
        "compaction put a flag-0 id among the flag-1 ones"
    );
    assert_eq!(
        d.read(&total).unwrap()[0] as usize,
        alive,
        "compaction total"
    );
    let cspec = copy_u32::spec(d, None);
    let t_copy = median(
        timed(d, reps, |b| {
            copy_u32::record(b, &cspec, m, &idr, &out).unwrap()
        })
        .iter()
        .map(ns)
        .collect(),
    );
    let copy_gbs = (m as f64 * 8.0) / t_copy;
    // Minimal traffic of a stable partition: read flag and id, write id (12 B/element).
    let compact_gbs = (m as f64 * 12.0) / t_compact;
    println!(
        "copy 2^24 u32: {:.3} ms = {:.0} GB/s (read + write)",
        t_copy / 1e6,
        copy_gbs
    );
    println!(
        "compaction 2^24: {:.3} ms (count {:.3}, offsets {:.3}, scatter {:.3}) = {:.0} GB/s of minimal traffic = {:.0}% of copy",
        t_compact / 1e6, parts[0] / 1e6, parts[1] / 1e6, parts[2] / 1e6, compact_gbs, 100.0 * compact_gbs / copy_gbs
    );
}
