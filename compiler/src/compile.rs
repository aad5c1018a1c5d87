//! The compiler's last stage: validates a built module, compacts it and describes what
//! running it needs. The result, a [`CompiledKernel`], is target-neutral: each backend of
//! `cohort-runtime` lowers its naga module itself (SPIR-V for Vulkan, WGSL for wgpu; the
//! CPU backend runs the kernel's Rust function and reads only the facts recorded here).
//!
//! Data flow: `ir::kernel::build_kernel` → [`compile`] → `CompiledKernel` → a backend.
//! Modules are compacted so that names and ids do not depend on how many throw-away
//! expressions the builder made; that keeps the lowered code, and its snapshots, stable.

use std::sync::atomic::{AtomicU64, Ordering};

use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};

use crate::abi::{Binding, KernelFeatures, PrintSite};
use crate::ir::kernel::BuiltKernel;
use crate::spec::Spec;

/// A kernel that could not be compiled. Type-correct kernel source should never produce
/// one in a later stage than `build`: that is a compiler bug, reported at the kernel's
/// definition. At stage `build` the kernel asked for something its specialisation cannot
/// lower (e.g. `group_any` at grid level).
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}:{column}: kernel `{kernel}` ({spec}): {stage}: {message}{}", if *stage == "build" { "" } else { "\n(this is a Cohort compiler bug: the kernel type-checked, so its IR should be valid)" })]
pub struct CompileError {
    pub kernel: String,
    pub spec: String,
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub stage: &'static str,
    pub message: String,
}

impl CompileError {
    /// A failure at `stage` of compiling `built`, reported at the kernel's definition.
    pub fn at(built: &BuiltKernel, stage: &'static str, message: String) -> Self {
        CompileError {
            kernel: built.info.name.to_string(),
            spec: built.spec.suffix(),
            file: built.info.file.to_string(),
            line: built.info.line,
            column: built.info.column,
            stage,
            message,
        }
    }
}

/// One kernel specialisation, validated and compacted, as every backend receives it.
#[derive(Debug)]
pub struct CompiledKernel {
    /// Unique name of the specialisation (kernel name plus specialisation suffix).
    pub name: String,
    /// Distinguishes this compilation from every other one in the process: backends key
    /// their pipelines by (`name`, `id`), so two compilations that share a name never
    /// alias, and one compilation is lowered once per device.
    pub id: u64,
    /// The module, with one compute entry point.
    pub module: naga::Module,
    /// naga's validation result for `module`, which its writers need.
    pub info: ModuleInfo,
    /// The entry point's name in `module`.
    pub entry_point: String,
    pub workgroup_size: [u32; 3],
    pub bindings: Vec<Binding>,
    pub features: KernelFeatures,
    /// The kernel's `print!`-family calls, indexed by the site number its records carry.
    pub prints: Vec<PrintSite>,
    /// Whether invocations wait for each other on the CPU backend: a barrier, a subgroup
    /// operation or `group_any` above thread level (`group_share` is not one there: each
    /// invocation computes its group's value, see `ir::builder::Ctx::synchronises`).
    pub synchronises: bool,
    /// Where the kernel is defined, for messages about it (a lowering failure is a
    /// compiler bug reported there).
    pub location: String,
    pub spec: Spec,
    /// The kernel's `loops = finite` promise ([`crate::KernelInfo::finite_loops`]): the
    /// backends may lower its loops without naga's loop-bound counters.
    pub finite_loops: bool,
}

fn capabilities(uses_subgroups: bool) -> Capabilities {
    let mut caps = Capabilities::empty();
    if uses_subgroups {
        caps |= Capabilities::SUBGROUP | Capabilities::SUBGROUP_BARRIER;
    }
    caps
}

fn validate(module: &naga::Module, caps: Capabilities) -> Result<ModuleInfo, String> {
    Validator::new(ValidationFlags::all(), caps)
        .validate(module)
        .map_err(|e| {
            let inner = e.as_inner();
            format!("naga validation failed: {inner}\n{inner:?}")
        })
}

/// The entry point's name: the kernel's, with a `_` after a trailing digit, the one change
/// naga's WGSL namer makes to a kernel name, so that the name is the same in every target
/// language (a backend whose writer renames it further reads the name back).
fn entry_point_name(kernel: &str) -> String {
    if kernel.ends_with(|c: char| c.is_ascii_digit()) {
        format!("{kernel}_")
    } else {
        kernel.to_string()
    }
}

/// Validates and compacts a built kernel.
pub fn compile(built: &BuiltKernel, name: String) -> Result<CompiledKernel, CompileError> {
    let err = |stage: &'static str, message: String| CompileError::at(built, stage, message);
    if !built.unsupported.is_empty() {
        return Err(err("build", built.unsupported.join("; ")));
    }
    let caps = capabilities(built.uses_subgroups);
    let mut module = built.module.clone();
    validate(&module, caps).map_err(|m| err("validate", m))?;
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let entry_point = entry_point_name(built.info.name);
    module.entry_points[0].name = entry_point.clone();
    let info = validate(&module, caps).map_err(|m| err("validate after compact", m))?;
    static NEXT_ID: AtomicU64 = AtomicU64::new(0);
    Ok(CompiledKernel {
        name,
        id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        workgroup_size: [built.spec.workgroup_size, 1, 1],
        bindings: built.bindings.clone(),
        features: KernelFeatures {
            workgroup_memory_bytes: workgroup_memory_bytes(&module),
            subgroups: built.uses_subgroups,
            required_subgroup_size: built.spec.required_subgroup_size,
        },
        prints: built.prints.clone(),
        synchronises: built.synchronises,
        location: format!(
            "{}:{}:{}",
            built.info.file, built.info.line, built.info.column
        ),
        spec: built.spec,
        finite_loops: built.info.finite_loops,
        entry_point,
        module,
        info,
    })
}

/// Bytes of the module's workgroup variables (naga's layout: each variable aligned).
fn workgroup_memory_bytes(module: &naga::Module) -> u64 {
    let mut layouter = naga::proc::Layouter::default();
    if layouter.update(module.to_ctx()).is_err() {
        return 0;
    }
    let mut bytes = 0u64;
    for (_, v) in module.global_variables.iter() {
        if v.space == naga::AddressSpace::WorkGroup {
            let l = &layouter[v.ty];
            bytes = bytes.next_multiple_of(l.alignment.round_up(1) as u64) + l.size as u64;
        }
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::entry_point_name;

    #[test]
    fn entry_points_end_as_the_wgsl_namer_ends_them() {
        assert_eq!(entry_point_name("traverse8"), "traverse8_");
        assert_eq!(entry_point_name("extend"), "extend");
    }
}
