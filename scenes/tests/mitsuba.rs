//! The Mitsuba XML loader on small hand-written scenes: transform order, fov_axis, `$parameters`,
//! `ref`/`id`, twosided, named IORs, analytic shapes, warnings for what it cannot honour, and an
//! error naming file and line for every kind of malformed input (never a panic).

use std::path::{Path, PathBuf};

use cohort_scenes::{
    load_mitsuba, load_mitsuba_str, load_mitsuba_with, load_mitsuba_with_params, Bsdf, Camera,
    ErrorKind, FovAxis, LoadOptions, Loaded, Position, SceneError,
};
use glam::Vec3;

/// A fresh directory for one test's files.
fn tmp_dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-scenes-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A scene with a camera and the given body.
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
{body}
</scene>"#
    )
}

fn load_str(xml: &str) -> Loaded {
    load_mitsuba_str(xml, ".").unwrap_or_else(|e| panic!("{e}"))
}

fn error_of(xml: &str, dir: &Path) -> SceneError {
    let path = write(dir, "scene.xml", xml);
    match load_mitsuba(&path) {
        Ok(_) => panic!("expected an error"),
        Err(e) => {
            println!("{e}");
            e
        }
    }
}

/// Line (1-based) of the first line of `xml` containing `needle`.
fn line_of(xml: &str, needle: &str) -> u32 {
    xml.lines().position(|l| l.contains(needle)).expect(needle) as u32 + 1
}

fn rectangle_vertices(xml_transform: &str) -> Vec<Vec3> {
    let xml = scene(&format!(
        r#"<shape type="rectangle"><transform name="to_world">{xml_transform}</transform></shape>"#
    ));
    load_str(&xml).scene.triangles.positions
}

#[test]
fn transform_children_apply_in_document_order() {
    // scale then translate: x in [-1, 1] -> [-2, 2] -> [8, 12].
    let v = rectangle_vertices(r#"<scale x="2"/><translate x="10"/>"#);
    let xs = v
        .iter()
        .map(|p| p.x)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    assert_eq!(xs, (8.0, 12.0));
    // translate then scale: [-1, 1] -> [9, 11] -> [18, 22].
    let v = rectangle_vertices(r#"<translate x="10"/><scale x="2"/>"#);
    let xs = v
        .iter()
        .map(|p| p.x)
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    assert_eq!(xs, (18.0, 22.0));
    // rotate +90 about y (right-handed): the +z normal becomes +x; then translate moves it to x = 3.
    let xml = scene(
        r#"<shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate x="3"/></transform></shape>"#,
    );
    let s = load_str(&xml).scene;
    assert!(s.triangles.face_normal(0).distance(Vec3::X) < 1e-6);
    assert!(s
        .triangles
        .positions
        .iter()
        .all(|p| (p.x - 3.0).abs() < 1e-6));
    // A row-major <matrix> equals the same translation written as <translate>.
    let a = rectangle_vertices(r#"<matrix value="1 0 0 4  0 1 0 5  0 0 1 6  0 0 0 1"/>"#);
    let b = rectangle_vertices(r#"<translate x="4" y="5" z="6"/>"#);
    assert_eq!(a, b);
    // Uniform scale given as value, axis given as value.
    let a = rectangle_vertices(r#"<scale value="3"/><rotate value="0, 0, 1" angle="180"/>"#);
    let b = rectangle_vertices(r#"<scale x="3" y="3" z="3"/><rotate z="1" angle="180"/>"#);
    assert_eq!(a, b);
}

fn camera_with(fov_axis: &str, w: u32, h: u32) -> Camera {
    let xml = format!(
        r#"<scene version="3.0.0"><sensor type="perspective">
        <float name="fov" value="50"/>{}
        <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/><rfilter type="box"/></film>
        </sensor></scene>"#,
        if fov_axis.is_empty() {
            String::new()
        } else {
            format!(r#"<string name="fov_axis" value="{fov_axis}"/>"#)
        }
    );
    load_str(&xml).scene.camera
}

#[test]
fn fov_axis_follows_mitsuba() {
    let t = (25f32).to_radians().tan();
    let (w, h) = (200, 100);
    let aspect = 2.0;
    // Default is x.
    let c = camera_with("", w, h);
    assert_eq!(c.fov_axis, FovAxis::X);
    let (tx, ty) = c.tan_half_fov();
    assert!((tx - t).abs() < 1e-6 && (ty - t / aspect).abs() < 1e-6);
    // y: the vertical extent spans the 50 degrees.
    let (tx, ty) = camera_with("y", w, h).tan_half_fov();
    assert!((ty - t).abs() < 1e-6 && (tx - t * aspect).abs() < 1e-5);
    // smaller = y for a wide image, larger = x.
    assert_eq!(
        camera_with("smaller", w, h).tan_half_fov(),
        camera_with("y", w, h).tan_half_fov()
    );
    assert_eq!(
        camera_with("larger", w, h).tan_half_fov(),
        camera_with("x", w, h).tan_half_fov()
    );
    // ... and the other way round for a tall image.
    assert_eq!(
        camera_with("smaller", h, w).tan_half_fov(),
        camera_with("x", h, w).tan_half_fov()
    );
    assert_eq!(
        camera_with("larger", h, w).tan_half_fov(),
        camera_with("y", h, w).tan_half_fov()
    );
    // diagonal: the corner direction makes 25 degrees with the axis.
    let (tx, ty) = camera_with("diagonal", w, h).tan_half_fov();
    assert!(((tx * tx + ty * ty).sqrt() - t).abs() < 1e-5);
    // The corner ray of an x-axis camera leaves at the documented angle.
    let c = camera_with("x", w, h);
    let right_edge = c.ray_direction(1.0, 0.5);
    assert!((right_edge.angle_between(Vec3::Z) - 25f32.to_radians()).abs() < 1e-5);
}

#[test]
fn defaults_refs_twosided_iors_and_shapes() {
    let xml = scene(
        r#"
    <default name="albedo" value="0.25"/>
    <default name="res" value="16"/>
    <integrator type="path"><integer name="max_depth" value="$res"/></integrator>
    <bsdf type="twosided" id="paper"><bsdf type="diffuse"><rgb name="reflectance" value="$albedo"/></bsdf></bsdf>
    <bsdf type="dielectric" id="glass"><string name="int_ior" value="diamond"/><string name="ext_ior" value="water"/></bsdf>
    <shape type="rectangle"><ref id="paper"/></shape>
    <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/><ref id="glass"/></shape>
    <shape type="cube"><boolean name="flip_normals" value="true"/></shape>
    <emitter type="constant"><rgb name="radiance" value="0.5, 0.6, 0.7"/></emitter>"#,
    );
    let loaded = load_str(&xml);
    for w in &loaded.warnings {
        println!("{w}");
    }
    assert!(loaded.warnings.is_empty());
    let s = &loaded.scene;
    assert_eq!(s.integrator.max_depth, 16);
    assert_eq!(s.environment, Vec3::new(0.5, 0.6, 0.7));
    let paper = s.material_of(0);
    assert!(paper.two_sided);
    assert_eq!(
        paper.bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.25)
        }
    );

    let sphere = &s.objects[1];
    assert_eq!(sphere.triangles.len(), 5120);
    match s.materials[sphere.material as usize].bsdf {
        Bsdf::Dielectric {
            int_ior, ext_ior, ..
        } => assert_eq!((int_ior, ext_ior), (2.419, 1.333)),
        b => panic!("{b:?}"),
    }
    let center = Vec3::new(1.0, 2.0, 3.0);
    let normals = s
        .triangles
        .normals
        .as_ref()
        .expect("the sphere shades smoothly");
    for i in sphere.triangles.clone() {
        let i = i as usize;
        for k in 0..3 {
            let p = s.triangles.positions[3 * i + k];
            assert!(((p - center).length() - 0.5).abs() < 1e-5);
            assert!(normals[3 * i + k].distance((p - center).normalize()) < 1e-4);
        }
    }
    // Shapes without a BSDF get Mitsuba's default diffuse 0.5; flip_normals turns the cube inside out.
    let cube = &s.objects[2];
    assert_eq!(
        s.materials[cube.material as usize].bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.5)
        }
    );
    for i in cube.triangles.clone() {
        let [a, b, c] = s.triangles.vertices(i as usize);
        assert!(s.triangles.face_normal(i as usize).dot(a + b + c) < 0.0);
    }
    // Overriding a default from the caller (Mitsuba's -D).
    let dir = tmp_dir("params");
    let path = write(&dir, "scene.xml", &xml);
    let s = load_mitsuba_with_params(&path, &[("res", "3")])
        .unwrap()
        .scene;
    assert_eq!(s.integrator.max_depth, 3);
}

#[test]
fn obj_with_normals_shades_smooth_unless_face_normals() {
    let dir = tmp_dir("normals");
    write(
        &dir,
        "tri.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0.6 0 0.8\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n",
    );
    let body = |face_normals: bool| {
        scene(&format!(
            r#"<shape type="obj"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="{face_normals}"/></shape>"#
        ))
    };
    let smooth = load_mitsuba(write(&dir, "smooth.xml", body(false)))
        .unwrap()
        .scene;
    let normals = smooth.triangles.normals.unwrap();
    assert!(normals[0].distance(Vec3::new(0.6, 0.0, 0.8)) < 1e-6);
    let flat = load_mitsuba(write(&dir, "flat.xml", body(true)))
        .unwrap()
        .scene;
    assert!(flat.triangles.normals.is_none());
}

/// Under `lenient`, unsupported plugins are warnings at their line, with a stand-in.
#[test]
fn unsupported_features_warn_with_file_and_line() {
    let xml = scene(
        r#"
    <shape type="sdfgrid"/>
    <shape type="rectangle">
        <bsdf type="pplastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/></bsdf>
    </shape>
    <shape type="rectangle">
        <bsdf type="diffuse"><float name="roughness" value="0.3"/></bsdf>
    </shape>
    <emitter type="sunsky"/>
    <shape type="rectangle"><bsdf type="roughplastic"><float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.1"/></bsdf></shape>
    <shape type="rectangle"><bsdf type="roughdielectric"><float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.1"/></bsdf></shape>
    <wibble/>"#,
    );
    let dir = tmp_dir("warnings");
    let path = write(&dir, "scene.xml", &xml);
    let lenient = LoadOptions {
        lenient: true,
        ..Default::default()
    };
    let loaded = load_mitsuba_with(&path, &lenient).unwrap();
    for w in &loaded.warnings {
        println!("{w}");
        assert_eq!(w.location.file, path);
    }
    let warned_at = |needle: &str, text: &str| {
        let line = line_of(&xml, needle);
        assert!(
            loaded
                .warnings
                .iter()
                .any(|w| w.location.position == Position::Line(line) && w.message.contains(text)),
            "no warning containing '{text}' at line {line}"
        );
    };
    warned_at(r#"type="sdfgrid""#, "shape 'sdfgrid' is not supported");
    warned_at(r#"type="pplastic""#, "bsdf 'pplastic' is not supported");
    warned_at("roughness", "'roughness'");
    warned_at("sunsky", "emitter 'sunsky' is not supported");
    warned_at("roughplastic", "anisotropic");
    // An anisotropic rough dielectric is rendered as it is, without a warning.
    let rd = line_of(&xml, "roughdielectric");
    assert!(!loaded
        .warnings
        .iter()
        .any(|w| w.location.position == Position::Line(rd)));
    assert!(loaded.scene.materials.iter().any(|m| matches!(
        m.bsdf,
        Bsdf::RoughDielectric { alpha, .. } if (alpha.u, alpha.v) == (0.3, 0.1)
    )));
    warned_at("<wibble/>", "<wibble>");
    // The stand-in for pplastic keeps its colour.
    let s = &loaded.scene;
    assert!(s.materials.iter().any(|m| m.bsdf
        == Bsdf::Diffuse {
            reflectance: Vec3::new(0.2, 0.4, 0.6)
        }));
}

#[test]
fn malformed_xml_names_file_and_line() {
    let dir = tmp_dir("bad-xml");
    let xml = "<scene version=\"3.0.0\">\n  <shape type=\"rectangle\">\n  </shap>\n</scene>\n";
    let e = error_of(xml, &dir);
    assert_eq!(e.kind, ErrorKind::Xml);
    assert_eq!(e.location.file, dir.join("scene.xml"));
    assert_eq!(e.location.line_number(), Some(3));
    assert!(e.to_string().contains("scene.xml:3"));

    let e = error_of("<notascene/>", &dir);
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Syntax, Some(1))
    );

    // A bad number, an unknown parameter, a bad boolean: each at its line.
    for (needle, body) in [
        (
            "abc",
            r#"<shape type="sphere"><float name="radius" value="abc"/></shape>"#,
        ),
        (
            "$nope",
            r#"<shape type="sphere"><float name="radius" value="$nope"/></shape>"#,
        ),
        (
            "maybe",
            r#"<shape type="cube"><boolean name="flip_normals" value="maybe"/></shape>"#,
        ),
        (
            "NaN",
            r#"<shape type="sphere"><float name="radius" value="NaN"/></shape>"#,
        ),
        (
            "radius",
            r#"<shape type="sphere"><string name="radius" value="1"/></shape>"#,
        ),
    ] {
        let xml = scene(body);
        let e = error_of(&xml, &dir);
        assert_eq!(e.kind, ErrorKind::Syntax, "{e}");
        assert_eq!(e.location.line_number(), Some(line_of(&xml, needle)), "{e}");
    }
    let xml = "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">\n<float name=\"fov\" value=\"30\"/>\n<string name=\"fov_axis\" value=\"z\"/>\n</sensor>\n</scene>";
    let e = error_of(xml, &dir);
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Syntax, Some(4)),
        "{e}"
    );
}

#[test]
fn missing_mesh_file_names_the_referencing_line() {
    let dir = tmp_dir("missing-mesh");
    let xml = scene(
        r#"<shape type="obj">
        <string name="filename" value="meshes/nothere.obj"/>
    </shape>"#,
    );
    let e = error_of(&xml, &dir);
    assert_eq!(e.kind, ErrorKind::Io);
    assert_eq!(e.location.file, dir.join("scene.xml"));
    assert_eq!(e.location.line_number(), Some(line_of(&xml, "nothere.obj")));
    assert!(e.message.contains("nothere.obj"));
}

/// Loads a scene that references `file` (written with `contents`) and returns the error.
fn mesh_error(test: &str, file: &str, contents: &[u8]) -> (SceneError, PathBuf, String) {
    let dir = tmp_dir(test);
    let mesh = write(&dir, file, contents);
    let kind = if file.ends_with(".obj") { "obj" } else { "ply" };
    let xml = scene(&format!(
        r#"<shape type="{kind}">
        <string name="filename" value="{file}"/>
    </shape>"#
    ));
    let e = error_of(&xml, &dir);
    // The outer context points back at the XML line that named the mesh.
    assert_eq!(e.context.len(), 1, "{e}");
    assert_eq!(e.context[0].line_number(), Some(line_of(&xml, file)));
    (e, mesh, xml)
}

#[test]
fn obj_errors_name_the_mesh_line() {
    let (e, mesh, _) = mesh_error(
        "obj-index",
        "bad.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 1 2 3\nf 1 2 7\n",
    );
    assert_eq!(
        (e.kind, &e.location.file, e.location.line_number()),
        (ErrorKind::IndexOutOfRange, &mesh, Some(6))
    );
    let (e, _, _) = mesh_error(
        "obj-negative",
        "neg.obj",
        b"v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
    );
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::IndexOutOfRange, Some(3))
    );
    let (e, mesh, _) = mesh_error(
        "obj-nan",
        "nan.obj",
        b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
    );
    assert_eq!(
        (e.kind, &e.location.file, e.location.line_number()),
        (ErrorKind::NonFinite, &mesh, Some(2))
    );
    let (e, _, _) = mesh_error(
        "obj-syntax",
        "syntax.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n",
    );
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Syntax, Some(3))
    );
}

#[test]
fn ply_errors_name_line_or_byte_offset() {
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let (e, mesh, _) = mesh_error(
        "ply-index",
        "bad.ply",
        format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").as_bytes(),
    );
    assert_eq!(
        (e.kind, &e.location.file, e.location.line_number()),
        (ErrorKind::IndexOutOfRange, &mesh, Some(13))
    );
    let (e, _, _) = mesh_error(
        "ply-nan",
        "nan.ply",
        format!("{header}0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n").as_bytes(),
    );
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::NonFinite, Some(11))
    );
    let (e, _, _) = mesh_error(
        "ply-short",
        "short.ply",
        format!("{header}0 0 0\n1 0\n0 1 0\n3 0 1 2\n").as_bytes(),
    );
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Syntax, Some(11))
    );
    let (e, _, _) = mesh_error(
        "ply-header",
        "header.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nend_header\n",
    );
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Syntax, Some(4))
    );

    // Binary: a truncated file and a bad index report the byte offset and the element.
    let bin_header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let mut bytes = bin_header.as_bytes().to_vec();
    let body_start = bytes.len() as u64;
    for v in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bytes.extend(v.to_le_bytes());
    }
    let full = {
        let mut b = bytes.clone();
        b.push(3);
        for i in [0i32, 1, 9] {
            b.extend(i.to_le_bytes());
        }
        b
    };
    let (e, _, _) = mesh_error("ply-bin-index", "bad.ply", &full);
    assert_eq!(e.kind, ErrorKind::IndexOutOfRange);
    assert_eq!(
        e.location.position,
        Position::Byte {
            offset: body_start + 36,
            element: "face".into(),
            index: 0
        }
    );
    let truncated = &full[..full.len() - 30];
    let (e, _, _) = mesh_error("ply-bin-truncated", "cut.ply", truncated);
    assert_eq!(e.kind, ErrorKind::Truncated);
    match &e.location.position {
        Position::Byte { element, index, .. } => {
            assert_eq!((element.as_str(), *index), ("vertex", 1))
        }
        p => panic!("{p:?}"),
    }
    let mut nan = bytes.clone();
    nan[body_start as usize + 16..body_start as usize + 20]
        .copy_from_slice(&f32::INFINITY.to_le_bytes());
    nan.extend([3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
    let (e, _, _) = mesh_error("ply-bin-nan", "inf.ply", &nan);
    assert_eq!(e.kind, ErrorKind::NonFinite);
    assert!(
        matches!(&e.location.position, Position::Byte { element, index: 1, .. } if element == "vertex")
    );
}

#[test]
fn degenerate_triangles_are_dropped_with_a_warning() {
    let dir = tmp_dir("degenerate");
    write(
        &dir,
        "d.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 3 3 1\n",
    );
    let xml = scene(r#"<shape type="obj"><string name="filename" value="d.obj"/></shape>"#);
    let path = write(&dir, "scene.xml", &xml);
    let loaded = load_mitsuba(&path).unwrap();
    assert_eq!(loaded.scene.triangles.len(), 1);
    let w = loaded
        .warnings
        .iter()
        .find(|w| w.message.contains("degenerate"))
        .expect("warning");
    assert_eq!(w.location.line_number(), Some(line_of(&xml, "d.obj")));
    assert!(w.message.contains("2 degenerate"));
}

#[test]
fn garbage_never_panics() {
    let dir = tmp_dir("garbage");
    let inputs: Vec<Vec<u8>> = vec![
        b"".to_vec(),
        b"ply\n".to_vec(),
        b"ply\nformat binary_big_endian 1.0\nelement vertex 99999999999\nproperty double x\nend_header\n".to_vec(),
        b"ply\nformat binary_big_endian 1.0\nelement vertex 99999999999\nproperty double x\nproperty double y\nproperty double z\nend_header\n".to_vec(),
        b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n\xff\xff\xff\xff".to_vec(),
        b"ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n".to_vec(),
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n255 0 0\n".to_vec(),
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n5 5 5\n3 0 1 2\n".to_vec(),
        vec![0xff; 64],
        b"f 1 2 3\n".to_vec(),
        b"v 1 2\nf 1 1 1\n".to_vec(),
        b"v 0 0 0\nf 1 2 3 4 5 6 7 8 9 10\n".to_vec(),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1 2/2/2 3/3/3\n".to_vec(),
    ];
    for (i, data) in inputs.iter().enumerate() {
        for ext in ["obj", "ply"] {
            let name = format!("g{i}.{ext}");
            write(&dir, &name, data);
            let xml = scene(&format!(
                r#"<shape type="{ext}"><string name="filename" value="{name}"/></shape>"#
            ));
            let path = write(&dir, "scene.xml", &xml);
            // Either outcome is fine; reaching here without a panic is the test.
            let _ = load_mitsuba(&path);
        }
    }
    for xml in [
        "",
        "<",
        "<scene>",
        "<scene><shape/></scene>",
        "<scene><shape type=\"obj\"/></scene>",
        "<scene><sensor type=\"perspective\"><float name=\"fov\" value=\"1e40\"/></sensor></scene>",
    ] {
        let _ = load_mitsuba_str(xml, &dir);
    }
}

/// `principled` and `principledthin` read as Mitsuba reads them: its defaults, `eta` from
/// `specular`, and errors at the line for what it refuses or the renderer cannot take.
#[test]
fn principled_parameters_defaults_and_errors() {
    let principled = |bsdf: &str| {
        let loaded = load_str(&scene(&format!("<shape type=\"rectangle\">{bsdf}</shape>")));
        match loaded.scene.materials.last().unwrap().bsdf {
            Bsdf::Principled(p) => p,
            other => panic!("{other:?}"),
        }
    };
    let p = principled(r#"<bsdf type="principled"/>"#);
    assert!(!p.thin);
    assert_eq!(p.base_color, Vec3::splat(0.5));
    assert_eq!((p.roughness, p.metallic, p.spec_trans), (0.5, 0.0, 0.0));
    // specular 0.5: eta = 2 / (1 - sqrt(0.04)) - 1 = 1.5.
    assert!((p.eta - 1.5).abs() < 1e-6);
    assert_eq!(p.sampling_rates, [1.0, 1.0, 1.0, 0.0]);
    let p = principled(
        r#"<bsdf type="principled"><float name="specular" value="0.7"/><float name="clearcoat" value="0.3"/><float name="main_specular_sampling_rate" value="2"/></bsdf>"#,
    );
    assert!((p.eta - (2.0 / (1.0 - (0.08f32 * 0.7).sqrt()) - 1.0)).abs() < 1e-6);
    assert_eq!((p.clearcoat, p.sampling_rates[0]), (0.3, 2.0));
    // Transmission needs an interface: eta 1 becomes 1.001, as in Mitsuba.
    let p = principled(
        r#"<bsdf type="principled"><float name="eta" value="1"/><float name="spec_trans" value="0.5"/></bsdf>"#,
    );
    assert_eq!(p.eta, 1.001);
    let p =
        principled(r#"<bsdf type="principledthin"><float name="diff_trans" value="1.5"/></bsdf>"#);
    assert!(p.thin);
    assert_eq!((p.diff_trans, p.eta, p.metallic), (1.5, 1.5, 0.0));

    let dir = tmp_dir("principled");
    for (bsdf, needle, message) in [
        (
            r#"<bsdf type="principled"><float name="eta" value="1.4"/><float name="specular" value="0.5"/></bsdf>"#,
            "specular",
            "either 'eta' or 'specular'",
        ),
        (
            r#"<bsdf type="principled"><float name="metallic" value="1.5"/></bsdf>"#,
            "metallic",
            "'metallic' must lie in [0, 1]",
        ),
        (
            r#"<bsdf type="principled"><texture type="uniform" name="roughness"><float name="value" value="2"/></texture></bsdf>"#,
            "texture",
            "'roughness' must lie in [0, 1], not 2",
        ),
        (
            r#"<bsdf type="principledthin"><float name="clearcoat" value="0.5"/></bsdf>"#,
            "clearcoat",
            "'clearcoat'",
        ),
    ] {
        let xml = scene(&format!("<shape type=\"rectangle\">\n{bsdf}\n</shape>"));
        let e = error_of(&xml, &dir).to_string();
        assert!(e.contains(message), "{e}");
        assert!(e.contains(&format!(":{}", line_of(&xml, needle))), "{e}");
    }
}
