//! What a compiled kernel hands to a backend: shader code for each backend plus the
//! binding layout. Produced by the `cohort` language crate (front end → naga IR → emit),
//! consumed by `Device::dispatch`. Backends never see naga IR or syn types, only this (the
//! CPU backend runs `host`, the kernel's Rust function compiled with the program).

/// How a kernel parameter is bound. Every binding lives in bind group / descriptor set 0,
/// at the binding index given by `Binding::binding`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    /// `var<storage, read>`
    StorageRead,
    /// `var<storage, read_write>` (also used for atomics)
    StorageReadWrite,
    /// `var<uniform>`
    Uniform,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Binding {
    pub binding: u32,
    pub kind: BindingKind,
    /// Parameter name in the kernel source, for error messages.
    pub name: String,
}

/// Device features a kernel needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelFeatures {
    /// Uses subgroup operations.
    pub subgroups: bool,
    /// Needs the subgroup to be exactly this wide (Vulkan: requiredSubgroupSize).
    pub required_subgroup_size: Option<u32>,
    /// Bytes of workgroup memory (`#[workgroup]` arrays) one workgroup uses; a launch
    /// checks it against the device's limit.
    pub workgroup_memory_bytes: u64,
}

/// One compiled kernel specialisation.
#[derive(Clone, Debug)]
pub struct KernelArtifact {
    /// Unique name of the specialisation (kernel name plus specialisation suffix); the
    /// pipeline caches are keyed by it together with a hash of the code.
    pub name: String,
    pub entry_point: String,
    pub wgsl: String,
    pub spirv: Vec<u32>,
    pub workgroup_size: [u32; 3],
    pub bindings: Vec<Binding>,
    pub features: KernelFeatures,
    /// The kernel's own Rust function for the native CPU backend (`None` for kernels
    /// given only as WGSL / SPIR-V, which the CPU backend refuses).
    pub host: Option<crate::cpu::HostKernel>,
    /// The kernel's `print!`-family calls, indexed by the site number its records carry
    /// (empty for a kernel that does not print: it has no print binding).
    pub prints: Vec<crate::print::PrintSite>,
}
