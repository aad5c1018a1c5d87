//! Device enumeration (`Device::all`, `Device::new_index`), which `--devices` uses to
//! render on every GPU of a machine: indices follow each backend's list of usable
//! devices, and an index past the end is a clear error naming the devices there are.

use cohort_runtime::{BackendKind, Device, RuntimeError};

#[test]
fn every_device_opens_by_index_and_past_the_end_is_an_error() {
    for kind in [BackendKind::Vulkan, BackendKind::Wgpu] {
        // Skips (or fails under CI=true) where the backend has no adapter at all.
        if Device::for_tests(kind).is_none() {
            continue;
        }
        let all = Device::all(kind).unwrap();
        assert!(!all.is_empty(), "{kind:?}");
        for (i, d) in all.iter().enumerate() {
            let again = Device::new_index(kind, i).unwrap();
            assert_eq!(
                again.info().adapter_name,
                d.info().adapter_name,
                "{kind:?} device {i}"
            );
        }
        let past = all.len();
        match Device::new_index(kind, past) {
            Err(e @ RuntimeError::NoSuchDevice { .. }) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(&format!("no {} device {past}", kind.name())),
                    "{msg}"
                );
                assert!(
                    msg.contains(&format!("0: {}", all[0].info().adapter_name)),
                    "{msg}"
                );
            }
            other => panic!("{kind:?} device {past} of {past}: {other:?}"),
        }
    }
}
