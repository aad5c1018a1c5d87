//! Which form runs a kernel that has both. The vector form wins on arithmetic-heavy kernels
//! and can lose on divergent ones (a BVH traversal's lanes walk different nodes and gather
//! everything they load), and which one wins depends on the scene as much as on the kernel.
//! So by default the backend measures: the forms alternate over a kernel's first
//! dispatches, then the faster one runs the kernel, and one dispatch in 16 (fewer where the
//! other is much slower) runs the other to keep the comparison current. Both forms compute
//! the same bits, so the choice changes only speed.
//!
//! A dispatch's time per invocation drifts over a render (its first bounces are coherent,
//! later ones are not; long paths are left at the end), so two forms timed at different
//! moments do not compare: a form last timed early looks cheaper than it is. Each
//! comparison is therefore a sandwich, the other form's dispatch between two of one form,
//! against the geometric mean of its neighbours, which cancels a steady drift. (With a
//! running average of each form's own timings instead, the traversal of stanford-like ran
//! its slower vector form in up to half of its dispatches: 112 of 242 in one render.)
//!
//! The estimate is kept beside the vector form's object in the cache (`{key}.verdict`), so
//! a later run on this machine starts from it: it runs the faster form from its first
//! dispatch and explores the other at the usual rate, skipping the alternation (whose
//! host dispatches cost a 256x256 render about 20 ms of 300-530). Its sandwiches then
//! refine the estimate as before, which corrects one carried over from another scene.

use std::collections::HashMap;
use std::sync::Mutex;

/// How the CPU backend picks a kernel's form (`COHORT_CPU_SIMD`: `0` or `host`, `1` or
/// `vector`, otherwise measured).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Forms {
    /// Host forms only.
    Host,
    /// The vector form wherever a kernel has one.
    Vector,
    /// Each kernel's faster form, timed on its first dispatches.
    Measured,
}

impl Forms {
    /// The mode `COHORT_CPU_SIMD` asks for.
    pub fn from_env() -> Forms {
        match std::env::var("COHORT_CPU_SIMD").as_deref() {
            Ok("0") | Ok("host") => Forms::Host,
            Ok("1") | Ok("vector") => Forms::Vector,
            _ => Forms::Measured,
        }
    }
}

/// At most one dispatch in this many runs the form that is currently slower, so that its
/// estimate follows the workload (a render's first bounces are coherent, its later ones
/// are not).
const EXPLORE_EVERY: u64 = 16;

/// Where the slower form is much slower, it runs more rarely: so that running it costs at
/// most this share of the kernel's time. A fixed one in 16 cost `extend` on the README's
/// scene 9 % (its host form takes 2-2.4x its vector form's time).
const EXPLORE_COST: f64 = 0.02;

/// The rarest exploring dispatch: one in this many.
const EXPLORE_MAX: u64 = 256;

/// Weight of a new sandwich in the running estimate of the forms' ratio.
const WEIGHT: f64 = 0.25;

/// The forms alternate over a kernel's first this many dispatches: each form's first
/// dispatch warms its code and data and is not compared, the rest give three sandwiches.
const ALTERNATE: u64 = 7;

#[derive(Default, Clone, Copy)]
struct Trial {
    /// Running estimate of ln(vector time / host time) per invocation, from sandwiches.
    log_ratio: Option<f64>,
    /// The last two timed dispatches, newest last: (vector form, ns per invocation,
    /// compared: not the form's first dispatch).
    last: [Option<(bool, f64, bool)>; 2],
    /// Dispatches timed, per form (0: vector, 1: host).
    timed: [u64; 2],
    dispatches: u64,
    /// The form last reported faster (for the log).
    faster: Option<bool>,
    /// Whether `log_ratio` started from an earlier run's estimate (no alternation).
    prior: bool,
    /// The estimate as last kept on disk.
    saved: Option<f64>,
}

impl Trial {
    fn vector_faster(&self) -> Option<bool> {
        self.log_ratio.map(|r| r <= 0.0)
    }

    /// One dispatch in this many runs the slower form: the running cost of doing so,
    /// (slower / faster - 1) / interval, stays within `EXPLORE_COST`.
    fn explore_every(&self) -> u64 {
        let Some(r) = self.log_ratio else {
            return EXPLORE_EVERY;
        };
        let ratio = r.abs().exp();
        let every = ((ratio - 1.0) / EXPLORE_COST).ceil();
        if every.is_finite() {
            (every as u64).clamp(EXPLORE_EVERY, EXPLORE_MAX)
        } else {
            EXPLORE_MAX
        }
    }
}

/// How many dispatches of one kernel ran in each form on a CPU device
/// (`Device::form_counts`): what a render's speed on the CPU backend depends on.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FormCount {
    /// The kernel's artifact name.
    pub kernel: String,
    /// In its vector form.
    pub vector: u64,
    /// In its host form, chosen: it measured faster, or `COHORT_CPU_SIMD=host`.
    pub host: u64,
    /// In its host form while its vector form was not compiled yet (it compiles once the
    /// host form has run for about as long as the compile takes, or comes from the cache
    /// of an earlier run).
    pub pending: u64,
    /// In its host form because it has no vector form (`COHORT_CPU_SIMD_LOG=1` says why).
    pub host_only: u64,
    /// In its whole-dispatch form (`cpu::DispatchForm`).
    pub whole: u64,
}

impl FormCount {
    /// Each count by its field's name, in field order (`--stats` writes them so).
    pub fn by_form(&self) -> [(&'static str, u64); 5] {
        [
            ("vector", self.vector),
            ("host", self.host),
            ("pending", self.pending),
            ("host_only", self.host_only),
            ("whole", self.whole),
        ]
    }
}

/// Which [`FormCount`] field a dispatch counts in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ran {
    Vector,
    Host,
    Pending,
    HostOnly,
    Whole,
}

/// The dispatches of a device's kernels by form, in the order the kernels first ran.
#[derive(Default)]
pub(crate) struct FormCounts(Mutex<Vec<FormCount>>);

impl FormCounts {
    pub fn add(&self, kernel: &str, ran: Ran) {
        let mut v = self.0.lock().unwrap_or_else(|e| e.into_inner());
        let i = match v.iter().position(|c| c.kernel == kernel) {
            Some(i) => i,
            None => {
                v.push(FormCount {
                    kernel: kernel.to_string(),
                    ..Default::default()
                });
                v.len() - 1
            }
        };
        let c = &mut v[i];
        *match ran {
            Ran::Vector => &mut c.vector,
            Ran::Host => &mut c.host,
            Ran::Pending => &mut c.pending,
            Ran::HostOnly => &mut c.host_only,
            Ran::Whole => &mut c.whole,
        } += 1;
    }

    pub fn get(&self) -> Vec<FormCount> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// A kept estimate is rewritten once it has moved by this much (ln of the ratio).
const SAVE_STEP: f64 = 0.02;

/// The measured choices of one device, by kernel name.
#[derive(Default)]
pub struct Chooser {
    trials: Mutex<HashMap<String, Trial>>,
}

impl Chooser {
    /// Whether the next dispatch of `kernel` runs its vector form: each form until it has
    /// an estimate, then the faster one, and every [`Trial::explore_every`]-th dispatch
    /// the other. `key` is the vector form's cache key: the estimate kept under it by an
    /// earlier run, if any, is the starting one.
    pub fn vector_next(&self, kernel: &str, key: Option<u64>) -> bool {
        self.next_with(kernel, || key.and_then(super::llvm::verdict))
    }

    /// [`Chooser::vector_next`] with the kept estimate from `prior`, read on the kernel's
    /// first dispatch.
    fn next_with(&self, kernel: &str, prior: impl FnOnce() -> Option<f64>) -> bool {
        let mut t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let tr = t.entry(kernel.to_string()).or_insert_with(|| {
            let log_ratio = prior();
            if let (Some(r), true) = (log_ratio, super::log()) {
                eprintln!(
                    "cohort: `{kernel}`: vector form {:.3}x the host form's time in an earlier run: starts with its {} form",
                    r.exp(),
                    if r <= 0.0 { "vector" } else { "host" }
                );
            }
            Trial {
                log_ratio,
                prior: log_ratio.is_some(),
                saved: log_ratio,
                faster: log_ratio.map(|r| r <= 0.0),
                ..Default::default()
            }
        });
        match tr.vector_faster() {
            // Alternating, from the vector form: a sandwich completes on every dispatch.
            Some(_) if tr.dispatches < ALTERNATE && !tr.prior => tr.dispatches % 2 == 0,
            None => tr.dispatches % 2 == 0,
            Some(v) => {
                let every = tr.explore_every();
                v != (tr.dispatches % every == every - 1)
            }
        }
    }

    /// Records a timed dispatch of `kernel` in the vector form (`vector`) or the host form;
    /// keeps the estimate under `key` (the vector form's cache key) when it has moved.
    pub fn record(&self, kernel: &str, key: Option<u64>, vector: bool, ns: u64, invocations: u64) {
        let save = self.record_ns(kernel, vector, ns, invocations);
        if let (Some(key), Some(r)) = (key, save) {
            super::llvm::save_verdict(key, r);
        }
    }

    /// [`Chooser::record`] without the disk: the estimate to keep, if it moved by
    /// [`SAVE_STEP`] since it was last kept.
    fn record_ns(&self, kernel: &str, vector: bool, ns: u64, invocations: u64) -> Option<f64> {
        let mut t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let tr = t.entry(kernel.to_string()).or_default();
        let x = (ns.max(1) as f64 / invocations.max(1) as f64).ln();
        let form = usize::from(!vector);
        let compared = tr.timed[form] > 0;
        tr.timed[form] += 1;
        // A sandwich: the other form's dispatch between the previous one of this form and
        // this one, none of them a form's first.
        if let [Some((v0, x0, c0)), Some((v1, x1, c1))] = tr.last {
            if v0 == vector && v1 != vector && c0 && c1 && compared {
                // ln(other / this form), turned into ln(vector / host).
                let other = x1 - 0.5 * (x0 + x);
                let sample = if vector { -other } else { other };
                tr.log_ratio = Some(
                    tr.log_ratio
                        .map_or(sample, |old| (1.0 - WEIGHT) * old + WEIGHT * sample),
                );
            }
        }
        tr.last = [tr.last[1], Some((vector, x, compared))];
        tr.dispatches += 1;
        let faster = tr.vector_faster();
        if faster.is_some() && faster != tr.faster {
            tr.faster = faster;
            if super::log() {
                let r = tr.log_ratio.unwrap_or(0.0).exp();
                eprintln!(
                    "cohort: `{kernel}`: vector form {r:.3}x the host form's time: runs its {} form",
                    if r <= 1.0 { "vector" } else { "host" }
                );
            }
        }
        match (tr.log_ratio, tr.saved) {
            (Some(r), Some(s)) if (r - s).abs() < SAVE_STEP => None,
            (Some(r), _) => {
                tr.saved = Some(r);
                Some(r)
            }
            (None, _) => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(vector_ns: f64, host_ns: f64) -> Trial {
        Trial {
            log_ratio: Some((vector_ns / host_ns).ln()),
            ..Default::default()
        }
    }

    #[test]
    fn a_much_slower_form_is_explored_rarely() {
        // Near-even forms: one in 16, the most often.
        assert_eq!(trial(100.0, 105.0).explore_every(), EXPLORE_EVERY);
        // 2.4x slower: (2.4 - 1) / 0.02 = 70.
        assert_eq!(trial(100.0, 240.0).explore_every(), 70);
        assert_eq!(trial(240.0, 100.0).explore_every(), 70);
        // Far slower, or a zero estimate: the rarest.
        assert_eq!(trial(1.0, 1000.0).explore_every(), EXPLORE_MAX);
        assert_eq!(trial(0.0, 10.0).explore_every(), EXPLORE_MAX);
    }

    /// Runs `n` dispatches of kernel "k" where the dispatch numbered `d` takes
    /// `ns(d, vector)`; returns how many ran the vector form after the alternation.
    fn vector_runs(c: &Chooser, n: u64, ns: impl Fn(u64, bool) -> f64) -> u64 {
        let mut vector = 0;
        for d in 0..n {
            let v = c.vector_next("k", None);
            if d >= ALTERNATE {
                vector += u64::from(v);
            }
            c.record("k", None, v, ns(d, v) as u64, 1);
        }
        vector
    }

    #[test]
    fn the_faster_form_runs_and_the_slower_one_is_explored() {
        let c = Chooser::default();
        // The first seven dispatches alternate, from the vector form.
        let mut order = Vec::new();
        for _ in 0..ALTERNATE {
            let v = c.vector_next("k", None);
            order.push(v);
            c.record("k", None, v, if v { 100 } else { 240 }, 1);
        }
        assert_eq!(order, [true, false, true, false, true, false, true]);
        // Vector is 2.4x faster: it runs, except once in 70 dispatches.
        let mut host_runs = 0;
        for _ in 0..700 {
            let v = c.vector_next("k", None);
            host_runs += usize::from(!v);
            c.record("k", None, v, if v { 100 } else { 240 }, 1);
        }
        assert_eq!(host_runs, 10);
    }

    #[test]
    fn a_drifting_cost_does_not_mislead_the_choice() {
        // Each dispatch costs more than the one before (a render's bounces get less
        // coherent), the first one much less; the vector form takes 1.3x the host's time
        // at any moment, then the other way round. The faster form runs but for its
        // explorations (one in 16).
        let drift = |d: u64| {
            if d == 0 {
                40.0
            } else {
                1000.0 * (1.0 + d as f64 / 20.0)
            }
        };
        let n = 400;
        let c = Chooser::default();
        let v = vector_runs(&c, n, |d, v| drift(d) * if v { 1.3 } else { 1.0 });
        assert!(v <= (n - ALTERNATE) / 16 + 1, "vector ran {v} times");
        let c = Chooser::default();
        let v = vector_runs(&c, n, |d, v| drift(d) * if v { 1.0 } else { 1.3 });
        assert!(
            v >= (n - ALTERNATE) - (n - ALTERNATE) / 16 - 1,
            "vector ran {v} times"
        );
    }

    /// Runs `n` dispatches of kernel "k" starting from the kept estimate `prior`; returns
    /// each dispatch's form and the estimates that were to be kept, in order.
    fn with_prior(prior: f64, n: u64, ns: impl Fn(bool) -> f64) -> (Vec<bool>, Vec<f64>) {
        let c = Chooser::default();
        let (mut forms, mut kept) = (Vec::new(), Vec::new());
        for _ in 0..n {
            let v = c.next_with("k", || Some(prior));
            forms.push(v);
            kept.extend(c.record_ns("k", v, ns(v) as u64, 1));
        }
        (forms, kept)
    }

    #[test]
    fn an_earlier_estimate_skips_the_alternation() {
        // Kept: vector 2.4x faster. The host form runs first at its exploration (one in
        // 70), not in an alternation.
        let (forms, kept) = with_prior(
            (100.0f64 / 240.0).ln(),
            140,
            |v| {
                if v {
                    100.0
                } else {
                    240.0
                }
            },
        );
        let host: Vec<usize> = (0..forms.len()).filter(|&d| !forms[d]).collect();
        assert_eq!(host, [69, 139]);
        // The first host dispatch warms up and gives no sandwich, so nothing new is kept.
        assert!(kept.is_empty(), "{kept:?}");
    }

    #[test]
    fn a_wrong_earlier_estimate_is_corrected_and_kept() {
        // Kept: vector 1.3x faster; in this run it is 1.3x slower. The sandwiches around
        // the explorations turn the estimate within a few of them; then the host form
        // runs but for its explorations.
        let (forms, kept) = with_prior(-(1.3f64.ln()), 400, |v| if v { 130.0 } else { 100.0 });
        let late_vector = forms[100..].iter().filter(|&&v| v).count();
        assert!(
            late_vector <= 300 / 16 + 1,
            "vector ran {late_vector} times"
        );
        // What was kept moved towards, and ended near, this run's ratio.
        let last = *kept.last().expect("an estimate was kept");
        assert!(
            kept.len() >= 2 && (last - 1.3f64.ln()).abs() < 0.1,
            "{kept:?}"
        );
        // Each kept estimate moved by at least SAVE_STEP from the one kept before it.
        let mut before = vec![-(1.3f64.ln())];
        before.extend(&kept[..kept.len() - 1]);
        assert!(before
            .iter()
            .zip(&kept)
            .all(|(a, b)| (b - a).abs() >= SAVE_STEP));
    }
}
