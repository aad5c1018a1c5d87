//! The `cohort` command as a user runs it: listing scenes, rendering small images,
//! clear errors for bad input, and outputs that a failed run never clobbers.

use std::process::Command;

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
}

/// Asserts that a run succeeded, showing what it wrote to stderr if it did not.
fn assert_ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn has_gpu() -> bool {
    cohort::runtime::Device::for_tests(cohort::runtime::BackendKind::Vulkan).is_some()
}

#[test]
fn lists_embedded_scenes() {
    let out = cohort().arg("scenes").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["cornell", "confroom", "fairyforest", "sponza", "stanford"] {
        assert!(text.contains(name), "missing {name} in:\n{text}");
    }
}

#[test]
fn the_png_goes_beside_the_exr_unless_named() {
    let dir = tempdir();
    let render = |extra: &[&std::ffi::OsStr]| {
        cohort()
            .current_dir(&dir)
            .args(["render", "--width", "8", "--height", "8", "--paths", "2"])
            .args(["--backend", "cpu"])
            .args(extra)
            .output()
            .unwrap()
    };
    // Two shards with their own --out keep one PNG each, beside their EXRs.
    std::fs::create_dir(dir.join("s")).unwrap();
    for k in ["0", "1"] {
        let exr = dir.join("s").join(format!("part{k}.exr"));
        let shard = format!("{k}/2");
        let out = render(&[
            "--shard".as_ref(),
            shard.as_ref(),
            "--out".as_ref(),
            exr.as_ref(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let png = std::fs::read(dir.join("s").join(format!("part{k}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
    }
    assert!(
        !dir.join("render.png").exists(),
        "a PNG was written where the command ran"
    );
    // An --out that would be the PNG's name too is refused before anything renders.
    let out = render(&["--out".as_ref(), "x.png".as_ref()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("x.png") && err.contains("--png"), "{err}");
    assert!(!dir.join("x.png").exists());
    // --png still names it.
    let out = render(&[
        "--out".as_ref(),
        "x.png".as_ref(),
        "--png".as_ref(),
        "y.png".as_ref(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(dir.join("y.png")).unwrap()[1..4], b"PNG");
}

/// A library named by `COHORT_LIBLLVM` that loads but cannot run the JIT (here libm, which
/// is no LLVM at all) leaves the CPU backend on its host forms, and `cohort devices` says
/// which library was refused and why; the render still runs.
#[test]
fn a_libllvm_that_cannot_run_the_jit_is_named_with_its_reason() {
    let dir = tempdir();
    let out = cohort()
        .current_dir(&dir)
        .arg("devices")
        .env("COHORT_LIBLLVM", "libm.so.6")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let cpu = text
        .lines()
        .find(|l| l.starts_with("cpu"))
        .unwrap_or_default();
    assert!(
        cpu.contains("host forms (no libLLVM (15 or newer) could run the JIT (libm.so.6: ")
            && cpu.contains("LLVMInitializeX86TargetInfo"),
        "{text}"
    );
    let out = cohort()
        .current_dir(&dir)
        .args(["render", "--width", "8", "--height", "8", "--paths", "1"])
        .args(["--backend", "cpu"])
        .env("COHORT_LIBLLVM", "libm.so.6")
        .env("COHORT_CPU_SIMD", "vector")
        .output()
        .unwrap();
    assert_ok(&out);
}

/// `COHORT_CPU_SIMD_PERF_MAP=1` names the vector forms of a render's kernels, at their
/// code's address and size, in the map `perf` reads (`/tmp/perf-PID.map`).
#[test]
fn the_perf_map_names_the_vector_forms() {
    if let Err(e) = cohort::runtime::cpu::simd::llvm_library() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and no vector form: {e}"
        );
        return;
    }
    let dir = tempdir();
    let child = cohort()
        .current_dir(&dir)
        .args(["render", "--width", "16", "--height", "16", "--paths", "1"])
        .args(["--backend", "cpu"])
        .env("COHORT_CPU_SIMD", "vector")
        .env("COHORT_CPU_SIMD_PERF_MAP", "1")
        .env("COHORT_CACHE_DIR", dir.join("cache"))
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let map = std::path::PathBuf::from(format!("/tmp/perf-{}.map", child.id()));
    let out = child.wait_with_output().unwrap();
    assert_ok(&out);
    let text = std::fs::read_to_string(&map).unwrap_or_default();
    let _ = std::fs::remove_file(&map);
    let entries: Vec<(u64, u64, &str)> = text
        .lines()
        .map(|l| {
            let mut f = l.splitn(3, ' ');
            let mut hex = || u64::from_str_radix(f.next().unwrap(), 16).unwrap();
            let (addr, size) = (hex(), hex());
            (addr, size, f.next().unwrap())
        })
        .collect();
    for kernel in ["init_paths", "traverse8", "extend"] {
        assert!(
            entries.iter().any(|(a, s, name)| *a > 0
                && *s > 0
                && name.starts_with(&format!("cohort vector form {kernel}__"))),
            "no entry for `{kernel}` in {}:\n{text}",
            map.display()
        );
    }
    // No two kernels' code overlaps.
    let mut spans: Vec<(u64, u64)> = entries.iter().map(|(a, s, _)| (*a, a + s)).collect();
    spans.sort();
    assert!(spans.windows(2).all(|w| w[0].1 <= w[1].0), "{text}");
}

#[test]
fn renders_and_writes_outputs() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    let (exr, png, stats) = (dir.join("a.exr"), dir.join("a.png"), dir.join("a.json"));
    let out = cohort()
        .args([
            "render",
            "--width",
            "24",
            "--height",
            "16",
            "--paths",
            "2",
            "--backend",
            "vulkan",
        ])
        .arg("--out")
        .arg(&exr)
        .arg("--png")
        .arg(&png)
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(std::fs::metadata(&exr).unwrap().len() > 100);
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[1..4], b"PNG");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["width"], 24);
    assert_eq!(json["paths_per_pixel"], 2.0);
    // Forms are the CPU backend's alone.
    assert_eq!(json["cpu_forms"], serde_json::json!({}));
    assert!(!String::from_utf8_lossy(&out.stdout).contains("cpu forms"));
    // Each pipeline thread's time, by its kernels' names: the stages this render uses.
    let kernels = json["startup_s"]["kernels"].as_object().unwrap();
    for stage in ["init_paths", "traverse", "extend"] {
        assert!(
            kernels.keys().any(|k| k.contains(stage)),
            "no {stage} in {kernels:?}"
        );
    }
    assert!(kernels
        .values()
        .all(|t| t.as_f64().is_some_and(|t| t >= 0.0)));
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
}

#[test]
fn bad_input_fails_clearly_and_keeps_existing_outputs() {
    let dir = tempdir();
    let png = dir.join("keep.png");
    std::fs::write(&png, b"good image").unwrap();
    let bad_xml = dir.join("bad.xml");
    std::fs::write(&bad_xml, "<scene version=\"3.0.0\">\n  <shape type=\"obj\">\n    <string name=\"filename\" value=\"missing.obj\"/>\n  </shape>\n</scene>\n").unwrap();
    for args in [
        vec![
            "render".to_string(),
            "--scene".into(),
            "no-such-scene".into(),
        ],
        vec![
            "render".to_string(),
            "--scene".into(),
            bad_xml.display().to_string(),
        ],
        vec!["render".to_string(), "--paths".into(), "0".into()],
        vec!["render".to_string(), "--algorithm".into(), "bogus".into()],
        vec!["render".to_string(), "--backend".into(), "metal".into()],
        vec!["render".to_string(), "--rr".into(), "sometimes".into()],
        vec![
            "render".to_string(),
            "--algorithm".into(),
            "grid".into(),
            "--rr".into(),
            "whole".into(),
        ],
        vec![
            "render".to_string(),
            "--algorithm".into(),
            "warp".into(),
            "--rr".into(),
            "whole".into(),
            "--end-continue".into(),
            "0".into(),
        ],
    ] {
        let out = cohort()
            .args(&args)
            .arg("--png")
            .arg(&png)
            .arg("--out")
            .arg(dir.join("x.exr"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
        assert_eq!(
            std::fs::read(&png).unwrap(),
            b"good image",
            "{args:?} clobbered the output"
        );
    }
    // The XML error names the file and line.
    let out = cohort()
        .args(["render", "--scene"])
        .arg(&bad_xml)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.xml") && err.contains(":3"), "{err}");
    // An output whose directory does not exist fails before the render, naming the path,
    // and the other output (written first, before this was checked) is untouched.
    let out = cohort()
        .args([
            "render",
            "--backend",
            "cpu",
            "--width",
            "16",
            "--height",
            "16",
        ])
        .args(["--paths", "1"])
        .arg("--out")
        .arg(dir.join("no-such-dir").join("x.exr"))
        .arg("--png")
        .arg(&png)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no-such-dir") && err.contains("does not exist"),
        "{err}"
    );
    assert_eq!(std::fs::read(&png).unwrap(), b"good image");
}

/// Whole-group termination is reachable from the command line and recorded in the stats.
#[test]
fn renders_with_whole_group_termination() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    let stats = dir.join("w.json");
    let out = cohort()
        .args([
            "render",
            "--width",
            "32",
            "--height",
            "32",
            "--paths",
            "2",
            "--backend",
            "vulkan",
            "--algorithm",
            "warp",
            "--rr",
            "whole",
        ])
        .args(["--end-continue", "0.25", "--n", "8"])
        .arg("--out")
        .arg(dir.join("w.exr"))
        .arg("--png")
        .arg(dir.join("w.png"))
        .arg("--stats")
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("whole-group end (q = 0.25)"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["whole_group_end"], 0.25);
    assert_eq!(json["group_rr"], true);
    assert_eq!(json["paths_per_pixel"], 2.0);
}

fn tempdir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!(
        "cohort-cli-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}
/// A sensor and an integrator for the small scenes below (8 x 8 pixels).
const SETUP: &str = r#"<integrator type="path"/>
<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>"#;

fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(&p, text).unwrap();
    p
}

fn scene_file(dir: &std::path::Path, name: &str, body: &str) -> std::path::PathBuf {
    write(
        dir,
        name,
        &format!("<scene version=\"3.0.0\">\n{SETUP}\n{body}\n</scene>\n"),
    )
}

/// `cohort render --scene <scene>` with small outputs in `dir`; returns (exit code, stdout, stderr).
fn render_scene(
    dir: &std::path::Path,
    scene: &std::path::Path,
    extra: &[&str],
) -> (i32, String, String) {
    let out = cohort()
        .args(["render", "--paths", "2", "--backend", "vulkan", "--scene"])
        .arg(scene)
        .arg("--out")
        .arg(dir.join("r.exr"))
        .arg("--png")
        .arg(dir.join("r.png"))
        .arg("--stats")
        .arg(dir.join("r.json"))
        .args(extra)
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    (
        code,
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Broken scenes of every kind end with exit 1 and an error naming the problem, never a panic
/// (exit 101). These fail while loading, before any GPU work.
#[test]
fn broken_scenes_fail_cleanly() {
    let dir = tempdir();
    write(
        &dir,
        "cycle-a.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"cycle-b.xml\"/>\n</scene>",
    );
    write(
        &dir,
        "cycle-b.xml",
        "<scene version=\"3.0.0\">\n<include filename=\"cycle-a.xml\"/>\n</scene>",
    );
    let cases = [
        (
            scene_file(
                &dir,
                "mesh.xml",
                r#"<shape type="obj"><string name="filename" value="gone.obj"/></shape>"#,
            ),
            vec!["mesh.xml:4", "gone.obj", "not found"],
        ),
        (
            dir.join("cycle-a.xml"),
            vec!["include cycle", "cycle-a.xml -> ", "cycle-b.xml -> "],
        ),
        (
            scene_file(
                &dir,
                "include.xml",
                r#"<include filename="parts/gone.xml"/>"#,
            ),
            vec!["include.xml:4", "parts/gone.xml", "not found"],
        ),
        (
            scene_file(
                &dir,
                "unknown.xml",
                r#"<shape type="sphere"><bsdf type="nosuch"/></shape>"#,
            ),
            vec![
                "unknown.xml:4",
                "unknown bsdf plugin 'nosuch'",
                "use --lenient to render without it",
            ],
        ),
        (
            // A plugin Mitsuba has and the renderer does not (point lights are supported).
            scene_file(&dir, "sunsky.xml", r#"<emitter type="sunsky"/>"#),
            vec![
                "sunsky.xml:4",
                "emitter 'sunsky'",
                "use --lenient to render without it",
            ],
        ),
        (
            scene_file(
                &dir,
                "ref.xml",
                r#"<shape type="sphere"><ref id="nothing"/></shape>"#,
            ),
            vec!["ref.xml:4", "nothing"],
        ),
        (
            scene_file(
                &dir,
                "param.xml",
                r#"<shape type="sphere"><float name="radius" value="$r"/></shape>"#,
            ),
            vec!["param.xml:4", "$r"],
        ),
        (
            write(
                &dir,
                "xml.xml",
                "<scene version=\"3.0.0\">\n<shape>\n</scene>",
            ),
            vec!["xml.xml:3", "malformed XML"],
        ),
        (
            write(&dir, "noversion.xml", "<scene>\n</scene>"),
            vec!["noversion.xml:1", "version"],
        ),
        (write(&dir, "empty-file.xml", ""), vec!["empty-file.xml"]),
    ];
    for (scene, expected) in cases {
        let (code, _, err) = render_scene(&dir, &scene, &[]);
        assert_eq!(code, 1, "{}: exit {code}\n{err}", scene.display());
        assert!(err.contains("error:") && !err.contains("panicked"), "{err}");
        for e in expected {
            assert!(err.contains(e), "{}: no '{e}' in:\n{err}", scene.display());
        }
    }
}

/// A negative number for a numeric option is a value error naming the option (clap's value
/// parser), not "unexpected argument"; options that may be negative accept it.
#[test]
fn negative_numbers_are_value_errors() {
    for (flag, value) in [
        ("--paths", "-1"),
        ("--width", "-1"),
        ("--height", "-5"),
        ("--seed", "-3"),
        ("--n", "-2"),
        ("--interleave", "-1"),
        ("--light-cells", "-4"),
    ] {
        let out = cohort().args(["render", flag, value]).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: {err}");
        let upper = flag
            .trim_start_matches("--")
            .replace('-', "_")
            .to_uppercase();
        assert!(
            err.contains(&format!("invalid value '{value}' for '{flag} <{upper}>'")),
            "{err}"
        );
        assert!(!err.contains("unexpected argument"), "{err}");
    }
    // Numbers with a range are checked by the parser too: a usage error naming the option.
    for args in [
        vec!["render", "--time", "-1"],
        vec![
            "render",
            "--end-continue",
            "-0.5",
            "--rr",
            "whole",
            "--algorithm",
            "warp",
        ],
        vec!["render", "--reorder", "-1"],
        vec!["figures", "--time", "-1"],
        vec!["compare", "a.exr", "b.exr", "--tolerance", "-1"],
    ] {
        let out = cohort().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        // The option given a negative value is named.
        let flag = args
            .windows(2)
            .find(|w| w[1].starts_with("-0") || w[1] == "-1")
            .map(|w| w[0])
            .unwrap();
        assert!(
            err.contains("invalid value '-") && err.contains(flag),
            "{args:?}: {err}"
        );
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
    // --exposure -1 is a valid value: the run gets as far as the next error.
    let out = cohort()
        .args(["render", "--exposure", "-1", "--paths", "0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("invalid value '0' for '--paths <PATHS>'"),
        "{err}"
    );
    let out = cohort().args(["render", "-D", "novalue"]).output().unwrap();
    assert!(String::from_utf8_lossy(&out.stderr).contains("expected NAME=VALUE"));
}

/// An empty scene renders black and a scene with only a constant emitter renders its radiance
/// (once a bytemuck panic, exit 101).
#[test]
fn empty_and_emitter_only_scenes_render() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    for (name, body, mean) in [
        ("empty.xml", "", "0.0000 0.0000 0.0000"),
        (
            "env.xml",
            r#"<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#,
            "0.5000 0.5000 0.5000",
        ),
        (
            "no-area-light.xml",
            r#"<shape type="sphere"/>"#,
            "0.0000 0.0000 0.0000",
        ),
    ] {
        let scene = scene_file(&dir, name, body);
        for integrator in ["nee", "path"] {
            let (code, out, err) = render_scene(&dir, &scene, &["--integrator", integrator]);
            assert_eq!(code, 0, "{name} {integrator}: {err}");
            assert!(
                out.contains(&format!("mean radiance  {mean}")),
                "{name} {integrator}: {out}"
            );
        }
    }
}

/// Strict refuses what the renderer does not implement; --lenient renders without it, warning.
#[test]
fn lenient_renders_what_strict_refuses() {
    let dir = tempdir();
    let scene = scene_file(
        &dir,
        "lenient.xml",
        "<emitter type=\"sunsky\"/>\n<shape type=\"rectangle\"><bsdf type=\"pplastic\"><rgb name=\"diffuse_reflectance\" value=\"0.2, 0.4, 0.6\"/></bsdf></shape>\n<emitter type=\"constant\"/>",
    );
    let (code, _, err) = render_scene(&dir, &scene, &[]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("lenient.xml:4") && err.contains("use --lenient to render without it"),
        "{err}"
    );
    if !has_gpu() {
        return;
    }
    let (code, _, err) = render_scene(&dir, &scene, &["--lenient"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("lenient.xml:4: warning: emitter 'sunsky' is not supported"),
        "{err}"
    );
    assert!(
        err.contains("lenient.xml:5: warning: bsdf 'pplastic' is not supported")
            && err.contains("replaced by diffuse [0.2, 0.4, 0.6]"),
        "{err}"
    );
}

/// The scene-file structure end to end: an <include>d part, a <path> search folder, a <ref> in
/// a BSDF (twosided around a ref'd BSDF, a ref'd texture), a nested integrator's max_depth and
/// -D overriding a <default>.
#[test]
fn scene_structure_end_to_end() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    write(
        &dir,
        "assets/quad.obj",
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n",
    );
    write(
        &dir,
        "parts/light.xml",
        r#"<scene version="3.0.0"><shape type="rectangle"><transform name="to_world"><translate z="2"/></transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>"#,
    );
    let scene = write(
        &dir,
        "structure.xml",
        r#"<scene version="3.0.0">
<default name="res" value="16"/>
<path value="assets"/>
<integrator type="moment"><integrator type="path"><integer name="max_depth" value="3"/></integrator></integrator>
<sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/><rfilter type="box"/></film></sensor>
<include filename="parts/light.xml"/>
<texture type="srgb" id="grey"><rgb name="color" value="0.5"/></texture>
<bsdf type="diffuse" id="paint"><ref name="reflectance" id="grey"/></bsdf>
<shape type="obj"><string name="filename" value="quad.obj"/><bsdf type="twosided"><ref id="paint"/></bsdf></shape>
</scene>
"#,
    );
    let (code, _, err) = render_scene(&dir, &scene, &["-D", "res=8"]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(
        (json["width"].as_u64(), json["height"].as_u64()),
        (Some(8), Some(8))
    );
    assert_eq!(json["triangles"], 4);
    assert_eq!(json["scene_integrator"]["max_depth"], 3);
    // Without -D the <default> applies; an unused -D is refused as in Mitsuba.
    let (code, _, err) = render_scene(&dir, &scene, &[]);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(json["width"], 16);
    let (code, _, err) = render_scene(&dir, &scene, &["-D", "nosuch=1"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("nosuch=1"), "{err}");
}
/// Without --paths, a Mitsuba scene renders its sampler's sample_count (embedded scenes: 64).
#[test]
fn xml_scene_renders_its_sample_count() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    let scene = write(
        &dir,
        "spp.xml",
        r#"<scene version="3.0.0"><integrator type="path"/>
<sensor type="perspective"><sampler type="independent"><integer name="sample_count" value="3"/></sampler><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
<emitter type="constant"/></scene>"#,
    );
    let out = cohort()
        .args(["render", "--backend", "vulkan", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(dir.join("s.exr"))
        .arg("--png")
        .arg(dir.join("s.png"))
        .arg("--stats")
        .arg(dir.join("s.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(json["paths_per_pixel"], 3.0);
}

/// `--wavefront` sets the slots in flight (whole copies of the image, at most one per path
/// of the budget), and `--stats` and the summary report them.
#[test]
fn the_wavefront_is_chosen_and_reported() {
    let dir = tempdir();
    for (wavefront, slots) in [
        ("1", 24 * 16),
        ("1000", 3 * 24 * 16),
        ("100000", 4 * 24 * 16),
    ] {
        let stats = dir.join(format!("w{wavefront}.json"));
        let out = cohort()
            .args([
                "render",
                "--backend",
                "cpu",
                "--width",
                "24",
                "--height",
                "16",
            ])
            .args(["--paths", "4", "--wavefront", wavefront, "--out"])
            .arg(dir.join("w.exr"))
            .arg("--png")
            .arg(dir.join("w.png"))
            .arg("--stats")
            .arg(&stats)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("{slots} slots in flight")), "{text}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(json["slots"], slots, "--wavefront {wavefront}");
        assert_eq!(json["paths_per_pixel"], 4.0);
        // The CPU backend says which form ran each dispatch: one traversal and one
        // `extend` per iteration.
        assert!(text.contains("cpu forms      init_paths "), "{text}");
        let forms = json["cpu_forms"].as_object().unwrap();
        for stage in ["traverse", "extend"] {
            let (_, c) = forms
                .iter()
                .find(|(k, _)| k.starts_with(stage))
                .unwrap_or_else(|| panic!("no {stage} in {forms:?}"));
            let total: u64 = ["vector", "host", "pending", "host_only", "whole"]
                .iter()
                .map(|f| c[f].as_u64().unwrap())
                .sum();
            assert_eq!(json["iterations"], total, "{stage}: {c}");
        }
    }
    let out = cohort()
        .args(["render", "--backend", "cpu", "--wavefront", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "--wavefront 0 is a usage error");
}

/// `COHORT_CPU_SIMD_LANES` sets the block width of the CPU backend's vector forms, and
/// `cohort devices` says it; a width the vector forms do not take is named in a warning,
/// and the CPU's register width (8 or 16) stays.
#[test]
fn cohort_cpu_simd_lanes_sets_the_vector_width() {
    let llvm = cohort::runtime::cpu::simd::llvm_library().is_ok();
    for (value, lanes) in [("32", &["32"][..]), ("12", &["8", "16"][..])] {
        let out = cohort()
            .arg("devices")
            .env("COHORT_CPU_SIMD_LANES", value)
            .output()
            .unwrap();
        assert_ok(&out);
        let (text, err) = (
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr),
        );
        let cpu = text
            .lines()
            .find(|l| l.starts_with("cpu"))
            .unwrap_or_default();
        if llvm {
            assert!(
                lanes
                    .iter()
                    .any(|n| cpu.contains(&format!("{n}-lane vector forms"))),
                "{value}: {text}"
            );
        }
        assert_eq!(
            err.contains("COHORT_CPU_SIMD_LANES=\"12\" is not one of [8, 16, 32]"),
            value == "12",
            "{value}: {err}"
        );
    }
}

/// The CPU backend's whole-dispatch traversals (`cohort_kernels::traverse_stream`, on CPUs
/// with AVX-512) render the image that the kernels' host forms render, bit for bit, and
/// the `cpu forms` line says which ran.
#[test]
fn stream_traversals_render_the_host_forms_image() {
    let dir = tempdir();
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../render/tests/scenes/stanford-like/scene.xml"
    );
    let render = |name: &str, forms: Option<&str>| {
        let mut c = cohort();
        c.current_dir(&dir)
            .args([
                "render",
                "--scene",
                scene,
                "--backend",
                "cpu",
                "--integrator",
                "nee",
            ])
            .args(["--width", "48", "--height", "48", "--paths", "4"])
            .args(["--out", &format!("{name}.exr")]);
        if let Some(f) = forms {
            c.env("COHORT_CPU_SIMD", f);
        }
        let out = c.output().unwrap();
        assert_ok(&out);
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        (
            std::fs::read(dir.join(format!("{name}.png"))).unwrap(),
            text,
        )
    };
    let (host, host_text) = render("host", Some("host"));
    let (stream, text) = render("stream", None);
    assert!(!host_text.contains("whole-dispatch"), "{host_text}");
    #[cfg(target_arch = "x86_64")]
    let avx512 = std::arch::is_x86_feature_detected!("avx512f");
    #[cfg(not(target_arch = "x86_64"))]
    let avx512 = false;
    assert_eq!(
        text.contains("traverse8") && text.contains("whole-dispatch"),
        avx512,
        "{text}"
    );
    assert!(host == stream, "the stream traversals changed the image");
}
