//! `cohort render` with point, spot and directional lights: implicit path tracing cannot
//! reach them and says so; `--roulette` is checked.

use std::process::Command;

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
}

fn has_gpu() -> bool {
    cohort::runtime::Device::for_tests(cohort::runtime::BackendKind::Vulkan).is_some()
}

fn point_scene() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../render/tests/scenes/mitsuba/point.xml")
}

fn out_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("cohort-emitters-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn implicit_path_tracing_warns_about_delta_lights() {
    if !has_gpu() {
        return;
    }
    let dir = out_dir("warn");
    let run = |integrator: &str| {
        let out = cohort()
            .args([
                "render",
                "--paths",
                "1",
                "--backend",
                "vulkan",
                "--integrator",
                integrator,
            ])
            .arg("--scene")
            .arg(point_scene())
            .arg("--out")
            .arg(dir.join("a.exr"))
            .arg("--png")
            .arg(dir.join("a.png"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let warned = run("path");
    assert!(
        warned.contains("1 point, spot or directional light(s)")
            && warned.contains("--integrator nee"),
        "{warned}"
    );
    assert!(!run("nee").contains("point, spot or directional"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unknown_roulette_is_refused() {
    let out = cohort()
        .args(["render", "--roulette", "sometimes", "--scene", "cornell"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("invalid value 'sometimes' for '--roulette <ROULETTE>'")
            && err.contains("[possible values: auto, fixed, mitsuba]"),
        "{err}"
    );
}
