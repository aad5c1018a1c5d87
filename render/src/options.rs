//! What a render is asked to do: the paper's configurations ([`Algorithm`], [`InPatch`]),
//! the integrator, the budget, and every other option of [`RenderOptions`], with the
//! checks that do not need a scene ([`RenderOptions::check`]).

use std::time::Duration;

use cohort::Group;

use crate::{RenderError, Roulette, Shard};

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
    /// Retire finished slots from the live list where the image allows it
    /// ([`Self::retires`]); false keeps every slot listed, for comparisons. The image is
    /// the same either way.
    pub retire: bool,
    /// How shading is organised: one kernel, material queues, or the faster of the two
    /// measured on the render (the default).
    pub shading: Shading,
    /// Russian roulette continuation probability (the paper: 0.8).
    pub rr_continue: f32,
    /// Which Russian roulette ends paths: the paper's fixed `rr_continue` (the default), or
    /// Mitsuba's throughput-based one from the scene's `rr_depth`.
    pub roulette: Roulette,
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
    /// Whether a renderer of a `width` x `height` image takes these options; the error
    /// says what is wrong (what `Renderer::new` and `reconfigure` would return).
    pub fn check(&self, width: u32, height: u32) -> Result<(), RenderError> {
        validate(self, width, height)
    }

    /// Whether every random number a path draws depends only on (seed, pixel, path):
    /// independent diffuse sampling, per-path roulette and independent light samples.
    /// Then the shards of a paths budget merge into the unsplit run's image; otherwise
    /// group draws keyed by iteration enter, and the merge is statistical.
    pub fn per_path_sampling(&self) -> bool {
        !self.algorithm.coherent
            && !self.group_rr
            && self.whole_group_end.is_none()
            && !self.coherent_light
    }

    /// Invocations per coherence group where `extend` keys the group draws by the slot it
    /// shades (`Frame::group_slots`, `cohort_kernels::group_draw`), else 0. That key does
    /// not change when finished slots leave the list, so such a run retires them. It
    /// needs every invocation to compute its group's draws itself: at thread level, and
    /// at warp and block level where the backend recomputes group shares (`per_lane`,
    /// `Spec::recompute_group_share`); on a GPU a group's leader computes them once, and
    /// after a retirement a warp would hold slots of several groups. Not with
    /// whole-group ends, which vote among the invocations of a group, nor where groups
    /// form over material queues or compacted lists.
    pub(crate) fn group_slots(&self, per_lane: bool) -> u32 {
        if self.per_path_sampling()
            || self.whole_group_end.is_some()
            || self.compact
            || self.shading == Shading::Queues
        {
            return 0;
        }
        match self.algorithm.group {
            Group::Thread => 1,
            Group::Warp if per_lane => cohort::spec::WARP,
            Group::Block(n) if per_lane => n,
            _ => 0,
        }
    }

    /// Whether the renderer retires finished slots from the live list
    /// (`cohort_kernels::retire`): where the image does not depend on which invocation
    /// takes a slot, and without compaction, whose lists keep every slot. So where no
    /// group shares a draw, where the draws are keyed by slot ([`Self::group_slots`]),
    /// and at grid level, where every slot is in the one group.
    pub(crate) fn retires(&self, per_lane: bool) -> bool {
        self.retire
            && !self.compact
            && (self.per_path_sampling()
                || self.group_slots(per_lane) != 0
                || (self.algorithm.group == Group::Grid && self.whole_group_end.is_none()))
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
    pub(crate) fn shard_budget(&self) -> Budget {
        match self.budget {
            Budget::PathsPerPixel(_) => Budget::PathsPerPixel(self.path_range().1),
            time => time,
        }
    }
}

/// How shading is organised (`crate::design`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// Both designs measured on the render, batch by batch, and the faster kept, where
    /// the choice cannot change the image: a GPU that times its dispatches, draws keyed
    /// by path (`RenderOptions::per_path_sampling`) and a scene of more than one queue.
    /// Elsewhere one kernel.
    #[default]
    Auto,
    /// One `extend` built with the scene's kinds shades every ray.
    Kernel,
    /// Material queues (`cohort_kernels::queues`): after the traversal the live rays are
    /// partitioned by the BSDF kind they hit, and one `extend` per kind, built with that
    /// kind alone, shades its queue (pbrt-v4's wavefront organisation). Draws keyed by
    /// path do not depend on it (the image is the same bit for bit); with coherent
    /// groups, the groups form over the queues.
    Queues,
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
            retire: true,
            shading: Shading::Auto,
            rr_continue: 0.8,
            roulette: Roulette::Fixed,
            whole_group_end: None,
            integrator: IntegratorKind::Path,
            coherent_light: false,
            light_cells: 4,
            shard: Shard::WHOLE,
            wavefront: None,
        }
    }
}

/// Checks the options that do not depend on the scene, for an image of `w` x `h`.
pub(crate) fn validate(opts: &RenderOptions, w: u32, h: u32) -> Result<(), RenderError> {
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
