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
        Ok(j) => Ok(j
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .library()
            .to_string()),
        Err(e) => Err(e.clone()),
    }
}

/// The LLVM IR of a kernel's vector form, or what in it the vector form does not cover.
pub fn lower_to_llvm_ir(k: &CompiledKernel) -> Result<String, String> {
    lower::lower(k, lower::RUN)
}

/// A kernel's vector form: being compiled, or compiled (or refused, with the reason).
enum State {
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

/// The vector form of `k` (compiled once per process, keyed by the compilation's id), or
/// `None` where it has none. The first call starts compiling it on a thread of its own;
/// until that is done, `wait: false` returns `None` at once (the backend runs the host
/// form meanwhile, so that LLVM's time does not delay the first dispatch) and
/// `wait: true` waits for it.
pub fn compiled(k: &Arc<CompiledKernel>, wait: bool) -> Option<SimdKernel> {
    let c = cache();
    let mut kernels = c.kernels.lock().unwrap_or_else(|e| e.into_inner());
    if let std::collections::hash_map::Entry::Vacant(e) = kernels.entry(k.id) {
        e.insert(State::Pending);
        let k = Arc::clone(k);
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
    loop {
        match kernels.get(&k.id) {
            Some(State::Done(r)) => return r.as_ref().ok().copied(),
            _ if !wait => return None,
            _ => kernels = c.done.wait(kernels).unwrap_or_else(|e| e.into_inner()),
        }
    }
}

fn build(k: &CompiledKernel) -> Result<SimdKernel, String> {
    let jit = llvm::jit().as_ref().map_err(Clone::clone)?;
    let ir = lower::lower(k, lower::RUN)?;
    let mut jit = jit.lock().unwrap_or_else(|e| e.into_inner());
    let addr = jit.compile(&ir, lower::RUN).map_err(|e| {
        // The lowering wrote IR that LLVM refuses: a bug of this backend, not the kernel's.
        format!(
            "{e} (a Cohort CPU backend bug, kernel `{}` at {})",
            k.name, k.location
        )
    })?;
    // SAFETY: the entry is defined by `lower::driver` with exactly `RunFn`'s signature.
    let run = unsafe { std::mem::transmute::<usize, RunFn>(addr) };
    Ok(SimdKernel { run })
}
