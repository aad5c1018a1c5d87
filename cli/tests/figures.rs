//! `cohort figures` end to end on a tiny sweep: the CSV's rows and columns, the
//! round-robin groups (`normal` measured with every N, ratios against it), the plots, the
//! cached reference, clear errors for bad lists, and a sweep split into shards
//! (`--shard K/N`) that `cohort figures-merge` puts back together.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn cohort() -> Command {
    Command::new(env!("CARGO_BIN_EXE_cohort"))
}

fn has_gpu() -> bool {
    cohort::runtime::Device::for_tests(cohort::runtime::BackendKind::Vulkan).is_some()
}

fn tempdir() -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "cohort-figures-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

const TINY: &[&str] = &[
    "figures",
    "--scenes",
    "cornell",
    "--configs",
    "normal,warp,grid",
    "--n",
    "4,16",
    "--time",
    "0.05",
    "--reference-time",
    "0.2",
    "--width",
    "32",
    "--height",
    "32",
    "--backend",
    "vulkan",
];

fn parse_csv(text: &str) -> (Vec<String>, Vec<HashMap<String, String>>) {
    // The device name may be quoted (it can hold commas); no other field is.
    let split = |line: &str| -> Vec<String> {
        let mut fields = Vec::new();
        let (mut cur, mut quoted) = (String::new(), false);
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut cur)),
                c => cur.push(c),
            }
        }
        fields.push(cur);
        fields
    };
    let mut lines = text.lines();
    let header = split(lines.next().expect("header"));
    let rows = lines
        .map(|l| {
            let f = split(l);
            assert_eq!(
                f.len(),
                header.len(),
                "row has {} fields, header {}: {l}",
                f.len(),
                header.len()
            );
            header.iter().cloned().zip(f).collect()
        })
        .collect();
    (header, rows)
}

fn num(row: &HashMap<String, String>, key: &str) -> f64 {
    row[key]
        .parse::<f64>()
        .unwrap_or_else(|_| panic!("{key} = `{}` is not a number in {row:?}", row[key]))
}

fn assert_image(path: &Path, magic: &[u8]) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        bytes.len() > 5_000,
        "{} is only {} bytes",
        path.display(),
        bytes.len()
    );
    assert!(
        bytes.windows(magic.len()).take(64).any(|w| w == magic),
        "{} lacks {magic:?}",
        path.display()
    );
}

#[test]
fn tiny_sweep_writes_csv_plots_and_reuses_the_reference() {
    if !has_gpu() {
        return;
    }
    let dir = tempdir();
    let out = cohort()
        .args(TINY)
        .arg("--out-dir")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");

    let (header, rows) = parse_csv(&std::fs::read_to_string(dir.join("figures.csv")).unwrap());
    for col in [
        "scene",
        "config",
        "n",
        "rr",
        "compaction",
        "interleave",
        "paths_per_pixel",
        "paths_per_s",
        "rays_per_s",
        "kernel_ms_traverse",
        "kernel_ms_extend",
        "kernel_ms_compact",
        "rms_percent",
        "rms_abs",
        "paths_per_s_vs_normal",
        "group_n",
        "rms_at_1spp",
    ] {
        assert!(
            header.iter().any(|h| h == col),
            "missing column {col} in {header:?}"
        );
    }
    // D in {1, 5} x 3 columns x 2 N, each a group of normal + 2 configs.
    assert_eq!(rows.len(), 2 * 3 * 2 * (1 + 2), "{rows:#?}");
    // The CSV prints ratios and RMS with 5 decimals: half of the last one is rounding.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-4 * b.abs().max(1e-9) + 5e-6;
    for d in ["1", "5"] {
        for (rr, compaction) in [("path", "true"), ("group", "true"), ("group", "false")] {
            for group_n in ["4", "16"] {
                let sel: Vec<_> = rows
                    .iter()
                    .filter(|r| {
                        r["interleave"] == d
                            && r["rr"] == rr
                            && r["compaction"] == compaction
                            && r["group_n"] == group_n
                    })
                    .collect();
                let what = format!("D={d} rr={rr} compaction={compaction} N={group_n}");
                assert_eq!(sel.len(), 3, "{what}");
                let normal: Vec<_> = sel.iter().filter(|r| r["config"] == "normal").collect();
                assert_eq!(normal.len(), 1, "normal once per group: {what}");
                assert_eq!(normal[0]["n"], "", "normal does not depend on N");
                assert_eq!(num(normal[0], "paths_per_s_vs_normal"), 1.0);
                for config in ["warp", "grid"] {
                    let point: Vec<_> = sel.iter().filter(|r| r["config"] == config).collect();
                    assert_eq!(point.len(), 1, "{config} {what}");
                    assert_eq!(point[0]["n"], group_n, "{config} {what}");
                    // Against the normal of its own group, not another group's.
                    let ratio = num(point[0], "paths_per_s") / num(normal[0], "paths_per_s");
                    assert!(
                        close(num(point[0], "paths_per_s_vs_normal"), ratio),
                        "{config} {what}: {point:?} vs {normal:?}"
                    );
                }
                if compaction == "false" {
                    assert!(
                        sel.iter().all(|r| num(r, "kernel_ms_compact") == 0.0),
                        "no compaction ran"
                    );
                }
            }
        }
    }
    for r in &rows {
        assert_eq!(r["scene"], "cornell");
        assert_eq!((num(r, "width"), num(r, "height")), (32.0, 32.0));
        for key in [
            "paths_per_pixel",
            "paths_per_s",
            "rays_per_s",
            "kernel_ms_traverse",
            "kernel_ms_extend",
            "kernel_ms_total",
            "paths_per_s_vs_normal",
        ] {
            let v = num(r, key);
            assert!(v.is_finite() && v > 0.0, "{key} = {v} in {r:?}");
        }
        let rms = num(r, "rms_percent");
        assert!(
            rms.is_finite() && rms > 0.0 && rms < 1000.0,
            "rms {rms} in {r:?}"
        );
        assert!(
            close(
                num(r, "rms_at_1spp"),
                rms * num(r, "paths_per_pixel").sqrt()
            ),
            "rms_at_1spp in {r:?}"
        );
        assert!(
            num(r, "kernel_ms_total") >= 50.0,
            "the 0.05 s budget was spent: {r:?}"
        );
    }

    for stem in ["fig4_cornell", "fig5_cornell", "fig7_cornell_d5"] {
        assert_image(&dir.join(format!("{stem}.png")), b"PNG");
        assert_image(&dir.join(format!("{stem}.svg")), b"<svg");
        let svg = std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap();
        for text in ["warp", "grid", "normal", "N (hemisphere"] {
            assert!(svg.contains(text), "{stem}.svg lacks `{text}`");
        }
    }
    // No temporary files are left behind.
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");

    // A second (smaller) run reuses the cached reference instead of rendering it again.
    let reference = dir.join("reference_cornell_32x32.exr");
    let before = std::fs::metadata(&reference).unwrap().modified().unwrap();
    let out = cohort()
        .args([
            "figures",
            "--scenes",
            "cornell",
            "--configs",
            "normal",
            "--n",
            "4",
            "--time",
            "0.02",
            "--width",
            "32",
            "--height",
            "32",
            "--backend",
            "vulkan",
            "--interleave",
            "none",
        ])
        .args(["--slices", "1"])
        .arg("--out-dir")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("reusing the reference"), "{stderr}");
    assert_eq!(
        std::fs::metadata(&reference).unwrap().modified().unwrap(),
        before,
        "the reference was rewritten"
    );
    let (_, rows) = parse_csv(&std::fs::read_to_string(dir.join("figures.csv")).unwrap());
    assert_eq!(rows.len(), 3, "normal once per column");
    assert!(rows.iter().all(|r| r["group_n"] == "4"));
    assert!(rows.iter().all(|r| num(r, "rms_percent").is_finite()));

    // Whole-group termination columns: every configuration but the grid (which cannot vote).
    let out = cohort()
        .args([
            "figures",
            "--scenes",
            "cornell",
            "--configs",
            "warp,grid",
            "--n",
            "4",
            "--time",
            "0.02",
            "--width",
            "32",
            "--height",
            "32",
        ])
        .args([
            "--backend",
            "vulkan",
            "--interleave",
            "none",
            "--columns",
            "whole,whole-no",
            "--end-continue",
            "0.4",
            "--slices",
            "2",
        ])
        .arg("--out-dir")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let (_, rows) = parse_csv(&std::fs::read_to_string(dir.join("figures.csv")).unwrap());
    assert_eq!(rows.len(), 4, "normal and warp, in two columns: {rows:#?}");
    assert!(
        rows.iter()
            .all(|r| r["rr"] == "whole" && r["config"] != "grid"),
        "{rows:#?}"
    );
    assert_eq!(
        rows.iter().filter(|r| r["compaction"] == "false").count(),
        2
    );

    // The same sweep with light sampling: coherent configurations run with either integrator.
    let out = cohort()
        .args([
            "figures",
            "--scenes",
            "cornell",
            "--configs",
            "warp",
            "--n",
            "4",
            "--time",
            "0.02",
            "--width",
            "32",
            "--height",
            "32",
        ])
        .args([
            "--backend",
            "vulkan",
            "--interleave",
            "none",
            "--columns",
            "path",
            "--slices",
            "1",
            "--integrator",
            "nee",
        ])
        .arg("--out-dir")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let (_, rows) = parse_csv(&std::fs::read_to_string(dir.join("figures.csv")).unwrap());
    assert_eq!(rows.len(), 2, "normal and warp: {rows:#?}");
    assert!(
        rows.iter()
            .all(|r| num(r, "rms_percent").is_finite() && num(r, "rms_percent") > 0.0),
        "{rows:#?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_lists_fail_naming_the_value() {
    let dir = tempdir();
    for (args, needle) in [
        (vec!["--scenes", "cornell,nowhere"], "nowhere"),
        (vec!["--configs", "normal,bogus"], "bogus"),
        (vec!["--configs", "block_100"], "block_100"),
        (vec!["--n", "4,abc"], "abc"),
        (vec!["--n", "4,0"], "'0'"),
        (vec!["--n", "4,2000"], "2000"),
        (vec!["--n", "4,,8"], "invalid value ''"),
        (vec!["--n", "8,8"], "`8`"),
        (vec!["--interleave", "4"], "`4`"),
        (vec!["--time", "0"], "--time"),
        (vec!["--slices", "0"], "--slices"),
        (vec!["--columns", "path,sideways"], "sideways"),
        (vec!["--columns", "rr,rr"], "`rr`"),
        (vec!["--end-continue", "0"], "--end-continue"),
        (vec!["--integrator", "photon"], "photon"),
        (vec!["--shard", "3/3"], "--shard"),
        (vec!["--shard", "1"], "K/N"),
    ] {
        let out = cohort()
            .arg("figures")
            .args(&args)
            .arg("--out-dir")
            .arg(&dir)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("error") && err.contains(needle),
            "{args:?}: {err}"
        );
    }
    // Nothing was rendered or written.
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The sweep of the shard test: one scene, two configurations, two N, the three columns,
/// no Fig. 7: 6 groups of 3 points. The CPU backend, so that it runs anywhere.
const SHARDED: &[&str] = &[
    "figures",
    "--scenes",
    "cornell",
    "--configs",
    "warp,grid",
    "--n",
    "4,16",
    "--time",
    "0.02",
    "--reference-time",
    "0.1",
    "--width",
    "32",
    "--height",
    "32",
    "--interleave",
    "none",
    "--slices",
    "2",
    "--backend",
    "cpu",
];

/// The columns that say which point a row is (the measured values differ between runs).
const KEY_COLUMNS: &[&str] = &[
    "scene",
    "width",
    "height",
    "config",
    "label",
    "n",
    "rr",
    "compaction",
    "interleave",
    "seed",
    "time_budget_s",
    "group_n",
];

fn keys(rows: &[HashMap<String, String>]) -> Vec<Vec<String>> {
    rows.iter()
        .map(|r| KEY_COLUMNS.iter().map(|k| r[*k].clone()).collect())
        .collect()
}

/// A shard's CSV without its `#` lines: figures.csv's header and rows.
fn shard_rows(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(text.starts_with("# cohort figures shard"), "{text}");
    let body: String = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| format!("{l}\n"))
        .collect();
    parse_csv(&body).1
}

fn merge(shards: &[PathBuf], out_dir: &Path) -> std::process::Output {
    cohort()
        .arg("figures-merge")
        .args(shards)
        .arg("--out-dir")
        .arg(out_dir)
        .output()
        .unwrap()
}

#[test]
fn shards_merge_into_the_unsharded_csv_and_plots() {
    let dir = tempdir();
    let whole = dir.join("whole");
    let out = cohort()
        .args(SHARDED)
        .arg("--out-dir")
        .arg(&whole)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (_, whole_rows) = parse_csv(&std::fs::read_to_string(whole.join("figures.csv")).unwrap());
    assert_eq!(whole_rows.len(), 6 * 3);

    // Three shards at once, sharing an out dir that already holds the reference.
    let sharded = dir.join("shards");
    std::fs::create_dir_all(&sharded).unwrap();
    std::fs::copy(
        whole.join("reference_cornell_32x32.exr"),
        sharded.join("reference_cornell_32x32.exr"),
    )
    .unwrap();
    let running: Vec<_> = (0..3)
        .map(|k| {
            cohort()
                .args(SHARDED)
                .args(["--shard", &format!("{k}/3"), "--out-dir"])
                .arg(&sharded)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for (k, child) in running.into_iter().enumerate() {
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "shard {k}: {stderr}");
        assert!(
            stderr.contains("reusing the reference"),
            "shard {k}: {stderr}"
        );
    }
    let shard_path = |k: u32| sharded.join(format!("figures.shard-{k}-of-3.csv"));
    let shards: Vec<PathBuf> = (0..3).map(shard_path).collect();

    // Whole groups, dealt round-robin in the plan's order (column, then N): shard K has
    // groups K and K + 3 of path/4, path/16, rr/4, rr/16, rr-no/4, rr-no/16.
    let groups = [
        ("path", "true", "4"),
        ("path", "true", "16"),
        ("group", "true", "4"),
        ("group", "true", "16"),
        ("group", "false", "4"),
        ("group", "false", "16"),
    ];
    let mut union = Vec::new();
    for (k, path) in shards.iter().enumerate() {
        let rows = shard_rows(path);
        let mut of_groups: Vec<(&str, &str, &str)> = rows
            .iter()
            .map(|r| {
                let g = groups
                    .iter()
                    .find(|g| {
                        (g.0, g.1, g.2) == (&r["rr"][..], &r["compaction"][..], &r["group_n"][..])
                    })
                    .unwrap_or_else(|| panic!("shard {k}: row of no group: {r:?}"));
                *g
            })
            .collect();
        of_groups.dedup();
        assert_eq!(of_groups, vec![groups[k], groups[k + 3]], "shard {k}");
        assert_eq!(rows.len(), 2 * 3, "shard {k}: whole groups");
        union.extend(keys(&rows));
    }
    // Disjoint, and together every point of the unsharded run.
    let mut sorted = union.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), union.len(), "a point is in two shards");
    let mut expected = keys(&whole_rows);
    expected.sort();
    assert_eq!(sorted, expected);
    // Shards write no plots and no figures.csv.
    for entry in std::fs::read_dir(&sharded).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            name.starts_with("figures.shard-") || name.starts_with("reference_"),
            "a shard wrote {name}"
        );
    }

    // The merge: the unsharded run's rows in its order, each as its shard wrote it, and
    // the plots.
    let merged = dir.join("merged");
    let out = merge(
        &[shards[2].clone(), shards[0].clone(), shards[1].clone()],
        &merged,
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("warning"), "one reference: {stderr}");
    let merged_text = std::fs::read_to_string(merged.join("figures.csv")).unwrap();
    let (header, merged_rows) = parse_csv(&merged_text);
    let (whole_header, _) = parse_csv(&std::fs::read_to_string(whole.join("figures.csv")).unwrap());
    assert_eq!(header, whole_header);
    assert_eq!(keys(&merged_rows), keys(&whole_rows));
    let shard_texts: Vec<String> = shards
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    for line in merged_text.lines().skip(1) {
        let holders = shard_texts
            .iter()
            .filter(|t| t.lines().any(|l| l == line))
            .count();
        assert_eq!(
            holders, 1,
            "merged row not copied from exactly one shard: {line}"
        );
    }
    for stem in ["fig4_cornell", "fig5_cornell"] {
        assert_image(&merged.join(format!("{stem}.png")), b"PNG");
        assert_image(&merged.join(format!("{stem}.svg")), b"<svg");
    }
    let names: Vec<String> = std::fs::read_dir(&merged)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");

    // Refusals, each naming what is wrong; nothing is written.
    let refused = dir.join("refused");
    let fails = |inputs: &[PathBuf], needles: &[&str]| {
        let out = merge(inputs, &refused);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{inputs:?} should fail");
        for needle in needles {
            assert!(
                stderr.contains(needle),
                "{inputs:?}: `{needle}` not in {stderr}"
            );
        }
        assert!(!refused.join("figures.csv").exists());
    };
    // A missing shard.
    fails(
        &[shards[0].clone(), shards[2].clone()],
        &["shard 1/3 missing"],
    );
    // A shard twice.
    fails(
        &[shards[0].clone(), shards[1].clone(), shards[0].clone()],
        &["both shard 0/3"],
    );
    // A shard of another plan (another seed).
    let other_dir = dir.join("other");
    std::fs::create_dir_all(&other_dir).unwrap();
    let other = other_dir.join("figures.shard-1-of-3.csv");
    assert!(shard_texts[1].contains("\n# seed=1\n"));
    std::fs::write(
        &other,
        shard_texts[1].replace("\n# seed=1\n", "\n# seed=2\n"),
    )
    .unwrap();
    fails(
        &[shards[0].clone(), other.clone(), shards[2].clone()],
        &[&other.display().to_string(), "seed `2`, not `1`"],
    );
    // A malformed row: the file and its line.
    let lines: Vec<&str> = shard_texts[1].lines().collect();
    let last = lines.len();
    let malformed = other_dir.join("malformed.csv");
    let mut text = lines[..last - 1].join("\n");
    text.push('\n');
    text.push_str(&lines[last - 1].replacen(',', ";", 1));
    std::fs::write(&malformed, text).unwrap();
    fails(
        &[shards[0].clone(), malformed.clone(), shards[2].clone()],
        &[&format!("{}: line {last}", malformed.display())],
    );
    // An interrupted shard: its last row is missing.
    let interrupted = other_dir.join("interrupted.csv");
    std::fs::write(&interrupted, lines[..last - 1].join("\n")).unwrap();
    fails(
        &[shards[0].clone(), interrupted.clone(), shards[2].clone()],
        &[&interrupted.display().to_string(), "incomplete"],
    );
    // A shard measured against another reference merges, with a warning.
    let reference_line = shard_texts[1]
        .lines()
        .find(|l| l.starts_with("# reference.cornell=32x32 fnv1a-64:"))
        .unwrap();
    let own_reference = other_dir.join("own-reference.csv");
    let text = shard_texts[1].replace(reference_line, "# reference.cornell=32x32 fnv1a-64:0");
    std::fs::write(&own_reference, text).unwrap();
    let out = merge(
        &[shards[0].clone(), own_reference.clone(), shards[2].clone()],
        &other_dir.join("merged"),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains("different references"),
        "{stderr}"
    );
    // figures.csv of an unsharded run is not a shard.
    fails(
        &[whole.join("figures.csv")],
        &[
            &whole.join("figures.csv").display().to_string(),
            "not a shard",
        ],
    );
    let _ = std::fs::remove_dir_all(&dir);
}
