//! Coherence groups: one source, every group level. The leader of each group draws a
//! value from (seed, group index); every member of the group receives it.
use cohort::prelude::*;

#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct PickParams {
    pub seed: u32,
    pub n: u32,
}

/// A 32-bit integer hash (lowbias32).
#[kernel_fn]
pub fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

#[kernel(workgroup = 256, group = Warp)]
pub fn group_pick(#[builtin(global_index)] gi: u32, p: &PickParams, out: &mut [u32]) {
    let pick = group_share(|group| hash(p.seed ^ hash(group)));
    let i = gi as usize;
    if i < p.n as usize {
        out[i] = pick;
    }
}
