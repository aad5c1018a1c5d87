//! How the intrinsics that have no plain-Rust equivalent lower to naga IR: barriers,
//! subgroup operations and atomics. The `cohort` crate pairs each with its host meaning
//! (`cohort::intrinsics`); the front end rewrites a call `f(args)` into `f::ir(args)`,
//! which calls the builder here.

use std::sync::atomic::{AtomicI32, AtomicU32, Ordering};

use naga::{
    Barrier, CollectiveOperation as Co, Expression, GatherMode, Statement, SubgroupOperation as So,
};

use super::builder::with;
use super::types::GpuType;
use super::val::{Place, Val};

/// `OpControlBarrier` over the workgroup.
pub fn workgroup_barrier() {
    with(|c| {
        c.synchronises = true;
        c.stmt(Statement::ControlBarrier(Barrier::WORK_GROUP))
    });
}

/// `OpControlBarrier` with storage-buffer memory semantics.
pub fn storage_barrier() {
    with(|c| {
        c.synchronises = true;
        c.stmt(Statement::ControlBarrier(Barrier::STORAGE))
    });
}

/// `OpControlBarrier` over the subgroup.
pub fn subgroup_barrier() {
    with(|c| {
        c.uses_subgroups = true;
        c.synchronises = true;
        c.stmt(Statement::ControlBarrier(Barrier::SUB_GROUP))
    });
}

/// WGSL's `workgroupUniformLoad` of `p`.
pub fn workgroup_uniform_load<T: GpuType>(p: Place<T>) -> Val<T> {
    with(|c| {
        c.synchronises = true;
        let ty = T::naga_type(&mut c.module);
        let result = c.expr(Expression::WorkGroupUniformLoadResult { ty });
        c.stmt(Statement::WorkGroupUniformLoad {
            pointer: p.ptr,
            result,
        });
        Val::from_handle(result)
    })
}

/// A subgroup collective operation (`OpGroupNonUniform*` reduce or scan).
pub fn subgroup_op<T: GpuType>(op: So, collective: Co, x: Val<T>) -> Val<T> {
    with(|c| {
        c.uses_subgroups = true;
        c.synchronises = true;
        let ty = T::naga_type(&mut c.module);
        let result = c.expr(Expression::SubgroupOperationResult { ty });
        c.stmt(Statement::SubgroupCollectiveOperation {
            op,
            collective_op: collective,
            argument: x.h,
            result,
        });
        Val::from_handle(result)
    })
}

fn subgroup_gather<T: GpuType>(mode: GatherMode, x: Val<T>) -> Val<T> {
    with(|c| {
        c.uses_subgroups = true;
        c.synchronises = true;
        let ty = T::naga_type(&mut c.module);
        let result = c.expr(Expression::SubgroupOperationResult { ty });
        c.stmt(Statement::SubgroupGather {
            mode,
            argument: x.h,
            result,
        });
        Val::from_handle(result)
    })
}

/// `OpGroupNonUniformBroadcast` from lane `lane`.
pub fn subgroup_broadcast<T: GpuType>(x: Val<T>, lane: Val<u32>) -> Val<T> {
    subgroup_gather(GatherMode::Broadcast(lane.h), x)
}

/// `OpGroupNonUniformBroadcastFirst`.
pub fn subgroup_broadcast_first<T: GpuType>(x: Val<T>) -> Val<T> {
    subgroup_gather(GatherMode::BroadcastFirst, x)
}

/// `OpGroupNonUniformShuffle` from lane `lane`.
pub fn subgroup_shuffle<T: GpuType>(x: Val<T>, lane: Val<u32>) -> Val<T> {
    subgroup_gather(GatherMode::Shuffle(lane.h), x)
}

/// `OpGroupNonUniformBallot`.
pub fn subgroup_ballot(p: Val<bool>) -> Val<glam::UVec4> {
    with(|c| {
        c.uses_subgroups = true;
        c.synchronises = true;
        let result = c.expr(Expression::SubgroupBallotResult);
        c.stmt(Statement::SubgroupBallot {
            result,
            predicate: Some(p.h),
        });
        Val::from_handle(result)
    })
}

/// `OpAtomicCompareExchange`, the previous value.
pub fn atomic_compare_exchange(a: Place<AtomicU32>, current: Val<u32>, new: Val<u32>) -> Val<u32> {
    with(|c| {
        let ty = c.module.generate_predeclared_type(
            naga::PredeclaredType::AtomicCompareExchangeWeakResult(naga::Scalar::U32),
        );
        let result = c.expr(Expression::AtomicResult {
            ty,
            comparison: true,
        });
        c.stmt(Statement::Atomic {
            pointer: a.ptr,
            fun: naga::AtomicFunction::Exchange {
                compare: Some(current.h),
            },
            value: new.h,
            result: Some(result),
        });
        Val::from_handle(c.expr(Expression::AccessIndex {
            base: result,
            index: 0,
        }))
    })
}

macro_rules! atomic_place {
    ($atomic:ty, $int:ty, $scalar:expr) => {
        impl Place<$atomic> {
            fn rmw(self, fun: naga::AtomicFunction, v: Val<$int>) -> Val<$int> {
                with(|c| {
                    let ty = c.ty(naga::TypeInner::Scalar($scalar));
                    let result = c.expr(Expression::AtomicResult {
                        ty,
                        comparison: false,
                    });
                    c.stmt(Statement::Atomic {
                        pointer: self.ptr,
                        fun,
                        value: v.h,
                        result: Some(result),
                    });
                    Val::from_handle(result)
                })
            }
            pub fn fetch_add(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::Add, v)
            }
            pub fn fetch_sub(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::Subtract, v)
            }
            pub fn fetch_min(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::Min, v)
            }
            pub fn fetch_max(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::Max, v)
            }
            pub fn fetch_and(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::And, v)
            }
            pub fn fetch_or(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::InclusiveOr, v)
            }
            pub fn fetch_xor(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::ExclusiveOr, v)
            }
            pub fn swap(self, v: Val<$int>, _o: Ordering) -> Val<$int> {
                self.rmw(naga::AtomicFunction::Exchange { compare: None }, v)
            }
            pub fn load(self, _o: Ordering) -> Val<$int> {
                Val::from_handle(with(|c| c.expr(Expression::Load { pointer: self.ptr })))
            }
            pub fn store(self, v: Val<$int>, _o: Ordering) {
                with(|c| {
                    c.stmt(Statement::Store {
                        pointer: self.ptr,
                        value: v.h,
                    })
                })
            }
        }
    };
}
atomic_place!(AtomicU32, u32, naga::Scalar::U32);
atomic_place!(AtomicI32, i32, naga::Scalar::I32);
