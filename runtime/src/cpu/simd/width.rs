//! How many lanes a kernel's vector form runs per block: one vector register of `f32`s of
//! the CPU it is compiled for (16 with AVX-512, 8 with AVX2).
//!
//! Measured (BENCHMARKS.md, 2026-11-30) on cornell-box and stanford-like at 256x256: with
//! AVX-512, 16 lanes took 0.84-0.92x the kernel time of 8 on cornell-box and the same on
//! stanford-like, and 32 lanes 1.0-1.7x (a divergent traversal waits for its slowest lane);
//! compiled for AVX2 on the same machine, 16 lanes took 1.07-1.33x the time of 8.

use std::sync::OnceLock;

use super::llvm;
use super::types::{DEFAULT_WIDTH, WIDTHS};

/// The width of a CPU device's blocks unless it was opened with one
/// (`Device::cpu_with_lanes`): `COHORT_CPU_SIMD_LANES` (8, 16 or 32) when set, else the
/// JIT's register width.
pub fn default_lanes() -> u32 {
    if let Some(n) = forced() {
        return n;
    }
    match llvm::jit() {
        Ok(j) => j.register_lanes(),
        Err(_) => DEFAULT_WIDTH,
    }
}

/// `COHORT_CPU_SIMD_LANES`, when it names a width the lowering takes (read once: a value it
/// does not take is reported once).
fn forced() -> Option<u32> {
    static FORCED: OnceLock<Option<u32>> = OnceLock::new();
    *FORCED.get_or_init(|| {
        let v = std::env::var("COHORT_CPU_SIMD_LANES").ok()?;
        let n = v.trim().parse().ok().filter(|n| WIDTHS.contains(n));
        if n.is_none() {
            eprintln!(
                "cohort: COHORT_CPU_SIMD_LANES={v:?} is not one of {WIDTHS:?}; the vector forms keep the CPU's register width"
            );
        }
        n
    })
}
