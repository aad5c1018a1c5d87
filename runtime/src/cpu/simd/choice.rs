//! Which form runs a kernel that has both. The vector form wins on arithmetic-heavy kernels
//! and can lose on divergent ones (a BVH traversal's lanes walk different nodes and gather
//! everything they load), and which one wins depends on the scene as much as on the kernel.
//! So by default the backend measures: each form runs a kernel's first dispatches in turn,
//! and then the one with less time per invocation keeps it. Both forms compute the same
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

/// Dispatches each form runs before the choice is made.
const TRIALS: u32 = 3;

#[derive(Default, Clone, Copy)]
struct Trial {
    /// Per form (0: vector, 1: host): nanoseconds, invocations and dispatches timed.
    ns: [u64; 2],
    invocations: [u64; 2],
    runs: [u32; 2],
    chosen: Option<bool>,
}

/// The measured choices of one device, by kernel name.
#[derive(Default)]
pub struct Chooser {
    trials: Mutex<HashMap<String, Trial>>,
}

impl Chooser {
    /// Whether the next dispatch of `kernel` runs its vector form.
    pub fn vector_next(&self, kernel: &str) -> bool {
        let t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        match t.get(kernel) {
            None => true,
            Some(tr) => tr.chosen.unwrap_or(tr.runs[0] <= tr.runs[1]),
        }
    }

    /// Records a timed dispatch of `kernel` in the vector form (`vector`) or the host form.
    pub fn record(&self, kernel: &str, vector: bool, ns: u64, invocations: u64) {
        let mut t = self.trials.lock().unwrap_or_else(|e| e.into_inner());
        let tr = t.entry(kernel.to_string()).or_default();
        if tr.chosen.is_some() {
            return;
        }
        let i = usize::from(!vector);
        tr.ns[i] += ns;
        tr.invocations[i] += invocations.max(1);
        tr.runs[i] += 1;
        if tr.runs[0] >= TRIALS && tr.runs[1] >= TRIALS {
            // Compare time per invocation: ns[0]/inv[0] <= ns[1]/inv[1].
            let vector_wins = u128::from(tr.ns[0]) * u128::from(tr.invocations[1])
                <= u128::from(tr.ns[1]) * u128::from(tr.invocations[0]);
            tr.chosen = Some(vector_wins);
            if super::log() {
                let per = |k: usize| tr.ns[k] as f64 / tr.invocations[k] as f64;
                eprintln!(
                    "cohort: `{kernel}`: vector form {:.1} ns per invocation, host form {:.1}: runs its {} form",
                    per(0),
                    per(1),
                    if vector_wins { "vector" } else { "host" }
                );
            }
        }
    }
}
