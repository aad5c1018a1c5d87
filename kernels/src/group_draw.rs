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

use crate::layout::*;
use crate::light::shared_light_draw;
use crate::rng::{hash, stream, uniform};
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
