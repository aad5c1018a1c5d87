//! Recording one iteration of the wavefront loop (the paper's §3) into a batch, stage by
//! stage: reorder (every `RenderOptions::reorder` iterations), traverse, queue (with
//! `RenderOptions::shading`), extend, the shadow pass of next-event estimation, compact. Each stage is a function of the
//! iteration's buffers ([`Wavefront`]), and labels every dispatch it records with its
//! [`Stage`] as it records it ([`LabelledBatch`]): kernel time is summed by stage, however
//! many dispatches a stage takes.

use cohort::runtime::{Batch, GpuBuffer};
use cohort::Grid;
use cohort_kernels::extend::extend;
use cohort_kernels::group_draw::{draw_groups, groups};
use cohort_kernels::integrator::Integrator;
use cohort_kernels::layout::Frame;
use cohort_kernels::path_end::PathEnd;
use cohort_kernels::reorder;
use cohort_kernels::sampling::DiffuseSampler;
use cohort_kernels::shading::SHADES_GROUP_TABLE;
use cohort_kernels::traverse::{trace_shadow, traverse};
use cohort_kernels::traverse_wide::{trace_shadow8, traverse8};
use cohort_kernels::{compact, queues, retire};

use crate::kernels::{extend_set, Specs};
use crate::paths::Paths;
use crate::{GpuScene, RenderError};

/// The stages of one iteration, in order; every dispatch is labelled with its stage so
/// that timings are summed by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    /// Sort the live rays for the traversal (every `RenderOptions::reorder` iterations).
    Reorder,
    /// Closest hit of every live ray.
    Traverse,
    /// Partition the hits into material queues (`RenderOptions::shading`).
    Queue,
    /// Shade, sample lights and the next direction, end or continue paths.
    Extend,
    /// Occlusion of the light samples; finish the slots (next-event estimation only).
    Shadow,
    /// Stable partition of the live rays: compaction (`RenderOptions::compact`), or the
    /// retirement of finished slots from the live list (`cohort_kernels::retire`).
    Compact,
}

/// A batch being recorded, with the stage of each of its dispatches, in order (zipped
/// with the `DispatchStats` of the completed submission).
pub(crate) struct LabelledBatch<'d> {
    pub(crate) batch: Batch<'d>,
    pub(crate) stages: Vec<Stage>,
}

impl<'d> LabelledBatch<'d> {
    pub(crate) fn new(batch: Batch<'d>) -> Self {
        LabelledBatch {
            batch,
            stages: Vec::new(),
        }
    }

    /// Runs `record`, labelling every dispatch it adds to the batch with `stage`.
    fn stage<E>(
        &mut self,
        stage: Stage,
        record: impl FnOnce(&mut Batch<'d>) -> Result<(), E>,
    ) -> Result<(), RenderError>
    where
        RenderError: From<E>,
    {
        let before = self.batch.len();
        record(&mut self.batch)?;
        let added = self.batch.len() - before;
        self.stages.extend(std::iter::repeat_n(stage, added));
        Ok(())
    }
}

/// What the stages of one iteration read: the kernels, the frame (this iteration's), the
/// scene, the path state, and the options that choose stages.
pub(crate) struct Wavefront<'a> {
    pub(crate) specs: &'a Specs,
    pub(crate) frame: &'a Frame,
    pub(crate) scene: &'a GpuScene,
    pub(crate) paths: &'a Paths,
    /// Whether the live rays are compacted after each iteration (`RenderOptions::compact`).
    pub(crate) compaction: bool,
    /// Sort the rays every this many iterations; 0 = never (`RenderOptions::reorder`).
    pub(crate) reorder_every: u32,
    /// Shade over material queues (`RenderOptions::shading`).
    pub(crate) queues: bool,
    /// At least the entries of the current list (the slots, or fewer once finished
    /// slots are retired): every stage's grid.
    pub(crate) listed: u32,
    /// Whether the group table already holds this iteration's draws, written by the
    /// previous iteration's `extend` (`cohort_kernels::group_draw`).
    pub(crate) tabled: bool,
}

impl<'a> Wavefront<'a> {
    /// Records one iteration; `cur` is the `idrays` buffer that lists the live rays.
    /// Returns the one that lists them afterwards (compaction writes the other).
    pub(crate) fn record_iteration<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &self,
        b: &mut LabelledBatch<'_>,
        cur: usize,
    ) -> Result<usize, RenderError> {
        let live = &self.paths.idrays[cur];
        let count = &self.paths.counts[cur];
        let traced = self.reorder(b, count, live)?;
        self.traverse(b, count, traced)?;
        self.extend::<S, E, I>(b, count, live)?;
        if I::NEE {
            self.shadow(b, count, live)?;
        }
        if !self.compaction {
            return Ok(cur);
        }
        self.compact(b, count, live, &self.paths.idrays[1 - cur])?;
        Ok(1 - cur)
    }

    /// Records the retirement of the finished slots from list `cur`
    /// (`cohort_kernels::retire`): the other list receives the slots not done, and its
    /// count their number. Returns the other list's index. Not with compaction, whose
    /// lists keep every slot.
    pub(crate) fn retire(
        &self,
        b: &mut LabelledBatch<'_>,
        cur: usize,
    ) -> Result<usize, RenderError> {
        debug_assert!(!self.compaction);
        let p = self.paths;
        b.stage(Stage::Compact, |b| {
            retire::record(
                b,
                &self.specs.live,
                &self.specs.compact,
                self.listed,
                &p.counts[cur],
                &p.idrays[cur],
                &p.state,
                &p.flags,
                &p.block_sums,
                &p.counts[1 - cur],
                &p.idrays[1 - cur],
            )
        })?;
        Ok(1 - cur)
    }

    /// On a sorting iteration, sorts the `live` rays by direction octant and origin cell
    /// and returns them in bin order; otherwise returns `live`. Only the traversal reads
    /// the sorted list: every other kernel keeps the slot order of `idrays`.
    fn reorder(
        &self,
        b: &mut LabelledBatch<'_>,
        count: &GpuBuffer<u32>,
        live: &'a GpuBuffer<u32>,
    ) -> Result<&'a GpuBuffer<u32>, RenderError> {
        let every = self.reorder_every;
        let sorting = every > 0 && self.frame.iteration.is_multiple_of(every);
        let p = self.paths;
        let Some(sort) = p.sort.as_ref().filter(|_| sorting) else {
            return Ok(live);
        };
        let buffers = sort.buffers();
        b.stage(Stage::Reorder, |b| {
            reorder::record(
                b,
                &self.specs.reorder,
                self.listed,
                count,
                live,
                &p.state,
                &p.ray_o,
                &p.ray_d,
                &buffers,
            )
        })?;
        Ok(&sort.sorted)
    }

    /// Closest hit of the rays listed in `traced`, into `hits`. The 8-wide tree is faster
    /// (BENCHMARKS.md); the BVH2 serves trees too deep for its stack.
    fn traverse(
        &self,
        b: &mut LabelledBatch<'_>,
        count: &GpuBuffer<u32>,
        traced: &GpuBuffer<u32>,
    ) -> Result<(), RenderError> {
        let (s, f, p, n) = (self.scene, self.frame, self.paths, self.listed);
        b.stage(Stage::Traverse, |b| match &s.nodes8 {
            Some(n8) => traverse8::record(
                b,
                &self.specs.traverse8,
                n,
                f,
                count,
                traced,
                &p.state,
                &p.ray_o,
                &p.ray_d,
                n8,
                &s.triangles,
                &p.hits,
            ),
            None => traverse::record(
                b,
                &self.specs.traverse,
                n,
                f,
                count,
                traced,
                &p.state,
                &p.ray_o,
                &p.ray_d,
                &s.nodes,
                &s.triangles,
                &p.hits,
            ),
        })
    }

    /// Shades the hits of the `live` rays, samples lights and the next direction, and
    /// ends or continues each path: one `extend` built with the scene's set over the live
    /// list, or, over material queues, one for each queue.
    fn extend<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &self,
        b: &mut LabelledBatch<'_>,
        count: &GpuBuffer<u32>,
        live: &GpuBuffer<u32>,
    ) -> Result<(), RenderError> {
        let (s, p) = (self.scene, self.paths);
        let Some(q) = p.queues.as_ref().filter(|_| self.queues) else {
            let set = extend_set(s, self.frame);
            let mut all = Grid::Threads(self.listed);
            if set & SHADES_GROUP_TABLE != 0 {
                if !self.tabled {
                    self.draw_groups::<S>(b)?;
                }
                // Every group's invocation writes its next draws, listed or not.
                all = Grid::Threads(self.listed.max(groups(self.frame)));
            }
            return self.shade::<S, E, I>(b, all, set, count, live);
        };
        b.stage(Stage::Queue, |b| {
            queues::record(
                b,
                &self.specs.queues,
                self.listed,
                count,
                live,
                &p.state,
                &p.hits,
                &s.triangles,
                &s.materials,
                &q.buffers(),
            )
        })?;
        for (i, &set) in q.plan.sets.iter().enumerate() {
            let grid = Grid::Indirect {
                args: &q.args,
                offset_elems: 3 * i,
            };
            self.shade::<S, E, I>(b, grid, set, &q.queued, &q.out)?;
        }
        Ok(())
    }

    /// Every slot group's draws of this iteration into the group table that `extend`
    /// reads with `SHADES_GROUP_TABLE` (`cohort_kernels::group_draw::draw_groups`): for
    /// a run's first iteration, after which each `extend` writes the next one's.
    fn draw_groups<S: DiffuseSampler>(&self, b: &mut LabelledBatch<'_>) -> Result<(), RenderError> {
        let f = self.frame;
        b.stage(Stage::Extend, |b| {
            draw_groups::record::<S>(b, &self.specs.groups, groups(f), f, &self.paths.group_table)
        })
    }

    /// One `extend` built with `set`, over `grid`, for the rays that `count` and `list`
    /// give (the live list, or a material queue).
    fn shade<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &self,
        b: &mut LabelledBatch<'_>,
        grid: Grid<'_>,
        set: u32,
        count: &GpuBuffer<u32>,
        list: &GpuBuffer<u32>,
    ) -> Result<(), RenderError> {
        let (s, p) = (self.scene, self.paths);
        b.stage(Stage::Extend, |b| {
            extend::record::<S, E, I>(
                b,
                &self.specs.extend,
                grid,
                set,
                self.frame,
                count,
                list,
                &p.hits,
                &s.triangles,
                &s.shading_normals,
                &s.tex_coords,
                &s.textures,
                &p.film_filter,
                &s.materials,
                &s.lights,
                &s.delta_lights,
                &p.state,
                &p.ray_o,
                &p.ray_d,
                &p.beta,
                &p.radiance,
                &p.accum,
                &p.shadow_o,
                &p.shadow_d,
                &p.nee,
                &p.flags,
                &p.counters,
                &p.group_table,
            )
        })
    }

    /// Traces the shadow rays of the `live` slots and adds the unoccluded light samples.
    fn shadow(
        &self,
        b: &mut LabelledBatch<'_>,
        count: &GpuBuffer<u32>,
        live: &GpuBuffer<u32>,
    ) -> Result<(), RenderError> {
        let (s, f, p, n) = (self.scene, self.frame, self.paths, self.listed);
        b.stage(Stage::Shadow, |b| match &s.nodes8 {
            Some(n8) => trace_shadow8::record(
                b,
                &self.specs.shadow8,
                n,
                f,
                count,
                live,
                &p.shadow_o,
                &p.shadow_d,
                &p.nee,
                n8,
                &s.triangles,
                &p.radiance,
                &p.accum,
            ),
            None => trace_shadow::record(
                b,
                &self.specs.shadow,
                n,
                f,
                count,
                live,
                &p.shadow_o,
                &p.shadow_d,
                &p.nee,
                &s.nodes,
                &s.triangles,
                &p.radiance,
                &p.accum,
            ),
        })
    }

    /// Lists the rays of `live` that go on into `out`, in order.
    fn compact(
        &self,
        b: &mut LabelledBatch<'_>,
        count: &GpuBuffer<u32>,
        live: &GpuBuffer<u32>,
        out: &GpuBuffer<u32>,
    ) -> Result<(), RenderError> {
        let p = self.paths;
        b.stage(Stage::Compact, |b| {
            compact::record(
                b,
                &self.specs.compact,
                self.listed,
                count,
                &p.flags,
                &p.block_sums,
                &p.total,
                live,
                out,
            )
        })
    }
}
