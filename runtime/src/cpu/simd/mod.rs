//! The CPU backend's vector form of a kernel: its naga module lowered to LLVM IR that runs
//! `W` invocations per call in SIMD lanes (`lower`), compiled at run time by a libLLVM
//! found on the machine (`llvm`). Kernels it does not cover, and machines without a
//! libLLVM, keep the host form; where a kernel has both, `choice` picks one.
//! `COHORT_CPU_SIMD_LOG=1` says which form each kernel runs and why.

mod choice;
mod expr;
mod llvm;
mod lower;
mod memory;
mod types;

use std::collections::HashMap;
use std::sync::{Arc, Condvar, Mutex, OnceLock};

use cohort_compiler::CompiledKernel;

pub use choice::{Chooser, Forms};
pub use types::W as LANES;

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

/// The LLVM IR of a kernel's vector form, or what in it the vector form does not cover.
pub fn lower_to_llvm_ir(k: &CompiledKernel) -> Result<String, String> {
    lower::lower(k, lower::RUN)
}

/// Invocations a kernel runs in its host form before its vector form is compiled (about a
/// tenth of a second of work on one core): short runs, such as tests and thumbnails, never
/// wait for LLVM; anything longer compiles once per machine (objects are cached on disk)
/// and loads the object from then on.
pub const HOT_INVOCATIONS: u64 = 1 << 20;

/// A kernel's vector form: not compiled (with the invocations its host form has run),
/// being compiled, or compiled (or refused, with the reason).
enum State {
    Cold(u64),
    Pending,
    Done(Result<SimdKernel, String>),
}

struct Cache {
    kernels: Mutex<HashMap<u64, State>>,
    done: Condvar,
}

fn cache() -> &'static Cache {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    CACHE.get_or_init(|| Cache {
        kernels: Mutex::new(HashMap::new()),
        done: Condvar::new(),
    })
}

/// The vector form of `k` for a dispatch of `invocations`, or `None` where it has none
/// yet. The first call links it if its object file is cached. Otherwise it is compiled,
/// on a thread of its own, once the kernel has run `HOT_INVOCATIONS` (at once with
/// `wait`); until then `wait: false` returns `None` (the backend runs the host form, so
/// that LLVM's time never delays a dispatch) and `wait: true` waits for it.
pub fn compiled(k: &Arc<CompiledKernel>, wait: bool, invocations: u64) -> Option<SimdKernel> {
    let c = cache();
    let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
    if !kernels.contains_key(&k.id) {
        drop(kernels);
        let first = match probe(k) {
            Some(r) => State::Done(r),
            None => State::Cold(0),
        };
        kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
        kernels.entry(k.id).or_insert(first);
    }
    if let Some(State::Cold(n)) = kernels.get_mut(&k.id) {
        *n += invocations;
        if wait || *n >= HOT_INVOCATIONS {
            kernels.insert(k.id, State::Pending);
            spawn_build(Arc::clone(k));
        }
    }
    loop {
        match kernels.get(&k.id) {
            Some(State::Done(r)) => return r.as_ref().ok().copied(),
            _ if !wait => return None,
            _ => kernels = c.done.wait(kernels).unwrap_or_else(|e| e.into_inner()),
        }
    }
}

/// The vector form of `k` without compiling: linked from the object cache, or refused
/// (no libLLVM, or a construct the lowering does not cover); `None`: it must be compiled.
fn probe(k: &CompiledKernel) -> Option<Result<SimdKernel, String>> {
    let jit = match llvm::jit() {
        Ok(j) => j,
        Err(e) => return Some(Err(e.clone())),
    };
    let ir = match lower::lower(k, lower::RUN) {
        Ok(ir) => ir,
        Err(e) => return Some(Err(e)),
    };
    let r = jit.cached(&ir, lower::RUN)?.map(entry);
    if log() {
        if let Ok(v) = &r {
            eprintln!(
                "cohort: `{}` has a vector form (from the cache, entry at {:p})",
                k.name, v.run as *const ()
            );
        }
    }
    Some(r)
}

fn spawn_build(k: Arc<CompiledKernel>) {
    std::thread::spawn(move || {
        let start = std::time::Instant::now();
        let r = build(&k);
        if log() {
            match &r {
                Ok(v) => eprintln!(
                    "cohort: `{}` has a vector form (compiled in {:.3} s, entry at {:p})",
                    k.name,
                    start.elapsed().as_secs_f64(),
                    v.run as *const ()
                ),
                Err(e) => eprintln!("cohort: `{}` has no vector form: {e}", k.name),
            }
        }
        let c = cache();
        let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
        kernels.insert(k.id, State::Done(r));
        c.done.notify_all();
    });
}

fn build(k: &CompiledKernel) -> Result<SimdKernel, String> {
    let jit = llvm::jit().as_ref().map_err(Clone::clone)?;
    let ir = lower::lower(k, lower::RUN)?;
    let addr = jit.compile(&ir, lower::RUN).map_err(|e| {
        // The lowering wrote IR that LLVM refuses: a bug of this backend, not the kernel's.
        format!(
            "{e} (a Cohort CPU backend bug, kernel `{}` at {})",
            k.name, k.location
        )
    })?;
    Ok(entry(addr))
}

fn entry(addr: usize) -> SimdKernel {
    // SAFETY: the entry is defined by `lower::driver` with exactly `RunFn`'s signature.
    let run = unsafe { std::mem::transmute::<usize, RunFn>(addr) };
    SimdKernel { run }
}
