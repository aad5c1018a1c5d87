//! The values of `group_share` as the CPU backend keeps them: computed once per group and
//! call site, and handed to the group's other invocations as they run.
//!
//! Each invocation could compute its group's value itself (the closure reads only the
//! group index, uniform and `#[specialize]` values and constants, so every member gets
//! what the leader would), but a coherent sampler's value costs trigonometry, and the
//! invocations of one group run one after another on one thread. The cache lives as long
//! as one workgroup's run, within which the uniforms cannot change.

use std::cell::UnsafeCell;
use std::panic::Location;

/// The largest value kept (larger ones are computed by every invocation).
const VALUE_BYTES: usize = 64;
/// Call sites kept at once (a kernel has a handful; more evict the oldest).
const SITES: usize = 8;

#[derive(Clone, Copy)]
#[repr(C, align(16))]
struct Value([u8; VALUE_BYTES]);

#[derive(Clone, Copy)]
struct Entry {
    site: &'static Location<'static>,
    group: u32,
    value: Value,
}

/// One workgroup's shared values: for each call site, its last group's value.
pub(crate) struct ShareCache {
    entries: UnsafeCell<([Option<Entry>; SITES], usize)>,
}

impl ShareCache {
    pub(crate) fn new() -> ShareCache {
        ShareCache {
            entries: UnsafeCell::new(([None; SITES], 0)),
        }
    }

    /// Group `group`'s value at `site`, computed by `leader` the first time it is asked.
    pub(crate) fn get_or<T: Copy>(
        &self,
        site: &'static Location<'static>,
        group: u32,
        leader: impl FnOnce(u32) -> T,
    ) -> T {
        if std::mem::size_of::<T>() > VALUE_BYTES || std::mem::align_of::<T>() > 16 {
            return leader(group);
        }
        // SAFETY: one thread runs a workgroup; no reference into the cache outlives a
        // call, and `leader` runs while none is held.
        let hit = unsafe { &*self.entries.get() }
            .0
            .iter()
            .flatten()
            .find_map(|e| {
                (std::ptr::eq(e.site, site) && e.group == group)
                    .then(|| unsafe { (e.value.0.as_ptr() as *const T).read() })
            });
        if let Some(v) = hit {
            return v;
        }
        let v = leader(group);
        let mut value = Value([0; VALUE_BYTES]);
        // SAFETY: `T` fits and is aligned within `Value` (checked above).
        unsafe { (value.0.as_mut_ptr() as *mut T).write(v) };
        let (entries, next) = unsafe { &mut *self.entries.get() };
        let entry = Entry { site, group, value };
        match entries
            .iter_mut()
            .find(|e| e.is_some_and(|e| std::ptr::eq(e.site, site)))
        {
            Some(slot) => *slot = Some(entry),
            None => {
                entries[*next] = Some(entry);
                *next = (*next + 1) % SITES;
            }
        }
        v
    }
}
