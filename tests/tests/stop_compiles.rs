//! After `stop_background_compiles` (what a program calls as it ends, before exit destroys
//! LLVM's static objects) a kernel whose vector form is not compiled yet keeps its host
//! form: it runs, with the right results, and nothing waits for LLVM. Its own binary: the
//! stop is for the whole process.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use cohort::prelude::*;
use cohort::runtime::cpu::simd::Forms;
use cohort::runtime::Device;

#[kernel(workgroup = 64)]
pub fn affine(#[builtin(global_index)] gi: u32, xs: &[u32], out: &mut [u32]) {
    let i = gi as usize;
    if i < out.len() {
        out[i] = xs[i] * 3 + 1;
    }
}

#[test]
fn after_the_stop_a_kernel_runs_its_host_form_and_nothing_waits() {
    // No object file from an earlier run: the vector form would have to be compiled.
    let cache = std::env::temp_dir().join(format!("cohort-stop-compiles-{}", std::process::id()));
    std::env::set_var("COHORT_CACHE_DIR", &cache);
    let done = std::sync::Arc::new(AtomicBool::new(false));
    let watch = std::sync::Arc::clone(&done);
    // A compile that waited on the stopped compiler would hang the test binary.
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(120));
        if !watch.load(Ordering::SeqCst) {
            eprintln!("the dispatch after the stop still waits after 120 s");
            std::process::abort();
        }
    });
    cohort::runtime::stop_background_compiles();
    // Vector forms forced: without the stop, the dispatch would wait for the compile.
    let d = Device::cpu_with(Forms::Vector).unwrap();
    let n = 1000u32;
    let xs: Vec<u32> = (0..n).map(|i| i.wrapping_mul(2_654_435_761)).collect();
    let xs_b = d.upload(&xs).unwrap();
    let out = d.alloc::<u32>(n as usize).unwrap();
    affine::launch(&d, n, &xs_b, &out).unwrap();
    let got = d.read(&out).unwrap();
    done.store(true, Ordering::SeqCst);
    let objects: Vec<_> = std::fs::read_dir(cache.join("cpu-vector"))
        .map(|d| d.filter_map(|e| e.ok()).map(|e| e.path()).collect())
        .unwrap_or_default();
    let _ = std::fs::remove_dir_all(&cache);
    assert!(
        objects
            .iter()
            .all(|p| p.extension().is_none_or(|e| e != "o")),
        "LLVM compiled after the stop: {objects:?}"
    );
    let want: Vec<u32> = xs
        .iter()
        .map(|x| x.wrapping_mul(3).wrapping_add(1))
        .collect();
    assert_eq!(got, want);
}
