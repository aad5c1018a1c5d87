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
//! the same draws: [`draw_groups`] computes every group's once per iteration into a
//! table, and `extend` (`SHADES_GROUP_TABLE`) reads its slot's group's entries.

use crate::layout::*;
use crate::light::shared_light_draw;
use crate::rng::{hash, stream, uniform};
use crate::sampling::DiffuseSampler;
use cohort::prelude::*;

/// The key from which the diffuse sampler draws group `group`'s hemisphere patch
/// (`DiffuseSampler::group_value`).
#[kernel_fn]
pub fn patch_key(f: &Frame, group: u32) -> u32 {
    stream(f.group_seed, group, f.iteration, 0x5eed)
}

/// Group `group`'s Russian-roulette numbers: x for `group_rr`, y for whole-group ends.
#[kernel_fn]
pub fn roulette_draw(f: &Frame, group: u32) -> Vec2 {
    let k = stream(f.group_seed ^ 0x2b5e, group, f.iteration, 0x7a11);
    Vec2::new(uniform(k, 0), uniform(k, 1))
}

/// Group `group`'s cell of coherent glossy sampling (before the modulo by the cells).
#[kernel_fn]
pub fn glossy_cell_draw(f: &Frame, group: u32) -> u32 {
    hash(stream(f.group_seed ^ 0x61c8, group, f.iteration, 0x9e37))
}

/// Group `group`'s light pick and stratum of coherent light sampling.
#[kernel_fn]
pub fn light_draw(f: &Frame, group: u32) -> Vec2 {
    shared_light_draw(
        stream(f.group_seed ^ 0x11c3, group, f.iteration, 0x4a7f),
        f.light_cells,
    )
}

/// Entries of [`draw_groups`]' table per group: the patch, the glossy cell and the
/// roulette numbers' bits in the first, the light draw's bits in x and y of the second.
pub const TABLE_STRIDE: u32 = 2;

/// Entries of the group table of `slots` slots in groups of `group_slots`
/// ([`draw_groups`]; at least one group, so that there is always a buffer to bind).
pub fn table_len(slots: u32, group_slots: u32) -> usize {
    (TABLE_STRIDE * slots.div_ceil(group_slots.max(1)).max(1)) as usize
}

/// Every slot group's draws, once per iteration, into `table` (`TABLE_STRIDE` entries
/// per group): what `extend` reads with `SHADES_GROUP_TABLE` instead of computing its
/// group's draws in each invocation. The CPU backend runs 16 invocations as one vector
/// block, and computed in every block (4096 blocks for 65536 slots) the draws were what
/// kept coherent warps slower than `normal` in `extend`; over the groups they take 128
/// blocks (2048 warps of 32 slots), and `extend` reads two entries instead. The values
/// are the ones `extend` would compute, bit for bit.
#[kernel(workgroup = 64)]
pub fn draw_groups<S: DiffuseSampler>(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    table: &mut [UVec4],
) {
    // `gi < ceil(slots / group_slots)`, without a division.
    if gi * f.group_slots < f.slots {
        let mut patch = 0u32;
        if S::GROUP_VALUE {
            patch = S::group_value(patch_key(f, gi), f.patches_n);
        }
        let rr = roulette_draw(f, gi);
        let light = light_draw(f, gi);
        let at = (TABLE_STRIDE * gi) as usize;
        table[at] = UVec4::new(
            patch,
            glossy_cell_draw(f, gi),
            rr.x.to_bits(),
            rr.y.to_bits(),
        );
        table[at + 1] = UVec4::new(light.x.to_bits(), light.y.to_bits(), 0, 0);
    }
}
