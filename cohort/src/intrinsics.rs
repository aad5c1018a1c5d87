//! Functions kernels call that have no plain-Rust equivalent: barriers, subgroup
//! operations, atomics helpers and `group_share`.
//!
//! Each is a pair, like a user's `#[kernel_fn]`: a host function with the meaning it has
//! when the kernel runs on the host, and a module of the same name whose `ir` function
//! builds the GPU version. On the native CPU backend the host functions wait for the other
//! invocations of their subgroup or workgroup (`cohort::runtime::cpu::exchange`), so they
//! mean what they mean on a GPU; a kernel called directly on the host runs alone (a
//! subgroup of one lane). Each host function is `#[track_caller]`: the CPU backend tells
//! sync points apart by their call site (`runtime/src/cpu/lanes.rs`). The
//! front end rewrites a call `f(args)` into `f::ir(args)`, so both are found through the
//! same `use`.

use glam::UVec4;
use std::sync::atomic::{AtomicU32, Ordering};

use crate::host::SubgroupArith;
use crate::ir::{intrinsics as lower, GpuType, Place, Val};
use cohort_runtime::cpu::{self, GroupLevel, Scope};
use naga::{CollectiveOperation as Co, SubgroupOperation as So};

/// Waits until every invocation of the workgroup has arrived.
#[doc(alias = "OpControlBarrier")]
#[track_caller]
pub fn workgroup_barrier() {
    cpu::exchange::<(), ()>(Scope::Workgroup, None, |_| ());
}
pub mod workgroup_barrier {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir() {
        super::lower::workgroup_barrier()
    }
}

/// Makes storage-buffer writes of the workgroup visible to the workgroup.
#[doc(alias = "OpControlBarrier")]
#[track_caller]
pub fn storage_barrier() {
    cpu::exchange::<(), ()>(Scope::Workgroup, None, |_| ());
}
pub mod storage_barrier {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir() {
        super::lower::storage_barrier()
    }
}

/// Waits until every active invocation of the subgroup has arrived.
#[doc(alias = "OpControlBarrier")]
#[track_caller]
pub fn subgroup_barrier() {
    cpu::exchange::<(), ()>(Scope::Subgroup, None, |_| ());
}
pub mod subgroup_barrier {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir() {
        super::lower::subgroup_barrier()
    }
}

/// A value whose contents are unspecified until written: the initial value of a
/// `let mut` with a type, e.g. a traversal stack
/// `let mut stack: [u32; 64] = uninit();`, where `[0u32; 64]` would store 64 zeros per
/// invocation that are never read. An element read before it is written has an
/// unspecified value of its type (on the Vulkan backend whatever the variable's memory
/// held; zero on wgpu, whose WGSL zero-fills every variable, and here on the host and the
/// CPU backend), never undefined behaviour. docs/LANGUAGE.md, "Uninitialised locals".
pub fn uninit<T: bytemuck::Zeroable>() -> T {
    T::zeroed()
}
#[doc(hidden)]
pub mod uninit {
    /// Whether a call must be reached by every invocation of its group (docs/LANGUAGE.md
    /// section 11): no.
    pub const NEEDS_UNIFORM: bool = false;
    /// The front end lowers `let mut x: T = uninit();` to a variable without a store and
    /// refuses `uninit()` anywhere else, so this is never reached.
    pub fn ir<T: super::GpuType>() -> super::Val<T> {
        unreachable!("`uninit()` is lowered by the kernel front end")
    }
}

/// Reads workgroup memory after a workgroup barrier and gives every invocation the same
/// value (WGSL's `workgroupUniformLoad`): its result counts as uniform, so it can steer
/// loops that contain barriers. It must itself be reached in uniform control flow.
#[track_caller]
pub fn workgroup_uniform_load<T: Copy>(p: &T) -> T {
    let p: *const T = p;
    cpu::exchange::<(), ()>(Scope::Workgroup, None, |_| ());
    // SAFETY: read after the barrier, as on the GPU; `p` points into workgroup memory that
    // outlives the call.
    let v = unsafe { p.read() };
    // Every invocation reads before any writes again.
    cpu::exchange::<(), ()>(Scope::Workgroup, None, |_| ());
    v
}
pub mod workgroup_uniform_load {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir<T: super::GpuType>(p: super::Place<T>) -> super::Val<T> {
        super::lower::workgroup_uniform_load(p)
    }
}

/// The value the group's first invocation computes with `leader(group index)`, given to
/// every invocation of the group (its `group` level). On the host and the CPU backend no
/// invocation waits for another: the closure reads only the group's index, uniform and
/// `#[specialize]` values and constants (the macro checks it), so the value can be computed
/// by whichever member runs first (`cpu::group_value`, once per group and workgroup) or by
/// each invocation called directly.
#[track_caller]
pub fn group_share<T: Copy>(leader: impl FnOnce(u32) -> T) -> T {
    cpu::group_value(leader, crate::host::current_group)
}
pub mod group_share {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir<T: super::GpuType>(
        leader: impl FnOnce(super::Val<u32>) -> super::Val<T>,
    ) -> super::Val<T> {
        crate::ir::group::group_share(leader)
    }
}

/// True for every invocation of the kernel's coherence group (its `group` level: one
/// invocation, a 32-wide warp or a workgroup) when `p` holds for any of them; e.g. a group
/// that ends together when one of its paths ends. Every invocation of the workgroup must
/// reach the call (as for barriers). Not available at grid level: a dispatch cannot
/// exchange values between its workgroups (building such a kernel is a compile error).
/// Called directly on the host every invocation runs alone, so the group is that invocation.
#[track_caller]
pub fn group_any(p: bool) -> bool {
    let scope = match cpu::lane().map(|l| l.level) {
        None | Some(GroupLevel::Thread | GroupLevel::Grid) => return p,
        Some(GroupLevel::Warp) => Scope::Subgroup,
        Some(GroupLevel::Block) => Scope::Workgroup,
    };
    cpu::exchange(scope, Some(p), |v| v.values().any(|(_, q)| q)).unwrap_or(p)
}
pub mod group_any {
    /// Whether a call must be reached by every invocation of its group (checked at the
    /// calls of helpers that make it, docs/LANGUAGE.md section 11).
    pub const NEEDS_UNIFORM: bool = true;
    pub fn ir(p: super::Val<bool>) -> super::Val<bool> {
        crate::ir::group::group_any(p)
    }
}

/// A subgroup collective on the CPU backend: `fold` over the values of the active lanes
/// that `take(lane, me)` selects, in lane order, from zero. Alone on the host: `alone`.
#[track_caller]
fn host_collective<T: SubgroupArith>(
    x: T,
    take: fn(u32, u32) -> bool,
    fold: fn(Option<T>, T) -> T,
    alone: T,
) -> T {
    cpu::exchange(Scope::Subgroup, Some(x), |v| {
        v.values()
            .filter(|&(l, _)| take(l, v.me()))
            .fold(None, |acc, (_, y)| Some(fold(acc, y)))
            .unwrap_or_default()
    })
    .unwrap_or(alone)
}

fn all_lanes(_: u32, _: u32) -> bool {
    true
}

macro_rules! collective {
    ($name:ident, $op:expr, $co:expr, $take:expr, $fold:expr, $alone:expr, $doc:literal) => {
        #[doc = $doc]
        #[track_caller]
        pub fn $name<T: SubgroupArith>(x: T) -> T {
            #[allow(clippy::redundant_closure_call)]
            host_collective(x, $take, $fold, ($alone)(x))
        }
        pub mod $name {
            #[doc(hidden)]
            pub const NEEDS_UNIFORM: bool = false;
            #[allow(unused_imports)]
            use super::{Co, So};
            pub fn ir<T: super::GpuType>(x: super::Val<T>) -> super::Val<T> {
                super::lower::subgroup_op($op, $co, x)
            }
        }
    };
}
collective!(
    subgroup_add,
    So::Add,
    Co::Reduce,
    all_lanes,
    |a, y| a.map_or(y, |a| T::add(a, y)),
    |x| x,
    "Sum over the active lanes of the subgroup (in lane order on the CPU backend)."
);
collective!(
    subgroup_min,
    So::Min,
    Co::Reduce,
    all_lanes,
    |a, y| a.map_or(y, |a| T::min(a, y)),
    |x| x,
    "Minimum over the active lanes of the subgroup."
);
collective!(
    subgroup_max,
    So::Max,
    Co::Reduce,
    all_lanes,
    |a, y| a.map_or(y, |a| T::max(a, y)),
    |x| x,
    "Maximum over the active lanes of the subgroup."
);
collective!(
    subgroup_inclusive_add,
    So::Add,
    Co::InclusiveScan,
    |l, me| l <= me,
    |a, y| a.map_or(y, |a| T::add(a, y)),
    |x| x,
    "Sum over the active lanes up to and including this one."
);
collective!(
    subgroup_exclusive_add,
    So::Add,
    Co::ExclusiveScan,
    |l, me| l < me,
    |a, y| a.map_or(y, |a| T::add(a, y)),
    |_x| T::default(),
    "Sum over the active lanes before this one (zero in the first)."
);

/// Whether `p` holds in any active lane of the subgroup.
#[track_caller]
pub fn subgroup_any(p: bool) -> bool {
    cpu::exchange(Scope::Subgroup, Some(p), |v| v.values().any(|(_, q)| q)).unwrap_or(p)
}
pub mod subgroup_any {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir(p: super::Val<bool>) -> super::Val<bool> {
        super::lower::subgroup_op(super::So::Any, super::Co::Reduce, p)
    }
}
/// Whether `p` holds in every active lane of the subgroup.
#[track_caller]
pub fn subgroup_all(p: bool) -> bool {
    cpu::exchange(Scope::Subgroup, Some(p), |v| v.values().all(|(_, q)| q)).unwrap_or(p)
}
pub mod subgroup_all {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir(p: super::Val<bool>) -> super::Val<bool> {
        super::lower::subgroup_op(super::So::All, super::Co::Reduce, p)
    }
}

/// Bit i of the result is set when lane i is active and its predicate holds.
#[track_caller]
pub fn subgroup_ballot(p: bool) -> UVec4 {
    cpu::exchange(Scope::Subgroup, Some(p), |v| {
        let mut bits = [0u32; 4];
        for (l, q) in v.values() {
            if q && l < 128 {
                bits[(l / 32) as usize] |= 1 << (l % 32);
            }
        }
        UVec4::from_array(bits)
    })
    .unwrap_or(UVec4::new(p as u32, 0, 0, 0))
}
pub mod subgroup_ballot {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir(p: super::Val<bool>) -> super::Val<glam::UVec4> {
        super::lower::subgroup_ballot(p)
    }
}

/// The value of lane `lane` (a constant). An inactive lane's value is undefined on a
/// GPU; the CPU backend returns the caller's own.
#[track_caller]
pub fn subgroup_broadcast<T: Copy>(x: T, lane: u32) -> T {
    cpu::exchange(Scope::Subgroup, Some(x), |v| v.get(lane).unwrap_or(x)).unwrap_or(x)
}
pub mod subgroup_broadcast {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir<T: super::GpuType>(x: super::Val<T>, lane: super::Val<u32>) -> super::Val<T> {
        super::lower::subgroup_broadcast(x, lane)
    }
}
/// The value of the first active lane.
#[track_caller]
pub fn subgroup_broadcast_first<T: Copy>(x: T) -> T {
    cpu::exchange(Scope::Subgroup, Some(x), |v| {
        v.values().next().map_or(x, |(_, y)| y)
    })
    .unwrap_or(x)
}
pub mod subgroup_broadcast_first {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir<T: super::GpuType>(x: super::Val<T>) -> super::Val<T> {
        super::lower::subgroup_broadcast_first(x)
    }
}
/// The value of lane `lane` (any value, computed per lane). An inactive or missing lane's
/// value is undefined on a GPU; the CPU backend returns the caller's own.
#[track_caller]
pub fn subgroup_shuffle<T: Copy>(x: T, lane: u32) -> T {
    cpu::exchange(Scope::Subgroup, Some(x), |v| v.get(lane).unwrap_or(x)).unwrap_or(x)
}
pub mod subgroup_shuffle {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir<T: super::GpuType>(x: super::Val<T>, lane: super::Val<u32>) -> super::Val<T> {
        super::lower::subgroup_shuffle(x, lane)
    }
}

/// Atomic compare-exchange returning the previous value (whether or not it was
/// replaced); the same on host and GPU.
pub fn atomic_compare_exchange(a: &AtomicU32, current: u32, new: u32) -> u32 {
    match a.compare_exchange(current, new, Ordering::AcqRel, Ordering::Acquire) {
        Ok(v) | Err(v) => v,
    }
}
pub mod atomic_compare_exchange {
    #[doc(hidden)]
    pub const NEEDS_UNIFORM: bool = false;
    pub fn ir(
        a: super::Place<super::AtomicU32>,
        current: super::Val<u32>,
        new: super::Val<u32>,
    ) -> super::Val<u32> {
        super::lower::atomic_compare_exchange(a, current, new)
    }
}
