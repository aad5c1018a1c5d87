//! Running a kernel's plain Rust function on the host, one invocation at a time, for
//! tests and references. Kernels without barriers or cross-invocation communication
//! compute the same thing here as on the GPU; subgroups are one lane wide. (The CPU
//! backend, `BackendKind::Cpu`, runs whole kernels, barriers and subgroups included.)

pub mod ops;
mod subgroup;

pub use subgroup::SubgroupArith;

use std::cell::Cell;

use crate::spec::{Group, WARP};
use glam::UVec3;

thread_local! {
    static GROUP: Cell<u32> = const { Cell::new(0) };
}

/// The coherence group of the invocation the host is running (read by `group_share`): the
/// CPU backend's, or the one `for_each_invocation` set.
pub fn current_group() -> u32 {
    match cohort_runtime::cpu::lane() {
        Some(lane) => lane.group,
        None => GROUP.with(|g| g.get()),
    }
}

/// What a kernel's `#[builtin]` parameters would receive.
#[derive(Clone, Copy, Debug)]
pub struct Invocation {
    pub global_index: u32,
    pub local_index: u32,
    pub workgroup_index: u32,
    pub global_id: UVec3,
    pub local_id: UVec3,
    pub workgroup_id: UVec3,
    pub num_workgroups: UVec3,
    pub group: u32,
}

/// Calls `f` for each of `threads` invocations (rounded up to whole workgroups, like a
/// launch with `Grid::Threads`), in order, setting the group index for `group_share`.
pub fn for_each_invocation(
    threads: u32,
    workgroup_size: u32,
    group: Group,
    f: impl FnMut(Invocation),
) {
    let groups = threads.div_ceil(workgroup_size).max(1);
    for_each_invocation_in_groups([groups, 1, 1], workgroup_size, group, f)
}

/// Calls `f` for every invocation of a dispatch of `groups` workgroups (like a launch
/// with `Grid::Groups(groups)`), in `global_index` order: workgroups x fastest, then y,
/// then z; `global_index = workgroup_index * workgroup_size + local_index`.
pub fn for_each_invocation_in_groups(
    groups: [u32; 3],
    workgroup_size: u32,
    group: Group,
    mut f: impl FnMut(Invocation),
) {
    let [gx, gy, gz] = groups;
    for wz in 0..gz {
        for wy in 0..gy {
            for wx in 0..gx {
                let wg = wx.wrapping_add(gx.wrapping_mul(wy.wrapping_add(gy.wrapping_mul(wz))));
                for local in 0..workgroup_size {
                    let global = wg.wrapping_mul(workgroup_size).wrapping_add(local);
                    let g = match group {
                        Group::Thread => global,
                        Group::Warp => global / WARP,
                        Group::Block(_) => wg,
                        Group::Grid => 0,
                    };
                    GROUP.with(|c| c.set(g));
                    f(Invocation {
                        global_index: global,
                        local_index: local,
                        workgroup_index: wg,
                        global_id: UVec3::new(wx * workgroup_size + local, wy, wz),
                        local_id: UVec3::new(local, 0, 0),
                        workgroup_id: UVec3::new(wx, wy, wz),
                        num_workgroups: UVec3::new(gx, gy, gz),
                        group: g,
                    });
                }
            }
        }
    }
    GROUP.with(|c| c.set(0));
}
