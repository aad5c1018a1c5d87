//! Whole-group decisions (`group_any`): every invocation learns whether any member of its
//! coherence group voted. Three rounds in a loop, the middle one with nobody voting, check
//! that the group's flag starts from zero at every call.
use cohort::prelude::*;

#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, GpuType)]
#[repr(C)]
pub struct VoteParams {
    /// Invocation i votes when `values[i] < threshold` (in rounds 0 and 2).
    pub threshold: u32,
    pub n: u32,
}

#[kernel(workgroup = 256, group = Warp)]
pub fn group_vote(
    #[builtin(global_index)] gi: u32,
    p: &VoteParams,
    values: &[u32],
    out: &mut [u32],
) {
    let i = gi as usize;
    let mut bits = 0u32;
    for round in 0..3u32 {
        let limit = if round == 1 { 0 } else { p.threshold };
        let mine = gi < p.n && values[i] < limit;
        if group_any(mine) {
            bits |= 1u32 << round;
        }
    }
    if gi < p.n {
        out[i] = bits;
    }
}
