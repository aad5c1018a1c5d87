//! Dealing paths to finished slots. With a paths budget each slot renders its pixel's
//! paths one after another, so the slots whose paths happen to be long finish last, and
//! the last iterations of a render trace ever shorter lists: a GPU runs them part-empty.
//! Dealing took an H200 0.95-0.99x the kernel time of the same render without it, in
//! 12-27 % fewer iterations (BENCHMARKS.md, "Dealing paths to finished slots"); on the CPU
//! backend a shorter list is cheaper per path (it fits the caches), and dealing did not
//! pay, so the renderer deals on GPUs (`cohort_render::Deal`).
//!
//! At a retirement (`crate::retire`) the partition lists the `live` slots first and the
//! done ones after them. [`deal`] pairs the j-th done slot with the j-th live one and, if
//! the live slot has a path left after the one in flight, splits its remaining paths
//! between the two: a slot traces every `stride`-th path of its pixel (`Frame::copies`,
//! doubled by each split, [`path_stride`]), so the live slot keeps its current path and
//! every second one after it, and the done slot takes the others, starting with the next.
//! Every path of a pixel is still traced exactly once and draws from (seed, pixel, path).
//!
//! A slot sums its paths into `accum`, and the image sums a pixel's slots: a slot dealt
//! another pixel first deposits what it summed for its old one, with the segment's key
//! (pixel, first path), into `deposits`, and starts its sum anew. The image sums, per
//! pixel, the deposits and the slots' current sums in the order of their first paths, so
//! it does not depend on which thread or warp took which slot; with no deposit that is
//! the slot order of the image without dealing.
//!
//! Deposits fill `deposits` as the pairs deal, counted in `completed[2]`; a retirement
//! whose pairs might not fit deals none (`completed[3]`, the count when it began, keeps
//! that test the same for every pair).

use crate::extend::{camera_beta, camera_dir, camera_origin, film_sample, lens_offset};
use crate::layout::*;
use crate::rng::stream;
use cohort::prelude::*;

/// The distance between the paths a slot traces, from its `state.w`: `Frame::copies`,
/// doubled by each split of its paths ([`deal`]).
#[kernel_fn]
pub fn path_stride(f: &Frame, w: u32) -> u32 {
    f.copies << (w >> SPLITS_SHIFT)
}

/// Whether a slot tracing path `path` (not done) with `stride` (`path_stride`) has a path
/// after it in the budget (`path + stride` below `first_path + paths_per_pixel`), which it
/// could give away.
#[kernel_fn]
pub fn has_next_path(f: &Frame, path: u32, stride: u32) -> bool {
    // Relative to the first path, so that nothing wraps for budgets near 2^32.
    let rel = path - f.first_path;
    f.paths_per_pixel != 0 && rel < f.paths_per_pixel && f.paths_per_pixel - rel > stride
}

/// Pairs a retirement forms: `min(live, done)`, or none if their deposits could overflow
/// `capacity` records after the `used` ones. The same number in [`deal`] and
/// [`deal_commit`].
#[kernel_fn]
pub fn deal_pairs(listed: u32, live: u32, used: u32, capacity: u32) -> u32 {
    let done = listed - live;
    let mut pairs = live.min(done);
    if used > capacity || capacity - used < pairs {
        pairs = 0;
    }
    pairs
}

/// Elements of `deposits` for `slots` slots that trace at most `paths_per_slot` paths
/// each: two `Vec4` per record (the sum, then the segment's pixel and first path as
/// bits). A slot deposits once per deal it takes, and takes at most one path fewer than it
/// traces; measured, renders at 32 paths per pixel dealt up to 1.8 times per slot
/// (BENCHMARKS.md, "Dealing paths to finished slots"). A render that runs out of records
/// only stops dealing.
pub fn deposits_len(slots: usize, paths_per_slot: u32) -> usize {
    let per_slot = (paths_per_slot as usize).clamp(1, DEPOSITS_PER_SLOT);
    2 * (slots.max(1) * per_slot).min(MAX_DEPOSITS)
}

/// The most deposit records per slot.
pub const DEPOSITS_PER_SLOT: usize = 4;

/// The most deposit records of a render (256 MiB).
pub const MAX_DEPOSITS: usize = 1 << 23;

/// Pair `gi` of a retirement: `listed_count[0]` slots were listed, of which the partition
/// put `live_count[0]` live ones first in `idrays`. Live slot `idrays[gi]` gives every
/// second of its paths after the current one to finished slot `idrays[live + gi]`, which
/// deposits its sum and starts the first of them; where the live slot has no path left
/// after its current one, nothing happens.
#[kernel(workgroup = 64)]
pub fn deal(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    listed_count: &[u32],
    live_count: &[u32],
    idrays: &[u32],
    film_filter: &[f32],
    state: &mut [UVec4],
    ray_o: &mut [Vec4],
    ray_d: &mut [Vec4],
    beta: &mut [Vec4],
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
    segment_first: &mut [u32],
    deposits: &mut [Vec4],
    completed: &[AtomicU32],
) {
    let live = live_count[0];
    // The records written before this retirement, unchanged while it runs: every
    // invocation sees the same number of pairs.
    let before = completed[3].load(Ordering::Relaxed);
    let capacity = (deposits.len() / 2) as u32;
    if gi >= deal_pairs(listed_count[0], live, before, capacity) {
        return;
    }
    let giver = idrays[gi as usize] as usize;
    let taker = idrays[(live + gi) as usize] as usize;
    let g = state[giver];
    let stride = path_stride(f, g.w);
    if !has_next_path(f, g.y, stride) {
        return;
    }
    // Records are taken in whatever order the invocations run; the image orders them by
    // their keys.
    let at = 2 * completed[2].fetch_add(1, Ordering::Relaxed) as usize;
    let t = state[taker];
    deposits[at] = accum[taker];
    deposits[at + 1] = Vec4::new(
        f32::from_bits(t.x),
        f32::from_bits(segment_first[taker]),
        0.0,
        0.0,
    );
    // Both now step by twice the stride: the giver from its current path, the taker from
    // the next one.
    let splits = (g.w >> SPLITS_SHIFT) + 1;
    state[giver] = UVec4::new(g.x, g.y, g.z, (g.w & DONE) | (splits << SPLITS_SHIFT));
    let pixel = g.x;
    let path = g.y + stride;
    let key = stream(f.seed, pixel, path, 0);
    let fs = film_sample(f, film_filter, pixel, key);
    let film = fs.truncate();
    let lens = lens_offset(f, key);
    state[taker] = UVec4::new(pixel, path, 0, splits << SPLITS_SHIFT);
    ray_o[taker] = camera_origin(f, film, lens).extend(0.0);
    ray_d[taker] = camera_dir(f, film, lens).extend(1.0);
    beta[taker] = camera_beta(fs.w);
    radiance[taker] = Vec4::ZERO;
    accum[taker] = Vec4::ZERO;
    segment_first[taker] = path;
    // The taker is no longer done: the done count (`completed[1]`) drops by one.
    completed[1].fetch_sub(1, Ordering::Relaxed);
}

/// After [`deal`]: the list counts its pairs' finished slots again (`live_count[0]`
/// becomes live + pairs; a pair whose live slot had no path to give lists a finished
/// slot, which the stages skip), and `completed[3]` the records written so far.
#[kernel(workgroup = 64)]
pub fn deal_commit(
    #[builtin(global_index)] gi: u32,
    listed_count: &[u32],
    live_count: &mut [u32],
    deposits: &[Vec4],
    completed: &[AtomicU32],
) {
    if gi == 0 {
        let live = live_count[0];
        let before = completed[3].load(Ordering::Relaxed);
        let capacity = (deposits.len() / 2) as u32;
        live_count[0] = live + deal_pairs(listed_count[0], live, before, capacity);
        completed[3].store(completed[2].load(Ordering::Relaxed), Ordering::Relaxed);
    }
}

/// Dispatches that [`record`] adds to a batch.
pub const DISPATCHES: usize = 2;

/// The specialisations of [`deal`] and [`deal_commit`].
pub struct Specs {
    pub deal: cohort::Spec,
    pub commit: cohort::Spec,
}

impl Specs {
    pub fn new(device: &cohort::runtime::Device) -> Specs {
        Specs {
            deal: deal::spec(device, None),
            commit: deal_commit::spec(device, None),
        }
    }

    /// Their compiled artifacts.
    pub fn artifacts(
        &self,
    ) -> Result<Vec<std::sync::Arc<cohort::runtime::KernelArtifact>>, cohort::emit::CompileError>
    {
        Ok(vec![
            deal::artifact(&self.deal)?,
            deal_commit::artifact(&self.commit)?,
        ])
    }
}

/// The path state [`record`] reads and changes, one entry per slot (`segment_first`:
/// the first path of the slot's current sum) and the deposits
/// ([`deposits_len`]).
pub struct Slots<'a> {
    pub film_filter: &'a cohort::runtime::GpuBuffer<f32>,
    pub state: &'a cohort::runtime::GpuBuffer<UVec4>,
    pub ray_o: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub ray_d: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub beta: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub radiance: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub accum: &'a cohort::runtime::GpuBuffer<Vec4>,
    pub segment_first: &'a cohort::runtime::GpuBuffer<u32>,
    pub deposits: &'a cohort::runtime::GpuBuffer<Vec4>,
    /// [completed paths, slots done, deposit records, deposit records before this
    /// retirement]
    pub completed: &'a cohort::runtime::GpuBuffer<u32>,
}

/// Records the dealing after a retirement into `batch` ([`DISPATCHES`] dispatches): of
/// the `listed_count[0] <= n` slots listed before it, the partition put the
/// `live_count[0]` live ones first in `idrays`.
#[allow(clippy::too_many_arguments)]
pub fn record(
    batch: &mut cohort::runtime::Batch<'_>,
    specs: &Specs,
    n: u32,
    f: &Frame,
    listed_count: &cohort::runtime::GpuBuffer<u32>,
    live_count: &cohort::runtime::GpuBuffer<u32>,
    idrays: &cohort::runtime::GpuBuffer<u32>,
    s: &Slots<'_>,
) -> cohort::Result<()> {
    deal::record(
        batch,
        &specs.deal,
        n.div_ceil(2),
        f,
        listed_count,
        live_count,
        idrays,
        s.film_filter,
        s.state,
        s.ray_o,
        s.ray_d,
        s.beta,
        s.radiance,
        s.accum,
        s.segment_first,
        s.deposits,
        s.completed,
    )?;
    deal_commit::record(
        batch,
        &specs.commit,
        1u32,
        listed_count,
        live_count,
        s.deposits,
        s.completed,
    )
}
