//! `cohort-runtime`: runs compiled Cohort kernels.
//!
//! Data flow: the `cohort-compiler` crate compiles a kernel into a target-neutral
//! [`CompiledKernel`] (a validated naga module, its binding layout and needs); the `cohort`
//! crate wraps it, with the kernel's Rust function, in a [`KernelArtifact`]. A [`Device`]
//! (one of three backends: wgpu, which lowers the module to WGSL; raw Vulkan through `ash`,
//! which lowers it to SPIR-V; or the native CPU backend, which runs the Rust function on
//! every core) owns [`GpuBuffer`]s and turns `dispatch(kernel, args, groups)` into a
//! pipeline (lowered and compiled once per device), a bind group / descriptor set and one
//! queue submission, optionally timed with GPU timestamps ([`DispatchStats`]).
//!
//! Module map: `artifact` (what a backend is handed), `backend` (the trait every backend
//! implements, and the type-erased buffer handle), `device` (the public facade,
//! argument checks, batches), `buffer` (typed buffers and size rules), `wgpu_backend`,
//! `vulkan_init` (opening a raw Vulkan device) and `vulkan_backend` (buffers, pipelines,
//! submission on it), `cpu_backend` and `cpu` (the CPU backend and its lanes),
//! `pipeline_cache` (lower and compile once per device), `timing` (timestamp ticks →
//! nanoseconds), `print` (kernels' print buffers, decoded after a dispatch), `error`.

pub mod artifact;
mod backend;
mod buffer;
pub mod cpu;
mod cpu_backend;
#[doc(hidden)]
pub mod crash_report;
mod device;
mod disk_cache;
mod error;
mod exit_hook;
mod float_controls;
mod hash;
mod pipeline_cache;
pub mod print;
mod spirv_locals;
mod timing;
mod vulkan_backend;
mod vulkan_init;
mod wgpu_backend;

pub use artifact::*;

/// Each GPU backend's lowering of a compiled kernel, as its pipelines use it (also for
/// snapshot tests of the generated code).
pub mod lower {
    pub use crate::vulkan_backend::lower as spirv;
    pub use crate::wgpu_backend::{lower as wgsl, Wgsl};
}
pub use buffer::{BufferArg, GpuBuffer};
pub use device::{
    Batch, Completed, Device, DeviceInfo, Dispatch, DispatchStats, ReadBack, Submission,
};
pub use disk_cache::cache_dir;
pub use error::{Result, RuntimeError};
pub use hash::hash64;

/// What a program calls as it ends (the `cohort` CLI does): waits, at most 5 s, for a
/// CPU vector form that LLVM is compiling in the background, and starts no other (kernels
/// then keep their host forms). A program that returns from `main` does the same as its
/// main thread exits, before exit destroys LLVM's static objects; one that ends with
/// `std::process::exit` on another thread waits in an `atexit` handler, after the
/// destruction of any static object that the compile in flight was first to create.
/// Called before exit, nothing is destroyed yet. Call it once, at the end.
pub fn stop_background_compiles() {
    cpu::simd::stop_compiles("as the program ends");
}

/// Which GPU API a [`Device`] drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BackendKind {
    /// wgpu (Vulkan backend only), lowering kernels to WGSL.
    Wgpu,
    /// Raw Vulkan through `ash`, lowering kernels to SPIR-V.
    Vulkan,
    /// The native CPU backend, running `KernelArtifact::host` on every core.
    Cpu,
}

impl BackendKind {
    /// Parses a backend name as given on command lines or in environment variables.
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "wgpu" => Some(BackendKind::Wgpu),
            "vulkan" | "ash" => Some(BackendKind::Vulkan),
            "cpu" => Some(BackendKind::Cpu),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            BackendKind::Wgpu => "wgpu",
            BackendKind::Vulkan => "vulkan",
            BackendKind::Cpu => "cpu",
        }
    }
}

impl std::fmt::Display for BackendKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
