//! Glue between a compiled kernel and the runtime, used by the launch functions that
//! `#[kernel]` generates: the artifact cache, grid sizing and the error type.

use std::any::TypeId;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use crate::emit::{CompileError, HostEntry};
use crate::ir::kernel::BuiltKernel;
use crate::spec::{KernelInfo, Spec};
use cohort_runtime::{Dispatch, GpuBuffer, KernelArtifact, RuntimeError};

/// Why a launch failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error(transparent)]
    Compile(#[from] CompileError),
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
}
pub type Result<T> = std::result::Result<T, Error>;

type CacheKey = (TypeId, Spec);
fn cache() -> &'static Mutex<HashMap<CacheKey, Arc<KernelArtifact>>> {
    static CACHE: OnceLock<Mutex<HashMap<CacheKey, Arc<KernelArtifact>>>> = OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// The compiled artifact of kernel `K` (a key type unique to the kernel and its generic
/// arguments) for `spec`, built and emitted on first use, with the kernel's host form.
pub fn artifact<K: 'static>(
    info: &'static KernelInfo,
    spec: Spec,
    build: impl FnOnce(&Spec) -> BuiltKernel,
    host: HostEntry,
) -> std::result::Result<Arc<KernelArtifact>, CompileError> {
    let key = (TypeId::of::<K>(), spec);
    if let Some(a) = cache().lock().unwrap().get(&key) {
        return Ok(a.clone());
    }
    let built = build(&spec);
    let name = format!("{}__{}{}", info.name, spec.suffix(), generic_suffix::<K>());
    let art = Arc::new(crate::emit::compile_with_host(&built, name, Some(host))?);
    cache().lock().unwrap().insert(key, art.clone());
    Ok(art)
}

fn generic_suffix<K>() -> String {
    let full = std::any::type_name::<K>();
    match full.find('<') {
        Some(i) => format!(
            "__{}",
            full[i..]
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect::<String>()
        ),
        None => String::new(),
    }
}

/// How many invocations to launch.
pub enum Grid<'a> {
    /// At least this many invocations (rounded up to whole workgroups); kernels check
    /// their own bounds, as in CUDA.
    Threads(u32),
    /// Exactly these workgroup counts.
    Groups([u32; 3]),
    /// Workgroup counts read by the GPU from a buffer (3 × u32 at `offset_elems`).
    Indirect {
        args: &'a GpuBuffer<u32>,
        offset_elems: usize,
    },
}
impl From<u32> for Grid<'_> {
    fn from(n: u32) -> Self {
        Grid::Threads(n)
    }
}
impl From<usize> for Grid<'_> {
    fn from(n: usize) -> Self {
        Grid::Threads(u32::try_from(n).expect("more than 2^32 invocations"))
    }
}

/// Workgroup counts for `threads` invocations: rows of at most `max_x` workgroups, so
/// that dispatches larger than the per-dimension limit still work (kernels see a linear
/// `global_index`).
pub fn groups_for_threads(threads: u32, workgroup_size: u32, max_x: u32) -> [u32; 3] {
    let groups = threads.div_ceil(workgroup_size).max(1);
    if groups <= max_x {
        [groups, 1, 1]
    } else {
        [max_x, groups.div_ceil(max_x), 1]
    }
}

pub fn dispatch_of<'a>(grid: Grid<'a>, spec: &Spec, max_x: u32) -> Dispatch<'a> {
    match grid {
        Grid::Threads(n) => Dispatch::Groups(groups_for_threads(n, spec.workgroup_size, max_x)),
        Grid::Groups(g) => Dispatch::Groups(g),
        Grid::Indirect { args, offset_elems } => Dispatch::Indirect { args, offset_elems },
    }
}
