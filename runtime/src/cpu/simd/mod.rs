//! The CPU backend's vector form of a kernel: its naga module lowered to LLVM IR that runs
//! `W` invocations per call in SIMD lanes (`lower`), compiled at run time by a libLLVM
//! found on the machine (`llvm`). Kernels it does not cover, and machines without a
//! libLLVM, keep the host form; `COHORT_CPU_SIMD=0` keeps it everywhere.

mod expr;
mod llvm;
mod lower;
mod memory;
mod types;

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use cohort_compiler::CompiledKernel;

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

/// Whether the vector form is wanted (`COHORT_CPU_SIMD=0` turns it off).
pub fn enabled() -> bool {
    static ON: OnceLock<bool> = OnceLock::new();
    *ON.get_or_init(|| std::env::var("COHORT_CPU_SIMD").map_or(true, |v| v != "0"))
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

type Cache = Mutex<HashMap<u64, Result<SimdKernel, String>>>;

/// The vector form of `k`, compiled once per process (keyed by the compilation's id), or
/// why it has none.
pub fn compile(k: &CompiledKernel) -> Result<SimdKernel, String> {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(r) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&k.id) {
        return r.clone();
    }
    let start = std::time::Instant::now();
    let r = build(k);
    if std::env::var("COHORT_CPU_SIMD").is_ok_and(|v| v == "verbose") {
        match &r {
            Ok(_) => eprintln!(
                "cohort: `{}` runs in vector form (compiled in {:.3} s)",
                k.name,
                start.elapsed().as_secs_f64()
            ),
            Err(e) => eprintln!("cohort: `{}` runs its host form: {e}", k.name),
        }
    }
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(k.id, r.clone());
    r
}

fn build(k: &CompiledKernel) -> Result<SimdKernel, String> {
    let jit = llvm::jit().as_ref().map_err(Clone::clone)?;
    let mut jit = jit.lock().unwrap_or_else(|e| e.into_inner());
    let symbol = jit.fresh_symbol();
    let ir = lower::lower(k, &symbol)?;
    let addr = jit.compile(&ir, &symbol).map_err(|e| {
        // The lowering wrote IR that LLVM refuses: a bug of this backend, not the kernel's.
        format!(
            "{e} (a Cohort CPU backend bug, kernel `{}` at {})",
            k.name, k.location
        )
    })?;
    // SAFETY: `symbol` is defined by `lower::driver` with exactly `RunFn`'s signature.
    let run = unsafe { std::mem::transmute::<usize, RunFn>(addr) };
    Ok(SimdKernel { run })
}

/// Shared handle for commands.
pub type Shared = Arc<SimdKernel>;
