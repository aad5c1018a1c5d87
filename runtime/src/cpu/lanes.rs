//! One workgroup on one CPU thread: its invocations (lanes), their sync points and the
//! values they exchange there.
//!
//! Release rule. After every lane has run to its next sync point (or finished), each
//! subgroup whose lanes wait at subgroup operations releases the lanes parked at the
//! earliest call site (file, line, column): in structured code the lanes inside an `if` or a
//! loop that the others have left are behind in the source, and on a GPU they run first,
//! with only themselves active. Lanes that finished take no part, as inactive lanes on a
//! GPU. When no subgroup operation is pending, every lane still running must wait at the
//! same workgroup-wide sync point (a barrier, or `group_any` at block
//! level), and all are released together; anything else is reported as the uniformity
//! error it is (docs/LANGUAGE.md, section 11).

use std::cell::{Cell, UnsafeCell};
use std::panic::Location;

use corosensei::stack::DefaultStack;
use corosensei::{Coroutine, CoroutineResult, Yielder};

use super::share::ShareCache;
use super::{Builtins, GroupLevel, HostBuf, HostKernel, LaneArgs, SUBGROUP_WIDTH};

/// Which invocations a sync point joins.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scope {
    /// The lanes of the invocation's subgroup ([`SUBGROUP_WIDTH`](super::SUBGROUP_WIDTH)
    /// consecutive `local_index` values).
    Subgroup,
    /// The whole workgroup.
    Workgroup,
}

/// The largest value one lane can post (a subgroup operation on a larger struct is refused
/// with a panic naming the size).
const SLOT_BYTES: usize = 256;
/// Each lane's stack. Kernels keep their data in registers-sized locals and small arrays;
/// the pages are only touched as deep as a kernel goes.
const STACK_BYTES: usize = 256 * 1024;

#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct Slot([u8; SLOT_BYTES]);

/// Where a parked lane waits.
#[derive(Clone, Copy)]
struct Park {
    scope: Scope,
    site: &'static Location<'static>,
}

fn site_key(s: &'static Location<'static>) -> (&'static str, u32, u32) {
    (s.file(), s.line(), s.column())
}

/// Whether two sync points are the same call site (one `Location` per site, as a rule;
/// compared by value where the compiler made two).
fn same_site(a: &'static Location<'static>, b: &'static Location<'static>) -> bool {
    std::ptr::eq(a, b) || site_key(a) == site_key(b)
}

/// The exchange area of the workgroup a thread is running: what each lane posted, and what
/// the lanes of the last release posted (read by those lanes when they resume).
struct Shared {
    posted: Box<[UnsafeCell<Slot>]>,
    has_post: Box<[Cell<bool>]>,
    released: Box<[UnsafeCell<Slot>]>,
    /// 0: not in the last release of its scope; 1: released, posted nothing; 2: released
    /// with a value.
    released_state: Box<[Cell<u8>]>,
    workgroup_size: u32,
}

impl Shared {
    fn new(lanes: usize) -> Shared {
        let slot = || UnsafeCell::new(Slot([0; SLOT_BYTES]));
        Shared {
            posted: (0..lanes).map(|_| slot()).collect(),
            has_post: (0..lanes).map(|_| Cell::new(false)).collect(),
            released: (0..lanes).map(|_| slot()).collect(),
            released_state: (0..lanes).map(|_| Cell::new(0)).collect(),
            workgroup_size: 0,
        }
    }

    fn release(&self, lane: usize, member: bool) {
        let state = if !member {
            0
        } else if self.has_post[lane].get() {
            // SAFETY: the lanes are suspended or finished; nothing else touches the slots.
            unsafe { *self.released[lane].get() = *self.posted[lane].get() };
            2
        } else {
            1
        };
        self.released_state[lane].set(state);
    }
}

/// The running invocation, reachable from its thread.
struct LaneCtx {
    /// Set per invocation where one context serves a workgroup's lanes in turn.
    lane: Cell<Lane>,
    subgroup: u32,
    /// Null while the kernel runs without coroutines.
    yielder: Cell<*const Yielder<(), Park>>,
    shared: *const Shared,
    /// The `group_share` values computed in this workgroup so far.
    shares: ShareCache,
}

/// The invocations one call of a kernel's host form runs: consecutive local indices of
/// one workgroup. The generated code asks for each lane's builtins as it runs it
/// ([`enter`](Self::enter)); inlined there, only the builtins the kernel reads are computed.
#[doc(hidden)]
pub struct Lanes<'a> {
    range: std::ops::Range<u32>,
    workgroup: u32,
    workgroup_id: [u32; 3],
    num_workgroups: [u32; 3],
    workgroup_size: u32,
    level: GroupLevel,
    /// The context `lane()` and the sync points read: set to each lane as it enters.
    ctx: &'a LaneCtx,
}

impl Lanes<'_> {
    /// The local indices to run, in order.
    #[inline]
    pub fn range(&self) -> std::ops::Range<u32> {
        self.range.clone()
    }

    /// Makes invocation `local` the running lane, and returns its builtins.
    #[inline]
    pub fn enter(&self, local: u32) -> Builtins {
        let n = self.workgroup_size;
        let global = self.workgroup.wrapping_mul(n).wrapping_add(local);
        let wid = self.workgroup_id;
        let group = match self.level {
            GroupLevel::Thread => global,
            GroupLevel::Warp => global / SUBGROUP_WIDTH,
            GroupLevel::Block => self.workgroup,
            GroupLevel::Grid => 0,
        };
        let b = Builtins {
            global_index: global,
            local_index: local,
            workgroup_index: self.workgroup,
            global_id: [wid[0].wrapping_mul(n).wrapping_add(local), wid[1], wid[2]],
            local_id: [local, 0, 0],
            workgroup_id: wid,
            num_workgroups: self.num_workgroups,
            workgroup_size: n,
            subgroup_size: SUBGROUP_WIDTH,
            subgroup_lane: local % SUBGROUP_WIDTH,
            subgroup_id: local / SUBGROUP_WIDTH,
            num_subgroups: n.div_ceil(SUBGROUP_WIDTH),
        };
        self.ctx.lane.set(Lane {
            level: self.level,
            group,
            local_index: local,
            subgroup_lane: b.subgroup_lane,
        });
        b
    }
}

thread_local! {
    static CURRENT: Cell<*const LaneCtx> = const { Cell::new(std::ptr::null()) };
}

/// Clears the thread's running lane when a workgroup ends, also by a panic.
struct ClearCurrent;
impl Drop for ClearCurrent {
    fn drop(&mut self) {
        CURRENT.with(|c| c.set(std::ptr::null()));
    }
}

/// Who the invocation the CPU backend is running on this thread is, as the group
/// intrinsics need to know it.
#[derive(Clone, Copy, Debug)]
pub struct Lane {
    pub level: GroupLevel,
    /// The coherence-group index: `global_index` at thread level, `global_index / 32` at
    /// warp level, the workgroup index at block level, 0 at grid level.
    pub group: u32,
    pub local_index: u32,
    pub subgroup_lane: u32,
}

/// The invocation the CPU backend is running on this thread; `None` outside it (a kernel
/// called directly on the host runs alone).
#[inline]
pub fn lane() -> Option<Lane> {
    let p = CURRENT.with(|c| c.get());
    // SAFETY: set only while the context it points to is alive.
    (!p.is_null()).then(|| unsafe { (*p).lane.get() })
}

/// The value of `group_share` at its call site for the running invocation's group:
/// computed by `leader` with the group's index once per group in a workgroup, where
/// invocations share it (above thread level). Where the calling thread runs no lane of the
/// CPU backend (a kernel called directly on the host), `leader(alone())`.
#[track_caller]
pub fn group_value<T: Copy>(leader: impl FnOnce(u32) -> T, alone: impl FnOnce() -> u32) -> T {
    let site = Location::caller();
    let p = CURRENT.with(|c| c.get());
    if p.is_null() {
        return leader(alone());
    }
    // SAFETY: set only while the context it points to is alive.
    let ctx = unsafe { &*p };
    let lane = ctx.lane.get();
    match lane.level {
        GroupLevel::Thread => leader(lane.group),
        _ => ctx.shares.get_or(site, lane.group, leader),
    }
}

/// The values the lanes of one release posted, as the lane reading them sees them.
pub struct View<'a, T> {
    shared: &'a Shared,
    first: u32,
    width: u32,
    me: u32,
    _t: std::marker::PhantomData<T>,
}

impl<T: Copy> View<'_, T> {
    /// This lane's index in the scope (`subgroup_lane`, or `local_index` for a workgroup).
    pub fn me(&self) -> u32 {
        self.me
    }

    /// What lane `lane` posted, if it is active and posted a value.
    pub fn get(&self, lane: u32) -> Option<T> {
        if lane >= self.width {
            return None;
        }
        let i = (self.first + lane) as usize;
        (self.shared.released_state[i].get() == 2).then(|| {
            // SAFETY: state 2 means the slot holds a `T` posted by this exchange.
            unsafe { (self.shared.released[i].get() as *const T).read() }
        })
    }

    /// The active lanes that posted a value, in lane order, with their values.
    pub fn values(&self) -> impl Iterator<Item = (u32, T)> + '_ {
        (0..self.width).filter_map(move |l| self.get(l).map(|v| (l, v)))
    }
}

/// A sync point of the CPU backend: posts `value` (or nothing), waits until the lanes of
/// `scope` that belong to this point have arrived, and returns what `read` makes of their
/// values. `None` when the calling thread is not running a lane of the CPU backend (a
/// kernel called directly on the host runs alone).
#[track_caller]
pub fn exchange<T: Copy, R>(
    scope: Scope,
    value: Option<T>,
    read: impl FnOnce(&View<'_, T>) -> R,
) -> Option<R> {
    let p = CURRENT.with(|c| c.get());
    if p.is_null() {
        return None;
    }
    // SAFETY: set only while the context it points to is alive.
    let ctx = unsafe { &*p };
    let yielder = ctx.yielder.get();
    assert!(
        !yielder.is_null(),
        "cohort compiler bug: a kernel that synchronises ran without lanes on the CPU backend"
    );
    assert!(
        std::mem::size_of::<T>() <= SLOT_BYTES && std::mem::align_of::<T>() <= 16,
        "the CPU backend exchanges values of at most {SLOT_BYTES} bytes between invocations; \
         this one has {}",
        std::mem::size_of::<T>()
    );
    // SAFETY: the shared area outlives the workgroup's lanes.
    let shared = unsafe { &*ctx.shared };
    let me = ctx.lane.get();
    let l = me.local_index as usize;
    if let Some(v) = value {
        // SAFETY: only this lane writes its slot, and only while the others are parked.
        unsafe { (shared.posted[l].get() as *mut T).write(v) };
    }
    shared.has_post[l].set(value.is_some());
    // SAFETY: the yielder belongs to this lane's coroutine, which is running.
    unsafe { &*yielder }.suspend(Park {
        scope,
        site: Location::caller(),
    });
    let (first, width, me) = match scope {
        Scope::Subgroup => {
            let first = ctx.subgroup * SUBGROUP_WIDTH;
            (
                first,
                SUBGROUP_WIDTH.min(shared.workgroup_size - first),
                me.subgroup_lane,
            )
        }
        Scope::Workgroup => (0, shared.workgroup_size, me.local_index),
    };
    Some(read(&View {
        shared,
        first,
        width,
        me,
        _t: std::marker::PhantomData,
    }))
}

/// A worker thread's reusable memory: lane stacks, the exchange area and workgroup memory.
pub(crate) struct Scratch {
    stacks: Vec<DefaultStack>,
    shared: Shared,
    workgroup_memory: Vec<u128>,
}

impl Scratch {
    pub(crate) fn new() -> Scratch {
        Scratch {
            stacks: Vec::new(),
            shared: Shared::new(0),
            workgroup_memory: Vec::new(),
        }
    }
}

/// Byte offsets of the `#[workgroup]` variables in one block, and its size in `u128`s.
fn workgroup_layout(vars: &[(usize, usize)]) -> (Vec<usize>, usize) {
    let mut offsets = Vec::with_capacity(vars.len());
    let mut at = 0usize;
    for &(size, align) in vars {
        assert!(align <= 16, "workgroup variable aligned to {align} bytes");
        at = at.div_ceil(16) * 16;
        offsets.push(at);
        at += size;
    }
    (offsets, at.div_ceil(16))
}

/// The dispatch a workgroup belongs to.
pub(crate) struct Launch<'a> {
    kernel: &'a HostKernel,
    bufs: &'a [HostBuf],
    workgroup_size: u32,
    num_workgroups: [u32; 3],
    /// Byte offsets of the `#[workgroup]` variables, and the block's size in `u128`s.
    workgroup_offsets: Vec<usize>,
    workgroup_words: usize,
}

impl<'a> Launch<'a> {
    pub(crate) fn new(
        kernel: &'a HostKernel,
        bufs: &'a [HostBuf],
        workgroup_size: u32,
        num_workgroups: [u32; 3],
    ) -> Launch<'a> {
        let (workgroup_offsets, workgroup_words) = workgroup_layout(&(kernel.workgroup_vars)());
        Launch {
            kernel,
            bufs,
            workgroup_size,
            num_workgroups,
            workgroup_offsets,
            workgroup_words,
        }
    }
}

enum LaneState {
    Runnable,
    Parked(Park),
    Done,
}

/// Runs every invocation of workgroup `linear` of `launch` on this thread.
pub(crate) fn run_workgroup(launch: &Launch<'_>, linear: u32, scratch: &mut Scratch) {
    let n = launch.workgroup_size;
    let [gx, gy, _] = launch.num_workgroups;
    let wid = [linear % gx, (linear / gx) % gy, linear / (gx * gy)];
    scratch.workgroup_memory.clear();
    scratch.workgroup_memory.resize(launch.workgroup_words, 0);
    let base = scratch.workgroup_memory.as_mut_ptr() as *mut u8;
    // SAFETY: every offset lies within the block just sized for them.
    let workgroup: Vec<*mut u8> = launch
        .workgroup_offsets
        .iter()
        .map(|&o| unsafe { base.add(o) })
        .collect();
    if scratch.shared.posted.len() < n as usize {
        scratch.shared = Shared::new(n as usize);
    }
    scratch.shared.workgroup_size = n;
    let shared: *const Shared = &scratch.shared;
    let lanes = |range: std::ops::Range<u32>, ctx| Lanes {
        range,
        workgroup: linear,
        workgroup_id: wid,
        num_workgroups: launch.num_workgroups,
        workgroup_size: n,
        level: launch.kernel.group,
        ctx,
    };
    let ctx_of = |local: u32| LaneCtx {
        lane: Cell::new(Lane {
            level: launch.kernel.group,
            group: 0,
            local_index: local,
            subgroup_lane: local % SUBGROUP_WIDTH,
        }),
        subgroup: local / SUBGROUP_WIDTH,
        yielder: Cell::new(std::ptr::null()),
        shared,
        shares: ShareCache::new(),
    };
    let _clear = ClearCurrent;

    let args = LaneArgs {
        bufs: launch.bufs,
        workgroup: &workgroup,
        constants: &launch.kernel.constants,
    };
    if !launch.kernel.synchronises {
        // One call for the whole workgroup, the lanes one after another: the buffers are
        // bound once, and one context follows the running lane (no subgroup field is read
        // without sync points).
        let ctx = ctx_of(0);
        CURRENT.with(|c| c.set(&ctx));
        (launch.kernel.invoke)(&args, &lanes(0..n, &ctx));
        return;
    }

    while scratch.stacks.len() < n as usize {
        scratch.stacks.push(
            DefaultStack::new(STACK_BYTES).expect("the CPU backend could not map a lane stack"),
        );
    }
    let ctxs: Vec<LaneCtx> = (0..n).map(ctx_of).collect();
    let one_lane: Vec<Lanes<'_>> = ctxs
        .iter()
        .enumerate()
        .map(|(l, ctx)| lanes(l as u32..l as u32 + 1, ctx))
        .collect();
    let invoke = launch.kernel.invoke;
    let args = &args;
    let mut lanes: Vec<_> = scratch
        .stacks
        .iter_mut()
        .zip(ctxs.iter().zip(&one_lane))
        .map(|(stack, (ctx, lane))| {
            // SAFETY: the coroutine borrows `ctx`, `lane` and `args`, which outlive it (it
            // is dropped at the end of this function, before them).
            unsafe {
                Coroutine::with_stack_unchecked(stack, move |y: &Yielder<(), Park>, ()| {
                    ctx.yielder.set(y);
                    invoke(args, lane)
                })
            }
        })
        .collect();
    let mut state: Vec<LaneState> = (0..n).map(|_| LaneState::Runnable).collect();
    // SAFETY: `shared` lives in `scratch`, which this function borrows throughout.
    let sh = unsafe { &*shared };
    let width = SUBGROUP_WIDTH as usize;
    loop {
        for (l, lane) in lanes.iter_mut().enumerate() {
            if !matches!(state[l], LaneState::Runnable) {
                continue;
            }
            CURRENT.with(|c| c.set(&ctxs[l]));
            state[l] = match lane.resume(()) {
                CoroutineResult::Yield(p) => LaneState::Parked(p),
                CoroutineResult::Return(()) => LaneState::Done,
            };
        }
        let mut released = false;
        for first in (0..n as usize).step_by(width) {
            let range = first..(first + width).min(n as usize);
            let mut earliest: Option<&'static Location<'static>> = None;
            for l in range.clone() {
                if let LaneState::Parked(p) = &state[l] {
                    if p.scope == Scope::Subgroup
                        && earliest
                            .is_none_or(|e| !same_site(e, p.site) && site_key(p.site) < site_key(e))
                    {
                        earliest = Some(p.site);
                    }
                }
            }
            let Some(site) = earliest else { continue };
            for l in range {
                let member = matches!(&state[l], LaneState::Parked(p)
                    if p.scope == Scope::Subgroup && same_site(p.site, site));
                sh.release(l, member);
                if member {
                    state[l] = LaneState::Runnable;
                    released = true;
                }
            }
        }
        if released {
            continue;
        }
        let mut site = None;
        for s in &state {
            match s {
                LaneState::Parked(p) => match site {
                    None => site = Some(p.site),
                    Some(first) if !same_site(first, p.site) => panic!(
                        "invocations of one workgroup wait at different sync points ({first} and {}): \
                         every invocation must reach the same barriers and group operations \
                         (docs/LANGUAGE.md, section 11)",
                        p.site
                    ),
                    Some(_) => {}
                },
                LaneState::Runnable => unreachable!("every lane ran to a sync point"),
                LaneState::Done => {}
            }
        }
        if site.is_none() {
            break;
        }
        for (l, s) in state.iter_mut().enumerate() {
            let parked = matches!(s, LaneState::Parked(_));
            sh.release(l, parked);
            if parked {
                *s = LaneState::Runnable;
            }
        }
    }
}
