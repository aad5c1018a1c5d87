//! Limits known only at run time are checked by `launch` before anything is dispatched
//! (docs/LANGUAGE.md, section 12): a kernel whose workgroup memory exceeds the device's is an
//! error naming the kernel, the bytes it needs and the limit (on the H100 such a launch hung).

mod common;

use cohort::prelude::*;
use cohort::runtime::RuntimeError;

/// 96 KiB of workgroup memory: more than lavapipe's and the H100's default 48-64 KiB.
#[kernel(workgroup = 64)]
pub fn too_much_workgroup_memory(
    #[builtin(local_index)] li: u32,
    #[workgroup] big: &mut [u32; 24576],
    out: &mut [u32],
) {
    big[li as usize] = li;
    workgroup_barrier();
    out[li as usize] = big[(63 - li) as usize];
}

/// 8 KiB: within every device's limit, runs and computes.
#[kernel(workgroup = 64)]
pub fn some_workgroup_memory(
    #[builtin(local_index)] li: u32,
    #[workgroup] small: &mut [u32; 2048],
    out: &mut [u32],
) {
    small[li as usize] = li;
    workgroup_barrier();
    out[li as usize] = small[(63 - li) as usize];
}

#[test]
fn workgroup_memory_over_the_limit_is_refused_before_dispatch() {
    for d in common::devices() {
        let out = d.alloc::<u32>(64).unwrap();
        let err = too_much_workgroup_memory::launch(&d, 64u32, &out).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(
                &err,
                cohort::Error::Runtime(RuntimeError::WorkgroupMemoryTooLarge { bytes: 98304, .. })
            ),
            "{:?}: {msg}",
            d.info().backend
        );
        assert!(
            msg.contains("too_much_workgroup_memory") && msg.contains("98304"),
            "{msg}"
        );
        some_workgroup_memory::launch(&d, 64u32, &out).unwrap();
        let got = d.read(&out).unwrap();
        assert_eq!(got, (0..64u32).rev().collect::<Vec<_>>());
    }
}
