//! The command line's options as the parser sees them: `--help` lists the values of every
//! choice, a bad value is a usage error (exit code 2) found before any scene is read or
//! device opened, negative numbers reach the value parser, and `--no-compact` is gone.
//! None of these tests needs a device.

use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn cohort(args: &[&str]) -> (Output, Duration) {
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_cohort"))
        .args(args)
        .output()
        .unwrap();
    (out, start.elapsed())
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The text of `--help` about one option: from its line to the next option's.
fn option_help<'a>(help: &'a str, flag: &str) -> &'a str {
    let start = help
        .find(&format!("{flag} <"))
        .unwrap_or_else(|| panic!("{flag} is not in the help:\n{help}"));
    let rest = &help[start + flag.len()..];
    let end = rest.find("\n  -").map_or(rest.len(), |i| i + 1);
    &rest[..end]
}

fn help_of(subcommand: &str) -> String {
    let (out, _) = cohort(&[subcommand, "--help"]);
    assert!(out.status.success(), "{}", stderr(&out));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn help_lists_the_values_of_every_choice() {
    let render: &[(&str, &[&str])] = &[
        ("--backend", &["wgpu", "vulkan", "cpu"]),
        (
            "--algorithm",
            &[
                "normal",
                "warp",
                "block_256",
                "block_512",
                "block_1024",
                "grid",
            ],
        ),
        ("--in-patch", &["uniform", "cosine", "equal-area"]),
        ("--rr", &["path", "group", "whole"]),
        ("--roulette", &["auto", "fixed", "mitsuba"]),
        ("--integrator", &["nee", "path"]),
    ];
    let figures: &[(&str, &[&str])] = &[
        ("--backend", &["wgpu", "vulkan", "cpu"]),
        ("--configs", &["normal", "warp", "block_256", "grid"]),
        ("--columns", &["path", "rr", "rr-no", "whole", "whole-no"]),
        ("--integrator", &["nee", "path"]),
    ];
    for (subcommand, choices) in [("render", render), ("view", render), ("figures", figures)] {
        let help = help_of(subcommand);
        for (flag, values) in choices {
            let text = option_help(&help, flag);
            assert!(
                text.contains("Possible values:"),
                "{subcommand} {flag}: {text}"
            );
            for v in *values {
                assert!(
                    text.contains(&format!("- {v}")),
                    "{subcommand} {flag} does not list `{v}`:\n{text}"
                );
            }
        }
    }
}

#[test]
fn every_option_has_help_and_defaults_that_differ_say_so() {
    for subcommand in [
        "render",
        "view",
        "figures",
        "figures-merge",
        "merge",
        "compare",
    ] {
        let help = help_of(subcommand);
        let lines: Vec<&str> = help.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim_start();
            let indent = line.len() - t.len();
            let is_item = (1..=6).contains(&indent) && (t.starts_with('-') || t.starts_with('<'));
            // Its text follows on the same line (short format) or on the next (long).
            let same_line = t
                .split_once("  ")
                .is_some_and(|(_, h)| !h.trim().is_empty());
            if is_item && !same_line {
                let next = lines.get(i + 1).map_or("", |l| l.trim());
                assert!(
                    !next.is_empty() && !next.starts_with(['-', '[']),
                    "{subcommand}: `{t}` has no help text"
                );
            }
        }
    }
    let render = help_of("render");
    let figures = help_of("figures");
    assert!(option_help(&render, "--integrator").contains("[default: nee]"));
    assert!(option_help(&figures, "--integrator").contains("[default: path]"));
    assert!(option_help(&render, "--integrator").contains("`cohort figures`"));
    assert!(option_help(&figures, "--integrator").contains("`cohort render`"));
    // "path" in each of its three meanings says which.
    assert!(option_help(&render, "--rr").contains("per-path"));
    assert!(option_help(&render, "--integrator").contains("Implicit path tracing"));
    assert!(option_help(&figures, "--columns").contains("per-path"));
    assert!(option_help(&render, "--seed").contains("Seed"));
}

/// A bad value is a usage error (exit code 2) before anything else happens: no scene is
/// read (the named scene does not exist, and the error is not about it), no device is
/// opened (no startup line, no note about the backend), and it is quick.
#[test]
fn bad_values_are_usage_errors_before_any_scene_or_device() {
    for args in [
        &["--n", "0"][..],
        &["--n", "1001"],
        &["--backend", "nonsense"],
        &["--algorithm", "block_100"],
        &["--in-patch", "sideways"],
        &["--rr", "sometimes"],
        &["--roulette", "sometimes"],
        &["--integrator", "photon"],
        &["--interleave", "4"],
        &["--width", "0"],
        &["--paths", "0"],
        &["--time", "0"],
        &["--time", "1e300"],
        &["--end-continue", "0"],
        &["--light-cells", "65"],
        &["--exposure", "inf"],
        &["--shard", "3/3"],
        &["--devices", "0,0"],
        &["--devices", "gpu"],
    ] {
        let mut all = vec!["render", "--scene", "no-such-dir/scene.xml"];
        all.extend_from_slice(args);
        let (out, took) = cohort(&all);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("invalid value"), "{args:?}: {err}");
        assert!(err.contains(args[0]), "{args:?}: {err}");
        assert!(
            !err.contains("no-such-dir") && !err.contains("note:") && !err.contains("triangles"),
            "{args:?}: {err}"
        );
        assert!(took < Duration::from_secs(1), "{args:?} took {took:?}");
    }
    // The names of a wrong choice are listed.
    let (out, _) = cohort(&["render", "--backend", "nonsense"]);
    assert!(
        stderr(&out).contains("[possible values: wgpu, vulkan, cpu]"),
        "{}",
        stderr(&out)
    );
    // Other block sizes than the listed ones are taken (this one fails on the scene).
    let (out, _) = cohort(&["render", "--algorithm", "block_64", "--scene", "nowhere"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr(&out).contains("unknown scene `nowhere`"));
}

/// Combinations the renderer refuses fail before the scene is read.
#[test]
fn refused_combinations_fail_before_the_scene_is_read() {
    for (args, needle) in [
        (&["--algorithm", "grid", "--rr", "whole"][..], "whole-group"),
        (
            &["--coherent-light", "--integrator", "path"],
            "next-event estimation",
        ),
        (&["--paths", "2", "--shard", "0/8"], "no path"),
        (&["--interleave", "3", "--width", "30"], "coprime"),
    ] {
        let mut all = vec!["render", "--scene", "no-such-dir/scene.xml"];
        all.extend_from_slice(args);
        let (out, took) = cohort(&all);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains(needle) && !err.contains("no-such-dir"),
            "{args:?}: {err}"
        );
        assert!(took < Duration::from_secs(1), "{args:?} took {took:?}");
    }
}

/// Negative numbers reach the value parser in every subcommand (cli.rs checks those of
/// `render` and `compare`): refused with a value error where meaningless, accepted where
/// they mean something (an exposure in stops).
#[test]
fn negative_numbers_are_values() {
    for args in [
        &["figures", "--n", "4,-8"][..],
        &["figures", "--slices", "-1"],
        &["figures", "--reference-time", "-2"],
        &["figures", "--end-continue", "-0.5"],
    ] {
        let (out, _) = cohort(args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("invalid value '") && !err.contains("unexpected argument"),
            "{args:?}: {err}"
        );
    }
    // An exposure may be negative: the run gets as far as the missing input.
    for args in [
        &["merge", "--exposure", "-1", "--out", "m.exr", "no-such.exr"][..],
        &["render", "--exposure", "-1", "--scene", "nowhere"],
    ] {
        let (out, _) = cohort(args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(!err.contains("invalid value"), "{args:?}: {err}");
    }
}

#[test]
fn no_compact_is_gone_and_compact_is_the_switch() {
    let (out, _) = cohort(&["render", "--no-compact"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("unexpected argument '--no-compact'"));
    let help = help_of("render");
    assert!(!help.contains("no-compact"));
    assert!(help.contains("--compact"));
}
