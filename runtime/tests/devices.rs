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

/// A process may open and drop devices again and again (a test suite does, a long sweep may):
/// the 40th device of each backend opens like the first. (With one wgpu instance per device,
/// the NVIDIA driver reported no adapter after about 17 wgpu devices in one process.)
#[test]
fn devices_open_again_and_again_in_one_process() {
    for kind in [BackendKind::Vulkan, BackendKind::Wgpu] {
        if Device::for_tests(kind).is_none() {
            continue;
        }
        for i in 0..40 {
            let d = Device::new(kind).unwrap_or_else(|e| panic!("{kind:?} device #{i}: {e}"));
            let b = d.upload(&[i as u32]).unwrap();
            assert_eq!(d.read(&b).unwrap(), vec![i as u32]);
        }
    }
}
