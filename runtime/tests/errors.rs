//! User mistakes must come back as clear `RuntimeError`s (naming kernel and parameter),
//! never as panics, driver crashes or silent garbage.

mod common;

use cohort_runtime::{
    BackendKind, BindingKind, Device, Dispatch, GpuBuffer, KernelCode, KernelFeatures, RuntimeError,
};
use common::*;

fn two_arg_kernel() -> cohort_runtime::KernelArtifact {
    artifact(
        "copy_pair",
        "@group(0) @binding(0) var<storage, read> src: array<u32>;
@group(0) @binding(1) var<storage, read_write> dst: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x < arrayLength(&dst)) { dst[gid.x] = src[gid.x]; }
}",
        vec![
            binding(0, BindingKind::StorageRead, "src"),
            binding(1, BindingKind::StorageReadWrite, "dst"),
        ],
        [64, 1, 1],
        KernelFeatures::default(),
    )
}

#[test]
fn wrong_argument_count_names_kernel_and_parameters() {
    let kernel = two_arg_kernel();
    for dev in devices() {
        let a: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let b: GpuBuffer<u32> = dev.alloc(64).unwrap();
        for args in [vec![a.arg()], vec![a.arg(), a.arg(), a.arg()], vec![]] {
            let err = dev
                .dispatch(&kernel, &args, Dispatch::Groups([1, 1, 1]))
                .unwrap_err();
            assert!(
                matches!(err, RuntimeError::ArgumentCount { expected: 2, .. }),
                "{err:?}"
            );
            let msg = err.to_string();
            assert!(
                msg.contains("copy_pair") && msg.contains("src, dst"),
                "{msg}"
            );
            assert!(msg.contains(&format!("given {}", args.len())), "{msg}");
        }
        // The batch path checks the same way and stays usable after an error.
        let mut batch = dev.batch();
        assert!(batch
            .dispatch(&kernel, &[a.arg()], Dispatch::Groups([1, 1, 1]))
            .is_err());
        assert!(batch.is_empty());
        batch
            .dispatch(&kernel, &[a.arg(), b.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap();
        assert_eq!(batch.submit().unwrap().len(), 1);
    }
}

#[test]
fn writable_aliasing_is_rejected_on_both_backends() {
    let kernel = two_arg_kernel();
    let both_read = artifact(
        "sum_pair",
        "@group(0) @binding(0) var<storage, read> p: array<u32>;
@group(0) @binding(1) var<storage, read> q: array<u32>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x < arrayLength(&out)) { out[gid.x] = p[gid.x] + q[gid.x]; }
}",
        vec![
            binding(0, BindingKind::StorageRead, "p"),
            binding(1, BindingKind::StorageRead, "q"),
            binding(2, BindingKind::StorageReadWrite, "out"),
        ],
        [64, 1, 1],
        KernelFeatures::default(),
    );
    for dev in devices() {
        let a = dev.upload(&[5u32; 64]).unwrap();
        let out: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let err = dev
            .dispatch(&kernel, &[a.arg(), a.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap_err();
        assert!(
            matches!(err, RuntimeError::AliasedArguments { .. }),
            "{err:?}"
        );
        let msg = err.to_string();
        assert!(msg.contains("`src`") && msg.contains("`dst`"), "{msg}");
        // Read-only aliasing is fine.
        dev.dispatch(
            &both_read,
            &[a.arg(), a.arg(), out.arg()],
            Dispatch::Groups([1, 1, 1]),
        )
        .unwrap();
        assert_eq!(dev.read(&out).unwrap(), vec![10; 64]);
        assert_validation_clean(&dev);
    }
}

#[test]
fn too_many_workgroups_is_rejected_per_dimension() {
    let kernel = affine_kernel("wide", 1, 1);
    for dev in devices() {
        let buf: GpuBuffer<u32> = dev.alloc(16).unwrap();
        let max = dev.info().max_workgroups_per_dim;
        // No driver allows 2^32 - 1 groups in any dimension; wgpu allows exactly `max`
        // in each (Vulkan drivers may allow more in x than in y and z).
        let mut cases = vec![[u32::MAX, 1, 1], [1, u32::MAX, 1], [1, 1, u32::MAX]];
        if dev.info().backend == BackendKind::Wgpu {
            cases.extend([[max + 1, 1, 1], [1, max + 1, 1], [1, 1, max + 1]]);
        }
        for groups in cases {
            let err = dev
                .dispatch(&kernel, &[buf.arg()], Dispatch::Groups(groups))
                .unwrap_err();
            assert!(
                matches!(err, RuntimeError::TooManyWorkgroups { .. }),
                "{err:?}"
            );
            let msg = err.to_string();
            assert!(msg.contains("wide") && msg.contains("workgroups"), "{msg}");
        }
        // At the limit it is accepted (every group stores the same constant: no races).
        let store7 = affine_kernel("wide_ok", 0, 7);
        dev.dispatch(
            &store7,
            &[buf.arg()],
            Dispatch::Groups([1, max.min(65535), 1]),
        )
        .unwrap();
        assert_eq!(dev.read(&buf).unwrap(), vec![7; 16]);
        assert_validation_clean(&dev);
    }
}

#[test]
fn indirect_arguments_out_of_range() {
    let kernel = affine_kernel("indirect_probe", 1, 1);
    for dev in devices() {
        let buf: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let args = dev.upload(&[1u32, 1, 1, 1]).unwrap();
        let err = dev
            .dispatch(
                &kernel,
                &[buf.arg()],
                Dispatch::Indirect {
                    args: &args,
                    offset_elems: 2,
                },
            )
            .unwrap_err();
        assert!(
            matches!(
                err,
                RuntimeError::IndirectOutOfRange {
                    offset_elems: 2,
                    len: 4,
                    ..
                }
            ),
            "{err:?}"
        );
        dev.dispatch(
            &kernel,
            &[buf.arg()],
            Dispatch::Indirect {
                args: &args,
                offset_elems: 1,
            },
        )
        .unwrap();
        assert_eq!(dev.read(&buf).unwrap(), vec![1; 64]);
    }
}

#[test]
fn buffers_of_other_devices_are_rejected() {
    let kernel = two_arg_kernel();
    let devs = devices();
    for dev in &devs {
        let other = Device::new(dev.info().backend).unwrap();
        let mine: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let theirs: GpuBuffer<u32> = other.alloc(64).unwrap();
        let err = dev
            .dispatch(
                &kernel,
                &[mine.arg(), theirs.arg()],
                Dispatch::Groups([1, 1, 1]),
            )
            .unwrap_err();
        assert!(matches!(err, RuntimeError::ForeignBuffer { .. }), "{err:?}");
        assert!(err.to_string().contains("`dst`"), "{err}");
        assert!(matches!(
            dev.read(&theirs),
            Err(RuntimeError::BufferNotOnDevice { op: "read" })
        ));
        assert!(dev.write(&theirs, 0, &[1]).is_err());
        let mine2: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let err = dev
            .dispatch(
                &kernel,
                &[mine.arg(), mine2.arg()],
                Dispatch::Indirect {
                    args: &theirs,
                    offset_elems: 0,
                },
            )
            .unwrap_err();
        assert!(matches!(err, RuntimeError::ForeignBuffer { .. }), "{err:?}");
    }
    // Across backends too.
    if let [a, b] = &devs[..] {
        let from_b: GpuBuffer<u32> = b.alloc(64).unwrap();
        let from_a: GpuBuffer<u32> = a.alloc(64).unwrap();
        let err = a
            .dispatch(
                &kernel,
                &[from_b.arg(), from_a.arg()],
                Dispatch::Groups([1, 1, 1]),
            )
            .unwrap_err();
        assert!(err.to_string().contains("`src`"), "{err}");
    }
}

#[test]
fn write_out_of_range() {
    for dev in devices() {
        let buf: GpuBuffer<u32> = dev.alloc(8).unwrap();
        let err = dev.write(&buf, 6, &[1, 2, 3]).unwrap_err();
        assert!(
            matches!(
                err,
                RuntimeError::WriteOutOfRange {
                    first: 6,
                    count: 3,
                    len: 8
                }
            ),
            "{err:?}"
        );
        assert!(dev.write(&buf, usize::MAX, &[1]).is_err());
        assert_eq!(dev.read(&buf).unwrap(), vec![0; 8]);
    }
}

#[test]
fn broken_shader_code_is_an_error_not_a_panic() {
    for dev in devices() {
        let mut kernel = affine_kernel("broken", 1, 1);
        let KernelCode::Shaders { wgsl, spirv, .. } = &mut kernel.code else {
            unreachable!("a hand-written kernel")
        };
        match dev.info().backend {
            BackendKind::Wgpu => *wgsl = "@compute @workgroup_size(64) fn main( {".into(),
            BackendKind::Vulkan => spirv.clear(),
            BackendKind::Cpu => unreachable!("these tests run the GPU backends"),
        }
        let buf: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let err = dev
            .dispatch(&kernel, &[buf.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap_err();
        assert!(
            matches!(err, RuntimeError::ShaderCompilation { .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains("broken"), "{err}");
        println!("{}: {err}", dev.info().backend);
        // A well-typed WGSL that fails validation (writing a read-only buffer).
        if dev.info().backend == BackendKind::Wgpu {
            let mut k = affine_kernel("bad_access", 1, 1);
            if let KernelCode::Shaders { wgsl, .. } = &mut k.code {
                *wgsl = wgsl.replace("read_write", "read");
            }
            let err = dev
                .dispatch(&k, &[buf.arg()], Dispatch::Groups([1, 1, 1]))
                .unwrap_err();
            assert!(
                matches!(err, RuntimeError::ShaderCompilation { .. }),
                "{err:?}"
            );
        }
        // The device is still fine afterwards.
        dev.dispatch(
            &affine_kernel("ok", 1, 1),
            &[buf.arg()],
            Dispatch::Groups([1, 1, 1]),
        )
        .unwrap();
        assert_eq!(dev.read(&buf).unwrap(), vec![1; 64]);
        assert!(dev
            .take_validation_messages()
            .iter()
            .all(|m| !m.contains("ok")));
    }
}

#[test]
fn unsatisfiable_subgroup_size_is_an_error() {
    let wgsl = "@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(subgroup_size) sg: u32) {
    out[gid.x] = sg;
}";
    for dev in devices() {
        let too_big = dev.info().subgroup_size_max * 2;
        let kernel = artifact(
            "pinned",
            wgsl,
            vec![binding(0, BindingKind::StorageReadWrite, "out")],
            [64, 1, 1],
            KernelFeatures {
                subgroups: true,
                required_subgroup_size: Some(too_big),
                ..Default::default()
            },
        );
        let buf: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let err = dev
            .dispatch(&kernel, &[buf.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap_err();
        assert!(
            matches!(err, RuntimeError::SubgroupSize { required, .. } if required == too_big),
            "{err:?}"
        );
        assert!(err.to_string().contains("pinned"), "{err}");
        assert_eq!(dev.cached_pipeline_count(), 0);
    }
}

#[test]
fn oversized_storage_binding_is_rejected() {
    let kernel = affine_kernel("huge", 1, 1);
    for dev in devices() {
        let max = dev.info().max_storage_buffer_binding_size;
        if max > 512 << 20 {
            continue; // Too large to allocate casually in a test.
        }
        let buf: GpuBuffer<u32> = dev.alloc((max / 4 + 1) as usize).unwrap();
        let err = dev
            .dispatch(&kernel, &[buf.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap_err();
        assert!(
            matches!(err, RuntimeError::BindingTooLarge { .. }),
            "{err:?}"
        );
        assert!(err.to_string().contains("`data`"), "{err}");
    }
}

#[test]
fn messages_and_names() {
    let err = RuntimeError::NoAdapter {
        backend: BackendKind::Vulkan,
        detail: "x".into(),
    };
    let msg = err.to_string();
    assert!(
        msg.starts_with("no Vulkan adapter found for the vulkan backend: x."),
        "{msg}"
    );
    assert!(msg.contains("apt-get install mesa-vulkan-drivers"), "{msg}");
    assert_eq!(BackendKind::parse("wgpu"), Some(BackendKind::Wgpu));
    assert_eq!(BackendKind::parse("vulkan"), Some(BackendKind::Vulkan));
    assert_eq!(BackendKind::parse("ash"), Some(BackendKind::Vulkan));
    assert_eq!(BackendKind::parse("metal"), None);
    for kind in [BackendKind::Wgpu, BackendKind::Vulkan] {
        assert_eq!(BackendKind::parse(kind.name()), Some(kind));
    }
}

/// The CPU backend runs a kernel's Rust function; a kernel given only as shader code has
/// none, and is refused with an error naming it rather than run wrongly.
#[test]
fn the_cpu_backend_refuses_kernels_without_a_host_form() {
    let dev = Device::new(BackendKind::Cpu).unwrap();
    let kernel = affine_kernel("shader_only", 2, 1);
    let buf: GpuBuffer<u32> = dev.alloc(64).unwrap();
    let err = dev
        .dispatch(&kernel, &[buf.arg()], Dispatch::Groups([1, 1, 1]))
        .unwrap_err();
    assert!(
        matches!(
            err,
            RuntimeError::MissingFeature {
                backend: BackendKind::Cpu,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("shader_only"), "{err}");
}
