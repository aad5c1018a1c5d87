//! Scenes' BVHs kept between runs, so that a large mesh's second render starts without
//! building its tree again (for a 127k-triangle scan the build is most of the host's
//! startup, longer than the device takes to open).
//!
//! One file per scene geometry in Cohort's cache folder (`cohort_runtime::cache_dir`, off
//! with `COHORT_CACHE_DIR=off`), named by a hash of the triangles' positions and materials
//! and of the tree builder's version ([`FORMAT`]). A file is used only if it is whole (its
//! payload checksum holds) and holds every triangle of the scene exactly once, bit for bit;
//! anything else is a miss, and the tree is built as if there were no cache. The builder is
//! deterministic, so a cached tree is the one a build would give, and so is the image.
//! Files are written through a temporary file and a rename; the [`KEEP`] most recently
//! written stay, and a killed write's temporary file is removed by a later save.

use cohort::runtime::hash64;
use cohort_kernels::layout::{BvhNode, Triangle, WideNode};
use cohort_scenes::{GpuBvh, GpuBvh8, Scene};
use std::path::{Path, PathBuf};

/// Bump when the BVH builder or the node layouts change: files of another format are
/// never read.
const FORMAT: u32 = 1;
/// Scenes with fewer triangles build faster than a file is read and checked.
pub const MIN_TRIANGLES: usize = 8192;
/// Cached trees kept in the folder (each about 100 bytes per triangle).
const KEEP: usize = 16;
/// A temporary file this old is left from a killed write (writing one takes well under a
/// second) and is removed by the next save.
const STALE: std::time::Duration = std::time::Duration::from_secs(600);
const MAGIC: &[u8; 8] = b"COHBVH\0\0";

/// The cache file for `scene`'s geometry, or `None` when caching is off or the scene is
/// too small to be worth it.
pub fn file_for(scene: &Scene) -> Option<PathBuf> {
    let tris = &scene.triangles;
    if tris.len() < MIN_TRIANGLES {
        return None;
    }
    let seed = hash64(FORMAT as u64, env!("CARGO_PKG_VERSION").as_bytes());
    let h = hash64(seed, bytemuck::cast_slice(&tris.positions));
    let key = hash64(h, bytemuck::cast_slice(&tris.materials));
    Some(cohort::runtime::cache_dir()?.join(format!("bvh-{key:016x}.bin")))
}

fn push_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// The file's bytes: magic, format, payload checksum, then the payload (counts, scalars,
/// and the three arrays as they lie in memory).
fn encode(bvh: &GpuBvh, wide: Option<&GpuBvh8>) -> Vec<u8> {
    let mut p = Vec::new();
    push_u32(&mut p, bvh.nodes.len() as u32);
    push_u32(&mut p, bvh.triangles.len() as u32);
    push_u32(&mut p, bvh.depth);
    for v in bvh
        .bounds_min
        .to_array()
        .into_iter()
        .chain(bvh.bounds_max.to_array())
    {
        push_u32(&mut p, v.to_bits());
    }
    push_u32(&mut p, wide.is_some() as u32);
    let (wn, wd, ws) = wide.map_or((0, 0, 0), |w| (w.nodes.len(), w.depth, w.stack_bound));
    push_u32(&mut p, wn as u32);
    push_u32(&mut p, wd);
    push_u32(&mut p, ws);
    p.extend_from_slice(bytemuck::cast_slice(&bvh.nodes));
    p.extend_from_slice(bytemuck::cast_slice(&bvh.triangles));
    if let Some(w) = wide {
        p.extend_from_slice(bytemuck::cast_slice(&w.nodes));
    }
    let mut out = Vec::with_capacity(p.len() + 20);
    out.extend_from_slice(MAGIC);
    push_u32(&mut out, FORMAT);
    out.extend_from_slice(&hash64(0, &p).to_le_bytes());
    out.extend_from_slice(&p);
    out
}

/// Reads `n` Pod values from the front of `bytes` (copied: the file's bytes need not be
/// aligned for them).
fn take<T: bytemuck::Pod>(bytes: &mut &[u8], n: usize) -> Option<Vec<T>> {
    let len = n.checked_mul(std::mem::size_of::<T>())?;
    if bytes.len() < len {
        return None;
    }
    let (head, rest) = bytes.split_at(len);
    *bytes = rest;
    Some(bytemuck::pod_collect_to_vec(head))
}

fn decode(data: &[u8]) -> Option<(GpuBvh, Option<GpuBvh8>)> {
    let rest = data.strip_prefix(MAGIC.as_slice())?;
    let mut r: &[u8] = rest;
    let format: Vec<u32> = take(&mut r, 1)?;
    let sum: Vec<u64> = take(&mut r, 1)?;
    if format[0] != FORMAT || sum[0] != hash64(0, r) {
        return None;
    }
    let h: Vec<u32> = take(&mut r, 13)?;
    let f = |i: usize| f32::from_bits(h[i]);
    let nodes = take::<BvhNode>(&mut r, h[0] as usize)?;
    let triangles = take::<Triangle>(&mut r, h[1] as usize)?;
    let wide_nodes = take::<WideNode>(&mut r, h[10] as usize)?;
    if !r.is_empty() || h[9] > 1 {
        return None;
    }
    let bvh = GpuBvh {
        nodes,
        triangles,
        depth: h[2],
        bounds_min: glam::Vec3::new(f(3), f(4), f(5)),
        bounds_max: glam::Vec3::new(f(6), f(7), f(8)),
    };
    let wide = (h[9] == 1).then(|| GpuBvh8 {
        nodes: wide_nodes,
        depth: h[11],
        stack_bound: h[12],
    });
    Some((bvh, wide))
}

/// Whether `bvh` holds each of `scene`'s triangles exactly once, with its vertices and
/// material bit for bit, as the builder writes them.
fn matches(scene: &Scene, bvh: &GpuBvh) -> bool {
    let tris = &scene.triangles;
    if bvh.triangles.len() != tris.len() {
        return false;
    }
    let mut seen = vec![false; tris.len()];
    bvh.triangles.iter().all(|t| {
        let p = t.original as usize;
        if p >= tris.len() || std::mem::replace(&mut seen[p], true) {
            return false;
        }
        let same = |a: glam::Vec3, b: glam::Vec3| {
            a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
        };
        let [v0, v1, v2] = tris.vertices(p);
        same(t.v0, v0)
            && same(t.v1, v1)
            && same(t.v2, v2)
            && t.material == tris.materials[p]
            && t.light_pdf.to_bits() == 0
    })
}

/// The cached tree of `scene` in `file`, if there is one that fits it.
pub fn load(file: &Path, scene: &Scene) -> Option<(GpuBvh, Option<GpuBvh8>)> {
    let data = std::fs::read(file).ok()?;
    let (bvh, wide) = decode(&data)?;
    matches(scene, &bvh).then_some((bvh, wide))
}

/// Writes the tree to `file` (through a temporary file and a rename) and keeps the folder
/// to its [`KEEP`] newest trees. Failures are ignored: the cache is an optimisation.
pub fn save(file: &Path, bvh: &GpuBvh, wide: Option<&GpuBvh8>) {
    let Some(dir) = file.parent() else { return };
    if std::fs::create_dir_all(dir).is_err() {
        return;
    }
    let tmp = file.with_extension(format!("tmp{}", std::process::id()));
    if std::fs::write(&tmp, encode(bvh, wide)).is_err() || std::fs::rename(&tmp, file).is_err() {
        let _ = std::fs::remove_file(&tmp);
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let now = std::time::SystemTime::now();
    let mut trees: Vec<(std::time::SystemTime, PathBuf)> = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name();
        let name = name.to_string_lossy();
        let Some(modified) = e.metadata().ok().and_then(|m| m.modified().ok()) else {
            continue;
        };
        if !name.starts_with("bvh-") {
            continue;
        }
        if name.ends_with(".bin") {
            trees.push((modified, e.path()));
        } else if name.contains(".tmp") && now.duration_since(modified).unwrap_or_default() > STALE
        {
            // A write that was killed before its rename; one still running is younger.
            let _ = std::fs::remove_file(e.path());
        }
    }
    if trees.len() > KEEP {
        trees.sort();
        for (_, old) in &trees[..trees.len() - KEEP] {
            let _ = std::fs::remove_file(old);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scan() -> Scene {
        cohort_scenes::embedded::load("stanford").expect("embedded scene")
    }

    #[test]
    fn a_cached_tree_is_the_built_one() {
        let scene = scan();
        assert!(scene.triangles.len() >= MIN_TRIANGLES);
        let (bvh, wide) = GpuBvh8::build_scene(&scene).unwrap();
        let dir = std::env::temp_dir().join(format!("cohort-bvh-cache-{}", std::process::id()));
        let file = dir.join("bvh-test.bin");
        save(&file, &bvh, wide.as_ref());
        let (b2, w2) = load(&file, &scene).expect("the file just written is read back");
        assert_eq!(b2, bvh);
        assert_eq!(w2, wide);

        // A damaged file is a miss, never a wrong tree.
        let mut data = std::fs::read(&file).unwrap();
        let mid = data.len() / 2;
        data[mid] ^= 1;
        std::fs::write(&file, &data).unwrap();
        assert!(load(&file, &scene).is_none());
        // So is a truncated one.
        std::fs::write(&file, &encode(&bvh, wide.as_ref())[..1000]).unwrap();
        assert!(load(&file, &scene).is_none());
        // And a whole file of other geometry.
        let mut moved = scene.clone();
        moved.triangles.positions[7].x += 1.0;
        save(&file, &bvh, wide.as_ref());
        assert!(load(&file, &moved).is_none());
        assert!(load(&file, &scene).is_some());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_newest_trees_stay() {
        let dir = std::env::temp_dir().join(format!("cohort-bvh-keep-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let old = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
        for i in 0..KEEP + 4 {
            let f = dir.join(format!("bvh-{i:016x}.bin"));
            std::fs::write(&f, b"x").unwrap();
            // Older first: file i was written i seconds after the first.
            let t = old + std::time::Duration::from_secs(i as u64);
            std::fs::File::options()
                .write(true)
                .open(&f)
                .unwrap()
                .set_modified(t)
                .unwrap();
        }
        std::fs::write(dir.join("vk-pipelines-x.bin"), b"pipelines").unwrap();
        // A killed write's leftover goes; a write in progress (a fresh file) stays.
        let killed = dir.join("bvh-0123456789abcdef.tmp99");
        std::fs::write(&killed, b"torn").unwrap();
        std::fs::File::options()
            .write(true)
            .open(&killed)
            .unwrap()
            .set_modified(old)
            .unwrap();
        std::fs::write(dir.join("bvh-fedcba9876543210.tmp98"), b"writing").unwrap();
        save(&dir.join("bvh-new.bin"), &GpuBvh::default(), None);
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        // The five oldest trees went; the new one and other files stayed.
        let mut expected: Vec<String> =
            (5..KEEP + 4).map(|i| format!("bvh-{i:016x}.bin")).collect();
        expected.push("bvh-new.bin".into());
        expected.push("bvh-fedcba9876543210.tmp98".into());
        expected.push("vk-pipelines-x.bin".into());
        expected.sort();
        assert_eq!(left, expected);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_name_follows_the_geometry() {
        let scene = scan();
        let mut moved = scene.clone();
        moved.triangles.positions[0].y = -moved.triangles.positions[0].y - 1.0;
        let mut remat = scene.clone();
        remat.triangles.materials[0] ^= 1;
        if let Some(a) = file_for(&scene) {
            assert_eq!(file_for(&scene), Some(a.clone()));
            assert_ne!(file_for(&moved), Some(a.clone()));
            assert_ne!(file_for(&remat), Some(a));
        }
        let small = cohort_scenes::embedded::load("cornell").unwrap();
        assert_eq!(file_for(&small), None);
    }
}
