//! Benchmark: time to build one kernel's naga module and emit WGSL + SPIR-V
//! (validation and compaction included), for every kernel variant of the test suite.
//! Prints the median over repeated fresh builds (the artifact cache is bypassed).
//!
//! `cargo run --release -p cohort-tests --example compile_times`

use std::time::Instant;

fn main() {
    let reps = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(25usize);
    println!("| kernel variant | build (ms) | build + emit (ms) | WGSL bytes | SPIR-V words |");
    println!("|---|---:|---:|---:|---:|");
    let mut worst = 0f64;
    for v in cohort_tests::variants::all() {
        let mut build = Vec::new();
        let mut total = Vec::new();
        let mut sizes = (0, 0);
        for _ in 0..reps {
            let t0 = Instant::now();
            let built = (v.build)(&v.spec);
            let t1 = Instant::now();
            let e = cohort::emit::emit(&built).expect("emit");
            let t2 = Instant::now();
            build.push((t1 - t0).as_secs_f64() * 1e3);
            total.push((t2 - t0).as_secs_f64() * 1e3);
            sizes = (e.wgsl.len(), e.spirv.len());
        }
        build.sort_by(f64::total_cmp);
        total.sort_by(f64::total_cmp);
        let (b, t) = (build[reps / 2], total[reps / 2]);
        worst = worst.max(t);
        println!(
            "| {} | {b:.3} | {t:.3} | {} | {} |",
            v.name, sizes.0, sizes.1
        );
    }
    println!("\nslowest build + emit: {worst:.3} ms (median of {reps})");
}
