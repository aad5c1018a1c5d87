//! Per-device map from a kernel artifact to its compiled pipeline. Every dispatch looks its
//! kernel up here first, so lowering and compiling (naga module → WGSL or SPIR-V → driver
//! pipeline) happen once per device and kernel. The key is the artifact name plus a hash
//! of everything that shapes the pipeline (for a compiled kernel, its compilation's id),
//! so two specialisations that share a name but differ in code never alias.

use std::collections::hash_map::DefaultHasher;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex};

use crate::{hash64, KernelArtifact, KernelCode, Result};

/// Which of a hand-written artifact's two codes a backend consumes; only that one goes into
/// the key, so a change to the other backend's code does not invalidate this backend's
/// pipeline.
#[derive(Clone, Copy)]
pub(crate) enum Code {
    Wgsl,
    Spirv,
}

fn code_hash(kernel: &KernelArtifact, code: Code) -> u64 {
    let mut rest = DefaultHasher::new();
    match (&kernel.code, code) {
        (KernelCode::Compiled(k), _) => (0u8, k.id).hash(&mut rest),
        (
            KernelCode::Shaders {
                wgsl, entry_point, ..
            },
            Code::Wgsl,
        ) => (1u8, hash64(1, wgsl.as_bytes()), entry_point).hash(&mut rest),
        (
            KernelCode::Shaders {
                spirv, entry_point, ..
            },
            Code::Spirv,
        ) => (2u8, hash64(2, bytemuck::cast_slice(spirv)), entry_point).hash(&mut rest),
    }
    kernel.bindings.hash(&mut rest);
    kernel.features.hash(&mut rest);
    rest.finish()
}

/// One key's pipeline, filled by the first thread that asks for it.
type Slot<P> = Arc<Mutex<Option<Arc<P>>>>;

pub(crate) struct PipelineCache<P> {
    code: Code,
    map: Mutex<HashMap<(String, u64), Slot<P>>>,
}

impl<P> PipelineCache<P> {
    pub(crate) fn new(code: Code) -> Self {
        PipelineCache {
            code,
            map: Mutex::new(HashMap::new()),
        }
    }

    /// Returns the cached pipeline or builds it with `create`. Only this key's slot is
    /// locked while compiling: two threads asking for the same new kernel compile it once,
    /// and different kernels compile at the same time (a renderer prepares its kernels on
    /// one thread each, and drivers compile pipelines in parallel).
    pub(crate) fn get_or_create(
        &self,
        kernel: &KernelArtifact,
        create: impl FnOnce() -> Result<P>,
    ) -> Result<Arc<P>> {
        let key = (kernel.name.clone(), code_hash(kernel, self.code));
        let slot = self
            .map
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .entry(key)
            .or_default()
            .clone();
        let mut slot = slot.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = &*slot {
            return Ok(p.clone());
        }
        let p = Arc::new(create()?);
        *slot = Some(p.clone());
        Ok(p)
    }

    pub(crate) fn len(&self) -> usize {
        let map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        map.values()
            .filter(|s| s.lock().unwrap_or_else(|e| e.into_inner()).is_some())
            .count()
    }

    /// Empties the cache so the owner can destroy the pipelines before its device.
    pub(crate) fn drain(&self) -> Vec<Arc<P>> {
        self.map
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .drain()
            .filter_map(|(_, s)| s.lock().unwrap_or_else(|e| e.into_inner()).take())
            .collect()
    }
}
