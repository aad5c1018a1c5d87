//! Scaling out from the command line: `cohort render --shard K/N` writes EXRs that
//! `cohort merge` combines into the unsplit render (through the files: path counts and
//! the header's provenance), `cohort merge` refuses files that do not belong together,
//! `cohort compare` tells the merge from anything else, and `--devices` renders on
//! every device of the machine (one here) as a plain run does.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use cohort_render::input::read_exr;
use cohort_render::merge::merge_tolerance;

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
}

fn has_gpu() -> bool {
    cohort::runtime::Device::for_tests(cohort::runtime::BackendKind::Vulkan).is_some()
}

fn tempdir() -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "cohort-shard-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const PATHS: u32 = 7;

/// Renders the embedded Cornell box at 20x16 with `PATHS` paths per pixel and `extra`
/// arguments to `out`.
fn render(dir: &Path, out: &str, extra: &[&str]) -> Output {
    cohort()
        .args([
            "render",
            "--width",
            "20",
            "--height",
            "16",
            "--paths",
            &PATHS.to_string(),
            "--backend",
            "vulkan",
        ])
        .args(extra)
        .arg("--out")
        .arg(dir.join(out))
        .arg("--png")
        .arg(dir.join(format!("{out}.png")))
        .output()
        .unwrap()
}

fn ok(out: Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr)
}

fn fails(out: Output) -> String {
    assert!(
        !out.status.success(),
        "should fail: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn compare(dir: &Path, a: &str, b: &str, extra: &[&str]) -> Output {
    cohort()
        .arg("compare")
        .arg(dir.join(a))
        .arg(dir.join(b))
        .args(extra)
        .output()
        .unwrap()
}

fn merge(dir: &Path, inputs: &[&str], out: &str) -> Output {
    cohort()
        .arg("merge")
        .args(inputs.iter().map(|i| dir.join(i)))
        .arg("--out")
        .arg(dir.join(out))
        .output()
        .unwrap()
}

/// Both integrators, per-path sampling: the merged shards' EXR is the unsplit run's
/// image within `merge_tolerance` (float summation order; see `cohort_render::merge`),
/// and bit for bit from one shard.
#[test]
fn merged_shard_files_are_the_unsplit_render() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    for integrator in ["nee", "path"] {
        let whole_name = format!("{integrator}-whole.exr");
        ok(render(&dir, &whole_name, &["--integrator", integrator]));
        let whole = read_exr(&dir.join(&whole_name)).unwrap();
        assert!(whole.image.paths.iter().all(|&p| p == PATHS));
        for n in [1u32, 3] {
            let names: Vec<String> = (0..n)
                .map(|k| format!("{integrator}-{k}of{n}.exr"))
                .collect();
            for (k, name) in names.iter().enumerate() {
                let shard = format!("{k}/{n}");
                let text = ok(render(
                    &dir,
                    name,
                    &["--integrator", integrator, "--shard", &shard],
                ));
                assert!(
                    n == 1 || text.contains(&format!("shard          {shard}")),
                    "{text}"
                );
                let attrs = read_exr(&dir.join(name)).unwrap().attributes;
                assert_eq!(attrs["cohort.shards"], shard);
                assert_eq!(attrs["cohort.merge"], "exact");
                assert_eq!(attrs["cohort.integrator"], integrator);
                assert_eq!(attrs["cohort.budget"], format!("paths={PATHS}"));
            }
            let merged_name = format!("{integrator}-merged{n}.exr");
            let inputs: Vec<&str> = names.iter().map(String::as_str).collect();
            let text = ok(merge(&dir, &inputs, &merged_name));
            assert!(!text.contains("warning"), "{text}");
            let merged = read_exr(&dir.join(&merged_name)).unwrap();
            assert_eq!(merged.image.paths, whole.image.paths);
            assert_eq!(
                merged.attributes["cohort.shards"],
                format!("0-{}/{n}", n - 1).replace("0-0/1", "0/1")
            );
            // `cohort compare` (what the cluster smoke test runs) agrees.
            let text = ok(compare(&dir, &merged_name, &whole_name, &[]));
            assert!(text.contains("same image"), "{text}");
            let tol = if n == 1 { 0.0 } else { merge_tolerance(PATHS) };
            for (i, (a, b)) in merged
                .image
                .pixels
                .iter()
                .zip(&whole.image.pixels)
                .enumerate()
            {
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= tol * a[c].abs().max(b[c].abs()),
                        "{integrator}, {n} shards, pixel {i}: {} vs {} (relative tolerance {tol})",
                        a[c],
                        b[c]
                    );
                }
            }
        }
    }
}

#[test]
fn merge_refuses_files_that_do_not_belong_together() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    for k in 0..3 {
        ok(render(
            &dir,
            &format!("s{k}.exr"),
            &["--shard", &format!("{k}/3")],
        ));
    }
    ok(render(
        &dir,
        "seed2.exr",
        &["--shard", "1/3", "--seed", "2"],
    ));
    ok(render(&dir, "of2.exr", &["--shard", "1/2"]));
    ok(render(
        &dir,
        "warp.exr",
        &["--shard", "1/3", "--algorithm", "warp"],
    ));

    let err = fails(merge(&dir, &["s0.exr", "seed2.exr"], "x.exr"));
    assert!(
        err.contains("seed2.exr does not belong with") && err.contains("seed `1` vs `2`"),
        "{err}"
    );
    let err = fails(merge(&dir, &["s0.exr", "warp.exr"], "x.exr"));
    assert!(
        err.contains("warp.exr") && err.contains("algorithm=normal"),
        "{err}"
    );
    let err = fails(merge(&dir, &["s0.exr", "of2.exr"], "x.exr"));
    assert!(err.contains("of2.exr holds shards 1/2"), "{err}");
    let err = fails(merge(&dir, &["s0.exr", "s1.exr", "s0.exr"], "x.exr"));
    assert!(err.contains("both hold shard 0/3"), "{err}");
    let err = fails(merge(&dir, &["s0.exr", "s1.exr.png"], "x.exr"));
    assert!(err.contains("s1.exr.png"), "{err}");
    assert!(
        !dir.join("x.exr").exists(),
        "a refused merge writes nothing"
    );

    // A subset merges, with a warning naming what is missing, unless --require-all
    // (the cluster recipes' merge step) makes it an error; merges merge again.
    let mut require_all = cohort();
    require_all
        .args(["merge", "--require-all"])
        .args(["s0.exr", "s2.exr"].map(|i| dir.join(i)))
        .arg("--out")
        .arg(dir.join("x.exr"));
    let err = fails(require_all.output().unwrap());
    assert!(
        err.contains("shards 1/3 are missing") && err.contains("--require-all"),
        "{err}"
    );
    assert!(
        !dir.join("x.exr").exists(),
        "a refused merge writes nothing"
    );
    let text = ok(merge(&dir, &["s0.exr", "s2.exr"], "part.exr"));
    assert!(
        text.contains("warning") && text.contains("without 1/3"),
        "{text}"
    );
    ok(merge(&dir, &["part.exr", "s1.exr"], "all.exr"));
    let all = read_exr(&dir.join("all.exr")).unwrap();
    assert_eq!(all.attributes["cohort.shards"], "0-2/3");
    assert!(all.image.paths.iter().all(|&p| p == PATHS));

    // `cohort compare` fails on a partial merge (its path counts differ), on another
    // seed's image (beyond float summation order), and on images of different sizes;
    // an explicit --tolerance loose enough for the noise lets the seeds pass.
    ok(render(&dir, "whole.exr", &[]));
    ok(render(&dir, "whole2.exr", &["--seed", "2"]));
    let text = ok(compare(&dir, "all.exr", "whole.exr", &[]));
    assert!(text.contains("same image"), "{text}");
    let err = fails(compare(&dir, "part.exr", "whole.exr", &[]));
    assert!(err.contains("path counts differ"), "{err}");
    let err = fails(compare(&dir, "whole2.exr", "whole.exr", &[]));
    assert!(err.contains("differ: relative difference"), "{err}");
    ok(compare(
        &dir,
        "whole2.exr",
        "whole.exr",
        &["--tolerance", "1e9"],
    ));
    ok(cohort()
        .args(["render", "--width", "8", "--height", "8", "--paths", "1"])
        .arg("--out")
        .arg(dir.join("small.exr"))
        .arg("--png")
        .arg(dir.join("small.png"))
        .output()
        .unwrap());
    let err = fails(compare(&dir, "small.exr", "whole.exr", &[]));
    assert!(err.contains("is 8x8 but") && err.contains("20x16"), "{err}");
    let err = fails(compare(&dir, "whole.exr", "nothing.exr", &[]));
    assert!(err.contains("nothing.exr"), "{err}");
}

/// One device here: `--devices all` (and `--devices 0`) render what a plain run does,
/// bit for bit; an index past the last device is an error naming the devices.
#[test]
fn devices_all_renders_the_plain_image_and_bad_indices_fail() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    ok(render(&dir, "plain.exr", &[]));
    let plain = read_exr(&dir.join("plain.exr")).unwrap().image;
    for devices in ["all", "0"] {
        let name = format!("devices-{devices}.exr");
        ok(render(&dir, &name, &["--devices", devices]));
        let img = read_exr(&dir.join(&name)).unwrap().image;
        assert_eq!(img.paths, plain.paths);
        let bits = |i: &cohort_render::Image| {
            i.pixels
                .iter()
                .flat_map(|p| p.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&img), bits(&plain), "--devices {devices}");
    }
    let err = fails(render(&dir, "bad.exr", &["--devices", "0,99"]));
    assert!(
        err.contains("no vulkan device 99") && err.contains("0: "),
        "{err}"
    );
    let err = fails(render(&dir, "bad.exr", &["--devices", "0,0"]));
    assert!(err.contains("listed twice"), "{err}");
    let err = fails(render(&dir, "bad.exr", &["--shard", "3/3"]));
    assert!(err.contains("--shard"), "{err}");
    let err = fails(render(&dir, "bad.exr", &["--shard", "0/8"]));
    assert!(err.contains("no path"), "{err}");
}
