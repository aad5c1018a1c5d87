//! Shared test helpers: turn hand-written WGSL into a `KernelArtifact` the way the compiler
//! would (WGSL for wgpu, SPIR-V through naga for Vulkan) and open every available backend.
#![allow(dead_code)]

use cohort_runtime::{
    BackendKind, Binding, BindingKind, Device, KernelArtifact, KernelCode, KernelFeatures,
};

pub const BACKENDS: [BackendKind; 2] = [BackendKind::Vulkan, BackendKind::Wgpu];

/// One device per backend that this machine has (skipping with a message otherwise).
pub fn devices() -> Vec<Device> {
    BACKENDS
        .iter()
        .filter_map(|&kind| Device::for_tests(kind))
        .collect()
}

pub fn binding(binding: u32, kind: BindingKind, name: &str) -> Binding {
    Binding {
        binding,
        kind,
        name: name.to_string(),
    }
}

/// Compiles `wgsl` (entry point `main`) to SPIR-V 1.3. The artifact keeps the WGSL as
/// written, so a test can check what the wgpu backend does with it.
pub fn artifact(
    name: &str,
    wgsl: &str,
    bindings: Vec<Binding>,
    workgroup_size: [u32; 3],
    features: KernelFeatures,
) -> KernelArtifact {
    // naga rejects `enable subgroups;` (see the wgpu backend); compile without it.
    let for_naga: String = wgsl
        .lines()
        .filter(|l| l.trim() != "enable subgroups;")
        .collect::<Vec<_>>()
        .join("\n");
    let module = naga::front::wgsl::parse_str(&for_naga)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&for_naga)));
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {:?}", e.into_inner()));
    let options = naga::back::spv::Options {
        lang_version: (1, 3),
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: "main".into(),
    };
    let spirv = naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    KernelArtifact {
        name: name.to_string(),
        code: KernelCode::Shaders {
            wgsl: wgsl.to_string(),
            spirv,
            entry_point: "main".to_string(),
        },
        workgroup_size,
        bindings,
        features,
        host: None,
        prints: Vec::new(),
    }
}

/// Fails the test if the Vulkan validation layer complained about anything this device did.
pub fn assert_validation_clean(dev: &Device) {
    let msgs = dev.take_validation_messages();
    assert!(
        msgs.is_empty(),
        "{:?} validation messages:\n{}",
        dev,
        msgs.join("\n")
    );
}

/// `out[i] = out[i] * mul + add` for i < arrayLength(out).
pub fn affine_kernel(name: &str, mul: u32, add: u32) -> KernelArtifact {
    let wgsl = format!(
        "@group(0) @binding(0) var<storage, read_write> data: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{
    let i = gid.x;
    if (i < arrayLength(&data)) {{
        data[i] = data[i] * {mul}u + {add}u;
    }}
}}"
    );
    artifact(
        name,
        &wgsl,
        vec![binding(0, BindingKind::StorageReadWrite, "data")],
        [64, 1, 1],
        KernelFeatures::default(),
    )
}

pub fn groups_for(n: usize, wg: u32) -> [u32; 3] {
    [(n as u32).div_ceil(wg), 1, 1]
}
