//! The CPU backend's vector form of a kernel: its naga module lowered to LLVM IR that runs
//! `W` invocations per call in SIMD lanes (`lower`), compiled at run time by a libLLVM
//! found on the machine (`llvm`). Kernels it does not cover, and machines without a
//! libLLVM, keep the host form; where a kernel has both, `choice` picks one.
//! `COHORT_CPU_SIMD_LOG=1` says which form each kernel runs and why;
//! `COHORT_CPU_SIMD_DUMP=DIR` writes each kernel's IR to `DIR/<kernel>.ll`;
//! `COHORT_CPU_SIMD_PERF_MAP=1` names each one's code for `perf` (`perf_map`).

mod acos;
mod choice;
mod deferred;
mod expr;
mod llvm;
mod lower;
mod memory;
mod perf_map;
mod rows;
mod sincos;
mod straight;
mod types;
mod width;

use std::collections::HashMap;
use std::sync::{Arc, Condvar, Mutex, OnceLock};

use cohort_compiler::CompiledKernel;

pub use choice::{Chooser, FormCount, Forms};
pub(crate) use choice::{FormCounts, Ran};
pub use llvm::stop_compiles;
pub use types::WIDTHS;
pub use width::default_lanes;

/// One binding as the vector form reads it: base address and bound size in bytes.
#[repr(C)]
#[derive(Clone, Copy)]
pub(crate) struct EnvEntry {
    pub ptr: *mut u8,
    pub bytes: u64,
}

/// `run(env, error_flag, first_workgroup, end_workgroup, nx, ny, nz)`.
type RunFn = unsafe extern "C" fn(*const EnvEntry, *mut u32, u32, u32, u32, u32, u32);

/// A kernel compiled to its vector form.
#[derive(Clone, Copy, Debug)]
pub struct SimdKernel {
    run: RunFn,
    /// Its object cache key: what the forms' measured ratio is kept under between runs
    /// ([`Chooser`]).
    pub key: u64,
}

impl SimdKernel {
    /// Runs workgroups `first..end` of a grid of `groups`; returns whether every access
    /// stayed in bounds.
    ///
    /// # Safety
    /// `env` holds the kernel's bindings in binding order, each valid for its size, and
    /// no other code writes them meanwhile except other workgroups of this dispatch.
    pub(crate) unsafe fn run(
        &self,
        env: &[EnvEntry],
        first: u32,
        end: u32,
        groups: [u32; 3],
    ) -> bool {
        let mut err = 0u32;
        (self.run)(
            env.as_ptr(),
            &mut err,
            first,
            end,
            groups[0],
            groups[1],
            groups[2],
        );
        err == 0
    }
}

/// Whether to say which form each kernel runs (`COHORT_CPU_SIMD_LOG=1`).
pub(crate) fn log() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var("COHORT_CPU_SIMD_LOG").is_ok_and(|v| v != "0"))
}

/// The libLLVM the vector form compiles with, or why there is none.
pub fn llvm_library() -> Result<String, String> {
    match llvm::jit() {
        Ok(j) => Ok(j.library().to_string()),
        Err(e) => Err(e.clone()),
    }
}

/// The LLVM IR of a kernel's vector form in blocks of [`default_lanes`], or what in it the
/// vector form does not cover.
pub fn lower_to_llvm_ir(k: &CompiledKernel) -> Result<String, String> {
    lower::lower(k, lower::RUN, default_lanes())
}

/// What LLVM is assumed to take per byte of IR before this process has compiled anything
/// (`COHORT_CPU_SIMD_LOG=1` prints each compile's rate: 0.4-1.6 us per byte at -O2
/// on the 2-core machine of BENCHMARKS.md).
const DEFAULT_NS_PER_IR_BYTE: f64 = 1000.0;

/// A kernel's vector form: not compiled (its IR, its object cache key, and the time its
/// host form has run on this machine, over runs, with what of that is on disk), being
/// compiled, or compiled (or refused, with the reason).
enum State {
    Cold {
        ir: Arc<str>,
        key: u64,
        host_ns: u64,
        saved_ns: u64,
    },
    Pending,
    Done(Result<SimdKernel, String>),
}

struct Cache {
    /// By kernel id and block width.
    kernels: Mutex<HashMap<(u64, u32), State>>,
    done: Condvar,
    /// Running estimate of LLVM's nanoseconds per byte of IR, from this process's compiles.
    ns_per_byte: Mutex<f64>,
}

fn cache() -> &'static Cache {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    CACHE.get_or_init(|| Cache {
        kernels: Mutex::new(HashMap::new()),
        done: Condvar::new(),
        ns_per_byte: Mutex::new(DEFAULT_NS_PER_IR_BYTE),
    })
}

/// Which form a dispatch of a kernel can run.
#[derive(Clone, Copy, Debug)]
pub enum Ready {
    /// Its vector form.
    Vector(SimdKernel),
    /// Its host form, for now: report the time it takes ([`ran_host`]), which decides
    /// when the vector form is compiled.
    NotYet,
    /// Its host form, always (no vector form: the reason was logged).
    Never,
}

/// The vector form of `k`, if it has one yet. The first call links it if its object file
/// is cached. Otherwise it is compiled on a thread of its own once the kernel's host form
/// has run as long as the compile is estimated to take (from the IR's size), counted over
/// runs on this machine (the time is kept beside the object cache): a kernel that runs
/// little never pays LLVM more than its host form took, and one that runs often compiles
/// once per machine. With `wait` it is compiled at once and waited for. `lanes` is the
/// width of its blocks (one of [`WIDTHS`]).
pub fn compiled(k: &Arc<CompiledKernel>, lanes: u32, wait: bool) -> Ready {
    let c = cache();
    let id = (k.id, lanes);
    let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
    if !kernels.contains_key(&id) {
        drop(kernels);
        let first = probe(k, lanes);
        kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
        kernels.entry(id).or_insert(first);
    }
    if wait {
        start_if_cold(&mut kernels, k, lanes);
    }
    loop {
        match kernels.get(&id) {
            Some(State::Done(Ok(v))) => return Ready::Vector(*v),
            Some(State::Done(Err(_))) => return Ready::Never,
            _ if !wait => return Ready::NotYet,
            _ => kernels = c.done.wait(kernels).unwrap_or_else(|e| e.into_inner()),
        }
    }
}

/// Records `ns` more of `k`'s host form (after [`Ready::NotYet`]); starts compiling its
/// vector form once that time, over runs, reaches the compile's estimate, and keeps it on
/// disk at every eighth of the estimate.
pub fn ran_host(k: &Arc<CompiledKernel>, lanes: u32, ns: u64) {
    let c = cache();
    let per_byte = *c.ns_per_byte.lock().unwrap_or_else(|e| e.into_inner());
    let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(State::Cold {
        ir,
        key,
        host_ns,
        saved_ns,
    }) = kernels.get_mut(&(k.id, lanes))
    {
        *host_ns += ns;
        let estimate = per_byte * ir.len() as f64;
        if *host_ns as f64 >= estimate {
            if log() {
                eprintln!(
                    "cohort: `{}`: its host form has run {:.2} s on this machine, its vector form's compile is estimated at {:.2} s: compiling",
                    k.name,
                    *host_ns as f64 * 1e-9,
                    estimate * 1e-9
                );
            }
            start_if_cold(&mut kernels, k, lanes);
        } else if (*host_ns - *saved_ns) as f64 >= estimate / 8.0 {
            *saved_ns = *host_ns;
            llvm::save_host_time(*key, *host_ns);
        }
    }
}

fn start_if_cold(kernels: &mut HashMap<(u64, u32), State>, k: &Arc<CompiledKernel>, lanes: u32) {
    if let Some(State::Cold { ir, key, .. }) = kernels.get(&(k.id, lanes)) {
        let (ir, key) = (Arc::clone(ir), *key);
        kernels.insert((k.id, lanes), State::Pending);
        spawn_build(Arc::clone(k), lanes, ir, key);
    }
}

/// The vector form of `k` without compiling: linked from the object cache, refused (no
/// libLLVM, or a construct the lowering does not cover), or `Cold` with its IR.
fn probe(k: &CompiledKernel, lanes: u32) -> State {
    let jit = match llvm::jit() {
        Ok(j) => j,
        Err(e) => {
            if log() {
                eprintln!("cohort: `{}` has no vector form: {e}", k.name);
            }
            return State::Done(Err(e.clone()));
        }
    };
    let ir: Arc<str> = match lower::lower(k, lower::RUN, lanes) {
        Ok(ir) => ir.into(),
        Err(e) => {
            if log() {
                eprintln!("cohort: `{}` has no vector form: {e}", k.name);
            }
            return State::Done(Err(e));
        }
    };
    if let Some(d) = std::env::var_os("COHORT_CPU_SIMD_DUMP") {
        let _ = std::fs::write(
            std::path::Path::new(&d).join(format!("{}.ll", k.name)),
            &*ir,
        );
    }
    let key = jit.key(&ir);
    let Some(r) = jit.cached(&ir, lower::RUN, &k.name) else {
        let host_ns = llvm::host_time(key);
        return State::Cold {
            ir,
            key,
            host_ns,
            saved_ns: host_ns,
        };
    };
    let r = r.map(|addr| entry(addr, key));
    if log() {
        if let Ok(v) = &r {
            eprintln!(
                "cohort: `{}` has a vector form (from the cache, entry at {:p})",
                k.name, v.run as *const ()
            );
        }
    }
    State::Done(r)
}

fn spawn_build(k: Arc<CompiledKernel>, lanes: u32, ir: Arc<str>, key: u64) {
    // Named, so that a crash report or a profile says which thread LLVM ran on.
    let build_thread = std::thread::Builder::new().name("cohort-llvm".into());
    let spawned = build_thread.spawn(move || {
        let r = build(&k, &ir, key);
        let took = r.as_ref().map_or(std::time::Duration::ZERO, |b| b.1);
        let r = r.map(|b| b.0);
        let c = cache();
        if !took.is_zero() {
            // The estimate follows this machine and library: half old, half new.
            let mut rate = c.ns_per_byte.lock().unwrap_or_else(|e| e.into_inner());
            *rate = 0.5 * *rate + 0.5 * took.as_nanos() as f64 / ir.len().max(1) as f64;
        }
        if log() {
            match &r {
                Ok(v) => eprintln!(
                    "cohort: `{}` has a vector form of {} lanes (compiled in {:.3} s, {} bytes of IR, {:.0} ns per byte; entry at {:p})",
                    k.name,
                    lanes,
                    took.as_secs_f64(),
                    ir.len(),
                    took.as_nanos() as f64 / ir.len().max(1) as f64,
                    v.run as *const ()
                ),
                Err(e) => eprintln!("cohort: `{}` has no vector form: {e}", k.name),
            }
        }
        let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
        kernels.insert((k.id, lanes), State::Done(r));
        c.done.notify_all();
    });
    // As `std::thread::spawn` does: a process that cannot start a thread cannot go on.
    spawned.expect("a thread for LLVM to compile a vector form on");
}

/// Compiles (or links from the cache) `k`'s vector form from its IR, whose cache key is
/// `key`; with LLVM's time.
fn build(
    k: &CompiledKernel,
    ir: &str,
    key: u64,
) -> Result<(SimdKernel, std::time::Duration), String> {
    let jit = llvm::jit().as_ref().map_err(Clone::clone)?;
    let (addr, took) = jit.compile(ir, lower::RUN, &k.name).map_err(|e| {
        // The lowering wrote IR that LLVM refuses: a bug of this backend, not the kernel's.
        format!(
            "{e} (a Cohort CPU backend bug, kernel `{}` at {})",
            k.name, k.location
        )
    })?;
    Ok((entry(addr, key), took))
}

fn entry(addr: usize, key: u64) -> SimdKernel {
    // SAFETY: the entry is defined by `lower::driver` with exactly `RunFn`'s signature.
    let run = unsafe { std::mem::transmute::<usize, RunFn>(addr) };
    SimdKernel { run, key }
}
