//! The `cohort` command as a user runs it: listing scenes, rendering small images,
//! clear errors for bad input, and outputs that a failed run never clobbers.

use std::process::Command;

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
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
fn renders_and_writes_outputs() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    let (exr, png, stats) = (dir.join("a.exr"), dir.join("a.png"), dir.join("a.json"));
    let out = cohort()
        .args(["render", "--width", "24", "--height", "16", "--paths", "2", "--backend", "vulkan"])
        .arg("--out").arg(&exr).arg("--png").arg(&png).arg("--stats").arg(&stats)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::metadata(&exr).unwrap().len() > 100);
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[1..4], b"PNG");
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["width"], 24);
    assert_eq!(json["paths_per_pixel"], 2.0);
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
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
        vec!["render".to_string(), "--scene".into(), "no-such-scene".into()],
        vec!["render".to_string(), "--scene".into(), bad_xml.display().to_string()],
        vec!["render".to_string(), "--paths".into(), "0".into()],
        vec!["render".to_string(), "--algorithm".into(), "bogus".into()],
        vec!["render".to_string(), "--backend".into(), "metal".into()],
        vec!["render".to_string(), "--rr".into(), "sometimes".into()],
        vec!["render".to_string(), "--algorithm".into(), "grid".into(), "--rr".into(), "whole".into()],
        vec!["render".to_string(), "--algorithm".into(), "warp".into(), "--rr".into(), "whole".into(), "--end-continue".into(), "0".into()],
    ] {
        let out = cohort().args(&args).arg("--png").arg(&png).arg("--out").arg(dir.join("x.exr")).output().unwrap();
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("error"), "{args:?}: {err}");
        assert_eq!(std::fs::read(&png).unwrap(), b"good image", "{args:?} clobbered the output");
    }
    // The XML error names the file and line.
    let out = cohort().args(["render", "--scene"]).arg(&bad_xml).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.xml") && err.contains(":3"), "{err}");
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
        .args(["render", "--width", "32", "--height", "32", "--paths", "2", "--backend", "vulkan", "--algorithm", "warp", "--rr", "whole"])
        .args(["--end-continue", "0.25", "--n", "8"])
        .arg("--out").arg(dir.join("w.exr")).arg("--png").arg(dir.join("w.png")).arg("--stats").arg(&stats)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).contains("whole-group end (q = 0.25)"));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(json["whole_group_end"], 0.25);
    assert_eq!(json["group_rr"], true);
    assert_eq!(json["paths_per_pixel"], 2.0);
}

fn tempdir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-cli-{}-{}", std::process::id(), std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_nanos()));
    std::fs::create_dir_all(&d).unwrap();
    d
}
