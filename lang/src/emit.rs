//! Back end: validates a built module, compacts it and writes WGSL and SPIR-V.
//!
//! Data flow: `ir::kernel::build_kernel` → [`compile`] → `KernelArtifact` (runtime).
//! Modules are compacted before writing so that names and ids do not depend on how many
//! throw-away expressions the builder made; that keeps snapshots stable.

use naga::valid::{Capabilities, ValidationFlags, Validator};

use crate::ir::kernel::BuiltKernel;
use crate::spec::Group;
use cohort_runtime::cpu::{GroupLevel, HostKernel};
use cohort_runtime::{KernelArtifact, KernelFeatures};

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

fn capabilities(uses_subgroups: bool) -> Capabilities {
    let mut caps = Capabilities::empty();
    if uses_subgroups {
        caps |= Capabilities::SUBGROUP | Capabilities::SUBGROUP_BARRIER;
    }
    caps
}

fn validate(module: &naga::Module, caps: Capabilities) -> Result<naga::valid::ModuleInfo, String> {
    Validator::new(ValidationFlags::all(), caps)
        .validate(module)
        .map_err(|e| {
            let inner = e.as_inner();
            format!("naga validation failed: {inner}\n{inner:?}")
        })
}

/// Output of the back end for one specialisation.
pub struct Emitted {
    pub module: naga::Module,
    pub wgsl: String,
    pub spirv: Vec<u32>,
    pub entry_point: String,
}

/// Validates, compacts and writes both shader languages.
pub fn emit(built: &BuiltKernel) -> Result<Emitted, CompileError> {
    let err = |stage: &'static str, message: String| CompileError {
        kernel: built.info.name.to_string(),
        spec: built.spec.suffix(),
        file: built.info.file.to_string(),
        line: built.info.line,
        column: built.info.column,
        stage,
        message,
    };
    if !built.unsupported.is_empty() {
        return Err(err("build", built.unsupported.join("; ")));
    }
    let caps = capabilities(built.uses_subgroups);
    let mut module = built.module.clone();
    validate(&module, caps).map_err(|m| err("validate", m))?;
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let info = validate(&module, caps).map_err(|m| err("validate after compact", m))?;
    let wgsl =
        naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
            .map_err(|e| err("write WGSL", e.to_string()))?;
    // The WGSL namer may rename the entry point (a name ending in a digit gets a `_`);
    // use its name for both languages so one `entry_point` serves both backends.
    let entry = wgsl_entry_point(&wgsl).unwrap_or_else(|| built.info.name.to_string());
    module.entry_points[0].name = entry.clone();
    let info = validate(&module, caps).map_err(|m| err("validate after rename", m))?;
    let options = naga::back::spv::Options {
        // Subgroup operations need SPIR-V 1.3; 1.0 would silently declare capabilities
        // that spirv-val rejects.
        lang_version: (1, 3),
        flags: naga::back::spv::WriterFlags::empty(),
        // Workgroup memory is zeroed by the driver (Vulkan 1.3 / the zero-initialize
        // extension, which the runtime enables), as WGSL promises, instead of naga's
        // polyfill: a store of every array by invocation 0 plus a barrier in every
        // kernel, which made a 16 KiB workgroup array cost seconds on lavapipe.
        zero_initialize_workgroup_memory:
            naga::back::spv::ZeroInitializeWorkgroupMemoryMode::Native,
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.clone(),
    };
    let spirv = naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| err("write SPIR-V", e.to_string()))?;
    Ok(Emitted {
        module,
        wgsl,
        spirv,
        entry_point: entry,
    })
}

fn wgsl_entry_point(wgsl: &str) -> Option<String> {
    let at = wgsl.find("@compute")?;
    let rest = &wgsl[at..];
    let f = rest.find("fn ")? + 3;
    let name: String = rest[f..]
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

/// Compiles a built kernel into what the runtime dispatches (without a host form: the CPU
/// backend refuses it; `#[kernel]`'s generated code uses [`compile_with_host`]).
pub fn compile(built: &BuiltKernel, name: String) -> Result<KernelArtifact, CompileError> {
    compile_with_host(built, name, None)
}

/// The kernel's own Rust function as the generated code hands it to the CPU backend.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct HostEntry {
    pub invoke: fn(&cohort_runtime::cpu::LaneArgs<'_>),
    pub workgroup_vars: fn() -> Vec<(usize, usize)>,
}

/// [`compile`], with the host form the CPU backend runs.
pub fn compile_with_host(
    built: &BuiltKernel,
    name: String,
    host: Option<HostEntry>,
) -> Result<KernelArtifact, CompileError> {
    let e = emit(built)?;
    let host = host.map(|h| HostKernel {
        invoke: h.invoke,
        workgroup_vars: h.workgroup_vars,
        group: match built.spec.group {
            Group::Thread => GroupLevel::Thread,
            Group::Warp => GroupLevel::Warp,
            Group::Block(_) => GroupLevel::Block,
            Group::Grid => GroupLevel::Grid,
        },
        synchronises: synchronises(&e.module),
    });
    Ok(KernelArtifact {
        host,
        prints: built.prints.clone(),
        name,
        entry_point: e.entry_point,
        wgsl: e.wgsl,
        spirv: e.spirv,
        workgroup_size: [built.spec.workgroup_size, 1, 1],
        bindings: built.bindings.clone(),
        features: KernelFeatures {
            workgroup_memory_bytes: workgroup_memory_bytes(&e.module),
            subgroups: built.uses_subgroups,
            required_subgroup_size: built.spec.required_subgroup_size,
        },
    })
}

/// Whether invocations of the kernel wait for each other: a barrier or a subgroup
/// operation anywhere in the module (group operations above thread level lower to these).
fn synchronises(module: &naga::Module) -> bool {
    fn block(b: &naga::Block) -> bool {
        use naga::Statement as S;
        b.iter().any(|s| match s {
            S::ControlBarrier(_)
            | S::WorkGroupUniformLoad { .. }
            | S::SubgroupBallot { .. }
            | S::SubgroupCollectiveOperation { .. }
            | S::SubgroupGather { .. } => true,
            S::Block(b) => block(b),
            S::If { accept, reject, .. } => block(accept) || block(reject),
            S::Switch { cases, .. } => cases.iter().any(|c| block(&c.body)),
            S::Loop {
                body, continuing, ..
            } => block(body) || block(continuing),
            _ => false,
        })
    }
    module.functions.iter().any(|(_, f)| block(&f.body))
        || module.entry_points.iter().any(|e| block(&e.function.body))
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
