//! Coherence groups: the one primitive through which every invocation of a group gets
//! the value that the group's leader computed (`group_share`).
//!
//! The specialisation's group level picks the lowering:
//! - `Thread`: each invocation computes it (group index = global index);
//! - `Warp`: lane 0 of each 32-invocation warp computes it; a subgroup broadcast shares
//!   it where subgroups are 32 wide, workgroup memory and a barrier elsewhere;
//! - `Block(n)`: invocation 0 of the workgroup computes it; workgroup memory + barrier;
//! - `Warp` and `Block(n)` with `Spec::recompute_group_share`: each invocation computes
//!   its group's value (group index = global index / 32, or the workgroup index), as the
//!   leader would; no barrier;
//! - `Grid`: every invocation computes it for group 0. The closure of a grid-level
//!   value reads only uniform values (the front end checks it), so each computes the same
//!   value, on the device: the host has no work between dispatches, and a batch of
//!   iterations needs no upload per iteration.

use naga::{AddressSpace, ArraySize, Barrier, Expression, GatherMode, Statement, TypeInner};

use super::builder::with;
use super::control::if_;
use super::kernel::add_global;
use super::ops::eq;
use super::types::GpuType;
use super::val::{lit, Place, Val, Var};
use crate::spec::{Group, WARP};

fn barrier() {
    with(|c| c.stmt(Statement::ControlBarrier(Barrier::WORK_GROUP)));
}

fn is_scalar_or_vector<T: GpuType>() -> bool {
    with(|c| {
        let ty = T::naga_type(&mut c.module);
        matches!(
            c.module.types[ty].inner,
            TypeInner::Scalar(_) | TypeInner::Vector { .. }
        )
    })
}

/// Builds `group_share(|group| leader_value)`. `leader` receives the group's index.
pub fn group_share<T: GpuType>(leader: impl FnOnce(Val<u32>) -> Val<T>) -> Val<T> {
    let (spec, site, pro) = with(|c| {
        let site = c.group_share_sites;
        c.group_share_sites += 1;
        (c.spec, site, c.prologue)
    });
    let local = Val::<u32>::from_handle(pro.local_index.expect("prologue"));
    let global = Val::<u32>::from_handle(pro.global_index.expect("prologue"));
    match spec.group {
        Group::Thread => leader(global),
        Group::Grid => leader(lit(0u32)),
        Group::Block(_) if spec.recompute_group_share => leader(Val::<u32>::from_handle(
            pro.workgroup_linear.expect("prologue"),
        )),
        Group::Warp if spec.recompute_group_share => leader(global / lit(WARP)),
        Group::Block(_) => {
            let ty = with(|c| T::naga_type(&mut c.module));
            let g = add_global(
                &format!("group_share_{site}"),
                AddressSpace::WorkGroup,
                ty,
                None,
            );
            let p = Place::<T>::from_handle(with(|c| c.expr(Expression::GlobalVariable(g))));
            let wg = Val::<u32>::from_handle(pro.workgroup_linear.expect("prologue"));
            if_(eq(local, lit(0u32)), || p.set(leader(wg)), || {});
            barrier();
            let v = Var::new("shared", p.get());
            // A second barrier keeps a leader in a later loop iteration from overwriting
            // the value before every invocation has read it.
            barrier();
            v.get()
        }
        Group::Warp if spec.warp_via_subgroup && is_scalar_or_vector::<T>() => {
            let lane = Val::<u32>::from_handle(pro.subgroup_lane.expect("prologue"));
            let v = Var::<T>::uninit("leader_value");
            let group = global / lit(WARP);
            if_(eq(lane, lit(0u32)), || v.set(leader(group)), || {});
            let arg = v.get();
            let zero = lit(0u32);
            with(|c| {
                c.uses_subgroups = true;
                let ty = T::naga_type(&mut c.module);
                let result = c.expr(Expression::SubgroupOperationResult { ty });
                c.stmt(Statement::SubgroupGather {
                    mode: GatherMode::Broadcast(zero.h),
                    argument: arg.h,
                    result,
                });
                Val::from_handle(result)
            })
        }
        Group::Warp => {
            let warps = spec.workgroup_size / WARP;
            let ty = with(|c| {
                let base = T::naga_type(&mut c.module);
                let stride = T::GPU_SIZE.div_ceil(T::GPU_ALIGN) * T::GPU_ALIGN;
                c.ty(TypeInner::Array {
                    base,
                    size: ArraySize::Constant(std::num::NonZeroU32::new(warps).unwrap()),
                    stride: stride as u32,
                })
            });
            let g = add_global(
                &format!("group_share_{site}"),
                AddressSpace::WorkGroup,
                ty,
                None,
            );
            let arr = Place::<[T; 1]>::from_handle(with(|c| c.expr(Expression::GlobalVariable(g))));
            let warp_in_wg = local / lit(WARP);
            let slot = super::val::place_index(arr, warp_in_wg);
            let group = global / lit(WARP);
            if_(
                eq(local % lit(WARP), lit(0u32)),
                || slot.set(leader(group)),
                || {},
            );
            barrier();
            let v = Var::new("shared", slot.get());
            barrier();
            v.get()
        }
    }
}

/// Builds `group_any(p)`: true for every invocation of the group when `p` holds for any
/// of them. Every invocation of the workgroup must reach it (the macro checks that).
pub fn group_any(p: Val<bool>) -> Val<bool> {
    let (spec, pro) = with(|c| (c.spec, c.prologue));
    let local = Val::<u32>::from_handle(pro.local_index.expect("prologue"));
    match spec.group {
        Group::Thread => p,
        Group::Grid => {
            // A dispatch cannot wait for all its workgroups, so no invocation can learn
            // in time what the others decided.
            with(|c| {
                c.unsupported.push(
                    "`group_any` has no grid-level lowering: invocations of different workgroups cannot \
                     exchange values within one dispatch; use group = Warp or Block(n)"
                        .into(),
                )
            });
            p
        }
        Group::Warp if spec.warp_via_subgroup => super::intrinsics::subgroup_op(
            naga::SubgroupOperation::Any,
            naga::CollectiveOperation::Reduce,
            p,
        ),
        Group::Warp | Group::Block(_) => {
            with(|c| c.synchronises = true);
            // One flag per group in workgroup memory (zero-initialised at launch): set by
            // the invocations where `p` holds, read by all, cleared by the group's leader
            // once everybody has read it, so the next call starts from zero.
            let slots = match spec.group {
                Group::Warp => spec.workgroup_size / WARP,
                _ => 1,
            };
            let ty = with(|c| {
                let base = <std::sync::atomic::AtomicU32 as GpuType>::naga_type(&mut c.module);
                c.ty(TypeInner::Array {
                    base,
                    size: ArraySize::Constant(std::num::NonZeroU32::new(slots).unwrap()),
                    stride: 4,
                })
            });
            let site = with(|c| {
                let s = c.group_share_sites;
                c.group_share_sites += 1;
                s
            });
            let g = add_global(
                &format!("group_any_{site}"),
                AddressSpace::WorkGroup,
                ty,
                None,
            );
            let arr = Place::<[std::sync::atomic::AtomicU32; 1]>::from_handle(with(|c| {
                c.expr(Expression::GlobalVariable(g))
            }));
            let (slot_index, leader) = match spec.group {
                Group::Warp => (local / lit(WARP), eq(local % lit(WARP), lit(0u32))),
                _ => (lit(0u32), eq(local, lit(0u32))),
            };
            let slot = super::val::place_index(arr, slot_index);
            if_(
                p,
                || {
                    slot.fetch_or(lit(1u32), std::sync::atomic::Ordering::Relaxed);
                },
                || {},
            );
            barrier();
            let v = Var::new(
                "any",
                super::ops::ne(slot.load(std::sync::atomic::Ordering::Relaxed), lit(0u32)),
            );
            barrier();
            if_(
                leader,
                || slot.store(lit(0u32), std::sync::atomic::Ordering::Relaxed),
                || {},
            );
            // The clear must land before anybody sets the flag again.
            barrier();
            v.get()
        }
    }
}
