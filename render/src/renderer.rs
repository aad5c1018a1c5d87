//! The iteration loop of the wavefront path tracer (the paper's §3): per iteration one
//! batch `traverse8` (or `traverse`) → `extend::<S, E>` → `compact_*`, until the budget
//! (completed paths per pixel, or accumulated GPU time of those kernels, as in the
//! paper) is spent.
//!
//! A run is resumable: [`Renderer::start`] begins it and [`Renderer::advance`] continues
//! it to a cumulative budget, keeping the image and statistics in between, so that
//! several renderers can take turns on the GPU (`cohort figures` does, so that each sees
//! the same clock changes). [`Renderer::render`] is one start and one advance.

use std::time::{Duration, Instant};

use cohort::runtime::{Device, DispatchStats, GpuBuffer, ReadBack, Submission};
use cohort_kernels::display::{display, DisplayParams};
use cohort_kernels::extend::init_paths;
use cohort_kernels::integrator::Integrator;
use cohort_kernels::layout::Frame;
use cohort_kernels::path_end::PathEnd;
use cohort_kernels::sampling::DiffuseSampler;
use cohort_scenes::{morton_pixel_order, Camera, Scene};
use glam::{Vec3, Vec4};

use crate::design::Choice;
use crate::iteration::{LabelledBatch, Stage, Wavefront};
use crate::kernels::{extend_set, with_types, Advance, Compile, Prepare};
use crate::options::validate;
use crate::paths::Paths;
use crate::{GpuScene, Image};

// The renderer's vocabulary, at the paths it has always had (`cohort_render::renderer::X`).
pub use crate::error::RenderError;
pub use crate::options::{
    interleave_permutes, Algorithm, Budget, InPatch, IntegratorKind, RenderOptions, Shading,
};
pub use crate::stats::{HostTimes, KernelTimes, RenderStats, Startup};

/// The wavefront path tracer: one scene on one device, its path state and the run in
/// progress.
pub struct Renderer<'d> {
    pub(crate) device: &'d Device,
    pub(crate) scene: std::sync::Arc<GpuScene>,
    pub(crate) frame: Frame,
    pub(crate) paths: Paths,
    slot_to_pixel: Vec<u32>,
    pub(crate) opts: RenderOptions,
    /// The camera at the rendered size (the scene's, until `set_camera`).
    camera: Camera,
    /// The run in progress: `None` until `start`.
    run: Option<Run>,
    pub(crate) startup: Startup,
    /// The design each run starts with (`crate::design`), chosen with the pipelines.
    pub(crate) design: Choice,
}

/// What a run carries from one `advance` to the next.
struct Run {
    /// Cumulative over the run.
    stats: RenderStats,
    /// Which of the two `idrays` buffers holds the live rays (compaction swaps them).
    cur: usize,
    /// Slots not done at the last read-back.
    live: u64,
    /// At least the entries of list `cur`: the slots, or the slots not done when the
    /// finished ones were last retired (`cohort_kernels::retire`).
    listed: u32,
    /// GPU seconds of one iteration in the last submission: sizes the next one.
    per_iteration: Option<f64>,
    /// The design of the run's batches, a trial until both are measured.
    design: Choice,
    /// The iteration whose group draws the group table holds, written by the `extend`
    /// recorded last (`cohort_kernels::group_draw`); `None` before the run's first.
    tabled: Option<u32>,
}

/// A submitted batch of iterations and what its results are read into.
struct Pending<'d> {
    submission: Submission<'d>,
    /// The stage of each dispatch, in order.
    stages: Vec<Stage>,
    iterations: u32,
    /// Shaded over material queues, and the batch's index in the run's trial.
    queued: bool,
    trial_index: u32,
    counters: ReadBack<u32>,
}

/// The run's completed paths after a read-back of the device's count, a u32 that wraps
/// at 2^32 (a 256x256 image reaches it at 65,536 paths per pixel): `total` grows by the
/// count's increase modulo 2^32, exact because a batch completes fewer paths than that.
fn add_completed(total: u64, counter: u32) -> u64 {
    total + counter.wrapping_sub(total as u32) as u64
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
        apply_options(&mut frame, &opts, draws_per_lane(device));
        // The path state is laid out and allocated on one thread while the pipelines are
        // built and created on others: neither needs the other.
        let compile = Compile {
            d: device,
            opts: &opts,
            shading: extend_set(&gpu, &frame),
            wide: gpu.nodes8.is_some(),
        };
        let (allocated, compiled) = std::thread::scope(|t| {
            let allocating = t.spawn(|| {
                let started = Instant::now();
                let slot_to_pixel = slot_order(w, h, opts.interleave).repeat(copies as usize);
                let paths = Paths::alloc(device, &slot_to_pixel, &camera);
                (paths, slot_to_pixel, started.elapsed())
            });
            let compiled = with_types(&opts, compile);
            let allocated = allocating.join().expect("the path-state thread panicked");
            (allocated, compiled)
        });
        let (paths, slot_to_pixel, path_state) = allocated;
        let (paths, compiled) = (paths?, compiled?);
        let startup = Startup {
            bvh_build: gpu.bvh_build,
            upload: gpu.upload,
            path_state,
            pipelines: Duration::ZERO,
            kernels: Vec::new(),
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
            design: Choice::Fixed(false),
        };
        r.adopt(compiled)?;
        Ok(r)
    }

    /// Where the time before the first iteration went.
    pub fn startup(&self) -> Startup {
        self.startup.clone()
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
        apply_options(&mut self.frame, &opts, draws_per_lane(self.device));
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
        apply_options(&mut self.frame, &opts, draws_per_lane(self.device));
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
        // Retiring (below) shortened a list of an earlier run.
        for count in &p.counts {
            d.write(count, 0, &[n])?;
        }
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
            listed: n,
            per_iteration: None,
            design: self.design.clone(),
            tabled: None,
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

    pub(crate) fn advance_kernels<S: DiffuseSampler, E: PathEnd, I: Integrator>(
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
        // Lists this short are not worth a retirement's four dispatches.
        const RETIRE_FROM: u32 = 256;
        let retires = self.opts.retires(draws_per_lane(self.device));
        let retire_at = retire_at(self.device);
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
                        // Fewer than 2^32 paths end in one batch (each slot ends at most
                        // one per iteration): the completed count's wrap (below) is exact.
                        let most = (u32::MAX as u64 / n.max(1) as u64).clamp(1, 64) as f64;
                        let mut want =
                            (TARGET_SUBMIT.as_secs_f64() / per_iter.max(1e-7)).clamp(1.0, most);
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
                let (queued_batch, trial_index) = run.design.next_batch();
                let mut b = LabelledBatch::new(d.batch());
                for k in 0..batch_iterations {
                    self.frame.iteration = run.stats.iterations + queued + k;
                    let mut wavefront = Wavefront {
                        specs: &specs,
                        frame: &self.frame,
                        scene: &self.scene,
                        paths: p,
                        compaction: self.opts.compact,
                        reorder_every: self.opts.reorder,
                        queues: queued_batch,
                        listed: run.listed,
                        tabled: run.tabled == Some(self.frame.iteration),
                    };
                    // Once at most `retire_at` of the listed slots are live, list only
                    // those: the slots finished since the last read-back stay listed (and
                    // skipped) until the next retirement, so `live` bounds the new list.
                    let (num, den) = retire_at;
                    if retires
                        && run.live * den <= run.listed as u64 * num
                        && run.listed > RETIRE_FROM
                    {
                        run.cur = wavefront.retire(&mut b, run.cur)?;
                        run.listed = run.live as u32;
                        wavefront.listed = run.listed;
                    }
                    run.cur = wavefront.record_iteration::<S, E, I>(&mut b, run.cur)?;
                    run.tabled = Some(self.frame.iteration + 1);
                }
                let LabelledBatch { mut batch, stages } = b;
                let counters = batch.read_back(&p.counters)?;
                let submitting = Instant::now();
                run.stats.host.record += submitting - recording;
                let submission = batch.submit_async()?;
                run.stats.host.submit += submitting.elapsed();
                run.stats.host.batches += 1;
                in_flight.push_back(Pending {
                    submission,
                    stages,
                    iterations: batch_iterations,
                    queued: queued_batch,
                    trial_index,
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
            // Every dispatch was labelled with its stage as it was recorded.
            debug_assert_eq!(oldest.stages.len(), completed.stats.len());
            let mut batch_time = Duration::ZERO;
            let mut shading_time = Duration::ZERO;
            for (stage, t) in oldest.stages.iter().zip(&completed.stats) {
                stats.kernel.add(*stage, ns(t));
                batch_time += ns(t);
                if matches!(stage, Stage::Queue | Stage::Extend) {
                    shading_time += ns(t);
                }
            }
            if oldest.queued {
                stats.queued_iterations += oldest.iterations;
            }
            run.design.observe(
                oldest.queued,
                oldest.trial_index,
                shading_time,
                oldest.iterations,
            );
            run.per_iteration = Some(batch_time.as_secs_f64() / oldest.iterations as f64);
            stats.iterations += oldest.iterations;
            // Slots that finished inside a submission are counted as live until its
            // read-back: an upper bound on the rays traced.
            stats.rays += run.live * oldest.iterations as u64;
            let counters = completed.read(oldest.counters);
            stats.completed_paths = add_completed(stats.completed_paths, counters[0]);
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

/// Whether device `d` has every invocation of a warp or block compute the group's draws
/// itself (`Spec::recompute_group_share`), which lets them be keyed by slot
/// (`RenderOptions::group_slots`).
pub(crate) fn draws_per_lane(d: &Device) -> bool {
    d.info().target().recompute_group_share
}

/// Writes the options into the frame the kernels read (`per_lane`: [`draws_per_lane`]).
fn apply_options(frame: &mut Frame, opts: &RenderOptions, per_lane: bool) {
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
    frame.group_slots = opts.group_slots(per_lane);
}

/// The share of the listed slots, as (numerator, denominator), at or below which so many
/// are live that a retirement pays: a retirement costs a partition of the list, a listed
/// finished slot costs each stage its skip. On an H200, half measured about 1 % slower
/// than three quarters and nine tenths 0.5 % faster. On the CPU backend, whose partition
/// runs as whole-dispatch loops, nineteen twentieths took 0.96x (cornell-box) and 0.975x
/// (stanford-like) of three quarters' kernel time at 256x256, and ninety-nine hundredths
/// no less (BENCHMARKS.md).
fn retire_at(device: &Device) -> (u64, u64) {
    if device.info().backend == cohort::runtime::BackendKind::Cpu {
        (19, 20)
    } else {
        (3, 4)
    }
}

/// Pixel of every ray slot. Interleaved sampling: slot g renders pixel D * Morton(g)
/// (mod the size), which spreads a group's block of pixels over the image.
fn slot_order(w: u32, h: u32, d: u32) -> Vec<u32> {
    if d == 1 {
        return morton_pixel_order(w, h);
    }
    morton_pixel_order(w, h)
        .into_iter()
        .map(|p| {
            let (x, y) = (p % w, p / w);
            ((y as u64 * d as u64 % h as u64) * w as u64 + (x as u64 * d as u64 % w as u64)) as u32
        })
        .collect()
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

    #[test]
    fn the_completed_count_goes_past_the_devices_u32() {
        assert_eq!(add_completed(0, 0), 0);
        assert_eq!(add_completed(0, 1000), 1000);
        assert_eq!(add_completed(1000, 1000), 1000);
        let near = u32::MAX as u64 - 5;
        assert_eq!(add_completed(near, 10), u32::MAX as u64 + 11);
        assert_eq!(add_completed(1 << 32, 0), 1 << 32);
        assert_eq!(add_completed((3 << 32) + 7, 100), (3 << 32) + 100);
    }

    /// Slices of a run give the image of one render: batching does not change which
    /// paths are traced, only when the host looks. On the CPU backend, warp groups read
    /// their draws from the group table, which each `extend` fills for the next
    /// iteration, across slices too.
    #[test]
    fn a_run_in_slices_renders_what_one_render_does() {
        // The CPU run without compaction, which keys group draws by list place.
        for (kind, compact) in [(BackendKind::Vulkan, true), (BackendKind::Cpu, false)] {
            if let Some(d) = Device::for_tests(kind) {
                run_in_slices(&d, compact);
            }
        }
    }

    fn run_in_slices(d: &Device, compact: bool) {
        let scene = cornell();
        let opts = |budget| RenderOptions {
            compact,
            ..opts(budget)
        };
        let (whole, whole_stats) = Renderer::new(d, &scene, opts(Budget::PathsPerPixel(6)))
            .unwrap()
            .render(|_, _| {})
            .unwrap();

        let mut r = Renderer::new(d, &scene, opts(Budget::PathsPerPixel(6))).unwrap();
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

    /// After a render on the CPU backend, the group table holds the draws of the last
    /// iteration recorded (read by its `extend`) and of the one after (written by it), in
    /// their halves, and the sampler's parameters of their patches, as the host computes
    /// them.
    #[test]
    fn extend_leaves_the_next_iterations_group_draws_in_the_table() {
        use cohort_kernels::group_draw::{
            draws_entry, groups, light_entry, params_entry, table_at,
        };
        use cohort_kernels::sampling::CoherentUniform;
        let d = Device::for_tests(BackendKind::Cpu).unwrap();
        // Without compaction, whose lists group slots by their place, not by slot.
        let o = RenderOptions {
            compact: false,
            ..opts(Budget::PathsPerPixel(3))
        };
        let mut r = Renderer::new(&d, &cornell(), o).unwrap();
        r.render(|_, _| {}).unwrap();
        let f = r.frame;
        assert!(
            f.group_slots > 1,
            "warp groups are tabled on the CPU backend"
        );
        let table = d.read(&r.paths.group_table).unwrap();
        let last = f.iteration;
        assert!(last > 2, "several iterations");
        for it in [last, last + 1] {
            for g in 0..groups(&f) {
                let at = table_at(&f, g, it);
                let what = format!("group {g}, iteration {it} of {last}");
                assert_eq!(
                    table[at],
                    draws_entry::<CoherentUniform>(&f, g, it),
                    "{what}"
                );
                assert_eq!(table[at + 1], light_entry(&f, g, it), "{what}");
                assert_eq!(
                    table[at + 2],
                    params_entry::<CoherentUniform>(&f, table[at]),
                    "{what}"
                );
            }
        }
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
