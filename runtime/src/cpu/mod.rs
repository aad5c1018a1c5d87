//! The native CPU backend's side of a kernel: what the code `#[kernel]` generates hands to
//! it ([`HostKernel`], [`LaneArgs`]) and what the host forms of the group intrinsics call
//! while the backend runs them ([`exchange`], [`lane`]).
//!
//! The backend runs each kernel's plain Rust function, compiled natively. Workgroups run in
//! parallel on every core. Within a workgroup, a kernel that synchronises (barriers,
//! subgroup operations, `group_any` above thread level) runs each
//! invocation as a coroutine on its own stack: an invocation that reaches a sync point
//! posts its value and parks, and `lanes` releases the invocations that belong together
//! once all of them have arrived (the work-item loop of CPU OpenCL compilers, with the
//! split at barriers done by stack switching instead of by rewriting the code). Kernels
//! that never synchronise run their invocations as a plain loop.
//!
//! Everything here except [`exchange`], [`lane`] and their types is called only by
//! generated code.

mod lanes;
mod share;
pub mod simd;

pub use lanes::{exchange, group_value, lane, Lane, Lanes, Scope, View};
pub(crate) use lanes::{run_workgroup, Launch, Scratch};

/// The subgroup width the CPU backend gives kernels (the width of an NVIDIA warp, so that
/// `group = Warp` kernels see the same groups as on the GPUs they were tuned for).
pub const SUBGROUP_WIDTH: u32 = 32;

/// A kernel's coherence-group level as the CPU backend needs it (`cohort::Group` without
/// the block size, which is the workgroup size).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GroupLevel {
    Thread,
    Warp,
    Block,
    Grid,
}

/// What the CPU backend runs for one kernel specialisation.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct HostKernel {
    /// Runs invocations: the kernel's own function with the buffers and workgroup memory
    /// of `LaneArgs`, bound once, for each lane of `Lanes`.
    pub invoke: Invoke,
    /// Size and alignment of each `#[workgroup]` parameter, in parameter order.
    pub workgroup_vars: fn() -> Vec<(usize, usize)>,
    pub group: GroupLevel,
    /// Whether invocations wait for each other (barriers, subgroup operations,
    /// `group_any` above thread level): if not, the backend runs them one after another
    /// without coroutines. `group_share` does not wait: each invocation computes its
    /// group's value.
    pub synchronises: bool,
    /// The values of the kernel's `#[specialize]` parameters (`Spec::constants`).
    pub constants: [u32; cohort_compiler::spec::MAX_CONSTANTS],
    /// The kernel's whole-dispatch form (`#[kernel(cpu_dispatch = path)]`), if it has one.
    pub dispatch: Option<DispatchForm>,
}

/// A kernel's whole-dispatch form: runs all `invocations` of one dispatch at once, with
/// the same effect as running each of them (the buffers of [`LaneArgs`], no workgroup
/// memory), and may spread the work over the cores itself. It returns `false`, having
/// done nothing, where it cannot run (say, a CPU without the instructions it needs): the
/// backend then runs the kernel's other forms. Where a kernel has one, the backend runs it
/// unless `COHORT_CPU_SIMD` names another form. For work whose invocations gain from being
/// done together: the renderer's traversals trace their rays as one stream
/// (`cohort_kernels::traverse_stream`).
pub type DispatchForm = fn(&LaneArgs<'_>, u64) -> bool;

/// The builtin values of one invocation (docs/LANGUAGE.md, section 9).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, Default)]
pub struct Builtins {
    pub global_index: u32,
    pub local_index: u32,
    pub workgroup_index: u32,
    pub global_id: [u32; 3],
    pub local_id: [u32; 3],
    pub workgroup_id: [u32; 3],
    pub num_workgroups: [u32; 3],
    pub workgroup_size: u32,
    pub subgroup_size: u32,
    pub subgroup_lane: u32,
    pub subgroup_id: u32,
    pub num_subgroups: u32,
}

/// One bound buffer: its memory and its logical size.
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct HostBuf {
    pub(crate) ptr: *mut u8,
    pub(crate) bytes: usize,
}
// The backend hands buffers to invocations on several threads; what they do with them is
// what kernels do with GPU memory (docs/LANGUAGE.md, section 13).
unsafe impl Send for HostBuf {}
unsafe impl Sync for HostBuf {}

/// A kernel's host form as the CPU backend calls it: the invocations `Lanes` names, in
/// order, with the dispatch's buffers and the workgroup's memory.
#[doc(hidden)]
pub type Invoke = fn(&LaneArgs<'_>, &Lanes<'_>);

/// What invocations are called with. The buffers are the kernel's storage and uniform
/// parameters in parameter order (not the generated `__lengths` or `group_share` bindings).
#[doc(hidden)]
pub struct LaneArgs<'a> {
    pub(crate) bufs: &'a [HostBuf],
    pub(crate) workgroup: &'a [*mut u8],
    pub(crate) constants: &'a [u32],
}

impl<'a> LaneArgs<'a> {
    /// The raw value of the kernel's `k`-th `#[specialize]` parameter.
    pub fn constant(&self, k: usize) -> u32 {
        self.constants[k]
    }

    fn buf<T>(&self, i: usize) -> HostBuf {
        let b = self.bufs[i];
        assert!(
            (b.ptr as usize) % std::mem::align_of::<T>() == 0,
            "cohort CPU backend: buffer {i} is not aligned for its element type"
        );
        b
    }

    /// A read-only (or atomic) storage parameter.
    ///
    /// # Safety
    /// Buffer `i` must hold `T`s (as the launch functions guarantee).
    pub unsafe fn storage<T>(&self, i: usize) -> &'a [T] {
        let b = self.buf::<T>(i);
        std::slice::from_raw_parts(b.ptr as *const T, b.bytes / std::mem::size_of::<T>())
    }

    /// A writable storage parameter, as a raw slice: the invocations of a dispatch write
    /// the same buffer at once, so none of them may hold it as a `&mut` across a sync point.
    ///
    /// # Safety
    /// As for [`storage`](Self::storage).
    pub unsafe fn storage_mut<T>(&self, i: usize) -> *mut [T] {
        let b = self.buf::<T>(i);
        std::ptr::slice_from_raw_parts_mut(b.ptr as *mut T, b.bytes / std::mem::size_of::<T>())
    }

    /// A uniform parameter.
    ///
    /// # Safety
    /// As for [`storage`](Self::storage).
    pub unsafe fn uniform<T>(&self, i: usize) -> &'a T {
        &*(self.buf::<T>(i).ptr as *const T)
    }

    /// The workgroup's `w`-th `#[workgroup]` parameter.
    ///
    /// # Safety
    /// `T` must be that parameter's type.
    pub unsafe fn workgroup<T>(&self, w: usize) -> *mut T {
        self.workgroup[w] as *mut T
    }
}
