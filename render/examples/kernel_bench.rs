//! Benchmarks of single kernels on the GPU, timed with GPU timestamps (median of
//! repeated dispatches):
//! - BVH2 traversal of 2^20 primary rays and 2^20 unsorted diffuse rays over an
//!   embedded scene (default `confroom`, ~250k triangles), in Grays/s;
//! - stream compaction of 2^24 ray ids with random flags against a copy kernel of the
//!   same size, in GB/s of the minimal traffic.
//!
//! `cargo run --release -p cohort-render --example kernel_bench -- [scene] [backend]`

use cohort::runtime::{BackendKind, Device, DispatchStats};
use cohort_kernels::compact;
use cohort_kernels::copy::copy_u32;
use cohort_kernels::layout::{BvhNode, Frame, Triangle, MISS};
use cohort_kernels::traverse::{traverse, traverse_persistent};
use cohort_scenes::{embedded, GpuBvh};
use glam::{UVec4, Vec3, Vec4};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn ns(s: &DispatchStats) -> f64 {
    s.gpu_time_ns.expect("this benchmark needs GPU timestamps") as f64
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map(String::as_str).unwrap_or("confroom");
    let backend = args.get(2).and_then(|b| BackendKind::parse(b)).unwrap_or(BackendKind::Vulkan);
    let reps = 10;
    let d = Device::new(backend).expect("device");
    let info = d.info().clone();
    println!("device: {} [{}], subgroup {}", info.adapter_name, info.backend.name(), info.subgroup_size);

    let scene = embedded::load(scene_name).expect("unknown scene");
    let bvh = GpuBvh::build(&scene).expect("bvh");
    let nodes = d.upload::<BvhNode>(bytemuck::cast_slice(&bvh.nodes)).unwrap();
    let tris_host: &[Triangle] = bytemuck::cast_slice(&bvh.triangles);
    let tris = d.upload(tris_host).unwrap();
    let n = 1u32 << 20;
    let side = 1024u32;
    let cam = {
        let mut c = scene.camera.clone();
        c.width = side;
        c.height = side;
        c
    };
    let order = cohort_scenes::morton_pixel_order(side, side);
    let origin = cam.origin();
    let o: Vec<Vec4> = vec![origin.extend(0.0); n as usize];
    let dirs: Vec<Vec4> = order
        .iter()
        .map(|&p| cam.ray_direction(((p % side) as f32 + 0.5) / side as f32, ((p / side) as f32 + 0.5) / side as f32).extend(0.0))
        .collect();
    let frame = Frame { has_geometry: 1, slots: n, ..Default::default() };
    let count = d.upload(&[n]).unwrap();
    let ids = d.upload(&(0..n).collect::<Vec<u32>>()).unwrap();
    let state = d.alloc::<UVec4>(n as usize).unwrap();
    let hits = d.alloc::<Vec4>(n as usize).unwrap();
    let spec = traverse::spec(&d, None);
    let time_trace = |ob: &cohort::runtime::GpuBuffer<Vec4>, db: &cohort::runtime::GpuBuffer<Vec4>| {
        traverse::launch_spec(&d, &spec, n, &frame, &count, &ids, &state, ob, db, &nodes, &tris, &hits).unwrap();
        let mut b = d.batch();
        for _ in 0..reps {
            traverse::record(&mut b, &spec, n, &frame, &count, &ids, &state, ob, db, &nodes, &tris, &hits).unwrap();
        }
        median(b.submit().unwrap().iter().map(ns).collect())
    };
    let ob = d.upload(&o).unwrap();
    let db = d.upload(&dirs).unwrap();
    let t_primary = time_trace(&ob, &db);
    let primary_hits = d.read(&hits).unwrap();

    // Unsorted diffuse rays: cosine directions around the normal at each primary hit.
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut o2 = Vec::with_capacity(n as usize);
    let mut d2 = Vec::with_capacity(n as usize);
    let mut hit_count = 0;
    for (k, h) in primary_hits.iter().enumerate() {
        let dir = dirs[k].truncate();
        let tri = h.w.to_bits();
        if tri == MISS {
            o2.push(origin.extend(0.0));
            d2.push(dir.extend(0.0));
            continue;
        }
        hit_count += 1;
        let t = tris_host[tri as usize];
        let mut nrm = (t.v1 - t.v0).cross(t.v2 - t.v0).normalize();
        if nrm.dot(dir) > 0.0 {
            nrm = -nrm;
        }
        let p = origin + dir * h.x + nrm * 1e-3;
        let (u1, u2) = (rnd(), rnd());
        let r = u1.sqrt();
        let phi = 2.0 * std::f32::consts::PI * u2;
        let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u1).max(0.0).sqrt());
        let tangent = nrm.any_orthonormal_vector();
        let bitangent = nrm.cross(tangent);
        let w = tangent * local.x + bitangent * local.y + nrm * local.z;
        o2.push(p.extend(0.0));
        d2.push(w.extend(0.0));
    }
    let ob2 = d.upload(&o2).unwrap();
    let db2 = d.upload(&d2).unwrap();
    let t_diffuse = time_trace(&ob2, &db2);
    // Persistent threads: a fixed number of invocations drain an atomic ray counter.
    let next = d.alloc::<u32>(1).unwrap();
    let pspec = traverse_persistent::spec(&d, None);
    let mut persistent = Vec::new();
    for (label, ob, db) in [("primary", &ob, &db), ("diffuse", &ob2, &db2)] {
        for threads in [65536u32, 262144] {
            let mut times = Vec::new();
            for _ in 0..reps {
                d.write(&next, 0, &[0]).unwrap();
                times.push(ns(&traverse_persistent::launch_spec(&d, &pspec, threads, &frame, &count, &next, &ids, &state, ob, db, &nodes, &tris, &hits).unwrap()));
            }
            persistent.push((label, threads, median(times)));
        }
    }
    println!("scene {scene_name}: {} triangles, {} BVH nodes, {:.1}% primary rays hit", tris_host.len(), bvh.nodes.len(), 100.0 * hit_count as f64 / n as f64);
    println!("traversal primary: {:.3} ms = {:.2} Grays/s", t_primary / 1e6, n as f64 / t_primary);
    println!("traversal diffuse: {:.3} ms = {:.2} Grays/s", t_diffuse / 1e6, n as f64 / t_diffuse);
    for (label, threads, t) in persistent {
        println!("persistent traversal {label}, {threads} invocations: {:.3} ms = {:.2} Grays/s", t / 1e6, n as f64 / t);
    }

    // Compaction vs copy, 2^24 elements.
    let m = 1u32 << 24;
    let flags_host: Vec<u32> = (0..m).map(|i| (i.wrapping_mul(2654435761) >> 16) & 1).collect();
    let flags = d.upload(&flags_host).unwrap();
    let idr = d.upload(&(0..m).collect::<Vec<u32>>()).unwrap();
    let out = d.alloc::<u32>(m as usize).unwrap();
    let mcount = d.upload(&[m]).unwrap();
    let scratch = d.alloc::<u32>(compact::scratch_len(m as usize)).unwrap();
    let total = d.alloc::<u32>(1).unwrap();
    let cspecs = compact::specs(&d);
    let mut b = d.batch();
    for _ in 0..reps {
        compact::record(&mut b, &cspecs, m, &mcount, &flags, &scratch, &total, &idr, &out).unwrap();
    }
    let st = b.submit().unwrap();
    let k = compact::DISPATCHES;
    let per: Vec<f64> = st.chunks(k).map(|c| c.iter().map(ns).sum()).collect();
    let t_compact = median(per);
    let parts: Vec<f64> = (0..k).map(|i| median(st.iter().skip(i).step_by(k).map(ns).collect())).collect();
    let got = d.read(&out).unwrap();
    let alive = flags_host.iter().filter(|&&f| f == 1).count();
    assert!(got[..alive].windows(2).all(|w| w[0] < w[1]) && got[alive..].windows(2).all(|w| w[0] < w[1]), "compaction is not a stable partition");
    assert!(got[..alive].iter().all(|&i| flags_host[i as usize] == 1), "compaction put a flag-0 id among the flag-1 ones");
    assert_eq!(d.read(&total).unwrap()[0] as usize, alive, "compaction total");
    let cspec = copy_u32::spec(&d, None);
    let mut b = d.batch();
    for _ in 0..reps {
        copy_u32::record(&mut b, &cspec, m, &idr, &out).unwrap();
    }
    let t_copy = median(b.submit().unwrap().iter().map(ns).collect());
    let copy_gbs = (m as f64 * 8.0) / t_copy;
    // Minimal traffic of a stable partition: read flag and id, write id (12 B/element).
    let compact_gbs = (m as f64 * 12.0) / t_compact;
    println!("copy 2^24 u32: {:.3} ms = {:.0} GB/s (read + write)", t_copy / 1e6, copy_gbs);
    println!(
        "compaction 2^24: {:.3} ms (count {:.3}, offsets {:.3}, scatter {:.3}) = {:.0} GB/s of minimal traffic = {:.0}% of copy",
        t_compact / 1e6, parts[0] / 1e6, parts[1] / 1e6, parts[2] / 1e6, compact_gbs, 100.0 * compact_gbs / copy_gbs
    );
}
