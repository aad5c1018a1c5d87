//! Atomics: fetch_add into histogram bins, fetch_max and fetch_min, and a
//! compare-exchange; the result does not depend on invocation order.
use cohort::prelude::*;

#[kernel(workgroup = 128)]
pub fn histogram(
    #[builtin(global_index)] gi: u32,
    values: &[u32],
    bins: &[AtomicU32],
    stats: &[AtomicU32],
) {
    let i = gi as usize;
    if i >= values.len() {
        return;
    }
    let v = values[i];
    let b = (v % bins.len() as u32) as usize;
    bins[b].fetch_add(1, Ordering::Relaxed);
    stats[0].fetch_max(v, Ordering::Relaxed);
    stats[1].fetch_min(v, Ordering::Relaxed);
    stats[2].fetch_or(1u32 << (v % 32), Ordering::Relaxed);
    // Claims slot 3 for the smallest value 7 (only invocations holding 7 try).
    if v == 7 {
        atomic_compare_exchange(&stats[3], 0, 7);
    }
}
