//! `cohort-runtime`: runs compiled Cohort kernels on a GPU.
//!
//! Data flow: the `cohort` language crate compiles a kernel into a [`KernelArtifact`]
//! (WGSL + SPIR-V + binding layout + the host function). A [`Device`] (one of three
//! backends: wgpu consuming the WGSL, raw Vulkan through `ash` consuming the SPIR-V, or the
//! native CPU backend running the host function on every core) owns [`GpuBuffer`]s and turns
//! `dispatch(kernel, args, groups)` into a cached pipeline, a bind group / descriptor set
//! and one queue submission, optionally timed with GPU timestamps ([`DispatchStats`]).
//!
//! Module map: `artifact` (what the compiler hands over), `device` (the public facade,
//! argument checks, batches), `buffer` (typed buffers and size rules), `wgpu_backend`,
//! `vulkan_init` (opening a raw Vulkan device) and `vulkan_backend` (buffers, pipelines,
//! submission on it), `cpu_backend` and `cpu` (the CPU backend and its lanes), `pipeline_cache` (compile once per device),
//! `timing` (timestamp ticks → nanoseconds), `print` (kernels' print buffers, decoded after
//! a dispatch), `error`.

pub mod artifact;
mod buffer;
pub mod cpu;
mod cpu_backend;
mod device;
mod disk_cache;
mod error;
mod float_controls;
mod pipeline_cache;
pub mod print;
mod timing;
mod vulkan_backend;
mod vulkan_init;
mod wgpu_backend;

pub use artifact::*;
pub use buffer::{BufferArg, GpuBuffer};
pub use device::{
    Batch, Completed, Device, DeviceInfo, Dispatch, DispatchStats, ReadBack, Submission,
};
pub use error::{Result, RuntimeError};

/// Which GPU API a [`Device`] drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BackendKind {
    /// wgpu (Vulkan backend only), consuming `KernelArtifact::wgsl`.
    Wgpu,
    /// Raw Vulkan through `ash`, consuming `KernelArtifact::spirv`.
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
