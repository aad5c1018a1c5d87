//! A plain copy kernel: the memory-bandwidth baseline that compaction is measured
//! against (BENCHMARKS.md).

use cohort::prelude::*;

#[kernel(workgroup = 256)]
pub fn copy_u32(#[builtin(global_index)] gi: u32, src: &[u32], dst: &mut [u32]) {
    let i = gi as usize;
    if i < src.len() {
        dst[i] = src[i];
    }
}
