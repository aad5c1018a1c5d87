//! Which devices a command runs on: `--backend` and `--devices` (none: the best device;
//! `all`: every usable device of the backend; `0,2`: those indices, as `cohort devices`
//! lists them).

use cohort::runtime::{BackendKind, Device};

use crate::choices::DeviceList;

/// The backend `--backend` names, or the one `Device::best` would pick.
fn backend_kind(backend: Option<BackendKind>) -> Result<BackendKind, String> {
    match backend {
        Some(b) => Ok(b),
        None => Ok(Device::best().map_err(|e| e.to_string())?.info().backend),
    }
}

/// `Device::best`, with a note on stderr when it chose the CPU backend saying why (no GPU,
/// or only the software Vulkan driver).
pub fn best() -> Result<Device, String> {
    let (device, why) = Device::best_explained().map_err(|e| e.to_string())?;
    if let Some(why) = why {
        eprintln!("note: rendering on the CPU backend: {why} (--backend names another)");
    }
    Ok(device)
}

/// The device of `--backend`, or the best one found.
pub fn one(backend: Option<BackendKind>) -> Result<Device, String> {
    match backend {
        None => best(),
        Some(kind) => Device::new(kind).map_err(|e| e.to_string()),
    }
}

/// Opens the devices of `--devices` (parsed, so well formed) on `--backend`; every index
/// is checked before any work starts, so a missing one fails at once, naming the devices
/// there are.
pub fn open(
    backend: Option<BackendKind>,
    devices: Option<&DeviceList>,
) -> Result<Vec<Device>, String> {
    let Some(list) = devices else {
        return Ok(vec![one(backend)?]);
    };
    let kind = backend_kind(backend)?;
    match list {
        DeviceList::All => Device::all(kind).map_err(|e| e.to_string()),
        DeviceList::Indices(indices) => indices
            .iter()
            .map(|&i| Device::new_index(kind, i).map_err(|e| format!("--devices: {e}")))
            .collect(),
    }
}

/// `cohort devices`: every usable device of each backend, by index.
pub fn list() -> Result<(), String> {
    for kind in [BackendKind::Vulkan, BackendKind::Wgpu, BackendKind::Cpu] {
        match Device::all(kind) {
            Ok(devices) => {
                for (i, d) in devices.iter().enumerate() {
                    let info = d.info();
                    println!(
                        "{:<7} {i}  {} ({}){}{}",
                        kind.name(),
                        info.adapter_name,
                        info.driver,
                        match (info.f32_subnormals, info.f32_nan_inf) {
                            (true, true) => ", f32 subnormals and NaN kept",
                            (true, false) => ", f32 subnormals kept (NaN may be folded)",
                            (false, true) => ", f32 NaN kept (subnormals flushed to zero)",
                            (false, false) => "",
                        },
                        if info.uniforms_as_storage {
                            ", uniforms in storage buffers"
                        } else {
                            ""
                        }
                    );
                }
            }
            Err(e) => println!("{:<7} none: {e}", kind.name()),
        }
    }
    Ok(())
}
