//! A program that returns from `main` while LLVM compiles a vector form in the background
//! waits for that compile as its main thread exits, before exit destroys LLVM's static
//! objects (a compile that was first to use one crashed there). The case runs in a child
//! process, this test binary run again for the one test: libtest returns from `main` as
//! soon as the test returns.

use std::process::Command;
use std::time::{Duration, Instant};

use cohort::prelude::*;
use cohort::runtime::cpu::simd::Forms;
use cohort::runtime::Device;

/// Set in the child, to the cache folder it compiles into.
const CHILD: &str = "COHORT_EXIT_UNDER_COMPILE_CHILD";

#[kernel(workgroup = 64)]
pub fn polynomial(#[builtin(global_index)] gi: u32, xs: &[f32], out: &mut [Vec4]) {
    let i = gi as usize;
    if i < out.len() {
        let x = xs[i];
        let mut acc = Vec4::new(x, x * x, x + 1.0, 1.0 - x);
        let mut k = 0u32;
        while k < 8 {
            acc = acc * Vec4::splat(0.5) + Vec4::new(x, acc.x.abs().sqrt(), acc.y, acc.z.sin());
            k += 1;
        }
        out[i] = acc;
    }
}

#[test]
fn returning_from_main_waits_for_the_compile_in_flight() {
    if let Some(cache) = std::env::var_os(CHILD) {
        std::env::set_var("COHORT_CACHE_DIR", cache);
        // Vector forms forced: the dispatch waits for the compile, on a thread of its own,
        // while this test returns as soon as LLVM is at work on the kernel.
        std::thread::spawn(|| {
            let d = Device::cpu_with(Forms::Vector).unwrap();
            let xs = d.upload(&[0.5f32; 256]).unwrap();
            let out = d.alloc::<Vec4>(256).unwrap();
            polynomial::launch(&d, 256u32, &xs, &out).unwrap();
        });
        let start = Instant::now();
        loop {
            let now = cohort::runtime::crash_report::compiling_now();
            if now.is_some_and(|k| k.starts_with("polynomial")) {
                return;
            }
            assert!(
                start.elapsed() < Duration::from_secs(60),
                "LLVM never started on the kernel (compiling {now:?})"
            );
            std::thread::sleep(Duration::from_micros(200));
        }
    }
    if cohort::runtime::cpu::simd::llvm_library().is_err() {
        // No libLLVM: nothing compiles in the background (CI has one, from Mesa).
        assert!(std::env::var("CI").is_err(), "no libLLVM on CI");
        return;
    }
    let cache =
        std::env::temp_dir().join(format!("cohort-exit-under-compile-{}", std::process::id()));
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "returning_from_main_waits_for_the_compile_in_flight",
            "--nocapture",
            "--test-threads",
            "1",
        ])
        .env(CHILD, &cache)
        .env("COHORT_CPU_SIMD_LOG", "1")
        .output()
        .unwrap();
    let _ = std::fs::remove_dir_all(&cache);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "the child failed: {:?}\n{err}",
        out.status
    );
    assert!(
        err.lines().any(|l| l.starts_with("cohort: waited")
            && l.contains("as the main thread exits for the vector form of `polynomial")),
        "the main thread's exit did not wait for the compile:\n{err}"
    );
}
