//! Printing from kernels (docs/LANGUAGE.md, section 14): the same kernel prints the same
//! lines on every backend as its Rust function does on the host, in some order; a full
//! print buffer drops prints and says so.
//!
//! What a process prints is only visible from outside it, so each case runs this test
//! binary again as a child (`print_child`, selected by `COHORT_PRINT_CHILD`) and reads its
//! stdout and stderr between two markers.

mod common;

use cohort::prelude::*;
use cohort::runtime::{BackendKind, Device};

#[kernel_fn]
fn report(i: u32, x: f32) {
    println!("helper {i}: {:.2} {}", x * 0.5, x >= 0.0);
}

/// Prints from a third of the invocations (a divergent branch), from a helper, to stderr,
/// with positional, named and captured arguments, format specifications, vectors and
/// every scalar type. (`print!` with a newline: the test covers each macro.)
#[allow(clippy::print_with_newline)]
#[kernel(workgroup = 64)]
pub fn prints(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [u32]) {
    let n = xs.len() as u32;
    if gi < n {
        let x = xs[gi as usize];
        let v = Vec3::new(x, -x, 0.5);
        let k = gi as i32 - 3;
        if gi % 3 == 0 {
            println!(
                "gi={gi} x={} v={v:?} bits={:#010x} k={k:>4} u={:?} w={w}",
                x,
                x.to_bits(),
                UVec2::new(gi, n),
                w = IVec3::new(k, -k, 7)
            );
        }
        if gi == 5 {
            eprintln!("stderr from {}", gi);
        }
        print!("p{gi}\n");
        report(gi, x);
        out[gi as usize] = gi;
    }
}

/// One 1-word print per invocation: 2 words a record.
#[kernel(workgroup = 64)]
pub fn prints_a_lot(#[builtin(global_index)] gi: u32, out: &mut [u32]) {
    if gi < 100 {
        println!("{}", gi);
        out[gi as usize] = 1;
    }
}

const N: u32 = 150;
const BEGIN: &str = "=== cohort print test begins ===\n";
const END: &str = "=== cohort print test ends ===";

fn inputs() -> Vec<f32> {
    (0..N).map(|i| i as f32 * 0.25 - 3.0).collect()
}

/// The child: prints on one backend (or the host) between the markers, then exits.
#[test]
fn print_child() {
    let Ok(which) = std::env::var("COHORT_PRINT_CHILD") else {
        return;
    };
    let xs = inputs();
    print!("{BEGIN}");
    eprint!("{BEGIN}");
    if which == "host" {
        let mut out = vec![0u32; N as usize];
        for gi in 0..N {
            prints(gi, &xs, &mut out);
        }
    } else {
        let (kind, kernel) = which.split_once(':').expect("backend:kernel");
        let d = Device::new(BackendKind::parse(kind).expect("backend")).expect("device");
        if kernel == "prints" {
            let xs_buf = d.upload(&xs).unwrap();
            let out = d.alloc::<u32>(N as usize).unwrap();
            prints::launch(&d, N, &xs_buf, &out).unwrap();
            assert_eq!(d.read(&out).unwrap(), (0..N).collect::<Vec<_>>());
        } else {
            let out = d.alloc::<u32>(100).unwrap();
            prints_a_lot::launch(&d, 100u32, &out).unwrap();
            assert_eq!(d.read(&out).unwrap(), vec![1; 100]);
        }
    }
    println!("{END}");
    eprintln!("{END}");
}

/// Runs the child and returns its stdout and stderr lines between the markers, sorted
/// (invocations print in no particular order).
fn run_child(which: &str, envs: &[(&str, &str)]) -> (Vec<String>, Vec<String>) {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "print_child", "--nocapture", "--test-threads=1"])
        .env("COHORT_PRINT_CHILD", which)
        .envs(envs.iter().copied())
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        out.status.success(),
        "{which}: child failed\n{stdout}\n{stderr}"
    );
    let between = |s: &str| -> Vec<String> {
        let start = s
            .find(BEGIN)
            .unwrap_or_else(|| panic!("{which}: no marker in\n{s}"));
        let end = s
            .find(END)
            .unwrap_or_else(|| panic!("{which}: no end marker in\n{s}"));
        let mut lines: Vec<String> = s[start + BEGIN.len()..end]
            .lines()
            .map(str::to_string)
            .collect();
        lines.sort();
        lines
    };
    (between(&stdout), between(&stderr))
}

#[test]
fn every_backend_prints_what_the_host_prints() {
    let (host_out, host_err) = run_child("host", &[]);
    // The host's own lines, checked against what they must say.
    assert_eq!(host_out.len(), (N / 3 + 2 * N) as usize);
    assert!(host_out.contains(
        &"gi=3 x=-2.25 v=Vec3(-2.25, 2.25, 0.5) bits=0xc0100000 k=   0 u=UVec2(3, 150) w=[0, 0, 7]"
            .to_string()
    ));
    assert!(host_out.contains(&"helper 1: -1.38 false".to_string()));
    assert!(host_out.contains(&"p149".to_string()));
    assert_eq!(host_err, vec!["stderr from 5".to_string()]);
    for d in common::devices() {
        let backend = d.info().backend;
        drop(d);
        let (out, err) = run_child(&format!("{backend}:prints"), &[]);
        assert_eq!(out, host_out, "{backend}: stdout differs from the host's");
        assert_eq!(err, host_err, "{backend}: stderr differs from the host's");
    }
}

#[test]
fn a_full_print_buffer_drops_prints_and_says_how_many() {
    for d in common::devices() {
        let backend = d.info().backend;
        if common::is_cpu(&d) {
            // Its lanes print directly: nothing to drop.
            continue;
        }
        drop(d);
        // 64 bytes: 2 header words and 14 record words, 7 records of 2 words.
        let (out, err) = run_child(
            &format!("{backend}:prints_a_lot"),
            &[("COHORT_PRINT_BUFFER_BYTES", "64")],
        );
        assert_eq!(out.len(), 7, "{backend}: {out:?}");
        for line in &out {
            let gi: u32 = line.parse().unwrap();
            assert!(gi < 100, "{backend}: {line}");
        }
        assert_eq!(err.len(), 1, "{backend}: {err:?}");
        assert!(
            err[0].contains("kernel `prints_a_lot")
                && err[0].contains("93 prints were dropped")
                && err[0].contains("COHORT_PRINT_BUFFER_BYTES"),
            "{backend}: {}",
            err[0]
        );
    }
}
