//! Retiring finished slots from the live list. With a paths budget each slot renders its
//! pixel's paths one after another, and slots finish at different iterations: on
//! stanford-like at 256x256 and 32 paths, half the slots were done by iteration 110 of
//! 240, and more than half of all slot-iterations were of done slots.
//! Every stage still ran over the whole list, and a done slot is not free where lanes run
//! together: a GPU warp or a CPU vector block with one live lane costs as much as a full
//! one. So the renderer, once the slots not done are at most three quarters of those
//! listed, lists only them: [`mark_live`] flags each listed slot whose path is not done, and the
//! stable partition of [`crate::compact`] puts them first, in their order, and writes
//! their number as the new list's count. Done slots never come back (`DONE` is final
//! for a run), so the list stays a superset of the live slots; the stages already skip a
//! listed slot that is done.
//!
//! The image does not change: every stage works per slot, whatever its place in the list,
//! as long as no draw is shared by a group of neighbouring invocations (the renderer
//! retires only where every draw is keyed by path).

use crate::compact;
use crate::layout::*;
use cohort::prelude::*;

/// Compaction flag of list entry `gi`: 1 when its slot's path is not done.
#[kernel(workgroup = 64)]
pub fn mark_live(
    #[builtin(global_index)] gi: u32,
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    flags: &mut [u32],
) {
    if gi < count[0] {
        let s = idrays[gi as usize];
        flags[gi as usize] = (state[s as usize].w & DONE == 0) as u32;
    }
}

/// Dispatches that [`record`] adds to a batch.
pub const DISPATCHES: usize = 1 + compact::DISPATCHES;

/// The specialisation of [`mark_live`] (the partition's are [`compact::Specs`]).
pub fn spec(device: &cohort::runtime::Device) -> cohort::Spec {
    mark_live::spec(device, None)
}

/// [`mark_live`]'s and the partition's compiled artifacts.
pub fn artifacts(
    live: &cohort::Spec,
    compact_specs: &compact::Specs,
) -> Result<Vec<std::sync::Arc<cohort::runtime::KernelArtifact>>, cohort::emit::CompileError> {
    let mut v = vec![mark_live::artifact(live)?];
    v.extend(compact::artifacts(compact_specs)?);
    Ok(v)
}

/// Records the retirement of the done slots among the `count[0] <= n` listed in `idrays`
/// into `batch` ([`DISPATCHES`] dispatches): `out` receives the slots not done first, in
/// list order, then the done ones, and `out_count[0]` the number not done. `flags` needs
/// `n` elements and `scratch` [`compact::scratch_len`]`(n)`.
#[allow(clippy::too_many_arguments)]
pub fn record(
    batch: &mut cohort::runtime::Batch<'_>,
    live: &cohort::Spec,
    compact_specs: &compact::Specs,
    n: u32,
    count: &cohort::runtime::GpuBuffer<u32>,
    idrays: &cohort::runtime::GpuBuffer<u32>,
    state: &cohort::runtime::GpuBuffer<UVec4>,
    flags: &cohort::runtime::GpuBuffer<u32>,
    scratch: &cohort::runtime::GpuBuffer<u32>,
    out_count: &cohort::runtime::GpuBuffer<u32>,
    out: &cohort::runtime::GpuBuffer<u32>,
) -> cohort::Result<()> {
    mark_live::record(batch, live, n, count, idrays, state, flags)?;
    compact::record(
        batch,
        compact_specs,
        n,
        count,
        flags,
        scratch,
        out_count,
        idrays,
        out,
    )
}
