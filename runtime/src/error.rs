//! Everything that can go wrong between a kernel call site and the GPU, as one error type.
//! User mistakes (wrong argument count, foreign buffers, too many workgroups) are found on
//! the host before anything is recorded, so they come back as values naming the kernel and
//! the parameter instead of as driver crashes or panics.

use crate::BackendKind;

pub type Result<T> = std::result::Result<T, RuntimeError>;

/// `the devices are 0: A, 1: B`, for an error about a device index.
fn device_list(names: &[String]) -> String {
    if names.is_empty() {
        return "this machine has no usable device".into();
    }
    let list: Vec<String> = names
        .iter()
        .enumerate()
        .map(|(i, n)| format!("{i}: {n}"))
        .collect();
    format!("the devices are {}", list.join(", "))
}

#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    #[error(
        "no Vulkan adapter found for the {} backend: {detail}. Install a Vulkan driver \
         (on Debian: apt-get install mesa-vulkan-drivers)",
        backend.name()
    )]
    NoAdapter {
        backend: BackendKind,
        detail: String,
    },

    #[error(
        "there is no {} device {index}: {}",
        backend.name(),
        device_list(available)
    )]
    NoSuchDevice {
        backend: BackendKind,
        index: usize,
        /// The names of the devices there are, by index.
        available: Vec<String>,
    },

    #[error("could not create a {} device: {detail}", backend.name())]
    DeviceCreation {
        backend: BackendKind,
        detail: String,
    },

    #[error(
        "kernel `{kernel}` takes {expected} buffer argument(s) ({params}) but was given {got}"
    )]
    ArgumentCount {
        kernel: String,
        expected: usize,
        got: usize,
        params: String,
    },

    #[error("kernel `{kernel}`, parameter `{param}`: the buffer belongs to another device")]
    ForeignBuffer { kernel: String, param: String },

    #[error(
        "kernel `{kernel}`: parameters `{first}` and `{second}` are bound to the same buffer \
         and one of them is writable (wgpu forbids this aliasing, so both backends reject it)"
    )]
    AliasedArguments {
        kernel: String,
        first: String,
        second: String,
    },

    #[error("{op}: the buffer belongs to another device")]
    BufferNotOnDevice { op: &'static str },

    #[error(
        "kernel `{kernel}`, parameter `{param}`: binding of {size} bytes exceeds the device \
         limit of {max} bytes for {kind} bindings"
    )]
    BindingTooLarge {
        kernel: String,
        param: String,
        kind: &'static str,
        size: u64,
        max: u64,
    },

    #[error(
        "kernel `{kernel}`: dispatch of {groups:?} workgroups exceeds the device limit of \
         {max:?} workgroups per dimension (use a 2D/3D grid or a grid-stride loop)"
    )]
    TooManyWorkgroups {
        kernel: String,
        groups: [u32; 3],
        max: [u32; 3],
    },

    /// Checked before dispatch: a launch over the limit hung the H100 and was reported by
    /// the software driver's validation layer only afterwards.
    #[error(
        "kernel `{kernel}`: its #[workgroup] arrays take {bytes} bytes per workgroup, more \
         than the device's {max}: use smaller arrays (or fewer per kernel)"
    )]
    WorkgroupMemoryTooLarge {
        kernel: String,
        bytes: u64,
        max: u64,
    },

    #[error(
        "kernel `{kernel}`: workgroup size {size:?} exceeds the device limits (at most \
         {max_size:?} per dimension and {max_invocations} invocations)"
    )]
    WorkgroupTooLarge {
        kernel: String,
        size: [u32; 3],
        max_size: [u32; 3],
        max_invocations: u32,
    },

    #[error(
        "kernel `{kernel}`: indirect arguments at element {offset_elems} need 3 u32 but the \
         buffer holds {len}"
    )]
    IndirectOutOfRange {
        kernel: String,
        offset_elems: usize,
        len: usize,
    },

    #[error("kernel `{kernel}` needs {feature}, which the {} device does not support", backend.name())]
    MissingFeature {
        kernel: String,
        backend: BackendKind,
        feature: &'static str,
    },

    #[error("kernel `{kernel}` requires subgroup size {required} on the {} backend: {detail}", backend.name())]
    SubgroupSize {
        kernel: String,
        backend: BackendKind,
        required: u32,
        detail: String,
    },

    #[error("{location}: kernel `{kernel}`: writing {target} failed: {detail}\n(this is a Cohort compiler bug: the kernel's module was validated, so every target should accept it)")]
    Lowering {
        kernel: String,
        location: String,
        target: &'static str,
        detail: String,
    },

    #[error("kernel `{kernel}` failed to compile on the {} backend: {detail}", backend.name())]
    ShaderCompilation {
        kernel: String,
        backend: BackendKind,
        detail: String,
    },

    #[error("kernel `{kernel}` failed on the {} backend: {detail}", backend.name())]
    Dispatch {
        kernel: String,
        backend: BackendKind,
        detail: String,
    },

    #[error(
        "write of {count} element(s) at element {first} is out of range for a buffer of {len}"
    )]
    WriteOutOfRange {
        first: usize,
        count: usize,
        len: usize,
    },

    #[error(
        "the wgpu backend copies in 4-byte units; {what} of {bytes} bytes is not a multiple of 4"
    )]
    Unaligned { what: &'static str, bytes: u64 },

    #[error("could not allocate a buffer of {bytes} bytes on the {} backend: {detail}", backend.name())]
    Allocation {
        backend: BackendKind,
        bytes: u64,
        detail: String,
    },

    #[error("{call} failed: {result}")]
    Vulkan {
        call: &'static str,
        result: ash::vk::Result,
    },

    #[error("wgpu {context} failed: {detail}")]
    Wgpu {
        context: &'static str,
        detail: String,
    },
}

/// Tags a raw `ash` call result with the call's name so a driver failure says where it happened.
pub(crate) trait VkContext<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, ash::vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| RuntimeError::Vulkan { call, result })
    }
}
