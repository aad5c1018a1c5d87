//! The kernels a renderer's options choose: the trampolines that turn the options into
//! the kernels' type parameters (the diffuse strategy `S`, the path-end policy `E`, the
//! integrator `I`), the specialisations of every kernel an iteration may record
//! ([`Specs`]), and compiling their pipelines before any render.

use std::sync::Arc;
use std::time::{Duration, Instant};

use cohort::runtime::{BackendKind, Device, KernelArtifact};
use cohort_kernels::compact;
use cohort_kernels::extend::{extend, init_paths};
use cohort_kernels::group_draw::{self, draw_groups};
use cohort_kernels::integrator::{Implicit, Integrator, NextEvent};
use cohort_kernels::layout::Frame;
use cohort_kernels::path_end::{EachPath, PathEnd, WholeGroup};
use cohort_kernels::sampling::{
    CoherentCosine, CoherentEqualArea, CoherentUniform, Cosine, DiffuseSampler,
};
use cohort_kernels::shading::{group_draws, SHADES_GROUP_TABLE};
use cohort_kernels::traverse::{trace_shadow, traverse};
use cohort_kernels::traverse_wide::{trace_shadow8, traverse8};
use cohort_kernels::{queues, reorder, retire};

use crate::design::Choice;
use crate::paths::SortState;
use crate::queues::{plan, QueueState};
use crate::{
    Budget, GpuScene, InPatch, IntegratorKind, RenderError, RenderOptions, RenderStats, Renderer,
    Shading,
};

/// An operation over the kernels of the current options (see `Renderer::with_kernels`).
pub(crate) trait KernelOp {
    type Out;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out;
}

pub(crate) struct Advance<'a> {
    pub(crate) until: Budget,
    pub(crate) progress: &'a mut dyn FnMut(f64, &RenderStats),
}

impl KernelOp for Advance<'_> {
    type Out = Result<RenderStats, RenderError>;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out {
        r.advance_kernels::<S, E, I>(self.until, self.progress)
    }
}

pub(crate) struct Prepare;

impl KernelOp for Prepare {
    type Out = Result<(), RenderError>;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self, r: &mut Renderer<'_>) -> Self::Out {
        r.prepare_kernels::<S, E, I>()
    }
}

/// The specialisations of every kernel an iteration may record.
pub(crate) struct Specs {
    pub(crate) traverse: cohort::Spec,
    pub(crate) traverse8: cohort::Spec,
    pub(crate) extend: cohort::Spec,
    pub(crate) shadow: cohort::Spec,
    pub(crate) shadow8: cohort::Spec,
    pub(crate) compact: compact::Specs,
    /// `cohort_kernels::retire::mark_live` (the partition is `compact`'s).
    pub(crate) live: cohort::Spec,
    pub(crate) reorder: reorder::Specs,
    pub(crate) queues: queues::Specs,
    /// `cohort_kernels::group_draw::draw_groups`.
    pub(crate) groups: cohort::Spec,
}

/// An operation over the kernel types of a set of options (see [`with_types`]).
pub(crate) trait TypedOp {
    type Out;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self) -> Self::Out;
}

/// Runs `op` with the kernel types of `opts`: the diffuse strategy `S`, the path-end policy
/// `E` and the integrator `I` are chosen here, once, from the options, for every operation
/// that needs them.
pub(crate) fn with_types<O: TypedOp>(opts: &RenderOptions, op: O) -> O::Out {
    match (opts.algorithm.coherent, opts.in_patch) {
        (false, _) => sampler_types::<Cosine, O>(opts, op),
        (true, InPatch::Uniform) => sampler_types::<CoherentUniform, O>(opts, op),
        (true, InPatch::Cosine) => sampler_types::<CoherentCosine, O>(opts, op),
        (true, InPatch::EqualArea) => sampler_types::<CoherentEqualArea, O>(opts, op),
    }
}

/// [`with_types`] with the diffuse strategy chosen (by the options or by a caller).
fn sampler_types<S: DiffuseSampler, O: TypedOp>(opts: &RenderOptions, op: O) -> O::Out {
    match opts.whole_group_end {
        Some(_) => end_types::<S, WholeGroup, O>(opts, op),
        None => end_types::<S, EachPath, O>(opts, op),
    }
}

fn end_types<S: DiffuseSampler, E: PathEnd, O: TypedOp>(opts: &RenderOptions, op: O) -> O::Out {
    match opts.integrator {
        IntegratorKind::Path => op.run::<S, E, Implicit>(),
        IntegratorKind::Nee => op.run::<S, E, NextEvent>(),
    }
}

/// A [`KernelOp`] with its renderer.
struct OnRenderer<'r, 'd, O> {
    r: &'r mut Renderer<'d>,
    op: O,
}

impl<O: KernelOp> TypedOp for OnRenderer<'_, '_, O> {
    type Out = O::Out;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self) -> O::Out {
        self.op.run::<S, E, I>(self.r)
    }
}

impl Specs {
    /// The specialisations for device `d` and the options' group level.
    pub(crate) fn new(d: &Device, group: cohort::Group) -> Specs {
        Specs {
            traverse: traverse::spec(d, None),
            traverse8: traverse8::spec(d, None),
            extend: extend::spec(d, Some(group)),
            shadow: trace_shadow::spec(d, None),
            shadow8: trace_shadow8::spec(d, None),
            compact: compact::specs(d),
            live: retire::spec(d),
            reorder: reorder::specs(d),
            queues: queues::specs(d),
            groups: draw_groups::spec(d, None),
        }
    }
}

impl Renderer<'_> {
    /// Runs `op` with the kernel types of the current options ([`with_types`]).
    pub(crate) fn with_kernels<O: KernelOp>(&mut self, op: O) -> O::Out {
        let opts = self.opts.clone();
        with_types(&opts, OnRenderer { r: self, op })
    }

    /// [`with_kernels`](Self::with_kernels) with the diffuse strategy `S` of a caller.
    pub(crate) fn with_sampler<S: DiffuseSampler, O: KernelOp>(&mut self, op: O) -> O::Out {
        let opts = self.opts.clone();
        sampler_types::<S, _>(&opts, OnRenderer { r: self, op })
    }

    /// The specialisations of every kernel an iteration may record, for this device and
    /// the options' group level.
    pub(crate) fn specs(&self) -> Specs {
        Specs::new(self.device, self.opts.algorithm.group)
    }

    /// Compiles the pipelines of every kernel the options use (driver compilation, which
    /// the on-disk pipeline cache shortens on later runs), so that no render pays for it.
    pub(crate) fn prepare_kernels<S: DiffuseSampler, E: PathEnd, I: Integrator>(
        &mut self,
    ) -> Result<(), RenderError> {
        let compiled = Compile {
            d: self.device,
            opts: &self.opts,
            shading: extend_set(&self.scene, &self.frame),
            wide: self.scene.nodes8.is_some(),
        }
        .run::<S, E, I>()?;
        self.adopt(compiled)
    }

    /// Takes what [`Compile`] made (the design and the pipeline threads' times) and
    /// allocates the state of the stages it chose.
    pub(crate) fn adopt(&mut self, compiled: Compiled) -> Result<(), RenderError> {
        let started = Instant::now();
        let d = self.device;
        let specs = self.specs();
        self.startup.shading = self.scene.shading;
        let shading = extend_set(&self.scene, &self.frame);
        let queue_sets = plan(shading).sets;
        let queued = match compiled.design {
            Choice::Fixed(q) => q,
            Choice::Trial(_) => true,
        };
        self.design = compiled.design;
        self.startup.kernels = compiled.kernels;
        if self.opts.reorder > 0 && self.paths.sort.is_none() {
            self.paths.sort = Some(SortState::new(d, self.frame.slots, &self.scene)?);
        }
        if shading & SHADES_GROUP_TABLE != 0 {
            let len = group_draw::table_len(group_draw::groups(&self.frame));
            if self.paths.group_table.len() < len {
                self.paths.group_table = d.alloc(len)?;
            }
        }
        // The queues' dispatches are sized for the group level's workgroup.
        let wgs = specs.extend.workgroup_size;
        let stale = |q: &QueueState| {
            q.plan.table[queues::BLEND_ENTRY + 2] != wgs || q.plan.sets != queue_sets
        };
        if queued && self.paths.queues.as_ref().is_none_or(stale) {
            self.paths.queues = Some(QueueState::new(d, self.frame.slots, shading, wgs)?);
        }
        self.startup.pipelines += compiled.time + started.elapsed();
        Ok(())
    }
}

/// Building and creating the pipelines of every kernel a render with these options may
/// record. It needs the device, the options and two facts of the scene, not a renderer,
/// so that a new renderer compiles beside allocating its path state.
pub(crate) struct Compile<'a> {
    pub(crate) d: &'a Device,
    pub(crate) opts: &'a RenderOptions,
    /// `extend`'s set ([`extend_set`]).
    pub(crate) shading: u32,
    /// Whether the scene has its 8-wide tree (`GpuScene::nodes8`).
    pub(crate) wide: bool,
}

/// What [`Compile`] made.
pub(crate) struct Compiled {
    design: Choice,
    /// Each pipeline thread's kernels and time, longest first (`Startup::kernels`).
    kernels: Vec<(String, Duration)>,
    time: Duration,
}

impl TypedOp for Compile<'_> {
    type Out = Result<Compiled, RenderError>;
    fn run<S: DiffuseSampler, E: PathEnd, I: Integrator>(self) -> Self::Out {
        let started = Instant::now();
        let Compile {
            d,
            opts: o,
            shading,
            wide,
        } = self;
        let specs = Specs::new(d, o.algorithm.group);
        let compact = o.compact;
        let reorder = o.reorder > 0;
        let queue_sets = plan(shading).sets;
        let info = d.info();
        // `Auto` measures both designs where the choice cannot change the image and
        // timestamps can tell them apart (`crate::design`). Not on the software driver,
        // which would only pay for the partition and for more compilation, nor on the CPU
        // backend: there queues took 0.80-1.31x of one kernel's time on the test scenes
        // of several kinds (BENCHMARKS.md), and a trial would compile a vector form per
        // queue besides the one kernel's.
        let trial = queue_sets.len() > 1
            && o.per_path_sampling()
            && info.timestamps
            && !info.software_driver
            && info.backend != BackendKind::Cpu;
        let design = match o.shading {
            Shading::Kernel => Choice::Fixed(false),
            Shading::Queues => Choice::Fixed(true),
            Shading::Auto if trial => Choice::Trial(Default::default()),
            Shading::Auto => Choice::Fixed(false),
        };
        let (one, queued) = match design {
            Choice::Fixed(q) => (!q, q),
            Choice::Trial(_) => (true, true),
        };
        // The sets of the `extend`s this render may record: the scene's, one per queue.
        let mut sets = Vec::new();
        if one {
            sets.push(shading);
        }
        if queued {
            sets.extend(&queue_sets);
        }
        // Every stage this render uses, built (IR, WGSL or SPIR-V) and compiled by the
        // driver on a thread of its own: `extend` takes the longest, and the others
        // finish beside it.
        type Build<'s> =
            Box<dyn FnOnce() -> Result<Vec<Arc<KernelArtifact>>, RenderError> + Send + 's>;
        let mut builds: Vec<Build<'_>> = vec![
            Box::new(|| Ok(vec![init_paths::artifact(&init_paths::spec(d, None))?])),
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
        for &set in &sets {
            let spec = &specs.extend;
            builds.push(Box::new(move || {
                Ok(vec![extend::artifact::<S, E, I>(&extend::specialized(
                    spec, set,
                ))?])
            }));
        }
        if shading & SHADES_GROUP_TABLE != 0 {
            builds.push(Box::new(|| {
                Ok(vec![draw_groups::artifact::<S>(&specs.groups)?])
            }));
        }
        if queued {
            builds.push(Box::new(|| Ok(queues::artifacts(&specs.queues)?)));
        }
        if compact {
            builds.push(Box::new(|| Ok(compact::artifacts(&specs.compact)?)));
        }
        if o.retires(crate::renderer::draws_per_lane(d)) {
            builds.push(Box::new(|| {
                Ok(retire::artifacts(&specs.live, &specs.compact)?)
            }));
        }
        if reorder {
            builds.push(Box::new(|| Ok(reorder::artifacts(&specs.reorder)?)));
        }
        let mut kernels = std::thread::scope(|scope| {
            let threads: Vec<_> = builds
                .into_iter()
                .map(|build| {
                    scope.spawn(move || -> Result<(String, Duration), RenderError> {
                        let started = Instant::now();
                        let artifacts = build()?;
                        for a in &artifacts {
                            d.prepare(a)?;
                        }
                        let names: Vec<&str> = artifacts.iter().map(|a| a.name.as_str()).collect();
                        Ok((names.join("+"), started.elapsed()))
                    })
                })
                .collect();
            threads
                .into_iter()
                .map(|t| t.join().expect("a pipeline thread panicked"))
                .collect::<Result<Vec<_>, _>>()
        })?;
        kernels.sort_by_key(|k| std::cmp::Reverse(k.1));
        Ok(Compiled {
            design,
            kernels,
            time: started.elapsed(),
        })
    }
}

/// The set one `extend` over every ray is built and recorded with: the scene's, with the
/// frame's group draws (`cohort_kernels::shading::group_draws`). The queues' sets derive
/// from it (`crate::queues::plan`).
pub(crate) fn extend_set(scene: &GpuScene, frame: &Frame) -> u32 {
    scene.shading | group_draws(frame)
}
