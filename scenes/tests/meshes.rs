//! Mesh readers: the shared meshes load as they are (igea.ply's triangle strips included), PLY in
//! ASCII, binary little- and big-endian gives identical meshes, polygons become fans, strips keep
//! their winding.

use std::path::{Path, PathBuf};

use cohort_scenes::obj::{parse_obj, read_obj};
use cohort_scenes::ply::{parse_ply, read_ply};
use cohort_scenes::{shapes, TriMesh};
use glam::Vec3;

fn shared(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/scenes")
        .join(path)
}

fn signed_volume(m: &TriMesh) -> f64 {
    m.indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

#[test]
fn shared_obj_meshes() {
    for (file, triangles) in [
        ("meshes/stanford-bunny.obj", 69_451),
        ("meshes/ogre.obj", 124_008),
    ] {
        let t = std::time::Instant::now();
        let m = read_obj(&shared(file)).unwrap_or_else(|e| panic!("{e}"));
        println!(
            "{file}: {} triangles, {} vertices in {:?}",
            m.indices.len(),
            m.positions.len(),
            t.elapsed()
        );
        assert_eq!(m.indices.len(), triangles);
        assert!(m.normals.is_none());
        assert!(m.positions.iter().all(|p| p.is_finite()));
    }
    for file in [
        "stanford-like/meshes/sphere_5120.obj",
        "stanford-like/meshes/sphere_1280.obj",
    ] {
        let m = read_obj(&shared(file)).unwrap();
        // Unit icospheres, counter-clockwise = outward.
        assert!(
            (signed_volume(&m) - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.05,
            "{file}"
        );
    }
}

#[test]
fn igea_tristrips() {
    let t = std::time::Instant::now();
    let mut warnings = Vec::new();
    let m = read_ply(&shared("meshes/igea.ply"), &mut warnings).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "igea: {} triangles, {} vertices in {:?}, signed volume {}",
        m.indices.len(),
        m.positions.len(),
        t.elapsed(),
        signed_volume(&m)
    );
    assert!(warnings.is_empty());
    assert_eq!(m.positions.len(), 134_345);
    // The README says about 268k: stitching triangles (repeated vertices) are not faces.
    assert!(
        (260_000..280_000).contains(&m.indices.len()),
        "{}",
        m.indices.len()
    );
    assert!(m
        .indices
        .iter()
        .all(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2]));
    // Strips decoded with one consistent winding enclose a positive volume (about 40 % of the
    // 0.069 x 0.099 x 0.099 bounding box), i.e. counter-clockwise = outward.
    assert!(signed_volume(&m) > 2e-4);
}

/// A mesh with a quad (fan-triangulated) and normals, written in the three PLY encodings.
fn sample() -> (Vec<Vec3>, Vec<Vec3>, Vec<Vec<u32>>) {
    let s = shapes::icosphere(2);
    let mut faces: Vec<Vec<u32>> = s.indices.iter().map(|t| t.to_vec()).collect();
    // Merge the first two triangles' vertices into one quad-like polygon to exercise fans.
    faces.push(vec![0, 1, 2, 3]);
    let normals = s.normals.clone().unwrap();
    (s.positions, normals, faces)
}

fn ply_header(
    format: &str,
    n: usize,
    faces: usize,
    count: &str,
    index: &str,
    face_name: &str,
) -> String {
    format!(
        "ply\nformat {format} 1.0\ncomment written by the cohort-scenes tests\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty float nx\nproperty float ny\nproperty float nz\nelement face {faces}\nproperty list {count} {index} {face_name}\nproperty int flags\nend_header\n"
    )
}

fn write_binary(big_endian: bool, count: &str, index: &str) -> Vec<u8> {
    let (p, n, f) = sample();
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = ply_header(fmt, p.len(), f.len(), count, index, "vertex_index").into_bytes();
    let put = |out: &mut Vec<u8>, b: &[u8]| {
        if big_endian {
            out.extend(b.iter().rev());
        } else {
            out.extend(b);
        }
    };
    for (p, n) in p.iter().zip(&n) {
        for v in p.to_array() {
            put(&mut out, &v.to_le_bytes());
        }
        out.push(200);
        for v in n.to_array() {
            put(&mut out, &v.to_le_bytes());
        }
    }
    for face in &f {
        match count {
            "uchar" => out.push(face.len() as u8),
            "ushort" => put(&mut out, &(face.len() as u16).to_le_bytes()),
            _ => put(&mut out, &(face.len() as u32).to_le_bytes()),
        }
        for &i in face {
            match index {
                "int" => put(&mut out, &(i as i32).to_le_bytes()),
                "uint" => put(&mut out, &i.to_le_bytes()),
                _ => put(&mut out, &(i as u16).to_le_bytes()),
            }
        }
        put(&mut out, &7i32.to_le_bytes());
    }
    out
}

fn write_ascii() -> Vec<u8> {
    let (p, n, f) = sample();
    let mut out = ply_header("ascii", p.len(), f.len(), "uchar", "int", "vertex_indices");
    for (p, n) in p.iter().zip(&n) {
        // Rust's float Display round-trips exactly.
        out += &format!("{} {} {} 200 {} {} {}\n", p.x, p.y, p.z, n.x, n.y, n.z);
    }
    for face in &f {
        out += &format!(
            "{} {} 7\n",
            face.len(),
            face.iter()
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    out.into_bytes()
}

#[test]
fn ply_ascii_and_binary_agree() {
    let file = Path::new("sample.ply");
    let parse = |bytes: &[u8]| {
        let mut w = Vec::new();
        let m = parse_ply(bytes, file, &mut w).unwrap_or_else(|e| panic!("{e}"));
        // `red` alone and `flags` are no attributes Mitsuba reads: it warns, and so do we.
        let ignored: Vec<&str> = w.iter().map(|w| w.message.as_str()).collect();
        assert_eq!(ignored.len(), 2, "{ignored:?}");
        assert!(ignored[0].contains("'red' ignored") && ignored[1].contains("'flags' ignored"));
        assert!(m.attributes.is_empty());
        m
    };
    let ascii = parse(&write_ascii());
    let (p, n, f) = sample();
    assert_eq!(ascii.positions, p);
    assert_eq!(ascii.normals.as_ref().unwrap(), &n);
    assert_eq!(ascii.indices.len(), f.len() - 1 + 2);
    assert_eq!(
        ascii.indices[ascii.indices.len() - 2..],
        [[0, 1, 2], [0, 2, 3]]
    );
    for (big, count, index) in [
        (false, "uchar", "int"),
        (true, "uchar", "int"),
        (false, "uint", "uint"),
        (true, "ushort", "ushort"),
    ] {
        assert_eq!(
            parse(&write_binary(big, count, index)),
            ascii,
            "big endian {big}, {count} {index}"
        );
    }
}

#[test]
fn ply_tristrips_keep_one_winding() {
    let text = "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n\
        0 0 0\n0 1 0\n1 0 0\n1 1 0\n5 5 5\n6 5 5\n5 6 5\n\
        9 0 1 2 3 -1 4 5 6 6\n";
    let m = parse_ply(text.as_bytes(), Path::new("strip.ply"), &mut Vec::new()).unwrap();
    assert_eq!(m.indices, vec![[0, 1, 2], [2, 1, 3], [4, 5, 6]]);
    // Both strip triangles face the same way.
    let n = |t: [u32; 3]| {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        (b - a).cross(c - a).normalize()
    };
    assert_eq!(n(m.indices[0]), n(m.indices[1]));
}

#[test]
fn obj_polygons_become_fans_and_groups_concatenate() {
    let text = b"o first\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\no second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n";
    let m = parse_obj(text, Path::new("quad.obj")).unwrap();
    assert_eq!(m.indices.len(), 3);
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        assert_eq!((b - a).cross(c - a).normalize(), Vec3::Z);
    }
}
