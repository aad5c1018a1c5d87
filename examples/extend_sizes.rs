//! Measure: the size of the renderer's `extend` for given shading sets (the hexadecimal
//! sets `--stats` reports under `startup_s.kernels`, e.g. `extend__thread_wg64_c0x90025`),
//! as SPIR-V words and WGSL bytes. The driver's pipeline creation time grows faster than
//! this size (BENCHMARKS.md, "Code size against compile time"), so it is the first thing
//! to check when a shading change may slow a cold start. Default render: `Cosine`,
//! `EachPath`, `NextEvent`, thread level.
//!
//! `cargo run --release -p cohort-tests --example extend_sizes -- 0x90025 0x1`
//!
//! With `COHORT_WGSL_DIR` set, each set's WGSL is written there too (`extend_0x90025.wgsl`),
//! to diff what a shading feature adds.

use cohort::{Group, Spec};
use cohort_kernels::extend::extend;
use cohort_kernels::integrator::NextEvent;
use cohort_kernels::path_end::EachPath;
use cohort_kernels::sampling::Cosine;

fn main() {
    let sets: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| {
            u32::from_str_radix(a.trim_start_matches("0x"), 16)
                .unwrap_or_else(|_| panic!("`{a}` is not a hexadecimal shading set"))
        })
        .collect();
    if sets.is_empty() {
        eprintln!("usage: extend_sizes SET [SET...]   (hexadecimal, e.g. 0x90025)");
        std::process::exit(2);
    }
    println!("| set | SPIR-V words | WGSL bytes |");
    println!("|---|---:|---:|");
    for set in sets {
        let spec = Spec::portable(&extend::INFO, Group::Thread).with_constants(&[set]);
        let built = extend::build::<Cosine, EachPath, NextEvent>(&spec);
        let e = cohort::emit::emit(&built).expect("emit");
        println!("| {set:#x} | {} | {} |", e.spirv.len(), e.wgsl.len());
        if let Some(dir) = std::env::var_os("COHORT_WGSL_DIR") {
            let path = std::path::Path::new(&dir).join(format!("extend_{set:#x}.wgsl"));
            std::fs::write(&path, &e.wgsl)
                .unwrap_or_else(|err| panic!("writing {}: {err}", path.display()));
        }
    }
}
