//! What the traversal benchmarks share: GPU timing (median of repeated dispatches after
//! the clocks have ramped up), hit comparison and the benchmark rays of a scene.

// Each benchmark uses a part of this module.
#![allow(dead_code)]

use cohort::runtime::{Batch, Device, DispatchStats};
use cohort_kernels::layout::{Triangle, MISS};
use cohort_scenes::Scene;
use glam::{Vec3, Vec4};

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Records `reps` dispatches with `record` into batches and runs them until the GPU has
/// been busy for 0.3 s (its clocks ramp up from idle over about that time, and the host
/// phases of a benchmark let it idle), then once more; returns that batch's stats.
pub fn timed(d: &Device, reps: u32, record: impl Fn(&mut Batch)) -> Vec<DispatchStats> {
    let start = std::time::Instant::now();
    loop {
        let mut b = d.batch();
        for _ in 0..reps {
            record(&mut b);
        }
        let stats = b.submit().unwrap();
        if start.elapsed().as_secs_f64() > 0.3 {
            return stats;
        }
    }
}

pub fn ns(s: &DispatchStats) -> f64 {
    s.gpu_time_ns.expect("this benchmark needs GPU timestamps") as f64
}

/// Median GPU time in ns of one dispatch recorded by `record` (see [`timed`]).
pub fn median_ns(d: &Device, reps: u32, record: impl Fn(&mut Batch)) -> f64 {
    median(timed(d, reps, record).iter().map(ns).collect())
}

/// Hits that differ between two traversals: another triangle at a t that differs by more
/// than rounding.
pub fn differ(a: &[Vec4], b: &[Vec4]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(a, b)| {
            a.w.to_bits() != b.w.to_bits()
                && (a.w.to_bits() == MISS
                    || b.w.to_bits() == MISS
                    || (a.x - b.x).abs() > 1e-5 * a.x.abs().max(1.0))
        })
        .count()
}

/// 2^20 primary rays of the scene's camera at 1024x1024, pixels in Morton order:
/// (origins with tmin 0 in w, directions).
pub fn primary_rays(scene: &Scene) -> (Vec<Vec4>, Vec<Vec4>) {
    let side = 1024u32;
    let mut cam = scene.camera;
    cam.width = side;
    cam.height = side;
    let order = cohort_scenes::morton_pixel_order(side, side);
    let o = vec![cam.origin().extend(0.0); order.len()];
    let d = order
        .iter()
        .map(|&p| {
            cam.ray_direction(
                ((p % side) as f32 + 0.5) / side as f32,
                ((p / side) as f32 + 0.5) / side as f32,
            )
            .extend(0.0)
        })
        .collect();
    (o, d)
}

/// Unsorted diffuse rays: a cosine-distributed direction around the normal at each primary
/// hit (a fixed xorshift sequence), from 1e-3 above the surface; a missed primary ray is
/// traced again as it was. Returns (origins, directions, primary rays that hit).
pub fn diffuse_rays(
    o: &[Vec4],
    dirs: &[Vec4],
    primary_hits: &[Vec4],
    tris: &[Triangle],
) -> (Vec<Vec4>, Vec<Vec4>, usize) {
    let mut seed = 0x2545F4914F6CDD1Du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut o2 = Vec::with_capacity(o.len());
    let mut d2 = Vec::with_capacity(o.len());
    let mut hit_count = 0;
    for (k, h) in primary_hits.iter().enumerate() {
        let origin = o[k].truncate();
        let dir = dirs[k].truncate();
        let tri = h.w.to_bits();
        if tri == MISS {
            o2.push(o[k]);
            d2.push(dirs[k]);
            continue;
        }
        hit_count += 1;
        let t = tris[tri as usize];
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
    (o2, d2, hit_count)
}

/// The rays in a fixed pseudo-random order (Fisher-Yates over an xorshift sequence): the
/// renderer's order of rays after the first bounce, where neighbours are unrelated paths.
pub fn shuffled(o: &[Vec4], d: &[Vec4]) -> (Vec<Vec4>, Vec<Vec4>) {
    let mut idx: Vec<usize> = (0..o.len()).collect();
    let mut seed = 0x9E37_79B9_7F4A_7C15u64;
    for i in (1..idx.len()).rev() {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        idx.swap(i, (seed % (i as u64 + 1)) as usize);
    }
    (
        idx.iter().map(|&i| o[i]).collect(),
        idx.iter().map(|&i| d[i]).collect(),
    )
}

/// The Mitsuba scene at `path`, or the process ends naming the file and the error.
pub fn load_or_exit(path: &str) -> Scene {
    match cohort_scenes::mitsuba::load_mitsuba(path) {
        Ok(l) => l.scene,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    }
}
