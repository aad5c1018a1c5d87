//! `cohort check` on the CPU backend: the built-in diffuse strategies pass at every group
//! level, and the table names each of them.

use std::process::Command;

#[test]
fn check_passes_for_the_builtin_samplers_on_the_cpu_backend() {
    let runtime = std::env::temp_dir().join(format!("cohort-check-{}", std::process::id()));
    std::fs::create_dir_all(&runtime).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_cohort"))
        .args([
            "check",
            "--backend",
            "cpu",
            "--samples",
            "65536",
            "--samplers-only",
        ])
        .arg("--out")
        .arg(runtime.join("failures"))
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in [
        "normal (Cosine)",
        "CoherentUniform",
        "CoherentCosine",
        "CoherentEqualArea",
    ] {
        assert!(stdout.contains(name), "{name} missing:\n{stdout}");
    }
    assert!(stdout.contains("passed: all"), "{stdout}");
    std::fs::remove_dir_all(&runtime).unwrap();
}
