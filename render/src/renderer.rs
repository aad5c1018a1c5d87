//! The iteration loop of the wavefront path tracer (PAPER.md §3): per iteration one
//! batch `traverse8` (or `traverse`) → `extend::<S, E>` → `compact_*`, until the budget
//! (completed paths per pixel, or accumulated GPU time of those kernels, as in the
//! paper) is spent.
//!
//! A run is resumable: [`Renderer::start`] begins it and [`Renderer::advance`] continues
//! it to a cumulative budget, keeping the image and statistics in between, so that
//! several renderers can take turns on the GPU (`cohort figures` does, so that each sees
//! the same clock changes). [`Renderer::render`] is one start and one advance.

use std::sync::Arc;
use std::time::{Duration, Instant};

use cohort::runtime::{
    Batch, Device, DispatchStats, GpuBuffer, KernelArtifact, ReadBack, RuntimeError, Submission,
};
use cohort::Group;
use cohort_kernels::compact;
use cohort_kernels::display::{display, DisplayParams};
use cohort_kernels::extend::{extend, init_paths};
use cohort_kernels::integrator::{Implicit, Integrator, NextEvent};
use cohort_kernels::layout::Frame;
use cohort_kernels::path_end::{EachPath, PathEnd, WholeGroup};
use cohort_kernels::reorder;
use cohort_kernels::sampling::{
    CoherentCosine, CoherentEqualArea, CoherentUniform, Cosine, DiffuseSampler,
};
use cohort_kernels::traverse::{trace_shadow, traverse};
use cohort_kernels::traverse_wide::{trace_shadow8, traverse8};
use cohort_scenes::{morton_pixel_order, Camera, Scene};
use glam::{UVec4, Vec3, Vec4};

use crate::{GpuScene, Image, Shard};

/// A configuration of the paper: which invocations share a coherent draw, and whether
/// diffuse bounces sample coherently at all.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Algorithm {
    pub group: Group,
    /// false: the reference `normal` (independent cosine sampling per path).
    pub coherent: bool,
}

impl Algorithm {
    pub const NORMAL: Algorithm = Algorithm {
        group: Group::Thread,
        coherent: false,
    };

    /// `normal`, `warp`, `block_256`, `block_512`, `block_1024`, `grid` (and any
    /// `block_N` with N a multiple of 32 up to 1024).
    pub fn parse(s: &str) -> Option<Algorithm> {
        if s == "normal" {
            return Some(Algorithm::NORMAL);
        }
        let group = Group::parse(s)?;
        match group {
            Group::Thread => None,
            Group::Block(n) if n % 32 != 0 => None,
            _ => Some(Algorithm {
                group,
                coherent: true,
            }),
        }
    }

    pub fn name(self) -> String {
        if self.coherent {
            self.group.label()
        } else {
            "normal".into()
        }
    }
}

/// How a ray samples inside its group's patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InPatch {
    /// Uniform by solid angle, weighted by the exact pdf (the paper).
    Uniform,
    /// Cosine-weighted: pdf exactly cos/pi (beyond the paper).
    Cosine,
    /// Equal-area patches through the Shirley–Chiu concentric map (beyond the paper).
    EqualArea,
}

/// The light transport estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    /// Implicit path tracing: a path contributes only when it reaches an emitter (the
    /// paper's renderer).
    Path,
    /// Next-event estimation with MIS (Mitsuba's `path` integrator).
    Nee,
}

impl IntegratorKind {
    pub fn parse(s: &str) -> Option<IntegratorKind> {
        match s {
            "path" => Some(IntegratorKind::Path),
            "nee" => Some(IntegratorKind::Nee),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Nee => "nee",
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub enum Budget {
    /// Every pixel completes exactly this many paths.
    PathsPerPixel(u32),
    /// Accumulated GPU time of traverse + extend + compact, as the paper measures.
    KernelTime(Duration),
}

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub algorithm: Algorithm,
    pub in_patch: InPatch,
    /// N of the N x 4N patches (1..=1000).
    pub patches_n: u32,
    /// One Russian-roulette draw per group (`_rr`).
    pub group_rr: bool,
    /// Interleaved sampling: pixel coordinates multiplied by this odd factor (1 = off).
    pub interleave: u32,
    /// Glossy bounces sample coherently too (beyond the paper).
    pub coherent_glossy: bool,
    pub budget: Budget,
    pub seed: u32,
    /// Film size; `None` keeps the scene's.
    pub size: Option<(u32, u32)>,
    /// Run the compaction kernels (the paper's `(NO)` variants turn it off).
    pub compact: bool,
    /// Ray reordering (`cohort_kernels::reorder`): every this many iterations, sort the
    /// live rays by direction octant and origin cell before the traversal; 0 = never.
    /// The image is the same; only the traversal's order of rays changes.
    pub reorder: u32,
    /// Russian roulette continuation probability (the paper: 0.8).
    pub rr_continue: f32,
    /// Which Russian roulette ends paths: the paper's fixed `rr_continue` (the default), or
    /// Mitsuba's throughput-based one from the scene's `rr_depth`.
    pub roulette: crate::Roulette,
    /// Whole-group termination (beyond the paper): when a path of a group ends, the
    /// group's other paths play one shared roulette with this continuation probability
    /// (`cohort_kernels::path_end`). `None`: paths end one by one. Needs warp or block groups.
    pub whole_group_end: Option<f32>,
    /// Implicit path tracing or next-event estimation.
    pub integrator: IntegratorKind,
    /// Coherent light sampling (beyond the paper): a group shares its light pick and a
    /// stratum of the light (`cohort_kernels::light`). Needs `integrator: Nee`.
    pub coherent_light: bool,
    /// K of the K x K strata of coherent light sampling (1..=64).
    pub light_cells: u32,
    /// Which part of the budget's paths this run renders (`crate::shard`): shard K of N
    /// renders paths K*P/N..(K+1)*P/N of every pixel under a budget of P paths per pixel.
    pub shard: Shard,
    /// Ray slots to keep in flight: the wavefront holds this many paths at once (rounded
    /// up to whole copies of the image, several paths of each pixel; `crate::wavefront`).
    /// `None`: chosen from the device, enough to fill a GPU.
    pub wavefront: Option<u32>,
}

impl RenderOptions {
    /// Whether every random number a path draws depends only on (seed, pixel, path):
    /// independent diffuse sampling, per-path roulette and independent light samples.
    /// Then the shards of a paths budget merge into the unsplit run's image; otherwise
    /// group draws keyed by iteration enter, and the merge is statistical.
    /// Whether a renderer of a `width` x `height` image takes these options; the error
    /// says what is wrong (what `Renderer::new` and `reconfigure` would return).
    pub fn check(&self, width: u32, height: u32) -> Result<(), RenderError> {
        validate(self, width, height)
    }

    pub fn per_path_sampling(&self) -> bool {
        !self.algorithm.coherent
            && !self.group_rr
            && self.whole_group_end.is_none()
            && !self.coherent_light
    }

    /// The paths of every pixel this run renders: (first path index, how many; 0 for a
    /// time budget, which never stops a pixel).
    pub(crate) fn path_range(&self) -> (u32, u32) {
        match self.budget {
            Budget::PathsPerPixel(p) => {
                let r = self.shard.paths(p);
                (r.start, r.end - r.start)
            }
            Budget::KernelTime(_) => (self.shard.time_first_path(), 0),
        }
    }

    /// The budget of this run's own paths: a shard's share of a paths budget.
    fn shard_budget(&self) -> Budget {
        match self.budget {
            Budget::PathsPerPixel(_) => Budget::PathsPerPixel(self.path_range().1),
            time => time,
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            algorithm: Algorithm::NORMAL,
            in_patch: InPatch::Uniform,
            patches_n: 64,
            group_rr: false,
            interleave: 1,
            coherent_glossy: false,
            budget: Budget::PathsPerPixel(16),
            seed: 1,
            size: None,
            compact: true,
            reorder: 0,
            rr_continue: 0.8,
            roulette: crate::Roulette::Fixed,
            whole_group_end: None,
            integrator: IntegratorKind::Path,
            coherent_light: false,
            light_cells: 4,
            shard: Shard::WHOLE,
            wavefront: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error(transparent)]
    Kernel(#[from] cohort::Error),
    #[error(transparent)]
    Compile(#[from] cohort::emit::CompileError),
    #[error("cannot build the BVH: {0}")]
    Bvh(String),
    #[error("{0}")]
    Options(String),
}

#[derive(Clone, Copy, Debug, Default)]
pub struct KernelTimes {
    pub traverse: Duration,
    pub extend: Duration,
    /// The shadow pass of next-event estimation.
    pub shadow: Duration,
    pub compact: Duration,
    /// Sorting the rays before the traversal (`RenderOptions::reorder`).
    pub reorder: Duration,
}
impl KernelTimes {
    pub fn total(&self) -> Duration {
        self.traverse + self.extend + self.shadow + self.compact + self.reorder
    }
    /// Adds `t` to the time of `stage`.
    fn add(&mut self, stage: Stage, t: Duration) {
        match stage {
            Stage::Traverse => self.traverse += t,
            Stage::Extend => self.extend += t,
            Stage::Shadow => self.shadow += t,
            Stage::Compact => self.compact += t,
            Stage::Reorder => self.reorder += t,
        }
    }
}

/// The stages of one iteration, in order; every dispatch is labelled with its stage so
/// that timings are summed by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    /// Sort the live rays for the traversal (every `RenderOptions::reorder` iterations).
    Reorder,
    /// Closest hit of every live ray.
    Traverse,
    /// Shade, sample lights and the next direction, end or continue paths.
    Extend,
    /// Occlusion of the light samples; finish the slots (next-event estimation only).
    Shadow,
    /// Stable partition of the live rays.
    Compact,
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

/// Path state, structure of arrays, one entry per ray slot.
struct Paths {
    slot_pixel: GpuBuffer<u32>,
    /// The camera's reconstruction filter as `extend::film_sample` reads it
    /// (`cohort_scenes::FilmFilter::table`; one unused zero for the box).
    film_filter: GpuBuffer<f32>,
    idrays: [GpuBuffer<u32>; 2],
    state: GpuBuffer<UVec4>,
    ray_o: GpuBuffer<Vec4>,
    ray_d: GpuBuffer<Vec4>,
    beta: GpuBuffer<Vec4>,
    radiance: GpuBuffer<Vec4>,
    hits: GpuBuffer<Vec4>,
    accum: GpuBuffer<Vec4>,
    /// Next-event estimation: each slot's shadow ray (origin, tmax), (direction, status)
    /// and unoccluded light-sample contribution.
    shadow_o: GpuBuffer<Vec4>,
    shadow_d: GpuBuffer<Vec4>,
    nee: GpuBuffer<Vec4>,
    flags: GpuBuffer<u32>,
    /// Ray reordering's buffers, allocated by the first run that sorts.
    sort: Option<SortState>,
    count: GpuBuffer<u32>,
    block_sums: GpuBuffer<u32>,
    total: GpuBuffer<u32>,
    /// [completed paths, slots done]
    counters: GpuBuffer<u32>,
}

pub struct Renderer<'d> {
    device: &'d Device,
    scene: std::sync::Arc<GpuScene>,
    frame: Frame,
    paths: Paths,
    slot_to_pixel: Vec<u32>,
    opts: RenderOptions,
    /// The camera at the rendered size (the scene's, until `set_camera`).
    camera: Camera,
    /// The run in progress: `None` until `start`.
    run: Option<Run>,
    startup: Startup,
}

/// Where the time before the first iteration went (the scene's share is measured by
/// `GpuScene::prepare`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Startup {
    /// BVH build (binary and 8-wide) on the host.
    pub bvh_build: Duration,
    /// Uploading the scene and allocating the path state.
    pub upload: Duration,
    /// Pipeline creation of the kernels the options use (prepared before any render).
    pub pipelines: Duration,
    /// What `extend` was built for: the scene's BSDF kinds and shading features
    /// (`cohort_kernels::shading`, whose `label` names them).
    pub shading: u32,
}

/// What a run carries from one `advance` to the next.
struct Run {
    /// Cumulative over the run.
    stats: RenderStats,
    /// Which of the two `idrays` buffers holds the live rays (compaction swaps them).
    cur: usize,
    /// Slots not done at the last read-back.
    live: u64,
    /// GPU seconds of one iteration in the last submission: sizes the next one.
    per_iteration: Option<f64>,
}

/// A submitted batch of iterations and what its results are read into.
struct Pending<'d> {
    submission: Submission<'d>,
    /// The stage of each dispatch, in order.
    stages: Vec<Stage>,
    iterations: u32,
    counters: ReadBack<u32>,
}

fn ns(s: &DispatchStats) -> Duration {
    Duration::from_nanos(s.gpu_time_ns.unwrap_or(0))
}

impl<'d> Renderer<'d> {
    pub fn new(
        device: &'d Device,
        scene: &Scene,
        opts: RenderOptions,
    ) -> Result<Self, RenderError> {
        let gpu = GpuScene::prepare(device, scene)?;
        Self::with_scene(device, scene, gpu, opts)
    }

    /// A renderer over a scene already on the device (built once with
    /// `GpuScene::prepare`, shared by many renders, e.g. the points of a sweep).
    pub fn with_scene(
        device: &'d Device,
        scene: &Scene,
        gpu: std::sync::Arc<GpuScene>,
        opts: RenderOptions,
    ) -> Result<Self, RenderError> {
        let mut camera = scene.camera;
        if let Some((w, h)) = opts.size {
            if w == 0 || h == 0 {
                return Err(RenderError::Options(format!("image size {w}x{h} is empty")));
            }
            // The whole film at that size, unless it is the scene's own (crop) size.
            camera = camera.with_size(w, h);
        }
        let (w, h) = (camera.width, camera.height);
        let pixels = w as u64 * h as u64;
        if pixels > crate::wavefront::MAX_SLOTS {
            return Err(RenderError::Options(format!(
                "image size {w}x{h} is larger than this renderer supports (2^26 pixels)"
            )));
        }
        validate(&opts, w, h)?;
        let copies = crate::wavefront::copies(device, &opts, pixels);
        let n = pixels * copies as u64;
        let (max_depth, zero_depth) = crate::roulette::depth_fields(scene);
        let (rr_depth, roulette_throughput) = opts.roulette.frame_fields(scene);
        let mut frame = Frame {
            width: w,
            height: h,
            slots: n as u32,
            copies,
            shading_normals: gpu.has_shading_normals as u32,
            filter_radius: camera.filter.map_or(0.0, |f| f.radius),
            filter_border: camera.filter.map_or(0, |f| f.border()),
            environment: scene.environment,
            max_depth,
            zero_depth,
            rr_depth,
            roulette_throughput,
            hide_emitters: scene.integrator.hide_emitters as u32,
            has_geometry: (gpu.triangle_count > 0) as u32,
            iteration: 0,
            light_count: gpu.light_count,
            env_light: gpu.env_light,
            env_map: gpu.env_map,
            ..Default::default()
        };
        apply_camera(&mut frame, &camera);
        apply_options(&mut frame, &opts);
        let allocated = Instant::now();
        let n = n as usize;
        let slot_to_pixel = slot_order(w, h, opts.interleave).repeat(copies as usize);
        let blocks = compact::scratch_len(n);
        let paths = Paths {
            slot_pixel: device.upload(&slot_to_pixel)?,
            film_filter: match &camera.filter {
                Some(filter) => device.upload(&filter.table())?,
                None => device.upload(&[0.0f32])?,
            },
            idrays: [device.alloc(n)?, device.alloc(n)?],
            state: device.alloc(n)?,
            ray_o: device.alloc(n)?,
            ray_d: device.alloc(n)?,
            beta: device.alloc(n)?,
            radiance: device.alloc(n)?,
            hits: device.alloc(n)?,
            accum: device.alloc(n)?,
            shadow_o: device.alloc(n)?,
            shadow_d: device.alloc(n)?,
            nee: device.alloc(n)?,
            flags: device.alloc(n)?,
            sort: None,
            count: device.upload(&[n as u32])?,
            block_sums: device.alloc(blocks)?,
            total: device.alloc(1)?,
            counters: device.alloc(2)?,
        };
        let startup = Startup {
            bvh_build: gpu.bvh_build,
            upload: gpu.upload + allocated.elapsed(),
            pipelines: Duration::ZERO,
            shading: gpu.shading,
        };
        let mut r = Renderer {
            device,
            scene: gpu,
            frame,
            paths,
            slot_to_pixel,
            opts,
            camera,
            run: None,
            startup,
        };
        r.with_kernels(Prepare)?;
        Ok(r)
    }

    /// Where the time before the first iteration went.
    pub fn startup(&self) -> Startup {
        self.startup
    }

    /// Takes new options for the next run, keeping the scene, the image size, the
    /// wavefront (its copies of the image, `crate::wavefront`) and every buffer: cheaper than a new renderer (no allocation, no host-side set-up beyond a
    /// changed interleave), which keeps the GPU busy in sweeps (`cohort figures`). The
    /// size must stay the same; a run in progress is dropped.
    pub fn reconfigure(&mut self, opts: RenderOptions) -> Result<(), RenderError> {
        let (w, h) = self.size();
        if let Some(size) = opts.size {
            if size != (w, h) {
                return Err(RenderError::Options(format!(
                    "reconfigure cannot change the image size {w}x{h} to {}x{}",
                    size.0, size.1
                )));
            }
        }
        validate(&opts, w, h)?;
        if opts.interleave != self.opts.interleave {
            let copies = self.frame.copies as usize;
            self.slot_to_pixel = slot_order(w, h, opts.interleave).repeat(copies);
            self.device
                .write(&self.paths.slot_pixel, 0, &self.slot_to_pixel)?;
        }
        apply_options(&mut self.frame, &opts);
        self.opts = opts;
        self.run = None;
        self.with_kernels(Prepare)
    }

    /// Changes the budget of the next `render` or `start` (e.g. a short unmeasured
    /// warm-up first). A paths-per-pixel budget is also where the kernels stop each
    /// pixel, so change it between runs, not in the middle of one.
    pub fn set_budget(&mut self, budget: Budget) -> Result<(), RenderError> {
        let opts = RenderOptions {
            budget,
            ..self.opts.clone()
        };
        let (w, h) = self.size();
        validate(&opts, w, h)?;
        apply_options(&mut self.frame, &opts);
        self.opts = opts;
        Ok(())
    }

    pub fn size(&self) -> (u32, u32) {
        (self.frame.width, self.frame.height)
    }

    /// The options of the next (or current) run.
    pub fn options(&self) -> &RenderOptions {
        &self.opts
    }

    /// The camera rays start from, at the rendered size.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Moves the camera (an interactive viewer does, on every mouse drag): the next run
    /// starts from the new view, and a run in progress is dropped, since its image
    /// belongs to the old one. The image size stays (a different size is an error).
    pub fn set_camera(&mut self, camera: Camera) -> Result<(), RenderError> {
        let (w, h) = self.size();
        if (camera.width, camera.height) != (w, h) {
            return Err(RenderError::Options(format!(
                "set_camera cannot change the image size {w}x{h} to {}x{}",
                camera.width, camera.height
            )));
        }
        apply_camera(&mut self.frame, &camera);
        self.camera = camera;
        self.run = None;
        Ok(())
    }

    /// The paper's `display` kernel: tone-maps the current estimate (exposure `2^stops`,
    /// sRGB, as `output::write_png`) into `out`, `0x00RRGGBB` per pixel, row-major,
    /// writing only the image columns in `columns` (two renderers of one size can share
    /// `out` side by side). Runs on the renderer's device, after the iterations an
    /// `advance` submitted; returns the dispatch's statistics (its GPU time).
    pub fn display(
        &self,
        out: &GpuBuffer<u32>,
        stops: f32,
        columns: std::ops::Range<u32>,
    ) -> Result<DispatchStats, RenderError> {
        let (w, h) = self.size();
        if out.len() < (w as usize) * (h as usize) {
            return Err(RenderError::Options(format!(
                "display needs {} pixels of output, the buffer has {}",
                w as usize * h as usize,
                out.len()
            )));
        }
        let pixels = self.frame.slots / self.frame.copies;
        let params = DisplayParams {
            slots: pixels,
            copies: self.frame.copies,
            width: w,
            x_begin: columns.start,
            x_end: columns.end.min(w),
            scale: 2f32.powf(stops),
        };
        Ok(display::launch(
            self.device,
            pixels,
            &params,
            &self.paths.slot_pixel,
            &self.paths.accum,
            out,
        )?)
    }

    /// Renders until the budget is spent. `progress` receives the fraction done.
    /// The same as [`start`](Self::start), [`advance_with`](Self::advance_with) to the
    /// options' budget (a shard's share of it), then [`image`](Self::image).
    pub fn render(
        &mut self,
        progress: impl FnMut(f64, &RenderStats),
    ) -> Result<(Image, RenderStats), RenderError> {
        self.start()?;
        let stats = self.advance_with(self.opts.shard_budget(), progress)?;
        Ok((self.image()?, stats))
    }

    /// Renders with a user's diffuse sampling strategy `S` at the options' group level
    /// (see `examples/custom_sampler.rs`).
    pub fn render_custom<S: DiffuseSampler>(
        &mut self,
        mut progress: impl FnMut(f64, &RenderStats),
    ) -> Result<(Image, RenderStats), RenderError> {
        self.start()?;
        let stats = self.with_sampler::<S, _>(Advance {
            until: self.opts.shard_budget(),
            progress: &mut progress,
        })?;
        Ok((self.image()?, stats))
    }

    /// Begins a run from scratch (first camera ray of every slot, empty image, zero
    /// statistics) without spending any budget; [`advance`](Self::advance) then renders.
    /// Several renderers started together and advanced in turn share the GPU's clock
    /// changes, which separate renders one after another do not (`cohort figures`).
    pub fn start(&mut self) -> Result<(), RenderError> {
        let started = Instant::now();
        let d = self.device;
        let p = &self.paths;
        let n = self.frame.slots;
        let spec_init = init_paths::spec(d, None);
        init_paths::launch_spec(
            d,
            &spec_init,
            n,
            &self.frame,
            &p.film_filter,
            &p.slot_pixel,
            &p.idrays[0],
            &p.state,
            &p.ray_o,
            &p.ray_d,
            &p.beta,
            &p.radiance,
            &p.accum,
        )?;
        // A renderer can run again: each run starts from scratch. Copies of a pixel beyond
        // its paths budget start done (`init_paths`), and count as done slots.
        let idle = crate::wavefront::idle_slots(&self.frame);
        d.write(&p.counters, 0, &[0, idle])?;
        let stats = RenderStats {
            pixels: (n / self.frame.copies) as u64,
            slots: n as u64,
            wall: started.elapsed(),
            ..Default::default()
        };
        self.run = Some(Run {
            stats,
            cur: 0,
            live: (n - idle) as u64,
            per_iteration: None,
        });
        Ok(())
    }

    /// Continues the run begun by [`start`](Self::start) until the *cumulative* budget
    /// `until` is reached (kernel time, or paths per pixel on average, counting this
    /// run's own paths: a shard's, not the whole budget's), and returns the
    /// cumulative statistics; an `until` already reached renders nothing. Pixels stop at
    /// the paths-per-pixel count of the options' budget (fixed for the run), so a run
    /// under a time budget never ends by itself. The kernels are chosen by the options,
    /// as in [`render`](Self::render).
    pub fn advance(&mut self, until: Budget) -> Result<RenderStats, RenderError> {
        self.advance_with(until, |_, _| {})
    }

    /// [`advance`](Self::advance) with `progress` receiving the fraction of `until` done.
    pub fn advance_with(
        &mut self,
        until: Budget,
        mut progress: impl FnMut(f64, &RenderStats),
    ) -> Result<RenderStats, RenderError> {
        self.with_kernels(Advance {
            until,
            progress: &mut progress,
        })
    }

    /// Runs `op` with the kernel types of the current options: the diffuse strategy `S`,
    /// the path-end policy `E` and the integrator `I` are chosen here, once, from the
    /// options, for every operation that needs them.
    fn with_kernels<O: KernelOp>(&mut self, op: O) -> O::Out {
        match (self.opts.algorithm.coherent, self.opts.in_patch) {
            (false, _) => self.with_sampler::<Cosine, O>(op),
            (true, InPatch::Uniform) => self.with_sampler::<CoherentUniform, O>(op),
            (true, InPatch::Cosine) => self.with_sampler::<CoherentCosine, O>(op),
            (true, InPatch::EqualArea) => self.with_sampler::<CoherentEqualArea, O>(op),
        }
    }

    fn with_sampler<S: DiffuseSampler, O: KernelOp>(&mut self, op: O) -> O::Out {
        match self.opts.whole_group_end {
            Some(_) => self.with_end::<S, WholeGroup, O>(op),
            None => self.with_end::<S, EachPath, O>(op),
        }
    }

    fn with_end<S: DiffuseSampler, E: PathEnd, O: KernelOp>(&mut self, op: O) -> O::Out {
        match self.opts.integrator {
            IntegratorKind::Path => op.run::<S, E, Implicit>(self),
            IntegratorKind::Nee => op.run::<S, E, NextEvent>(self),
        }
    }

    /// The specialisations of every kernel an iteration may record, for this device and
    /// the options' group level.
    fn specs(&self) -> Specs {
        let d = self.device;
        Specs {
            traverse: traverse::spec(d, None),
            traverse8: traverse8::spec(d, None),
            extend: extend::spec(d, Some(self.opts.algorithm.group)),
            shadow: trace_shadow::spec(d, None),
            shadow8: trace_shadow8::spec(d, None),
            compact: compact::specs(d),
            reorder: reorder::specs(d),
        }
    }

    /// Compiles the pipelines of every kernel the options use (driver compilation, which
    /// the on-disk pipeline cache shortens on later runs), so that no render pays for it.
    fn prepare_kernels<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &mut self,
    ) -> Result<(), RenderError> {
        let started = Instant::now();
        let d = self.device;
        let specs = self.specs();
        let shading = self.scene.shading;
        self.startup.shading = shading;
        let wide = self.scene.nodes8.is_some();
        let compact = self.opts.compact;
        let reorder = self.opts.reorder > 0;
        // Every stage this render uses, built (IR, WGSL or SPIR-V) and compiled by the
        // driver on a thread of its own: `extend` takes the longest, and the others
        // finish beside it.
        type Build<'s> =
            Box<dyn FnOnce() -> Result<Vec<Arc<KernelArtifact>>, RenderError> + Send + 's>;
        let mut builds: Vec<Build<'_>> = vec![
            Box::new(|| Ok(vec![init_paths::artifact(&init_paths::spec(d, None))?])),
            Box::new(|| {
                Ok(vec![extend::artifact::<S, E, I>(&extend::specialized(
                    &specs.extend,
                    shading,
                ))?])
            }),
            Box::new(|| {
                Ok(vec![if wide {
                    traverse8::artifact(&specs.traverse8)?
                } else {
                    traverse::artifact(&specs.traverse)?
                }])
            }),
        ];
        if I::NEE {
            builds.push(Box::new(|| {
                Ok(vec![if wide {
                    trace_shadow8::artifact(&specs.shadow8)?
                } else {
                    trace_shadow::artifact(&specs.shadow)?
                }])
            }));
        }
        if compact {
            builds.push(Box::new(|| Ok(compact::artifacts(&specs.compact)?)));
        }
        if reorder {
            builds.push(Box::new(|| Ok(reorder::artifacts(&specs.reorder)?)));
        }
        std::thread::scope(|scope| {
            let threads: Vec<_> = builds
                .into_iter()
                .map(|build| {
                    scope.spawn(move || -> Result<(), RenderError> {
                        for a in build()? {
                            d.prepare(&a)?;
                        }
                        Ok(())
                    })
                })
                .collect();
            threads
                .into_iter()
                .try_for_each(|t| t.join().expect("a pipeline thread panicked"))
        })?;
        if reorder && self.paths.sort.is_none() {
            self.paths.sort = Some(SortState::new(d, self.frame.slots, &self.scene)?);
        }
        self.startup.pipelines += started.elapsed();
        Ok(())
    }

    fn advance_kernels<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &mut self,
        until: Budget,
        progress: &mut dyn FnMut(f64, &RenderStats),
    ) -> Result<RenderStats, RenderError> {
        let resumed = Instant::now();
        let specs = self.specs();
        let d = self.device;
        let p = &self.paths;
        let n = self.frame.slots;
        let Some(run) = self.run.as_mut() else {
            return Err(RenderError::Options(
                "advance before start: a run must be started first".into(),
            ));
        };
        let done = |stats: &RenderStats| match until {
            Budget::PathsPerPixel(pp) => {
                stats.completed_paths as f64 / (pp as f64 * stats.pixels as f64)
            }
            Budget::KernelTime(t) => stats.kernel.total().as_secs_f64() / t.as_secs_f64(),
        };
        // A run resumed at a budget it has already reached renders nothing; a fresh one
        // always runs at least one batch (warm-ups rely on it).
        if run.stats.iterations > 0 && (done(&run.stats) >= 1.0 || run.live == 0) {
            progress(1.0, &run.stats);
            return Ok(run.stats.clone());
        }
        let wall_before = run.stats.wall;
        // Several iterations go into one submission (about 10 ms of GPU work), and two
        // submissions are kept in flight: the host records and submits the next while the
        // GPU runs the current one, and reads each submission's counters through a copy
        // in that same submission. The GPU never waits for the host: an idle GPU also
        // lowers its clocks (1980 -> 345 MHz on the H100 and H200, reason "idle").
        const TARGET_SUBMIT: Duration = Duration::from_millis(10);
        const IN_FLIGHT: usize = 2;
        // Fewest iterations in a batch near the end of a paths budget.
        const TAIL_BATCH: f64 = 8.0;
        let mut in_flight: std::collections::VecDeque<Pending> = std::collections::VecDeque::new();
        loop {
            // Submit while fewer than IN_FLIGHT batches run and what is known (finished
            // batches, plus the estimated time of those in flight) leaves budget.
            while in_flight.len() < IN_FLIGHT {
                let queued: u32 = in_flight.iter().map(|q| q.iterations).sum();
                let stats = &run.stats;
                let projected_time = stats.kernel.total().as_secs_f64()
                    + run.per_iteration.unwrap_or(0.0) * queued as f64;
                let projected = match until {
                    Budget::KernelTime(t) => projected_time / t.as_secs_f64(),
                    Budget::PathsPerPixel(_) => done(stats),
                };
                let fresh = stats.iterations == 0 && in_flight.is_empty();
                if !fresh && (projected >= 1.0 || run.live == 0) {
                    break;
                }
                // The first submission of a run is one iteration, to measure one; until
                // then nothing else is queued.
                let batch_iterations = match run.per_iteration {
                    None if !in_flight.is_empty() => break,
                    None => 1,
                    Some(per_iter) => {
                        let mut want =
                            (TARGET_SUBMIT.as_secs_f64() / per_iter.max(1e-7)).clamp(1.0, 64.0);
                        match until {
                            // Do not overshoot a time budget by more than a tenth of what is left.
                            Budget::KernelTime(t) => {
                                want = want.min(
                                    (0.1 * (t.as_secs_f64() - projected_time).max(0.0)
                                        / per_iter.max(1e-7))
                                    .max(1.0),
                                )
                            }
                            // The iterations still needed, extrapolated from the paths
                            // completed so far, less those queued. Not below a floor: an
                            // iteration past the end costs little (finished slots return at
                            // once), while a small batch leaves the GPU idle as the host
                            // turns around (measured: 51 % over kernel time on cornell-box).
                            Budget::PathsPerPixel(_) => {
                                let it = stats.iterations as f64;
                                let remaining = if projected > 0.02 {
                                    it * (1.0 - projected.min(1.0)) / projected - queued as f64
                                } else {
                                    f64::INFINITY
                                };
                                want = want.min(remaining.max(TAIL_BATCH))
                            }
                        }
                        want as u32
                    }
                };
                let recording = Instant::now();
                let mut b = d.batch();
                let mut stages = Vec::new();
                for k in 0..batch_iterations {
                    self.frame.iteration = run.stats.iterations + queued + k;
                    run.cur = record_iteration::<S, E, I>(
                        &mut b,
                        &specs,
                        &self.frame,
                        &self.scene,
                        p,
                        run.cur,
                        self.opts.compact,
                        self.opts.reorder,
                        &mut stages,
                    )?;
                }
                let counters = b.read_back(&p.counters)?;
                let submitting = Instant::now();
                run.stats.host.record += submitting - recording;
                let submission = b.submit_async()?;
                run.stats.host.submit += submitting.elapsed();
                run.stats.host.batches += 1;
                in_flight.push_back(Pending {
                    submission,
                    stages,
                    iterations: batch_iterations,
                    counters,
                });
            }
            let Some(oldest) = in_flight.pop_front() else {
                // Nothing left to submit or wait for: the budget is reached.
                run.stats.wall = wall_before + resumed.elapsed();
                return Ok(run.stats.clone());
            };
            let waiting = Instant::now();
            let completed = oldest.submission.wait()?;
            let stats = &mut run.stats;
            stats.host.wait += waiting.elapsed();
            let mut batch_time = Duration::ZERO;
            for (stage, t) in oldest.stages.iter().zip(&completed.stats) {
                stats.kernel.add(*stage, ns(t));
                batch_time += ns(t);
            }
            run.per_iteration = Some(batch_time.as_secs_f64() / oldest.iterations as f64);
            stats.iterations += oldest.iterations;
            // Slots that finished inside a submission are counted as live until its
            // read-back: an upper bound on the rays traced.
            stats.rays += run.live * oldest.iterations as u64;
            let counters = completed.read(oldest.counters);
            stats.completed_paths = counters[0] as u64;
            run.live = n as u64 - counters[1] as u64;
            stats.wall = wall_before + resumed.elapsed();
            progress(done(stats).min(1.0), stats);
        }
    }

    /// The current estimate: per pixel, the mean of its completed paths. A pixel's slots
    /// (`Frame::copies`) are summed in slot order, so the sum does not depend on which
    /// slot finished first.
    pub fn image(&self) -> Result<Image, RenderError> {
        let accum = self.device.read(&self.paths.accum)?;
        let (w, h) = self.size();
        let mut sums = vec![Vec4::ZERO; (w * h) as usize];
        for (slot, a) in accum.iter().enumerate() {
            sums[self.slot_to_pixel[slot] as usize] += *a;
        }
        let paths: Vec<u32> = sums.iter().map(|a| a.w as u32).collect();
        let pixels = sums
            .iter()
            .map(|a| {
                if a.w > 0.0 {
                    a.truncate() / a.w
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        Ok(Image {
            width: w,
            height: h,
            pixels,
            paths,
        })
    }
}

/// An operation over the kernels of the current options (see `Renderer::with_kernels`).
trait KernelOp {
    type Out;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out;
}

struct Advance<'a> {
    until: Budget,
    progress: &'a mut dyn FnMut(f64, &RenderStats),
}

impl KernelOp for Advance<'_> {
    type Out = Result<RenderStats, RenderError>;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out {
        r.advance_kernels::<S, E, I>(self.until, self.progress)
    }
}

struct Prepare;

impl KernelOp for Prepare {
    type Out = Result<(), RenderError>;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out {
        r.prepare_kernels::<S, E, I>()
    }
}

/// The specialisations of every kernel an iteration may record.
struct Specs {
    traverse: cohort::Spec,
    traverse8: cohort::Spec,
    extend: cohort::Spec,
    shadow: cohort::Spec,
    shadow8: cohort::Spec,
    compact: compact::Specs,
    reorder: reorder::Specs,
}

/// Records one iteration of the wavefront loop, stage by stage (PAPER.md §3): traverse,
/// extend, the shadow pass with next-event estimation, compaction. Labels each dispatch
/// in `stages`; returns which `idrays` buffer holds the live rays afterwards.
#[allow(clippy::too_many_arguments)]
fn record_iteration<S: DiffuseSampler, E: PathEnd, I: Integrator>(
    b: &mut Batch<'_>,
    specs: &Specs,
    frame: &Frame,
    scene: &GpuScene,
    p: &Paths,
    cur: usize,
    compact: bool,
    reorder: u32,
    stages: &mut Vec<Stage>,
) -> Result<usize, RenderError> {
    let n = frame.slots;
    let mut record =
        |stage: Stage, dispatches: usize| stages.extend(std::iter::repeat_n(stage, dispatches));
    // The traversal reads the live rays in bin order on a sorting iteration; every other
    // kernel keeps the slot order of `idrays`.
    let sorting = reorder > 0 && frame.iteration.is_multiple_of(reorder);
    let traced = match p.sort.as_ref().filter(|_| sorting) {
        Some(sort) => {
            let buffers = sort.buffers();
            reorder::record(
                b,
                &specs.reorder,
                n,
                &p.count,
                &p.idrays[cur],
                &p.state,
                &p.ray_o,
                &p.ray_d,
                &buffers,
            )?;
            record(Stage::Reorder, reorder::DISPATCHES);
            &sort.sorted
        }
        None => &p.idrays[cur],
    };
    // The 8-wide tree is faster (BENCHMARKS.md); the BVH2 serves trees too deep for its stack.
    match &scene.nodes8 {
        Some(n8) => traverse8::record(
            b,
            &specs.traverse8,
            n,
            frame,
            &p.count,
            traced,
            &p.state,
            &p.ray_o,
            &p.ray_d,
            n8,
            &scene.triangles,
            &p.hits,
        )?,
        None => traverse::record(
            b,
            &specs.traverse,
            n,
            frame,
            &p.count,
            traced,
            &p.state,
            &p.ray_o,
            &p.ray_d,
            &scene.nodes,
            &scene.triangles,
            &p.hits,
        )?,
    }
    record(Stage::Traverse, 1);
    extend::record::<S, E, I>(
        b,
        &specs.extend,
        n,
        scene.shading,
        frame,
        &p.count,
        &p.idrays[cur],
        &p.hits,
        &scene.triangles,
        &scene.shading_normals,
        &scene.tex_coords,
        &scene.textures,
        &p.film_filter,
        &scene.materials,
        &scene.lights,
        &scene.delta_lights,
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
    )?;
    record(Stage::Extend, 1);
    if I::NEE {
        match &scene.nodes8 {
            Some(n8) => trace_shadow8::record(
                b,
                &specs.shadow8,
                n,
                frame,
                &p.count,
                &p.idrays[cur],
                &p.shadow_o,
                &p.shadow_d,
                &p.nee,
                n8,
                &scene.triangles,
                &p.radiance,
                &p.accum,
            )?,
            None => trace_shadow::record(
                b,
                &specs.shadow,
                n,
                frame,
                &p.count,
                &p.idrays[cur],
                &p.shadow_o,
                &p.shadow_d,
                &p.nee,
                &scene.nodes,
                &scene.triangles,
                &p.radiance,
                &p.accum,
            )?,
        }
        record(Stage::Shadow, 1);
    }
    if !compact {
        return Ok(cur);
    }
    compact::record(
        b,
        &specs.compact,
        n,
        &p.count,
        &p.flags,
        &p.block_sums,
        &p.total,
        &p.idrays[cur],
        &p.idrays[1 - cur],
    )?;
    record(Stage::Compact, compact::DISPATCHES);
    Ok(1 - cur)
}

/// Ray reordering's buffers (`cohort_kernels::reorder::SortBuffers`): the grid of origin
/// cells over the scene's bounds, each listed ray's bin, the histogram, and the live slots
/// in bin order (what the traversal reads instead of `idrays` on a sorting iteration).
struct SortState {
    cells: GpuBuffer<Vec4>,
    keys: GpuBuffer<u32>,
    bins: GpuBuffer<u32>,
    sorted: GpuBuffer<u32>,
}

impl SortState {
    fn new(d: &Device, slots: u32, scene: &GpuScene) -> Result<SortState, RenderError> {
        Ok(SortState {
            cells: d.upload(&reorder::cells(scene.bounds[0], scene.bounds[1]))?,
            keys: d.alloc(slots as usize)?,
            bins: d.alloc(reorder::HISTOGRAM_LEN)?,
            sorted: d.alloc(slots as usize)?,
        })
    }

    fn buffers(&self) -> reorder::SortBuffers<'_> {
        reorder::SortBuffers {
            cells: &self.cells,
            keys: &self.keys,
            bins: &self.bins,
            sorted: &self.sorted,
        }
    }
}

/// Checks the options that do not depend on the scene, for an image of `w` x `h`.
fn validate(opts: &RenderOptions, w: u32, h: u32) -> Result<(), RenderError> {
    if !(opts.rr_continue > 0.0 && opts.rr_continue <= 1.0) {
        return Err(RenderError::Options(format!(
            "Russian roulette continuation {} is not in (0, 1]",
            opts.rr_continue
        )));
    }
    if opts.patches_n == 0 || opts.patches_n > 1000 {
        return Err(RenderError::Options(format!(
            "patch count N = {} is not in 1..=1000",
            opts.patches_n
        )));
    }
    if !interleave_permutes(opts.interleave, w, h) {
        return Err(RenderError::Options(format!(
            "interleave factor {} must be odd and coprime with the image size {w}x{h} (so that it permutes the pixels)",
            opts.interleave
        )));
    }
    if opts.coherent_light && opts.integrator != IntegratorKind::Nee {
        return Err(RenderError::Options(
            "coherent light sampling needs next-event estimation (--integrator nee)".into(),
        ));
    }
    if opts.light_cells == 0 || opts.light_cells > 64 {
        return Err(RenderError::Options(format!(
            "light strata K = {} is not in 1..=64",
            opts.light_cells
        )));
    }
    if let Budget::PathsPerPixel(p) = opts.budget {
        if opts.shard.paths(p).is_empty() {
            return Err(RenderError::Options(format!(
                "shard {} of {p} paths per pixel has no path: split a budget of {p} paths into at most {p} shards",
                opts.shard
            )));
        }
    }
    if let Some(q) = opts.whole_group_end {
        if !(q > 0.0 && q <= 1.0) {
            return Err(RenderError::Options(format!("whole-group end continuation {q} is not in (0, 1] (0 would cut paths short: biased)")));
        }
        if opts.algorithm.group == Group::Grid {
            return Err(RenderError::Options(
                "whole-group termination needs warp or block groups: the grid cannot vote within one dispatch (and with 2^20 paths \
                     one of them ends at every bounce, so it would only be a group roulette; use --rr group)"
                    .into(),
            ));
        }
    }
    Ok(())
}

/// Writes the options into the frame the kernels read.
/// The camera fields of the frame: where rays start and how they spread.
fn apply_camera(frame: &mut Frame, camera: &Camera) {
    let f = camera.frame();
    frame.cam_origin = f.origin;
    frame.cam_forward = f.forward;
    frame.cam_right = f.right;
    frame.cam_up = f.up;
    frame.orthographic = f.orthographic as u32;
    frame.lens_radius = f.lens_radius;
    frame.focus_distance = f.focus_distance;
}

fn apply_options(frame: &mut Frame, opts: &RenderOptions) {
    frame.seed = opts.seed;
    (frame.first_path, frame.paths_per_pixel) = opts.path_range();
    frame.group_seed = opts.shard.group_seed(opts.seed);
    frame.rr_continue = opts.rr_continue;
    frame.patches_n = opts.patches_n;
    frame.group_rr = opts.group_rr as u32;
    frame.coherent_glossy = (opts.coherent_glossy && opts.algorithm.coherent) as u32;
    frame.group_end_continue = opts.whole_group_end.unwrap_or(0.0);
    frame.coherent_light = opts.coherent_light as u32;
    frame.light_cells = opts.light_cells;
}

/// Pixel of every ray slot. Interleaved sampling: slot g renders pixel D * Morton(g)
/// (mod the size), which spreads a group's block of pixels over the image.
fn slot_order(w: u32, h: u32, d: u32) -> Vec<u32> {
    morton_pixel_order(w, h)
        .into_iter()
        .map(|p| {
            let (x, y) = (p % w, p / w);
            ((y as u64 * d as u64 % h as u64) * w as u64 + (x as u64 * d as u64 % w as u64)) as u32
        })
        .collect()
}

/// Whether interleave factor `d` permutes the pixels of a `w` x `h` image (slot g renders
/// pixel D * Morton(g), `slot_order`): `d` odd and coprime with both sides.
pub fn interleave_permutes(d: u32, w: u32, h: u32) -> bool {
    d & 1 == 1 && gcd(d, w) == 1 && gcd(d, h) == 1
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cohort::runtime::BackendKind;

    fn cornell() -> Scene {
        cohort_scenes::embedded::load("cornell").unwrap()
    }

    fn opts(budget: Budget) -> RenderOptions {
        RenderOptions {
            algorithm: Algorithm::parse("warp").unwrap(),
            budget,
            size: Some((32, 32)),
            ..Default::default()
        }
    }

    /// Slices of a run give the image of one render: batching does not change which
    /// paths are traced, only when the host looks.
    #[test]
    fn a_run_in_slices_renders_what_one_render_does() {
        let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
            return;
        };
        let scene = cornell();
        let (whole, whole_stats) = Renderer::new(&d, &scene, opts(Budget::PathsPerPixel(6)))
            .unwrap()
            .render(|_, _| {})
            .unwrap();

        let mut r = Renderer::new(&d, &scene, opts(Budget::PathsPerPixel(6))).unwrap();
        assert!(
            r.advance(Budget::PathsPerPixel(1)).is_err(),
            "advance before start"
        );
        r.start().unwrap();
        let mut last = RenderStats::default();
        for until in [1, 2, 4, 6] {
            let s = r.advance(Budget::PathsPerPixel(until)).unwrap();
            assert!(
                s.completed_paths >= until as u64 * 32 * 32
                    && s.completed_paths >= last.completed_paths,
                "cumulative: {s:?}"
            );
            assert!(
                s.iterations >= last.iterations && s.kernel.total() >= last.kernel.total(),
                "cumulative: {s:?}"
            );
            last = s;
        }
        assert_eq!(last.completed_paths, whole_stats.completed_paths);
        let again = r.advance(Budget::PathsPerPixel(6)).unwrap();
        assert_eq!(
            (again.iterations, again.completed_paths),
            (last.iterations, last.completed_paths),
            "a reached budget renders nothing more"
        );
        let sliced = r.image().unwrap();
        assert_eq!(sliced.paths, whole.paths);
        assert!(
            sliced
                .pixels
                .iter()
                .zip(&whole.pixels)
                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)),
            "same image"
        );
    }

    #[test]
    fn time_slices_accumulate_and_start_resets() {
        let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
            return;
        };
        let mut r = Renderer::new(
            &d,
            &cornell(),
            opts(Budget::KernelTime(Duration::from_millis(20))),
        )
        .unwrap();
        r.start().unwrap();
        let first = r
            .advance(Budget::KernelTime(Duration::from_millis(10)))
            .unwrap();
        assert!(
            first.kernel.total() >= Duration::from_millis(10),
            "{first:?}"
        );
        // Budgets are cumulative, and one iteration may take longer than 10 ms (debug
        // kernels on the software driver): ask for 10 ms beyond what was spent.
        let until = first.kernel.total() + Duration::from_millis(10);
        let second = r.advance(Budget::KernelTime(until)).unwrap();
        assert!(
            second.kernel.total() >= until && second.iterations > first.iterations,
            "{second:?}"
        );
        assert!(
            second.completed_paths >= first.completed_paths
                && second.rays > first.rays
                && second.wall >= first.wall
        );
        let same = r.advance(Budget::KernelTime(first.kernel.total())).unwrap();
        assert_eq!(
            (same.iterations, same.completed_paths),
            (second.iterations, second.completed_paths),
            "an earlier budget renders nothing"
        );
        r.start().unwrap();
        assert_eq!(
            r.image().unwrap().paths.iter().sum::<u32>(),
            0,
            "start empties the image"
        );
        // The first submission of a run is one iteration, which spends any tiny budget.
        let restarted = r
            .advance(Budget::KernelTime(Duration::from_nanos(1)))
            .unwrap();
        assert_eq!(
            restarted.iterations, 1,
            "statistics start again: {restarted:?}"
        );
    }

    /// A reconfigured renderer renders exactly what a new one with those options does,
    /// including a changed interleave (its slot order is rewritten on the GPU, for every
    /// copy of the image in the wavefront), where both chose the same wavefront (the
    /// budget caps the copies, and a reconfigured renderer keeps its own).
    #[test]
    fn reconfigure_equals_a_new_renderer() {
        let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
            return;
        };
        let scene = cornell();
        let target = RenderOptions {
            algorithm: Algorithm::parse("block_256").unwrap(),
            patches_n: 5,
            group_rr: true,
            compact: false,
            interleave: 3,
            whole_group_end: Some(0.5),
            seed: 9,
            ..opts(Budget::PathsPerPixel(3))
        };
        let (fresh, _) = Renderer::new(&d, &scene, target.clone())
            .unwrap()
            .render(|_, _| {})
            .unwrap();
        let mut r = Renderer::new(&d, &scene, opts(Budget::PathsPerPixel(3))).unwrap();
        r.render(|_, _| {}).unwrap();
        r.reconfigure(target.clone()).unwrap();
        let (again, _) = r.render(|_, _| {}).unwrap();
        assert_eq!(again.paths, fresh.paths);
        assert!(
            again
                .pixels
                .iter()
                .zip(&fresh.pixels)
                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)),
            "same image"
        );
        assert!(
            r.reconfigure(RenderOptions {
                size: Some((16, 16)),
                ..target.clone()
            })
            .is_err(),
            "the size is fixed"
        );
        assert!(
            r.reconfigure(RenderOptions {
                interleave: 2,
                ..target
            })
            .is_err(),
            "options are checked"
        );
    }
}
