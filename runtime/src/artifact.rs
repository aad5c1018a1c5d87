//! What a backend is handed to run: a compiled kernel (the `cohort-compiler` crate's
//! target-neutral naga module, which each backend lowers itself: `lower`), or code written
//! for the GPU backends by hand; plus the binding layout, the kernel's needs and, for the
//! CPU backend, the kernel's own Rust function.

use std::sync::Arc;

pub use cohort_compiler::abi::{Binding, BindingKind, KernelFeatures};
pub use cohort_compiler::CompiledKernel;

/// A kernel's code, as its backends receive it.
#[derive(Clone, Debug)]
pub enum KernelCode {
    /// A compiled Cohort kernel: each backend lowers the module (SPIR-V for Vulkan, WGSL
    /// for wgpu) once per device.
    Compiled(Arc<CompiledKernel>),
    /// Shader code written by hand, one text per GPU backend (tests of the runtime, and
    /// kernels from elsewhere); the CPU backend cannot run it.
    Shaders {
        wgsl: String,
        spirv: Vec<u32>,
        entry_point: String,
    },
}

/// One kernel specialisation, ready to dispatch.
#[derive(Clone, Debug)]
pub struct KernelArtifact {
    /// Unique name of the specialisation (kernel name plus specialisation suffix); the
    /// pipeline caches are keyed by it together with the code's identity.
    pub name: String,
    pub code: KernelCode,
    pub workgroup_size: [u32; 3],
    pub bindings: Vec<Binding>,
    pub features: KernelFeatures,
    /// The kernel's own Rust function for the native CPU backend (`None` for kernels
    /// without one, which the CPU backend refuses).
    pub host: Option<crate::cpu::HostKernel>,
    /// The kernel's `print!`-family calls, indexed by the site number its records carry
    /// (empty for a kernel that does not print: it has no print binding).
    pub prints: Vec<crate::print::PrintSite>,
}

impl KernelArtifact {
    /// The artifact of a compiled kernel, with its host form when it has one.
    pub fn compiled(kernel: Arc<CompiledKernel>, host: Option<crate::cpu::HostKernel>) -> Self {
        KernelArtifact {
            name: kernel.name.clone(),
            workgroup_size: kernel.workgroup_size,
            bindings: kernel.bindings.clone(),
            features: kernel.features,
            prints: kernel.prints.clone(),
            host,
            code: KernelCode::Compiled(kernel),
        }
    }
}
