//! Where compiled pipelines are kept between runs: the driver's pipeline-cache blob, one
//! file per device, so the second run of a program skips the driver's shader compilation
//! (seconds for the path tracer's kernels on some drivers). The driver checks the blob's
//! header (vendor, device, driver version, cache UUID) and ignores data that does not fit,
//! so a stale or foreign file costs nothing but the compile it would have saved.
//!
//! Folder: `$COHORT_CACHE_DIR`, else `$XDG_CACHE_HOME/cohort`, else `$HOME/.cache/cohort`.
//! `COHORT_CACHE_DIR=off` turns it off.

use std::path::PathBuf;

/// Cohort's cache folder: `$COHORT_CACHE_DIR`, else `$XDG_CACHE_HOME/cohort`, else
/// `$HOME/.cache/cohort`; `None` when caching is off (`COHORT_CACHE_DIR=off`) or no folder
/// is known. The Vulkan backend keeps its pipelines there, the renderer its scenes' BVHs.
pub fn cache_dir() -> Option<PathBuf> {
    match std::env::var_os("COHORT_CACHE_DIR") {
        Some(d) if d == "off" => None,
        Some(d) => Some(PathBuf::from(d)),
        None => match std::env::var_os("XDG_CACHE_HOME") {
            Some(x) if !x.is_empty() => Some(PathBuf::from(x).join("cohort")),
            _ => Some(
                PathBuf::from(std::env::var_os("HOME")?)
                    .join(".cache")
                    .join("cohort"),
            ),
        },
    }
}

/// The cache file for a device named `device`, or `None` when caching is off or no folder
/// is known.
pub(crate) fn file_for(device: &str) -> Option<PathBuf> {
    let dir = cache_dir()?;
    let name: String = device
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    Some(dir.join(format!("vk-pipelines-{name}.bin")))
}

/// The saved blob, or nothing (a missing or unreadable file is an empty cache).
pub(crate) fn load(path: &Option<PathBuf>) -> Vec<u8> {
    path.as_ref()
        .and_then(|p| std::fs::read(p).ok())
        .unwrap_or_default()
}

/// Writes the blob through a temporary file and a rename, so a concurrent or interrupted
/// run never leaves a torn file. Failures are ignored: the cache is an optimisation.
pub(crate) fn save(path: &Option<PathBuf>, data: &[u8]) {
    let Some(path) = path else { return };
    if data.is_empty() {
        return;
    }
    let Some(dir) = path.parent() else { return };
    if std::fs::create_dir_all(dir).is_err() {
        return;
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    if std::fs::write(&tmp, data).is_ok() && std::fs::rename(&tmp, path).is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
}
