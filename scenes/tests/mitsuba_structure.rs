//! Scene-file structure read as Mitsuba 3.9.1 reads it (each expectation below was checked
//! against `mitsuba==3.9.1`, scalar_rgb, `mi.load_file`): `<include>`, `<path>`, `id`/`<ref>`
//! for every object kind, nested integrators, `<default>`/`$name`, `version`; unknown and
//! unsupported plugins as errors (strict) or warnings (lenient); empty scenes.

use std::path::{Path, PathBuf};

use cohort_scenes::{
    load_mitsuba, load_mitsuba_str, load_mitsuba_str_with, load_mitsuba_with, Bsdf, ErrorKind,
    LoadOptions, Loaded, SceneError,
};
use glam::{Mat4, Vec3};

fn tmp_dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-structure-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(&p, text).unwrap();
    p
}

/// A triangle with its first vertex at (x, 0, 0): tells which file a mesh was read from.
fn triangle_at(x: f32) -> String {
    format!("v {x} 0 0\nv {} 0 0\nv {x} 1 0\nf 1 2 3\n", x + 1.0)
}

/// A scene file with a sensor, an integrator and the given body, one element per line.
fn scene(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>
{body}
</scene>"#
    )
}

fn lenient() -> LoadOptions {
    LoadOptions {
        lenient: true,
        ..Default::default()
    }
}

fn load(path: &Path) -> Loaded {
    load_mitsuba(path).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(path: &Path) -> SceneError {
    match load_mitsuba(path) {
        Ok(_) => panic!("{} should not load", path.display()),
        Err(e) => {
            println!("{e}");
            e
        }
    }
}

fn line_of(text: &str, needle: &str) -> u32 {
    text.lines().position(|l| l.contains(needle)).expect(needle) as u32 + 1
}

fn first_x(l: &Loaded) -> Vec<f32> {
    l.scene
        .objects
        .iter()
        .map(|o| l.scene.triangles.positions[3 * o.triangles.start as usize].x)
        .collect()
}

#[test]
fn empty_scene_and_emitter_only_scene_load() {
    let l = load_mitsuba_str(&scene(""), ".").unwrap();
    assert!(l.scene.triangles.is_empty() && l.scene.materials.is_empty());
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let l = load_mitsuba_str(
        &scene(r#"<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#),
        ".",
    )
    .unwrap();
    assert!(l.scene.triangles.is_empty());
    assert_eq!(l.scene.environment, Vec3::splat(0.5));
    // Even a bare <scene> loads (with warnings for what Mitsuba would need to render it).
    let l = load_mitsuba_str(r#"<scene version="3.0.0"/>"#, ".").unwrap();
    assert!(l.warnings.iter().any(|w| w.message.contains("no sensor")));
    assert!(l
        .warnings
        .iter()
        .any(|w| w.message.contains("no <integrator>")));
}

#[test]
fn include_splices_files_relative_to_the_including_file() {
    let dir = tmp_dir("include");
    write(&dir, "m.obj", triangle_at(70.0));
    write(
        &dir,
        "sub/bsdf.xml",
        r#"<bsdf version="3.0.0" type="diffuse"><rgb name="reflectance" value="0.1"/></bsdf>"#,
    );
    // sub/inc.xml includes inner.xml from its own folder; its shape names m.obj, which Mitsuba
    // resolves from the MAIN file's folder.
    write(
        &dir,
        "sub/inc.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"inner.xml\"/>\n<shape type=\"obj\"><string name=\"filename\" value=\"m.obj\"/><include filename=\"bsdf.xml\"/></shape>\n</scene>",
    );
    write(
        &dir,
        "sub/inner.xml",
        r#"<scene version="3.0.0"><shape type="sphere"/></scene>"#,
    );
    let main = write(
        &dir,
        "main.xml",
        scene(r#"<include filename="sub/inc.xml"/>"#),
    );
    let l = load(&main);
    assert_eq!(l.scene.objects.len(), 2);
    assert_eq!(first_x(&l)[1], 70.0);
    assert_eq!(
        l.scene.materials[l.scene.objects[1].material as usize].bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.1)
        }
    );

    // Only sub/m.obj: not found (as in Mitsuba), and the error says where it looked and why.
    std::fs::rename(dir.join("m.obj"), dir.join("sub/m.obj")).unwrap();
    let e = load_err(&main);
    assert_eq!(e.kind, ErrorKind::Io);
    assert_eq!(e.location.file, dir.join("sub/inc.xml"));
    assert_eq!(e.location.line_number(), Some(3));
    assert!(
        e.message.contains("searched in") && e.message.contains("included file"),
        "{e}"
    );

    // A missing include is an error at the <include> line.
    let main = write(
        &dir,
        "missing.xml",
        scene(r#"<include filename="nope.xml"/>"#),
    );
    let e = load_err(&main);
    assert_eq!((e.kind, e.location.line_number()), (ErrorKind::Io, Some(7)));
    assert!(e.message.contains("nope.xml"));
    // An error inside an included file names that file and the including line.
    write(&dir, "broken.xml", "<scene version=\"3.0.0\">\n<shape type=\"sphere\"><float name=\"radius\" value=\"x\"/></shape>\n</scene>");
    let main = write(
        &dir,
        "inc-broken.xml",
        scene(r#"<include filename="broken.xml"/>"#),
    );
    let e = load_err(&main);
    assert_eq!(e.location.file, dir.join("broken.xml"));
    assert_eq!(e.location.line_number(), Some(2));
    assert_eq!(e.context[0].file, main);
    assert!(e.to_string().contains("inc-broken.xml:7"), "{e}");
}

#[test]
fn include_cycles_are_refused_with_the_chain() {
    let dir = tmp_dir("cycle");
    write(
        &dir,
        "a.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"sub/b.xml\"/>\n</scene>",
    );
    write(
        &dir,
        "sub/b.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"../a.xml\"/>\n</scene>",
    );
    let e = load_err(&dir.join("a.xml"));
    assert_eq!(e.kind, ErrorKind::Cycle);
    assert_eq!(e.location.file, dir.join("sub/b.xml"));
    assert_eq!(e.location.line_number(), Some(2));
    assert!(e.message.contains("include cycle"), "{e}");
    assert!(
        e.message.contains("a.xml -> ") && e.message.contains("b.xml -> "),
        "{e}"
    );
    let self_include = write(
        &dir,
        "self.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"self.xml\"/>\n</scene>",
    );
    let e = load_err(&self_include);
    assert_eq!(e.kind, ErrorKind::Cycle);
    // Including the same file twice (no cycle) is fine.
    write(
        &dir,
        "leaf.xml",
        r#"<scene version="3.0.0"><shape type="sphere"/></scene>"#,
    );
    let twice = write(
        &dir,
        "twice.xml",
        scene("<include filename=\"leaf.xml\"/>\n<include filename=\"leaf.xml\"/>"),
    );
    assert_eq!(load(&twice).scene.objects.len(), 2);
}

#[test]
fn path_folders_are_searched_before_the_scene_folder() {
    let dir = tmp_dir("path");
    write(&dir, "a.obj", triangle_at(0.0));
    write(&dir, "extra/a.obj", triangle_at(10.0));
    write(&dir, "extra/only.obj", triangle_at(20.0));
    write(&dir, "extra2/a.obj", triangle_at(30.0));
    let shapes = r#"<shape type="obj"><string name="filename" value="a.obj"/></shape>
<shape type="obj"><string name="filename" value="only.obj"/></shape>"#;
    // Mitsuba prepends each <path>: extra/a.obj wins over the scene folder's a.obj.
    let s = write(
        &dir,
        "s1.xml",
        scene(&format!("<path value=\"extra\"/>\n{shapes}")),
    );
    assert_eq!(first_x(&load(&s)), vec![10.0, 20.0]);
    // A <path> after the shapes still applies to them; the last <path> is searched first.
    let s = write(
        &dir,
        "s2.xml",
        scene(&format!(
            "{shapes}\n<path value=\"extra\"/>\n<path value=\"extra2\"/>"
        )),
    );
    assert_eq!(first_x(&load(&s)), vec![30.0, 20.0]);
    // Without the <path>: only.obj is not found, and the error lists the folders searched.
    let s = write(&dir, "s3.xml", scene(shapes));
    let e = load_err(&s);
    assert_eq!(e.kind, ErrorKind::Io);
    assert!(
        e.message.contains("only.obj") && e.message.contains("searched in"),
        "{e}"
    );
    // A missing folder, and a <path> that is not at the top level, are errors.
    let s = write(&dir, "s4.xml", scene(r#"<path value="nosuchdir"/>"#));
    assert!(load_err(&s).message.contains("nosuchdir"));
    let s = write(
        &dir,
        "s5.xml",
        scene(r#"<shape type="sphere"><path value="extra"/></shape>"#),
    );
    assert_eq!(load_err(&s).location.line_number(), Some(7));
    // load_mitsuba_str: relative to base_dir.
    let l = load_mitsuba_str(&scene(&format!("<path value=\"extra\"/>\n{shapes}")), &dir).unwrap();
    assert_eq!(first_x(&l), vec![10.0, 20.0]);
}

#[test]
fn refs_resolve_for_every_object_kind() {
    let xml = scene(
        r#"<shape type="rectangle"><ref id="later"/></shape>
<bsdf type="diffuse" id="later"><rgb name="reflectance" value="0.3"/></bsdf>
<shape type="rectangle"><bsdf type="twosided"><ref id="later"/></bsdf></shape>
<texture type="srgb" id="tex"><rgb name="color" value="0.1, 0.2, 0.3"/></texture>
<shape type="rectangle"><bsdf type="diffuse"><ref name="reflectance" id="tex"/></bsdf></shape>
<shape type="rectangle"><bsdf type="conductor"><texture type="uniform" name="specular_reflectance"><float name="value" value="0.7"/></texture></bsdf></shape>
<emitter type="area" id="light"><rgb name="radiance" value="2"/></emitter>
<shape type="rectangle" id="lamp"><ref id="light"/></shape>
<shape type="rectangle" id="plain"/>
<ref id="plain"/>
<sampler type="independent" id="spp"><integer name="sample_count" value="9"/></sampler>"#,
    )
    .replace(r#"<rfilter type="box"/></film>"#, r#"<rfilter type="box"/></film><ref id="spp"/>"#);
    let l = load_mitsuba_str(&xml, ".").unwrap_or_else(|e| panic!("{e}"));
    for w in &l.warnings {
        println!("{w}");
    }
    // The top-level sampler is only used through the sensor's ref; Mitsuba would also accept it.
    let s = &l.scene;
    let bsdf = |i: usize| s.materials[s.objects[i].material as usize];
    assert_eq!(
        bsdf(0).bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.3)
        }
    );
    assert!(!bsdf(0).two_sided);
    assert_eq!(
        bsdf(1).bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.3)
        }
    );
    assert!(bsdf(1).two_sided);
    assert_eq!(
        bsdf(2).bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::new(0.1, 0.2, 0.3)
        }
    );
    assert_eq!(
        bsdf(3).bsdf,
        Bsdf::Conductor {
            specular_reflectance: Vec3::splat(0.7),
            eta: Vec3::ZERO,
            k: Vec3::ONE,
        }
    );
    // The emitter by reference, and a shape added a second time by the top-level <ref>.
    assert_eq!(s.objects.len(), 7);
    assert_eq!(bsdf(4).emission, Some(Vec3::splat(2.0)));
    assert!(!l
        .warnings
        .iter()
        .any(|w| w.message.contains("must be nested")));
    // Mitsuba gives an emitting shape without a BSDF a black diffuse one.
    assert_eq!(
        bsdf(4).bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::ZERO
        }
    );
    assert_eq!((bsdf(5).emission, bsdf(6).emission), (None, None));
    assert_eq!(s.objects[5].triangles.len(), s.objects[6].triangles.len());
    assert_eq!(s.sample_count, 9);

    let dir = tmp_dir("refs");
    for (body, needle, kind) in [
        (r#"<shape type="sphere"><ref id="zz"/></shape>"#, "zz", ErrorKind::Syntax),
        ("<bsdf type=\"diffuse\" id=\"b\"/>\n<bsdf type=\"conductor\" id=\"b\"/>", "conductor", ErrorKind::Syntax),
        ("<bsdf type=\"twosided\" id=\"a\"><ref id=\"b\"/></bsdf>\n<bsdf type=\"twosided\" id=\"b\"><ref id=\"a\"/></bsdf>", "id=\"a\"", ErrorKind::Cycle),
        (r#"<shape type="sphere"><bsdf type="diffuse"><ref name="reflectance" id="s"/></bsdf></shape><sensor type="perspective" id="s"/>"#, "reflectance", ErrorKind::Syntax),
        (r#"<shape type="sphere"><bsdf type="twosided"><bsdf type="dielectric"/></bsdf></shape>"#, "twosided", ErrorKind::Syntax),
        (r#"<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.1 0.2 0.3"/></bsdf></shape>"#, "spectrum", ErrorKind::Syntax),
    ] {
        let xml = scene(body);
        let e = load_err(&write(&dir, "scene.xml", &xml));
        assert_eq!(e.kind, kind, "{e}");
        assert_eq!(e.location.line_number(), Some(line_of(&xml, needle)), "{e}");
    }
    // One area emitter on two shapes (Mitsuba: "an endpoint can only be attached to a single
    // shape"), here through a top-level <ref> adding the lamp twice.
    let xml = scene("<emitter type=\"area\" id=\"light\"/>\n<shape type=\"sphere\" id=\"lamp\"><ref id=\"light\"/></shape>\n<ref id=\"lamp\"/>");
    let e = load_err(&write(&dir, "shared-emitter.xml", &xml));
    assert_eq!(
        (e.kind, e.location.line_number()),
        (ErrorKind::Unsupported, Some(8))
    );
    let e = load_err(&write(&dir, "cycle.xml", scene("<bsdf type=\"twosided\" id=\"a\"><ref id=\"b\"/></bsdf>\n<bsdf type=\"twosided\" id=\"b\"><ref id=\"a\"/></bsdf>")));
    assert!(e.message.contains("a -> b -> a"), "{e}");
}

/// Textures vary a diffuse reflectance (a plastic's, a conductor's); elsewhere they are refused at their
/// line (strict) or replaced by their mean colour (lenient); a missing image is an error.
#[test]
fn textures_in_bsdfs_strict_and_lenient() {
    let xml = scene(
        r#"<texture type="checkerboard" id="checks"/>
<shape type="rectangle"><bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf></shape>
<shape type="rectangle"><bsdf type="plastic"><ref name="specular_reflectance" id="checks"/></bsdf></shape>"#,
    );
    let e = load_mitsuba_str(&xml, ".").unwrap_err();
    assert_eq!(e.kind, ErrorKind::Unsupported);
    assert_eq!(e.location.line_number(), Some(line_of(&xml, "checks\"/>")));
    assert!(
        e.message.contains("checkerboard")
            && e.message.contains("use --lenient to render without it"),
        "{e}"
    );
    let l = load_mitsuba_str_with(&xml, ".", &lenient()).unwrap();
    let s = &l.scene;
    let m = |i: usize| &s.materials[s.objects[i].material as usize];
    // The diffuse one reads the texture; the plastic's coating its mean (Mitsuba's
    // checkerboard defaults are 0.4 and 0.2).
    assert_eq!(m(0).texture, Some(0));
    assert_eq!(s.textures.len(), 1);
    let cohort_scenes::Bsdf::Plastic {
        specular_reflectance,
        ..
    } = m(1).bsdf
    else {
        panic!("not a plastic")
    };
    assert_eq!(
        (specular_reflectance, m(1).texture),
        (Vec3::splat(0.3), None)
    );
    assert!(l.warnings.iter().any(|w| w.message.contains("mean colour")));
    let missing = scene(
        r#"<shape type="rectangle"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="wood.png"/></texture></bsdf></shape>"#,
    );
    let e = load_mitsuba_str(&missing, ".").unwrap_err();
    assert_eq!(e.kind, ErrorKind::Io);
    assert!(e.message.contains("wood.png"), "{e}");
}

#[test]
fn nested_integrators_use_the_inner_one() {
    let read = |body: &str| {
        let xml = format!(r#"<scene version="3.0.0">{body}</scene>"#);
        load_mitsuba_str(&xml, ".").map(|l| (l.scene.integrator, l.warnings))
    };
    let (i, w) = read(r#"<integrator type="moment"><integrator type="path"><integer name="max_depth" value="7"/></integrator></integrator>"#).unwrap();
    assert_eq!((i.max_depth, i.rr_depth), (7, 5));
    assert!(w.iter().any(|w| w.message.contains("'moment'")));
    let (i, _) = read(r#"<integrator type="aov"><string name="aovs" value="dd.y:depth"/><integrator type="path" name="inner"><integer name="max_depth" value="5"/><integer name="rr_depth" value="3"/><boolean name="hide_emitters" value="true"/></integrator></integrator>"#).unwrap();
    assert_eq!((i.max_depth, i.rr_depth, i.hide_emitters), (5, 3, true));
    let (i, _) =
        read(r#"<integrator type="volpath"><integer name="max_depth" value="4"/></integrator>"#)
            .unwrap();
    assert_eq!(i.max_depth, 4);
    // What Mitsuba rejects.
    for body in [
        r#"<integrator type="path"><integer name="rr_depth" value="0"/></integrator>"#,
        r#"<integrator type="path"><integer name="max_depth" value="-2"/></integrator>"#,
        r#"<integrator type="path"><float name="max_depth" value="2"/></integrator>"#,
        r#"<integrator type="path"/><integrator type="path"/>"#,
    ] {
        assert!(read(body).is_err(), "{body}");
    }
    // `direct` is the path integrator's image at max_depth 2, said in a warning.
    let (i, w) =
        read(r#"<integrator type="direct"><integer name="emitter_samples" value="4"/><boolean name="hide_emitters" value="true"/></integrator>"#)
            .unwrap();
    assert_eq!((i.max_depth, i.hide_emitters), (2, true));
    assert!(w.iter().any(|w| w
        .message
        .contains("'direct' rendered by 'path' with max_depth 2")));
    // max_depth 0 is valid (Mitsuba renders black).
    assert_eq!(
        read(r#"<integrator type="path"><integer name="max_depth" value="0"/></integrator>"#)
            .unwrap()
            .0
            .max_depth,
        0
    );
}

#[test]
fn defaults_and_parameters_as_mitsuba() {
    let radius = |body: &str, params: &[(&str, &str)], lenient: bool| {
        let xml = scene(body);
        let options = LoadOptions {
            params: params
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect(),
            lenient,
        };
        load_mitsuba_str_with(&xml, ".", &options).map(|l| {
            let st = l.scene.stats();
            ((st.bounds_max.x - st.bounds_min.x) / 2.0, l.warnings)
        })
    };
    let close = |r: f32, v: f32| (r - v).abs() < 1e-3 * v;
    let sphere = r#"<shape type="sphere"><float name="radius" value="$r"/></shape>"#;
    let (r, _) = radius(
        &format!("<default name=\"r\" value=\"0.5\"/>\n{sphere}"),
        &[],
        false,
    )
    .unwrap();
    assert!(close(r, 0.5));
    // The caller's value wins, and the first <default> wins over a later one.
    let (r, _) = radius(
        &format!("<default name=\"r\" value=\"0.5\"/>\n{sphere}"),
        &[("r", "3")],
        false,
    )
    .unwrap();
    assert!(close(r, 3.0));
    let (r, _) = radius(
        &format!("<default name=\"r\" value=\"0.5\"/><default name=\"r\" value=\"2\"/>\n{sphere}"),
        &[],
        false,
    )
    .unwrap();
    assert!(close(r, 0.5));
    // A default applies from its element on: used before it, $r is undefined.
    let e = radius(
        &format!("{sphere}\n<default name=\"r\" value=\"0.5\"/>"),
        &[],
        false,
    )
    .unwrap_err();
    assert!(e.message.contains("$r"), "{e}");
    // Text substitution, longest name first: $resx is `res` + "x" unless `resx` is defined.
    let body = r#"<default name="res" value="2"/><shape type="sphere"><float name="radius" value="$resx"/></shape>"#;
    assert!(radius(body, &[], false).unwrap_err().message.contains("2x"));
    let body = r#"<default name="res" value="2"/><default name="resx" value="3"/><shape type="sphere"><float name="radius" value="$resx"/></shape>"#;
    assert!(close(radius(body, &[], false).unwrap().0, 3.0));
    // A <default> nested in an object applies too; \$ is a literal dollar.
    let body = r#"<shape type="sphere" id="a\$b"><default name="q" value="0.25"/><float name="radius" value="$q"/></shape>"#;
    assert!(close(radius(body, &[], false).unwrap().0, 0.25));
    // A parameter the scene never uses: rejected (Mitsuba), a warning when lenient.
    assert_eq!(
        radius("", &[("zz", "3")], false).unwrap_err().kind,
        ErrorKind::Unsupported
    );
    let (_, w) = radius("", &[("zz", "3")], true).unwrap();
    assert!(w.iter().any(|w| w.message.contains("zz=3")));
    // Parameters work in any attribute, e.g. the plugin type.
    let (r, _) = radius(
        r#"<default name="t" value="sphere"/><shape type="$t"/>"#,
        &[],
        false,
    )
    .unwrap();
    assert!(close(r, 1.0));
}

#[test]
fn version_attribute() {
    let with_version = |v: Option<&str>| {
        let attr = v.map(|v| format!(" version=\"{v}\"")).unwrap_or_default();
        format!(
            r#"<scene{attr}><integrator type="path"/><shape type="rectangle"><boolean name="flipNormals" value="true"/><bsdf type="diffuse"><rgb name="diffuseReflectance" value="0.2"/></bsdf></shape></scene>"#
        )
    };
    // No version, or one Mitsuba cannot parse: rejected unless lenient.
    for v in [None, Some("3"), Some("3.0"), Some("abc"), Some("3.0.0.1")] {
        let xml = with_version(v)
            .replace("flipNormals", "flip_normals")
            .replace("diffuseReflectance", "reflectance");
        let e = load_mitsuba_str(&xml, ".").unwrap_err();
        assert_eq!(e.kind, ErrorKind::Unsupported, "{v:?}: {e}");
        let l = load_mitsuba_str_with(&xml, ".", &lenient()).unwrap();
        assert!(
            l.warnings.iter().any(|w| w.message.contains("version")),
            "{v:?}"
        );
    }
    for v in ["3.0.0", "2.1.0", "4.0.0", "3.0.0-rc1", " 3.0.0"] {
        let xml = with_version(Some(v))
            .replace("flipNormals", "flip_normals")
            .replace("diffuseReflectance", "reflectance");
        load_mitsuba_str(&xml, ".").unwrap_or_else(|e| panic!("{v}: {e}"));
    }
    // Before 2.0.0, camelCase names are upgraded (and diffuse_reflectance becomes reflectance).
    let l = load_mitsuba_str(&with_version(Some("0.6.0")), ".").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        l.scene.materials[0].bsdf,
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.2)
        }
    );
    assert!(
        l.scene.triangles.face_normal(0).z < 0.0,
        "flipNormals was not read"
    );
    // ... but not in a 3.x file.
    assert!(load_mitsuba_str(&with_version(Some("3.0.0")), ".").is_err());
}

/// Every kind of plugin: an unknown name is an error at its line (as in Mitsuba) and, lenient,
/// a warning at its line; the scene still loads.
#[test]
fn unknown_plugins_strict_and_lenient() {
    let dir = tmp_dir("unknown");
    let cases = [
        r#"<shape type="sphere"><bsdf type="nosuch"/></shape>"#,
        r#"<bsdf type="nosuch" id="x"/>"#,
        r#"<shape type="nosuch"/>"#,
        r#"<emitter type="nosuch"/>"#,
        r#"<texture type="nosuch"/>"#,
        r#"<medium type="nosuch"/>"#,
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="nosuch" name="reflectance"/></bsdf></shape>"#,
    ];
    let sensor_cases = [
        r#"<sensor type="nosuch"/>"#,
        r#"<sensor type="perspective"><film type="nosuch"/></sensor>"#,
        r#"<sensor type="perspective"><sampler type="nosuch"/></sensor>"#,
        r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="nosuch"/></film></sensor>"#,
    ];
    let mut xmls: Vec<String> = cases.iter().map(|b| scene(b)).collect();
    xmls.extend(
        sensor_cases.iter().map(|b| {
            format!("<scene version=\"3.0.0\">\n<integrator type=\"path\"/>\n{b}\n</scene>")
        }),
    );
    xmls.push("<scene version=\"3.0.0\">\n<integrator type=\"nosuch\"/>\n</scene>".into());
    xmls.push("<scene version=\"3.0.0\">\n<integrator type=\"sphere\"/>\n</scene>".into());
    for xml in &xmls {
        let path = write(&dir, "scene.xml", xml);
        let needle = if xml.contains("nosuch") {
            "nosuch"
        } else {
            "integrator type=\"sphere\""
        };
        let line = line_of(xml, needle);
        let e = load_err(&path);
        assert_eq!(e.kind, ErrorKind::Unsupported, "{e}");
        assert_eq!(e.location.file, path);
        assert_eq!(e.location.line_number(), Some(line), "{e}");
        assert!(e.message.contains("unknown"), "{e}");
        assert!(
            e.message.contains("use --lenient to render without it"),
            "{e}"
        );
        let l = load_mitsuba_with(&path, &lenient()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            l.warnings
                .iter()
                .any(|w| w.location.line_number() == Some(line) && w.message.contains("unknown")),
            "{xml}: {:?}",
            l.warnings
        );
    }
}

/// Plugins Mitsuba has but the renderer does not: errors naming plugin, file and line; lenient,
/// a warning saying what stands in.
#[test]
fn unsupported_plugins_strict_and_lenient() {
    let dir = tmp_dir("unsupported");
    for (body, plugin, instead) in [
        (
            r#"<emitter type="directionalarea"/>"#,
            "emitter 'directionalarea'",
            "skipped",
        ),
        (r#"<emitter type="sunsky"/>"#, "emitter 'sunsky'", "skipped"),
        (
            r#"<shape type="rectangle"><bsdf type="pplastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/></bsdf></shape>"#,
            "bsdf 'pplastic'",
            "diffuse [0.2, 0.4, 0.6]",
        ),
        (
            r#"<shape type="rectangle"><bsdf type="thindielectric"/></shape>"#,
            "bsdf 'thindielectric'",
            "smooth dielectric",
        ),
        (r#"<shape type="sdfgrid"/>"#, "shape 'sdfgrid'", "skipped"),
        (
            r#"<shape type="rectangle"><medium type="homogeneous" name="interior"/></shape>"#,
            "homogeneous",
            "ignored",
        ),
        (
            r#"<sensor type="irradiancemeter"/>"#,
            "sensor 'irradiancemeter'",
            "perspective camera",
        ),
        (
            r#"<sensor type="radiancemeter"/>"#,
            "sensor 'radiancemeter'",
            "perspective camera",
        ),
    ] {
        let xml =
            format!("<scene version=\"3.0.0\">\n<integrator type=\"path\"/>\n{body}\n</scene>");
        let path = write(&dir, "scene.xml", &xml);
        let e = load_err(&path);
        assert_eq!(
            (e.kind, e.location.line_number()),
            (ErrorKind::Unsupported, Some(3)),
            "{e}"
        );
        assert!(e.to_string().contains("scene.xml:3"), "{e}");
        assert!(
            e.message.contains(plugin) && e.message.contains("use --lenient to render without it"),
            "{e}"
        );
        let l = load_mitsuba_with(&path, &lenient()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            l.warnings
                .iter()
                .any(|w| w.location.line_number() == Some(3)
                    && w.message.contains(plugin)
                    && w.message.contains(instead)),
            "{body}: {:?}",
            l.warnings
        );
    }
}

/// Elements, attributes and properties Mitsuba rejects: errors, warnings when lenient.
#[test]
fn unknown_elements_attributes_and_properties() {
    for body in [
        "<wibble/>",
        r#"<shape type="sphere"><wibble/></shape>"#,
        r#"<shape type="sphere" foo="x"/>"#,
        r#"<shape type="sphere"><float name="radius" value="2" foo="1"/></shape>"#,
        r#"<shape type="sphere"><float name="radius" value="1"/><float name="radius" value="2"/></shape>"#,
        r#"<shape type="sphere"><bsdf type="diffuse"><float name="roughness" value="0.3"/></bsdf></shape>"#,
        r#"<shape type="sphere"><transform name="to_world"><shear x="1"/></transform></shape>"#,
        r#"<float name="foo" value="1"/>"#,
        r#"<shape type="sphere"><bsdf type="diffuse"/><bsdf type="conductor"/></shape>"#,
        r#"<emitter type="constant"/><emitter type="constant"/>"#,
        r#"<default name="a" value="0.5" foo="x"/>"#,
    ] {
        let xml = scene(body);
        let e = load_mitsuba_str(&xml, ".").unwrap_err();
        assert_eq!(e.kind, ErrorKind::Unsupported, "{body}: {e}");
        assert_eq!(e.location.line_number(), Some(7), "{body}: {e}");
        let l =
            load_mitsuba_str_with(&xml, ".", &lenient()).unwrap_or_else(|e| panic!("{body}: {e}"));
        assert!(
            l.warnings
                .iter()
                .any(|w| w.location.line_number() == Some(7)),
            "{body}"
        );
    }
    // Always errors: a transform step outside <transform>, a point missing a coordinate.
    for body in [
        r#"<translate x="1"/>"#,
        r#"<shape type="sphere"><point name="center" x="1" y="2"/></shape>"#,
    ] {
        let xml = scene(body);
        assert_eq!(
            load_mitsuba_str_with(&xml, ".", &lenient())
                .unwrap_err()
                .kind,
            ErrorKind::Syntax,
            "{body}"
        );
    }
}

#[test]
fn analytic_disk_and_cylinder_match_mitsuba() {
    let xml = scene(
        r#"<shape type="cylinder"><point name="p0" value="1, 2, 3"/><point name="p1" value="1, 2, 5"/><float name="radius" value="0.5"/></shape>
<shape type="disk"><transform name="to_world"><translate z="1"/></transform></shape>"#,
    );
    let s = load_mitsuba_str(&xml, ".").unwrap().scene;
    let bounds = |i: usize| {
        let o = &s.objects[i];
        let ps =
            &s.triangles.positions[3 * o.triangles.start as usize..3 * o.triangles.end as usize];
        ps.iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(*p), hi.max(*p))
            })
    };
    // Mitsuba: [0.5, 1.5, 3]..[1.5, 2.5, 5] and [-1, -1, 1]..[1, 1, 1].
    let (lo, hi) = bounds(0);
    assert!(
        lo.distance(Vec3::new(0.5, 1.5, 3.0)) < 1e-5
            && hi.distance(Vec3::new(1.5, 2.5, 5.0)) < 1e-5
    );
    let (lo, hi) = bounds(1);
    assert!(lo.distance(Vec3::new(-1.0, -1.0, 1.0)) < 1e-5 && hi.distance(Vec3::ONE) < 1e-5);
    // Cylinder normals face outward, the disk's +z.
    for i in s.objects[0].triangles.clone() {
        let [a, b, c] = s.triangles.vertices(i as usize);
        let mid = (a + b + c) / 3.0;
        let out = Vec3::new(mid.x - 1.0, mid.y - 2.0, 0.0);
        assert!(s.triangles.face_normal(i as usize).dot(out) > 0.0);
    }
    for i in s.objects[1].triangles.clone() {
        assert!(s.triangles.face_normal(i as usize).distance(Vec3::Z) < 1e-5);
    }
}

#[test]
fn lookat_without_up_matches_mitsuba() {
    let xml = r#"<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="1,2,3" target="0,0.5,-1"/></transform></sensor></scene>"#;
    let m = load_mitsuba_str(xml, ".").unwrap().scene.camera.to_world;
    // mitsuba 3.9.1: sensors()[0].world_transform().matrix (row-major).
    let expected = Mat4::from_cols_array(&[
        -0.0407609, 0.972826, -0.227921, 1.0, //
        0.938859, -0.0407609, -0.341882, 2.0, //
        -0.341882, -0.227921, -0.911685, 3.0, //
        0.0, 0.0, 0.0, 1.0,
    ])
    .transpose();
    assert!(m.abs_diff_eq(expected, 1e-5), "{m}");
}

/// Absurd nesting or reference chains are errors, not a stack overflow.
#[test]
fn deep_nesting_and_long_reference_chains_are_refused() {
    let n = 100_000;
    let deep = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<bsdf type=\"twosided\">".repeat(n),
        "</bsdf>".repeat(n)
    );
    let e = load_mitsuba_str(&deep, ".").unwrap_err();
    assert!(e.message.contains("nested deeper"), "{e}");
    let chain: String = (0..5000)
        .map(|i| {
            format!(
                "<bsdf type=\"twosided\" id=\"b{i}\"><ref id=\"b{}\"/></bsdf>\n",
                i + 1
            )
        })
        .collect();
    let xml = scene(&format!(
        "{chain}<bsdf type=\"diffuse\" id=\"b5000\"/>\n<shape type=\"sphere\"><ref id=\"b0\"/></shape>"
    ));
    let e = load_mitsuba_str(&xml, ".").unwrap_err();
    assert!(e.message.contains("nested deeper"), "{e}");
    // Ordinary depths are fine.
    let xml = scene(&format!(
        "{}<bsdf type=\"diffuse\"/>{}",
        "<shape type=\"sphere\"><bsdf type=\"twosided\">", "</bsdf></shape>"
    ));
    load_mitsuba_str(&xml, ".").unwrap();
}

/// Sensor and film parameters the renderer cannot honour are warnings, not silence (a crop
/// window is honoured: `mitsuba_sensors.rs`).
#[test]
fn ignored_camera_and_film_parameters_warn() {
    let xml = r#"<scene version="3.0.0"><integrator type="path"/><sensor type="perspective"><float name="near_clip" value="1"/><float name="principal_point_offset_x" value="0.1"/><film type="hdrfilm"><string name="pixel_format" value="luminance"/><integer name="crop_width" value="4"/><rfilter type="gaussian"/></film><sampler type="stratified"/></sensor></scene>"#;
    let l = load_mitsuba_str(xml, ".").unwrap();
    for needle in [
        "near_clip",
        "principal_point_offset_x",
        "luminance",
        "stratified",
    ] {
        assert!(
            l.warnings.iter().any(|w| w.message.contains(needle)),
            "{needle}: {:?}",
            l.warnings
        );
    }
    let bad = xml.replace(r#"value="1"/>"#, r#"value="0"/>"#);
    assert!(load_mitsuba_str(&bad, ".").is_err());
}

/// Reconstruction filters as Mitsuba reads them: its default gaussian when a film names none,
/// each filter's parameters, `sample_border`, and errors for values Mitsuba would refuse.
#[test]
fn reconstruction_filters() {
    use cohort_scenes::{FilmFilter, FilterKind};
    let film = |inner: &str| {
        format!(
            r#"<scene version="3.0.0"><integrator type="path"/><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>{inner}</film></sensor><shape type="sphere"/></scene>"#
        )
    };
    let filter = |inner: &str| {
        load_mitsuba_str(&film(inner), ".")
            .unwrap()
            .scene
            .camera
            .filter
    };
    assert_eq!(filter(""), Some(FilmFilter::gaussian(0.5)));
    assert_eq!(filter(r#"<rfilter type="box"/>"#), None);
    let g = filter(r#"<rfilter type="gaussian"><float name="stddev" value="0.25"/></rfilter>"#)
        .unwrap();
    assert_eq!(
        (g.kind, g.radius),
        (FilterKind::Gaussian { stddev: 0.25 }, 1.0)
    );
    let t = filter(r#"<boolean name="sample_border" value="true"/><rfilter type="tent"><float name="radius" value="1.5"/></rfilter>"#).unwrap();
    assert_eq!(
        (t.kind, t.radius, t.sample_border, t.border()),
        (FilterKind::Tent, 1.5, true, 1)
    );
    let m = filter(r#"<rfilter type="mitchell"><float name="B" value="0"/><float name="C" value="0.5"/></rfilter>"#).unwrap();
    assert_eq!(m.values, FilmFilter::catmull_rom().values);
    assert_eq!(
        filter(r#"<rfilter type="lanczos"><integer name="lobes" value="2"/></rfilter>"#)
            .unwrap()
            .radius,
        2.0
    );
    // No film at all: Mitsuba's default film, with its default filter.
    let l = load_mitsuba_str(r#"<scene version="3.0.0"><integrator type="path"/><sensor type="perspective"/><shape type="sphere"/></scene>"#, ".").unwrap();
    assert_eq!(l.scene.camera.filter, Some(FilmFilter::gaussian(0.5)));
    for bad in [
        r#"<rfilter type="gaussian"><float name="stddev" value="-1"/></rfilter>"#,
        r#"<rfilter type="lanczos"><integer name="lobes" value="0"/></rfilter>"#,
        r#"<rfilter type="tent"><float name="radius" value="0"/></rfilter>"#,
    ] {
        let e = load_mitsuba_str(&film(bad), ".").unwrap_err().to_string();
        assert!(e.contains("rfilter"), "{e}");
    }
}

/// Conductors as Mitsuba reads them: a `material` name gives its complex index (the values
/// Mitsuba's RGB variants use, `scripts/conductor_iors.py`), `eta` and `k` give it directly
/// (defaults 0 and 1), both together are an error, and the microfacet distribution defaults
/// to Beckmann.
#[test]
fn conductor_materials_and_distributions() {
    use cohort_scenes::material::Microfacet;
    let load = |bsdf: &str| {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="sphere">{bsdf}</shape></scene>"#
        );
        load_mitsuba_str(&xml, ".").map(|l| l.scene.materials[0].bsdf)
    };
    let Bsdf::Conductor { eta, k, .. } =
        load(r#"<bsdf type="conductor"><string name="material" value="Au"/></bsdf>"#).unwrap()
    else {
        panic!("not a conductor")
    };
    // Mitsuba 3.9.1, scalar_rgb: mi.traverse(conductor Au) eta.value, k.value.
    assert!(
        (eta - Vec3::new(0.143036, 0.375307, 1.44205))
            .abs()
            .max_element()
            < 1e-5,
        "{eta}"
    );
    assert!(
        (k - Vec3::new(3.983, 2.38556, 1.60336)).abs().max_element() < 1e-5,
        "{k}"
    );
    let Bsdf::Conductor { eta, k, .. } = load(r#"<bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><float name="k" value="3"/></bsdf>"#).unwrap() else {
        panic!("not a conductor")
    };
    assert_eq!((eta, k), (Vec3::new(0.2, 0.9, 1.1), Vec3::splat(3.0)));
    let Bsdf::RoughConductor {
        distribution,
        alpha,
        ..
    } = load(r#"<bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>"#).unwrap()
    else {
        panic!("not a rough conductor")
    };
    assert_eq!(
        (distribution, alpha),
        (
            Microfacet::Beckmann,
            cohort_scenes::Roughness::isotropic(0.3)
        )
    );
    let Bsdf::RoughConductor { distribution, .. } =
        load(r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/></bsdf>"#)
            .unwrap()
    else {
        panic!("not a rough conductor")
    };
    assert_eq!(distribution, Microfacet::Ggx);
    for (bad, needle) in [
        (
            r#"<bsdf type="conductor"><string name="material" value="Au"/><float name="eta" value="1"/></bsdf>"#,
            "not both",
        ),
        (
            r#"<bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf>"#,
            "unknown conductor material",
        ),
        (
            r#"<bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf>"#,
            "distribution",
        ),
    ] {
        let e = load(bad).unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }
}

/// Mitsuba `blendbsdf`: the first BSDF is the material, the second its own material chosen
/// with probability `weight` (a nested blend second chooses again; one nested first is
/// moved second with weight 1 - w); a missing weight or a wrong number of BSDFs is an
/// error at the blend; a smooth (delta) BSDF in a blend warns only beside a masked BSDF.
#[test]
fn blend_bsdfs_become_chained_materials() {
    let diffuse =
        |r: f32| format!(r#"<bsdf type="diffuse"><rgb name="reflectance" value="{r}"/></bsdf>"#);
    let xml = |bsdf: String| {
        format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="rectangle">{bsdf}</shape></scene>"#
        )
    };
    let nested = format!(
        r#"<bsdf type="blendbsdf"><float name="weight" value="0.25"/>{}{}</bsdf>"#,
        diffuse(0.2),
        diffuse(0.3)
    );
    let outer = format!(
        r#"<bsdf type="blendbsdf"><float name="weight" value="0.6"/>{nested}{}</bsdf>"#,
        diffuse(0.1)
    );
    let s = cohort_scenes::load_mitsuba_str(&xml(outer), ".")
        .unwrap()
        .scene;
    let m = s.material_of(0);
    // The nested blend came first: it is moved second, with weight 1 - 0.6.
    assert_eq!(
        m.bsdf,
        cohort_scenes::Bsdf::Diffuse {
            reflectance: Vec3::splat(0.1)
        }
    );
    let b = m.blend.expect("a blend");
    assert!((b.weight - 0.4).abs() < 1e-6, "{}", b.weight);
    let second = &s.materials[b.other as usize];
    assert_eq!(
        second.bsdf,
        cohort_scenes::Bsdf::Diffuse {
            reflectance: Vec3::splat(0.2)
        }
    );
    let third = second.blend.expect("the nested blend's second");
    assert_eq!(third.weight, 0.25);
    assert_eq!(
        s.materials[third.other as usize].bsdf,
        cohort_scenes::Bsdf::Diffuse {
            reflectance: Vec3::splat(0.3)
        }
    );
    let g = s.gpu_materials();
    let first_gpu = g[s.triangles.materials[0] as usize];
    assert_eq!(
        (first_gpu.blend, first_gpu.blend_weight),
        (b.other + 1, b.weight)
    );

    let no_weight = format!(
        r#"<bsdf type="blendbsdf">{}{}</bsdf>"#,
        diffuse(0.2),
        diffuse(0.3)
    );
    let e = cohort_scenes::load_mitsuba_str(&xml(no_weight), ".")
        .unwrap_err()
        .to_string();
    assert!(e.contains("blendbsdf needs a 'weight'"), "{e}");
    let one = format!(
        r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/>{}</bsdf>"#,
        diffuse(0.2)
    );
    let e = cohort_scenes::load_mitsuba_str(&xml(one), ".")
        .unwrap_err()
        .to_string();
    assert!(e.contains("exactly two nested BSDFs, not 1"), "{e}");
    // A delta BSDF in a blend is weighed as Mitsuba weighs it: no warning; with a masked
    // BSDF beside it, it is not, and the loader says so.
    let delta_warns = |other: String| {
        let blend = format!(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/>{other}<bsdf type="conductor"/></bsdf>"#
        );
        let loaded = cohort_scenes::load_mitsuba_str(&xml(blend), ".").unwrap();
        loaded
            .warnings
            .iter()
            .any(|w| w.message.contains("smooth (delta) BSDF"))
    };
    assert!(!delta_warns(diffuse(0.2)));
    assert!(delta_warns(format!(
        r#"<bsdf type="mask"><float name="opacity" value="0.5"/>{}</bsdf>"#,
        diffuse(0.2)
    )));
}

/// A rough conductor's roughness as Mitsuba reads it: `alpha_u` and `alpha_v` together
/// (anisotropic), either as a texture read as a number (a checkerboard's colours swap, as
/// Mitsuba's `eval_1` reads it); `alpha` with them, or one of them alone, is an error.
#[test]
fn rough_conductor_roughness_anisotropic_and_textured() {
    use cohort_scenes::Roughness;
    let load = |bsdf: &str| {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="path"/><shape type="sphere">{bsdf}</shape></scene>"#
        );
        load_mitsuba_str(&xml, ".").map(|l| l.scene)
    };
    let alpha = |s: &cohort_scenes::Scene| match s.materials[0].bsdf {
        Bsdf::RoughConductor { alpha, .. } => alpha,
        other => panic!("not a rough conductor: {other:?}"),
    };
    let s = load(r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.25"/><float name="alpha_v" value="0.05"/></bsdf>"#).unwrap();
    assert_eq!(
        alpha(&s),
        Roughness {
            u: 0.25,
            v: 0.05,
            u_texture: None,
            v_texture: None
        }
    );
    let s = load(r#"<bsdf type="roughconductor"><texture type="checkerboard" name="alpha_u"><float name="color0" value="0.05"/><float name="color1" value="0.3"/></texture><float name="alpha_v" value="0.1"/></bsdf>"#).unwrap();
    let a = alpha(&s);
    assert_eq!((a.v, a.v_texture), (0.1, None));
    let t = a.u_texture.expect("a textured alpha_u");
    assert!(
        matches!(s.textures[t as usize], cohort_scenes::Texture::Checkerboard { color0, .. } if color0 == Vec3::splat(0.3)),
        "read as a number, the checkerboard's colours swap"
    );
    assert!(!a.is_constant_isotropic());
    assert!(alpha(
        &load(r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#).unwrap()
    )
    .is_constant_isotropic());
    for (bad, needle) in [
        (
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/><float name="alpha_u" value="0.2"/><float name="alpha_v" value="0.2"/></bsdf>"#,
            "not both",
        ),
        (
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.2"/></bsdf>"#,
            "both 'alpha_u' and 'alpha_v'",
        ),
        (
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="-1"/><float name="alpha_v" value="0.2"/></bsdf>"#,
            "alpha_u must be >= 0",
        ),
    ] {
        let e = load(bad).unwrap_err();
        assert!(e.message.contains(needle), "{bad}: {e}");
    }
}
