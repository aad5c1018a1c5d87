//! What a compiled kernel promises the code that runs it: its binding layout, the device
//! features it needs and the layout of the records its `print!` calls write. The compiler
//! decides these; every backend of `cohort-runtime` (and the CPU backend's host form)
//! honours them.

use std::sync::Arc;

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

/// Name of the binding through which a printing kernel writes its records; the runtime
/// binds it, launches do not pass it.
///
/// A kernel that prints has this one more binding: an array of `u32` words. Word 0 counts
/// the words reserved so far, word 1 the prints that did not fit; from word 2 on, each
/// print is a record: its site's index, then the site's argument words.
pub const PRINT_BINDING: &str = "__print";

/// Words before the first print record: the reservation cursor and the dropped-print count.
pub const HEADER_WORDS: usize = 2;

/// Turns a record's argument words into the text the site prints (the kernel's own
/// format string applied to the host values, so that it reads as the host's `println!`).
pub type PrintFormat = Arc<dyn Fn(&[u32]) -> String + Send + Sync>;

/// Where a site's text goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrintStream {
    /// `print!`, `println!`
    Stdout,
    /// `eprint!`, `eprintln!`
    Stderr,
}

/// One `print!`-family call in a kernel (or in a helper it calls).
#[derive(Clone)]
pub struct PrintSite {
    /// Argument words each record of this site carries.
    pub words: u32,
    pub stream: PrintStream,
    pub format: PrintFormat,
    /// `file:line:column` of the call, for messages about it.
    pub location: String,
}

impl std::fmt::Debug for PrintSite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PrintSite")
            .field("words", &self.words)
            .field("stream", &self.stream)
            .field("location", &self.location)
            .finish_non_exhaustive()
    }
}
