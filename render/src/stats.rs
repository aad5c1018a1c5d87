//! What a render reports: kernel time by stage, host time, paths and rays
//! ([`RenderStats`]), and where the time before the first iteration went ([`Startup`]).

use std::time::Duration;

use crate::iteration::Stage;

#[derive(Clone, Copy, Debug, Default)]
pub struct KernelTimes {
    pub traverse: Duration,
    pub extend: Duration,
    /// The shadow pass of next-event estimation.
    pub shadow: Duration,
    pub compact: Duration,
    /// Sorting the rays before the traversal (`RenderOptions::reorder`).
    pub reorder: Duration,
    /// Partitioning the hits into material queues (`RenderOptions::shading`).
    pub queue: Duration,
}
impl KernelTimes {
    pub fn total(&self) -> Duration {
        self.traverse + self.extend + self.shadow + self.compact + self.reorder + self.queue
    }
    /// Adds `t` to the time of `stage`.
    pub(crate) fn add(&mut self, stage: Stage, t: Duration) {
        match stage {
            Stage::Traverse => self.traverse += t,
            Stage::Extend => self.extend += t,
            Stage::Shadow => self.shadow += t,
            Stage::Compact => self.compact += t,
            Stage::Reorder => self.reorder += t,
            Stage::Queue => self.queue += t,
        }
    }
}

/// Stage by stage: what several devices' times add up to.
impl std::ops::AddAssign for KernelTimes {
    fn add_assign(&mut self, o: KernelTimes) {
        let KernelTimes {
            traverse,
            extend,
            shadow,
            compact,
            reorder,
            queue,
        } = o;
        self.traverse += traverse;
        self.extend += extend;
        self.shadow += shadow;
        self.compact += compact;
        self.reorder += reorder;
        self.queue += queue;
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub iterations: u32,
    pub completed_paths: u64,
    /// Rays traversed (live rays summed over iterations).
    pub rays: u64,
    pub kernel: KernelTimes,
    pub wall: Duration,
    pub pixels: u64,
    /// Ray slots of the wavefront: paths in flight at once (`RenderOptions::wavefront`).
    pub slots: u64,
    /// Iterations shaded over material queues (`RenderOptions::shading`); the others
    /// were shaded by one kernel.
    pub queued_iterations: u32,
    /// Where the host's time went: recording batches, submitting them, and waiting for
    /// the oldest one in flight (the GPU is busy then; recording while it is idle is
    /// what makes the wall time exceed the kernel time).
    pub host: HostTimes,
}

/// Host time of a render, by stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HostTimes {
    /// Batches submitted.
    pub batches: u32,
    pub record: Duration,
    pub submit: Duration,
    pub wait: Duration,
}

impl RenderStats {
    pub fn paths_per_pixel(&self) -> f64 {
        self.completed_paths as f64 / self.pixels.max(1) as f64
    }
    /// Completed paths per second of kernel time.
    pub fn paths_per_second(&self) -> f64 {
        self.completed_paths as f64 / self.kernel.total().as_secs_f64().max(1e-12)
    }
    /// Rays per second of traversal kernel time.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.kernel.traverse.as_secs_f64().max(1e-12)
    }
}

/// Where the time before the first iteration went (the scene's share is measured by
/// `GpuScene::prepare`).
#[derive(Clone, Debug, Default)]
pub struct Startup {
    /// BVH build (binary and 8-wide) on the host.
    pub bvh_build: Duration,
    /// Uploading the scene.
    pub upload: Duration,
    /// Laying out and allocating the path state, beside `pipelines`.
    pub path_state: Duration,
    /// Pipeline creation of the kernels the options use (prepared before any render).
    pub pipelines: Duration,
    /// Each pipeline thread's kernels (artifact names, `+`-joined) and the time it took to
    /// build and create them, longest first: the threads run side by side, so the first
    /// is what `pipelines` waited for (with empty caches, the driver compiling it).
    pub kernels: Vec<(String, Duration)>,
    /// What `extend` was built for: the scene's BSDF kinds and shading features
    /// (`cohort_kernels::shading`, whose `label` names them).
    pub shading: u32,
}
