//! Subgroup operations: ballot and popcount, exclusive and inclusive prefix sums,
//! broadcast of lane 0, any/all — the building blocks of stream compaction.
use cohort::prelude::*;

#[kernel(workgroup = 64)]
pub fn subgroup_scan(
    #[builtin(global_index)] gi: u32,
    #[builtin(subgroup_lane)] lane: u32,
    #[builtin(subgroup_size)] size: u32,
    flags: &[u32],
    exclusive: &mut [u32],
    inclusive: &mut [u32],
    votes: &mut [u32],
) {
    let i = gi as usize;
    let mut f = 0u32;
    if i < flags.len() {
        f = flags[i];
    }
    let keep = f != 0;
    let ballot = subgroup_ballot(keep);
    let below = ballot.x & ((1u32 << lane) - 1);
    let ex = subgroup_exclusive_add(f);
    let inc = subgroup_inclusive_add(f);
    let first = subgroup_broadcast(f, 0);
    let any = subgroup_any(keep) as u32;
    let all = subgroup_all(keep) as u32;
    let total = subgroup_add(f);
    if i < flags.len() {
        exclusive[i] = ex;
        inclusive[i] = inc;
        votes[i] = below.count_ones()
            + (first << 8)
            + (any << 16)
            + (all << 17)
            + (total << 20)
            + (size << 26);
    }
}
