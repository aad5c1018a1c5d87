//! Bound `u32` buffers as the CPU backend's whole-dispatch forms read and write them
//! (`cohort::runtime::cpu::DispatchForm`: `crate::compact`'s and `crate::queues`' loops).
//!
//! Buffers are read and written through bounds-checked raw views, never as references:
//! a dispatch may bind one buffer twice, as it may on a GPU. An index out of bounds panics,
//! as the host form's would, and the backend reports it as the dispatch's error.

use cohort::runtime::cpu::LaneArgs;

/// A bound buffer of `u32`s, read and written by index.
#[derive(Clone, Copy)]
pub(crate) struct Words {
    ptr: *mut u32,
    len: usize,
    /// Its parameter's name, for the panic message of an index out of bounds.
    name: &'static str,
}

impl Words {
    /// Storage parameter `i` of the dispatch.
    ///
    /// # Safety
    /// Buffer `i` holds `u32`s (the backend binds the kernel's buffers in parameter order).
    pub(crate) unsafe fn bound(a: &LaneArgs<'_>, i: usize, name: &'static str) -> Words {
        let s = a.storage_mut::<u32>(i);
        Words {
            ptr: s as *mut u32,
            len: s.len(),
            name,
        }
    }

    fn check(&self, i: usize) {
        assert!(
            i < self.len,
            "index out of bounds: `{}` has {} elements but the index is {i}",
            self.name,
            self.len
        );
    }

    pub(crate) fn get(&self, i: usize) -> u32 {
        self.check(i);
        // SAFETY: in bounds; the buffer stays bound for the dispatch.
        unsafe { self.ptr.add(i).read() }
    }

    pub(crate) fn set(&self, i: usize, v: u32) {
        self.check(i);
        // SAFETY: as for `get`.
        unsafe { self.ptr.add(i).write(v) }
    }
}

/// Workgroups of a dispatch of `invocations` in workgroups of `wg`.
pub(crate) fn groups(invocations: u64, wg: u32) -> u32 {
    (invocations / u64::from(wg)).min(u64::from(u32::MAX)) as u32
}
