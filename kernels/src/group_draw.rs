//! The random numbers a coherence group shares in `extend`: each is a function of the
//! frame's group seed, the group's index and the iteration, so that every invocation
//! that computes it for the same group gets the same bits.
//!
//! `extend` gets them in one of two ways. Through `group_share`, keyed by the group of
//! the invocation: its position in the live list. Or, with `SHADES_SLOT_GROUPS`, each
//! invocation computes them for the group of the slot it shades, `slot /
//! Frame::group_slots`. While the list holds every slot in order, the two keys are the
//! same number, so the image is the same bit for bit. Only the slot key stays the same
//! once finished slots leave the list (`crate::retire`): the renderer uses it where each
//! invocation computes its group's values anyway (the CPU backend's
//! `Spec::recompute_group_share`, and the thread level), so that coherent
//! configurations there can retire slots as `normal` does.
//!
//! Where a slot group holds more than one slot, its invocations need not each compute
//! the same draws: each group's are computed once per iteration into a table, and
//! `extend` (`SHADES_GROUP_TABLE`) reads its slot's group's entries. [`draw_groups`]
//! fills it for a run's first iteration; from then on each `extend` fills it for the
//! next.

use crate::layout::*;
use crate::light::shared_light_draw;
use crate::rng::{hash, stream, uniform};
use crate::sampling::DiffuseSampler;
use cohort::prelude::*;

/// The key from which the diffuse sampler draws group `group`'s hemisphere patch at
/// iteration `iteration` (`DiffuseSampler::group_value`).
#[kernel_fn]
pub fn patch_key(f: &Frame, group: u32, iteration: u32) -> u32 {
    stream(f.group_seed, group, iteration, 0x5eed)
}

/// Group `group`'s Russian-roulette numbers at `iteration`: x for `group_rr`, y for
/// whole-group ends.
#[kernel_fn]
pub fn roulette_draw(f: &Frame, group: u32, iteration: u32) -> Vec2 {
    let k = stream(f.group_seed ^ 0x2b5e, group, iteration, 0x7a11);
    Vec2::new(uniform(k, 0), uniform(k, 1))
}

/// Group `group`'s cell of coherent glossy sampling at `iteration` (before the modulo by
/// the cells).
#[kernel_fn]
pub fn glossy_cell_draw(f: &Frame, group: u32, iteration: u32) -> u32 {
    hash(stream(f.group_seed ^ 0x61c8, group, iteration, 0x9e37))
}

/// Group `group`'s light pick and stratum of coherent light sampling at `iteration`.
#[kernel_fn]
pub fn light_draw(f: &Frame, group: u32, iteration: u32) -> Vec2 {
    shared_light_draw(
        stream(f.group_seed ^ 0x11c3, group, iteration, 0x4a7f),
        f.light_cells,
    )
}

/// Entries of the group table per group and iteration: the patch, the glossy cell and
/// the roulette numbers' bits in the first ([`draws_entry`]), the light draw's bits in x
/// and y of the second ([`light_entry`]), the sampler's parameters of the patch in the
/// third ([`params_entry`]).
pub const TABLE_STRIDE: u32 = 3;

/// Frame `f`'s slot groups, `ceil(slots / group_slots)` (`group_slots` > 1: with the
/// group table).
#[kernel_fn]
pub fn groups(f: &Frame) -> u32 {
    (f.slots + f.group_slots - 1) / f.group_slots
}

/// Entries of the group table of `groups` slot groups: two halves, one per iteration
/// parity ([`table_at`]; at least one group, so that there is always a buffer to bind).
pub fn table_len(groups: u32) -> usize {
    (2 * TABLE_STRIDE * groups.max(1)) as usize
}

/// Whether `group` is one of frame `f`'s slot groups: `group < ceil(slots / group_slots)`,
/// without a division.
#[kernel_fn]
pub fn is_group(f: &Frame, group: u32) -> bool {
    group * f.group_slots < f.slots
}

/// Where group `group`'s entries for iteration `iteration` start in the group table: in
/// the half of the iteration's parity, so that `extend` can write the next iteration's
/// draws while it reads this one's.
#[kernel_fn]
pub fn table_at(f: &Frame, group: u32, iteration: u32) -> usize {
    (TABLE_STRIDE * ((iteration % 2) * groups(f) + group)) as usize
}

/// Group `group`'s first table entry at `iteration`: its patch (0 for a sampler without
/// one), its glossy cell and its roulette numbers' bits.
#[kernel_fn]
pub fn draws_entry<S: DiffuseSampler>(f: &Frame, group: u32, iteration: u32) -> UVec4 {
    let mut patch = 0u32;
    if S::GROUP_VALUE {
        patch = S::group_value(patch_key(f, group, iteration), f.patches_n);
    }
    let rr = roulette_draw(f, group, iteration);
    UVec4::new(
        patch,
        glossy_cell_draw(f, group, iteration),
        rr.x.to_bits(),
        rr.y.to_bits(),
    )
}

/// Group `group`'s third table entry, from its first (`draws`): the bits of the diffuse
/// sampler's parameters of its patch (`DiffuseSampler::group_params`; zero for a sampler
/// without them), which every ray of the group would otherwise compute.
#[kernel_fn]
pub fn params_entry<S: DiffuseSampler>(f: &Frame, draws: UVec4) -> UVec4 {
    let mut p = UVec4::ZERO;
    if S::GROUP_PARAMS {
        let v = S::group_params(draws.x, f.patches_n);
        p = UVec4::new(v.x.to_bits(), v.y.to_bits(), v.z.to_bits(), v.w.to_bits());
    }
    p
}

/// Group `group`'s second table entry at `iteration`: its light draw's bits.
#[kernel_fn]
pub fn light_entry(f: &Frame, group: u32, iteration: u32) -> UVec4 {
    let light = light_draw(f, group, iteration);
    UVec4::new(light.x.to_bits(), light.y.to_bits(), 0, 0)
}

/// Every slot group's draws of the frame's iteration into its half of `table`: what
/// `extend` reads with `SHADES_GROUP_TABLE` instead of computing its group's draws in
/// each invocation. The CPU backend runs 16 invocations as one vector block, and
/// computed in every block (4096 blocks for 65536 slots) the draws were what kept
/// coherent warps slower than `normal` in `extend`; over the groups they take 128 blocks
/// (2048 warps of 32 slots). The renderer dispatches this once, for a run's first
/// iteration: from then on each `extend` writes the next iteration's draws into the
/// other half beside its work, which spares a dispatch per iteration (about 40 us each on
/// two cores, more than the draws themselves). The values are the ones `extend` would
/// compute, bit for bit.
#[kernel(workgroup = 64)]
pub fn draw_groups<S: DiffuseSampler>(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    table: &mut [UVec4],
) {
    if is_group(f, gi) {
        let at = table_at(f, gi, f.iteration);
        let draws = draws_entry::<S>(f, gi, f.iteration);
        table[at] = draws;
        table[at + 1] = light_entry(f, gi, f.iteration);
        table[at + 2] = params_entry::<S>(f, draws);
    }
}
