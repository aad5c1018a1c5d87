//! From a built kernel to what the runtime dispatches: the compiler's target-neutral
//! [`CompiledKernel`] wrapped with the kernel's own Rust function for the CPU backend; and,
//! for snapshot tests and tools, the code each GPU backend would lower it to ([`emit`]).
//!
//! Data flow: `ir::kernel::build_kernel` → `cohort_compiler::compile` → [`KernelArtifact`]
//! (runtime) → each backend lowers the module once per device.

use std::sync::Arc;

pub use cohort_compiler::compile::{CompileError, CompiledKernel};

use crate::ir::kernel::BuiltKernel;
use crate::spec::Group;
use cohort_runtime::cpu::{GroupLevel, HostKernel};
use cohort_runtime::{KernelArtifact, RuntimeError};

/// Compiles a built kernel into what the runtime dispatches, without a host form (the CPU
/// backend refuses it; `#[kernel]`'s generated code uses [`compile_with_host`]).
pub fn compile(built: &BuiltKernel, name: String) -> Result<KernelArtifact, CompileError> {
    compile_with_host(built, name, None)
}

/// The kernel's own Rust function as the generated code hands it to the CPU backend.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct HostEntry {
    pub invoke: cohort_runtime::cpu::Invoke,
    pub workgroup_vars: fn() -> Vec<(usize, usize)>,
    /// `#[kernel(cpu_dispatch = path)]`.
    pub dispatch: Option<cohort_runtime::cpu::DispatchForm>,
}

/// [`compile`], with the host form the CPU backend runs.
pub fn compile_with_host(
    built: &BuiltKernel,
    name: String,
    host: Option<HostEntry>,
) -> Result<KernelArtifact, CompileError> {
    let compiled = cohort_compiler::compile(built, name)?;
    let host = host.map(|h| HostKernel {
        invoke: h.invoke,
        workgroup_vars: h.workgroup_vars,
        dispatch: h.dispatch,
        group: match compiled.spec.group {
            Group::Thread => GroupLevel::Thread,
            Group::Warp => GroupLevel::Warp,
            Group::Block(_) => GroupLevel::Block,
            Group::Grid => GroupLevel::Grid,
        },
        synchronises: compiled.synchronises,
        constants: compiled.spec.constants,
    });
    Ok(KernelArtifact::compiled(Arc::new(compiled), host))
}

/// A compiled kernel and the code the GPU backends lower it to.
pub struct Emitted {
    pub compiled: CompiledKernel,
    /// What the wgpu backend hands wgpu.
    pub wgsl: String,
    /// What the Vulkan backend hands the driver (before its float-controls patch).
    pub spirv: Vec<u32>,
    /// The entry point's name in both.
    pub entry_point: String,
}

/// Compiles a built kernel and lowers it as the wgpu and Vulkan backends do. A lowering
/// failure is reported as the compiler bug it is, at the kernel's definition.
pub fn emit(built: &BuiltKernel) -> Result<Emitted, CompileError> {
    let compiled = cohort_compiler::compile(built, built.info.name.to_string())?;
    let bug = |stage: &'static str, e: RuntimeError| {
        let message = match e {
            RuntimeError::Lowering { detail, .. } => detail,
            other => other.to_string(),
        };
        CompileError::at(built, stage, message)
    };
    let wgsl = cohort_runtime::lower::wgsl(&compiled).map_err(|e| bug("write WGSL", e))?;
    let spirv = cohort_runtime::lower::spirv(&compiled).map_err(|e| bug("write SPIR-V", e))?;
    Ok(Emitted {
        entry_point: wgsl.entry_point,
        wgsl: wgsl.code,
        spirv,
        compiled,
    })
}
