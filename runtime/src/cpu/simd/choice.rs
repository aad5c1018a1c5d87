//! Which form runs a kernel that has both. The vector form wins on arithmetic-heavy kernels
//! and can lose on divergent ones (a BVH traversal's lanes walk different nodes and gather
//! everything they load), and which one wins depends on the scene as much as on the kernel.
//! So by default the backend measures: each form runs one of a kernel's first dispatches,
//! then the one with less time per invocation (a running average) runs the kernel, and one
//! dispatch in 16 runs the other to keep its average current. Both forms compute the same
//! bits, so the choice changes only speed.

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

/// One dispatch in this many runs the form that is currently slower, so that its estimate
/// follows the workload (a render's first bounces are coherent, its later ones are not).
const EXPLORE_EVERY: u64 = 16;

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
}

/// The measured choices of one device, by kernel name.
#[derive(Default)]
pub struct Chooser {
    trials: Mutex<HashMap<String, Trial>>,
}

impl Chooser {
    /// Whether the next dispatch of `kernel` runs its vector form: each form until it has
    /// an estimate, then the faster one, and every `EXPLORE_EVERY`-th dispatch the other.
    pub fn vector_next(&self, kernel: &str) -> bool {
        let t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let Some(tr) = t.get(kernel) else {
            return true;
        };
        match (tr.estimate, tr.vector_faster()) {
            ([None, _], _) => true,
            ([_, None], _) => false,
            (_, Some(v)) => v != (tr.dispatches % EXPLORE_EVERY == EXPLORE_EVERY - 1),
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
