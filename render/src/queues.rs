//! Shading over material queues (`RenderOptions::shading`,
//! `cohort_kernels::queues`): which queues a scene has, the `extend` that shades each,
//! and their buffers on the device.
//!
//! A queue per BSDF kind of the scene's set, in the order of `shading::KINDS`, and one for
//! blends when the scene has any. Queue 0 also takes the misses and the done slots. A
//! kind's `extend` is built with that kind alone and the scene's features but blending; the
//! blends' with the scene's whole set (a blend reaches any of its kinds).

use cohort::runtime::{Device, GpuBuffer};
use cohort_kernels::queues::{self, QueueBuffers, BLEND_ENTRY, MAX_QUEUES, TABLE_LEN};
use cohort_kernels::shading::{kind_bit, queue_set, KINDS, SHADES_BLEND};

use crate::RenderError;

/// The queues of a scene's shading set: the table the kernels read and the set of the
/// `extend` that shades each queue.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Plan {
    /// Queue of each kind (by kind), of blends ([`BLEND_ENTRY`]), then the number of
    /// queues; the two dispatch entries after it are the caller's.
    pub(crate) table: [u32; TABLE_LEN],
    /// `extend`'s shading set for each queue, in queue order.
    pub(crate) sets: Vec<u32>,
}

/// The queues of a scene that shades with `set` (`GpuScene::shading`).
pub(crate) fn plan(set: u32) -> Plan {
    let kind_bits = KINDS.iter().fold(0, |a, &(k, _)| a | kind_bit(k));
    let features = set & !kind_bits & !SHADES_BLEND;
    let mut table = [0u32; TABLE_LEN];
    let mut sets = Vec::new();
    for &(kind, _) in KINDS.iter() {
        if set & kind_bit(kind) != 0 {
            table[kind as usize] = sets.len() as u32;
            sets.push(features | kind_bit(kind));
        }
    }
    if set & SHADES_BLEND != 0 {
        table[BLEND_ENTRY] = sets.len() as u32;
        sets.push(set);
    }
    // A scene without materials still has its misses to shade.
    if sets.is_empty() {
        sets.push(features);
    }
    debug_assert!(sets.len() as u32 <= MAX_QUEUES);
    table[BLEND_ENTRY + 1] = sets.len() as u32;
    let sets = sets
        .iter()
        .enumerate()
        .map(|(q, &s)| queue_set(s, q as u32))
        .collect();
    Plan { table, sets }
}

/// The queues' buffers for a wavefront of `slots` (`cohort_kernels::queues::QueueBuffers`).
pub(crate) struct QueueState {
    pub(crate) plan: Plan,
    table: GpuBuffer<u32>,
    keys: GpuBuffer<u32>,
    hist: GpuBuffer<u32>,
    pub(crate) queued: GpuBuffer<u32>,
    pub(crate) args: GpuBuffer<u32>,
    pub(crate) out: GpuBuffer<u32>,
}

impl QueueState {
    /// Buffers for `slots` rays shaded with `set` by an `extend` of `workgroup_size`.
    pub(crate) fn new(
        d: &Device,
        slots: u32,
        set: u32,
        workgroup_size: u32,
    ) -> Result<QueueState, RenderError> {
        let mut plan = plan(set);
        plan.table[BLEND_ENTRY + 2] = workgroup_size;
        plan.table[BLEND_ENTRY + 3] = d.info().max_workgroups_per_dim;
        Ok(QueueState {
            table: d.upload(&plan.table)?,
            keys: d.alloc(slots as usize)?,
            hist: d.alloc(queues::hist_len(slots))?,
            queued: d.alloc(4 * MAX_QUEUES as usize)?,
            args: d.alloc(3 * MAX_QUEUES as usize)?,
            out: d.alloc(2 * slots.max(1) as usize)?,
            plan,
        })
    }

    pub(crate) fn buffers(&self) -> QueueBuffers<'_> {
        QueueBuffers {
            table: &self.table,
            keys: &self.keys,
            hist: &self.hist,
            queued: &self.queued,
            args: &self.args,
            out: &self.out,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cohort_kernels::shading::{queue_index, SHADES_QUEUE, SHADES_TEXTURES};

    #[test]
    fn one_queue_per_kind_and_one_for_blends() {
        let (a, b) = (KINDS[0].0, KINDS[2].0);
        let set = kind_bit(a) | kind_bit(b) | SHADES_BLEND | SHADES_TEXTURES;
        let p = plan(set);
        assert_eq!(p.sets.len(), 3);
        assert_eq!(p.table[BLEND_ENTRY + 1], 3);
        assert_eq!((p.table[a as usize], p.table[b as usize]), (0, 1));
        assert_eq!(p.table[BLEND_ENTRY], 2);
        // A kind's queue: that kind and the features but blending; the blends': all.
        let base = |s: u32| s & !(SHADES_QUEUE | 0xff << 24);
        assert_eq!(base(p.sets[0]), kind_bit(a) | SHADES_TEXTURES);
        assert_eq!(base(p.sets[1]), kind_bit(b) | SHADES_TEXTURES);
        assert_eq!(base(p.sets[2]), set);
        for (q, s) in p.sets.iter().enumerate() {
            assert_eq!(queue_index(*s), q as u32);
            assert!(s & SHADES_QUEUE != 0);
        }
    }

    #[test]
    fn a_scene_without_materials_has_one_queue_for_its_misses() {
        let p = plan(0);
        assert_eq!(p.sets.len(), 1);
        assert_eq!(p.table[BLEND_ENTRY + 1], 1);
    }
}
