//! Which form runs a kernel that has both. The vector form wins on arithmetic-heavy kernels
//! and can lose on divergent ones (a BVH traversal's lanes walk different nodes and gather
//! everything they load), and which one wins depends on the scene as much as on the kernel.
//! So by default the backend measures: each form runs one of a kernel's first dispatches,
//! then the one with less time per invocation (a running average) runs the kernel, and one
//! dispatch in 16 (fewer where the other is much slower) runs the other to keep its average
//! current. Both forms compute the same bits, so the choice changes only speed.

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

/// Weight of a new timing in a form's running estimate.
const WEIGHT: f64 = 0.25;

#[derive(Default, Clone, Copy)]
struct Trial {
    /// Running estimate of nanoseconds per invocation, per form (0: vector, 1: host).
    estimate: [Option<f64>; 2],
    dispatches: u64,
    /// The form last reported faster (for the log).
    faster: Option<bool>,
}

impl Trial {
    fn vector_faster(&self) -> Option<bool> {
        match self.estimate {
            [Some(v), Some(h)] => Some(v <= h),
            _ => None,
        }
    }

    /// One dispatch in this many runs the slower form: the running cost of doing so,
    /// (slower / faster - 1) / interval, stays within `EXPLORE_COST`.
    fn explore_every(&self) -> u64 {
        let [Some(v), Some(h)] = self.estimate else {
            return EXPLORE_EVERY;
        };
        let ratio = v.max(h) / v.min(h).max(f64::MIN_POSITIVE);
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
}

impl FormCount {
    /// Each count by its field's name, in field order (`--stats` writes them so).
    pub fn by_form(&self) -> [(&'static str, u64); 4] {
        [
            ("vector", self.vector),
            ("host", self.host),
            ("pending", self.pending),
            ("host_only", self.host_only),
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
        } += 1;
    }

    pub fn get(&self) -> Vec<FormCount> {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// The measured choices of one device, by kernel name.
#[derive(Default)]
pub struct Chooser {
    trials: Mutex<HashMap<String, Trial>>,
}

impl Chooser {
    /// Whether the next dispatch of `kernel` runs its vector form: each form until it has
    /// an estimate, then the faster one, and every [`Trial::explore_every`]-th dispatch
    /// the other.
    pub fn vector_next(&self, kernel: &str) -> bool {
        let t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let Some(tr) = t.get(kernel) else {
            return true;
        };
        match (tr.estimate, tr.vector_faster()) {
            ([None, _], _) => true,
            ([_, None], _) => false,
            (_, Some(v)) => {
                let every = tr.explore_every();
                v != (tr.dispatches % every == every - 1)
            }
            (_, None) => true,
        }
    }

    /// Records a timed dispatch of `kernel` in the vector form (`vector`) or the host form.
    pub fn record(&self, kernel: &str, vector: bool, ns: u64, invocations: u64) {
        let mut t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let tr = t.entry(kernel.to_string()).or_default();
        let x = ns as f64 / invocations.max(1) as f64;
        let e = &mut tr.estimate[usize::from(!vector)];
        *e = Some(e.map_or(x, |old| (1.0 - WEIGHT) * old + WEIGHT * x));
        tr.dispatches += 1;
        let faster = tr.vector_faster();
        if faster.is_some() && faster != tr.faster {
            tr.faster = faster;
            if super::log() {
                let [Some(v), Some(h)] = tr.estimate else {
                    return;
                };
                eprintln!(
                    "cohort: `{kernel}`: vector form {v:.1} ns per invocation, host form {h:.1}: runs its {} form",
                    if v <= h { "vector" } else { "host" }
                );
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(vector_ns: f64, host_ns: f64) -> Trial {
        Trial {
            estimate: [Some(vector_ns), Some(host_ns)],
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

    #[test]
    fn the_faster_form_runs_and_the_slower_one_is_explored() {
        let c = Chooser::default();
        // First dispatch: vector (no estimate), second: host (no host estimate).
        assert!(c.vector_next("k"));
        c.record("k", true, 100, 1);
        assert!(!c.vector_next("k"));
        c.record("k", false, 240, 1);
        // Vector is 2.4x faster: it runs, except once in 70 dispatches.
        let mut host_runs = 0;
        for _ in 0..700 {
            let v = c.vector_next("k");
            host_runs += usize::from(!v);
            c.record("k", v, if v { 100 } else { 240 }, 1);
        }
        assert_eq!(host_runs, 10);
    }
}
