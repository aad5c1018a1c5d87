//! GPU tests that run on every available backend (lavapipe in CI): buffers, kernels,
//! indirect dispatch, batches with timestamps, uniforms, the pipeline cache, subgroups.

mod common;

use cohort_runtime::{BackendKind, BindingKind, Device, Dispatch, GpuBuffer, KernelFeatures};
use common::*;

#[test]
fn device_info_is_consistent() {
    for dev in devices() {
        let info = dev.info();
        assert!(info.subgroup_size_min >= 1, "{info:?}");
        assert!(info.subgroup_size_min <= info.subgroup_size_max, "{info:?}");
        assert!(
            (info.subgroup_size_min..=info.subgroup_size_max).contains(&info.subgroup_size),
            "{info:?}"
        );
        assert!(info.max_workgroups_per_dim >= 65535, "{info:?}");
        assert!(info.max_storage_buffer_binding_size >= 1 << 27, "{info:?}");
        assert!(!info.adapter_name.is_empty());
        println!("{info:?}");
    }
}

#[test]
fn upload_read_round_trip_of_several_sizes() {
    for dev in devices() {
        for len in [0usize, 1, 3, 4, 5, 17, 1000, 65_537, 1 << 20] {
            let data: Vec<u32> = (0..len as u32)
                .map(|i| i.wrapping_mul(2_654_435_761))
                .collect();
            let buf = dev.upload(&data).unwrap();
            assert_eq!(buf.len(), len);
            assert_eq!(buf.size_bytes(), 4 * len as u64);
            assert_eq!(dev.read(&buf).unwrap(), data, "{dev:?} len {len}");

            let floats: Vec<f32> = (0..len).map(|i| i as f32 * -0.25).collect();
            let fbuf = dev.upload(&floats).unwrap();
            assert_eq!(dev.read(&fbuf).unwrap(), floats, "{dev:?} f32 len {len}");
        }
        assert_validation_clean(&dev);
    }
}

#[test]
fn alloc_is_zeroed_and_write_lands_at_offset() {
    for dev in devices() {
        for len in [0usize, 1, 7, 4096] {
            let buf: GpuBuffer<u32> = dev.alloc(len).unwrap();
            assert_eq!(dev.read(&buf).unwrap(), vec![0; len], "{dev:?}");
        }
        // Allocations are recycled by the memory allocator: a fresh one must still read 0
        // after an earlier buffer of the same size held data and was dropped.
        drop(dev.upload(&vec![0xdead_beef_u32; 300]).unwrap());
        let buf: GpuBuffer<u32> = dev.alloc(300).unwrap();
        assert!(dev.read(&buf).unwrap().iter().all(|&v| v == 0), "{dev:?}");

        dev.write(&buf, 10, &[1, 2, 3]).unwrap();
        dev.write(&buf, 299, &[9]).unwrap();
        dev.write(&buf, 300, &[]).unwrap();
        let back = dev.read(&buf).unwrap();
        assert_eq!(&back[9..14], &[0, 1, 2, 3, 0]);
        assert_eq!(back[299], 9);
        assert_eq!(back.iter().filter(|&&v| v != 0).count(), 4);
        assert_validation_clean(&dev);
    }
}

/// More upload data than the Vulkan backend lets wait in staging memory for its copies
/// (256 MiB; beyond it, `create_buffer` submits at once): the uploads before that
/// submission, the one that triggers it, the zeroed allocations queued among them and the
/// upload after it all read back as written, on every backend.
#[test]
fn uploads_beyond_the_staging_limit_all_land() {
    // Five uploads of 52 MiB pass the limit; the sixth waits for the reads.
    const LEN: u32 = 13 << 20;
    // One value per upload (a fill and a compare that stay fast in a debug build), its
    // ends marked so that a copy at an offset or of another length shows.
    let data = |k: u32| -> Vec<u32> {
        let mut v = vec![0x5EED_0000 | k; LEN as usize];
        v[0] = k;
        v[LEN as usize - 1] = !k;
        v
    };
    for dev in devices() {
        let mut uploaded = Vec::new();
        let mut zeroed = Vec::new();
        for k in 0..6 {
            uploaded.push(dev.upload(&data(k)).unwrap());
            let z: GpuBuffer<u32> = dev.alloc(1000).unwrap();
            zeroed.push(z);
        }
        for (k, buf) in uploaded.iter().enumerate() {
            assert!(
                dev.read(buf).unwrap() == data(k as u32),
                "{dev:?}: upload {k} did not land"
            );
        }
        for z in &zeroed {
            assert!(dev.read(z).unwrap().iter().all(|&v| v == 0), "{dev:?}");
        }
        assert_validation_clean(&dev);
    }
}

/// A `Device` is shared by threads (the renderer uploads a scene's arrays and allocates its
/// path state beside creating pipelines): uploads, allocations, reads and pipeline creation
/// from several threads at once must each do what they do alone.
#[test]
fn threads_share_a_device() {
    for dev in devices() {
        std::thread::scope(|t| {
            for k in 0..6u32 {
                let dev = &dev;
                t.spawn(move || {
                    for round in 0..8u32 {
                        let data: Vec<u32> =
                            (0..1000 + 37 * k).map(|i| i ^ (k << 16) ^ round).collect();
                        let up = dev.upload(&data).unwrap();
                        let zero: GpuBuffer<u32> = dev.alloc(513 + k as usize).unwrap();
                        assert_eq!(dev.read(&up).unwrap(), data, "{dev:?} thread {k}");
                        assert!(dev.read(&zero).unwrap().iter().all(|&v| v == 0), "{dev:?}");
                    }
                });
            }
            let dev = &dev;
            t.spawn(move || {
                let y = run_saxpy(dev, 2.0, &[1.0, 2.0, 3.0], &[0.5, 0.5, 0.5]);
                assert_eq!(y, vec![2.5, 4.5, 6.5], "{dev:?}");
            });
        });
        assert_validation_clean(&dev);
    }
}

const SAXPY: &str = "
struct Params { a: f32, n: u32 }
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> x: array<f32>;
@group(0) @binding(2) var<storage, read_write> y: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i < params.n) {
        y[i] = params.a * x[i] + y[i];
    }
}";

fn saxpy_kernel() -> cohort_runtime::KernelArtifact {
    artifact(
        "saxpy",
        SAXPY,
        vec![
            binding(0, BindingKind::Uniform, "params"),
            binding(1, BindingKind::StorageRead, "x"),
            binding(2, BindingKind::StorageReadWrite, "y"),
        ],
        [64, 1, 1],
        KernelFeatures::default(),
    )
}

fn run_saxpy(dev: &Device, a: f32, x: &[f32], y: &[f32]) -> Vec<f32> {
    let kernel = saxpy_kernel();
    // 8 bytes of parameters: bound as a 16-byte uniform block.
    let params = dev.upload(&[a.to_bits(), x.len() as u32]).unwrap();
    let xb = dev.upload(x).unwrap();
    let yb = dev.upload(y).unwrap();
    dev.dispatch(
        &kernel,
        &[params.arg(), xb.arg(), yb.arg()],
        Dispatch::Groups(groups_for(x.len(), 64)),
    )
    .unwrap();
    dev.read(&yb).unwrap()
}

#[test]
fn saxpy_matches_host_and_is_identical_across_backends() {
    let n = 100_003;
    let x: Vec<f32> = (0..n).map(|i| (i as f32).sin()).collect();
    let y: Vec<f32> = (0..n).map(|i| (i % 97) as f32 * 0.5).collect();
    let a = 1.75f32;
    let results: Vec<(BackendKind, Vec<f32>)> = devices()
        .iter()
        .map(|dev| {
            let r = run_saxpy(dev, a, &x, &y);
            assert_validation_clean(dev);
            (dev.info().backend, r)
        })
        .collect();
    for (backend, r) in &results {
        for i in 0..n {
            let want = a * x[i] + y[i];
            assert!(
                (r[i] - want).abs() <= 1e-5 * want.abs().max(1.0),
                "{backend:?} y[{i}] = {} != {want}",
                r[i]
            );
        }
    }
    if let [(_, r0), (_, r1)] = &results[..] {
        let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(r0), bits(r1), "backends disagree");
    }
}

#[test]
fn empty_buffers_bind_and_zero_groups_dispatch() {
    for dev in devices() {
        let r = run_saxpy(&dev, 2.0, &[], &[]);
        assert!(r.is_empty());
        assert_validation_clean(&dev);
    }
}

#[test]
fn uniform_binding_feeds_the_kernel() {
    // A 12-byte uniform (rounded to 16 when bound) selects what every invocation writes.
    let wgsl = "
struct U { scale: u32, offset: u32, count: u32 }
@group(0) @binding(0) var<uniform> u: U;
@group(0) @binding(1) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(32)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x < u.count) {
        out[gid.x] = gid.x * u.scale + u.offset;
    }
}";
    let kernel = artifact(
        "uniform_affine",
        wgsl,
        vec![
            binding(0, BindingKind::Uniform, "u"),
            binding(1, BindingKind::StorageReadWrite, "out"),
        ],
        [32, 1, 1],
        KernelFeatures::default(),
    );
    for dev in devices() {
        let out: GpuBuffer<u32> = dev.alloc(100).unwrap();
        let u = dev.upload(&[3u32, 11, 90]).unwrap();
        assert_eq!(u.size_bytes(), 12);
        dev.dispatch(&kernel, &[u.arg(), out.arg()], Dispatch::Groups([4, 1, 1]))
            .unwrap();
        let got = dev.read(&out).unwrap();
        let want: Vec<u32> = (0..100)
            .map(|i| if i < 90 { i * 3 + 11 } else { 0 })
            .collect();
        assert_eq!(got, want, "{dev:?}");
        assert_validation_clean(&dev);
    }
}

const FILL_INDEX: &str = "
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@group(0) @binding(1) var<storage, read_write> meta_out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) ng: vec3<u32>) {
    if (gid.x == 0u) {
        meta_out[0] = arrayLength(&out);
        meta_out[1] = ng.x;
    }
    if (gid.x < arrayLength(&out)) {
        out[gid.x] = gid.x * 3u + 1u;
    }
}";

const MAKE_ARGS: &str = "
@group(0) @binding(0) var<storage, read> n: array<u32>;
@group(0) @binding(1) var<storage, read_write> args: array<u32>;
@compute @workgroup_size(1)
fn main() {
    args[3] = (n[0] + 63u) / 64u;
    args[4] = 1u;
    args[5] = 1u;
}";

#[test]
fn indirect_dispatch_uploaded_and_gpu_computed() {
    let fill = artifact(
        "fill_index",
        FILL_INDEX,
        vec![
            binding(0, BindingKind::StorageReadWrite, "out"),
            binding(1, BindingKind::StorageReadWrite, "meta_out"),
        ],
        [64, 1, 1],
        KernelFeatures::default(),
    );
    let make_args = artifact(
        "make_args",
        MAKE_ARGS,
        vec![
            binding(0, BindingKind::StorageRead, "n"),
            binding(1, BindingKind::StorageReadWrite, "args"),
        ],
        [1, 1, 1],
        KernelFeatures::default(),
    );
    let want = |n: u32| (0..n).map(|i| i * 3 + 1).collect::<Vec<u32>>();
    for dev in devices() {
        // Counts read from the host-uploaded buffer at element 3 (elements 0..3 are decoys
        // that would launch far too many groups if the offset were ignored).
        let n = 1001usize;
        let out: GpuBuffer<u32> = dev.alloc(n).unwrap();
        let meta_out: GpuBuffer<u32> = dev.alloc(2).unwrap();
        let args = dev.upload(&[9999u32, 9999, 9999, 16, 1, 1]).unwrap();
        dev.dispatch(
            &fill,
            &[out.arg(), meta_out.arg()],
            Dispatch::Indirect {
                args: &args,
                offset_elems: 3,
            },
        )
        .unwrap();
        assert_eq!(dev.read(&out).unwrap(), want(n as u32), "{dev:?}");
        // arrayLength sees the logical length, not the padded allocation.
        assert_eq!(dev.read(&meta_out).unwrap(), vec![n as u32, 16], "{dev:?}");

        // Counts computed by a previous dispatch in the same batch.
        let n = 3000usize;
        let out: GpuBuffer<u32> = dev.alloc(n).unwrap();
        let count = dev.upload(&[n as u32]).unwrap();
        let args: GpuBuffer<u32> = dev.alloc(6).unwrap();
        let mut batch = dev.batch();
        batch
            .dispatch(
                &make_args,
                &[count.arg(), args.arg()],
                Dispatch::Groups([1, 1, 1]),
            )
            .unwrap();
        batch
            .dispatch(
                &fill,
                &[out.arg(), meta_out.arg()],
                Dispatch::Indirect {
                    args: &args,
                    offset_elems: 3,
                },
            )
            .unwrap();
        assert_eq!(batch.submit().unwrap().len(), 2);
        assert_eq!(dev.read(&out).unwrap(), want(n as u32), "{dev:?}");
        assert_eq!(dev.read(&args).unwrap(), vec![0, 0, 0, 47, 1, 1]);
        assert_eq!(dev.read(&meta_out).unwrap(), vec![n as u32, 47], "{dev:?}");
        assert_validation_clean(&dev);
    }
}

#[test]
fn batch_runs_in_order_with_timings() {
    let inc = affine_kernel("inc", 1, 1);
    let double = affine_kernel("double", 2, 0);
    for dev in devices() {
        let n = 1 << 16;
        let data: GpuBuffer<u32> = dev.alloc(n).unwrap();
        let g = Dispatch::Groups(groups_for(n, 64));
        let mut batch = dev.batch();
        assert!(batch.is_empty());
        // Non-commuting sequence: 0 → 1 → 2 → 3 → 6 → 12.
        for k in [&inc, &double, &inc, &double, &double] {
            batch.dispatch(k, &[data.arg()], g).unwrap();
        }
        assert_eq!(batch.len(), 5);
        let stats = batch.submit().unwrap();
        assert_eq!(stats.len(), 5);
        assert!(dev.read(&data).unwrap().iter().all(|&v| v == 12), "{dev:?}");
        if dev.info().timestamps {
            let times: Vec<u64> = stats
                .iter()
                .map(|s| s.gpu_time_ns.expect("timestamps on"))
                .collect();
            assert!(
                times.iter().all(|&t| t < 10_000_000_000),
                "{dev:?} {times:?}"
            );
            assert!(times.iter().sum::<u64>() > 0, "{dev:?} {times:?}");
            let single = dev.dispatch(&inc, &[data.arg()], g).unwrap();
            assert!(single.gpu_time_ns.is_some());
            println!(
                "{:?}: batch times {times:?} ns, single {:?}",
                dev, single.gpu_time_ns
            );
        } else {
            assert!(stats.iter().all(|s| s.gpu_time_ns.is_none()));
        }
        assert!(dev.batch().submit().unwrap().is_empty());
        assert_validation_clean(&dev);
    }
}

/// The Vulkan backend records a new buffer's zero fill or upload copy into the next
/// submission rather than submitting it alone: it must still land before a batch that is
/// the first to use the buffer, and before a write to it. The memory handed out here held
/// data before, so a fill that is missing or comes too late shows.
#[test]
fn new_buffers_are_ready_for_the_first_batch_and_write() {
    let inc = affine_kernel("inc", 1, 1);
    let n = 4096usize;
    for dev in devices() {
        let old = dev.upload(&vec![0xdead_beef_u32; n]).unwrap();
        assert_eq!(dev.read(&old).unwrap()[n - 1], 0xdead_beef, "{dev:?}");
        drop(old);
        let zeroed: GpuBuffer<u32> = dev.alloc(n).unwrap();
        let data: Vec<u32> = (0..n as u32).map(|i| i * 3).collect();
        let uploaded = dev.upload(&data).unwrap();
        let mut batch = dev.batch();
        for b in [&zeroed, &uploaded] {
            batch
                .dispatch(&inc, &[b.arg()], Dispatch::Groups(groups_for(n, 64)))
                .unwrap();
        }
        batch.submit().unwrap();
        let z = dev.read(&zeroed).unwrap();
        assert!(z.iter().all(|&v| v == 1), "{dev:?}: {:?}", &z[..4]);
        let u = dev.read(&uploaded).unwrap();
        let wrong = (0..n).find(|&i| u[i] != data[i] + 1);
        assert_eq!(wrong, None, "{dev:?}: {:?}", &u[..4]);
        drop((zeroed, uploaded));
        let written: GpuBuffer<u32> = dev.alloc(n).unwrap();
        dev.write(&written, 5, &[7, 8]).unwrap();
        let back = dev.read(&written).unwrap();
        assert_eq!(&back[4..8], &[0, 7, 8, 0], "{dev:?}");
        assert_eq!(back.iter().filter(|&&v| v != 0).count(), 2, "{dev:?}");
        assert_validation_clean(&dev);
    }
}

#[test]
fn batch_keeps_dropped_buffers_alive_until_submit() {
    let inc = affine_kernel("inc", 1, 1);
    for dev in devices() {
        let keep: GpuBuffer<u32> = dev.alloc(64).unwrap();
        let mut batch = dev.batch();
        {
            let temp: GpuBuffer<u32> = dev.alloc(1 << 16).unwrap();
            batch
                .dispatch(&inc, &[temp.arg()], Dispatch::Groups([1024, 1, 1]))
                .unwrap();
        }
        batch
            .dispatch(&inc, &[keep.arg()], Dispatch::Groups([1, 1, 1]))
            .unwrap();
        batch.submit().unwrap();
        assert_eq!(dev.read(&keep).unwrap(), vec![1; 64]);
        assert_validation_clean(&dev);
    }
}

#[test]
fn pipeline_cache_reuses_by_name_and_code() {
    for dev in devices() {
        let buf: GpuBuffer<u32> = dev.alloc(256).unwrap();
        let g = Dispatch::Groups([4, 1, 1]);
        assert_eq!(dev.cached_pipeline_count(), 0);
        let inc = affine_kernel("cache_probe", 1, 1);
        dev.dispatch(&inc, &[buf.arg()], g).unwrap();
        assert_eq!(dev.cached_pipeline_count(), 1);
        // A separately built but identical artifact hits the cache.
        let inc_again = affine_kernel("cache_probe", 1, 1);
        for _ in 0..3 {
            dev.dispatch(&inc_again, &[buf.arg()], g).unwrap();
        }
        assert_eq!(dev.cached_pipeline_count(), 1);
        assert_eq!(dev.read(&buf).unwrap(), vec![4; 256]);
        // Same name, different code: a new pipeline, and the new code runs.
        let add10 = affine_kernel("cache_probe", 1, 10);
        dev.dispatch(&add10, &[buf.arg()], g).unwrap();
        assert_eq!(dev.cached_pipeline_count(), 2);
        assert_eq!(dev.read(&buf).unwrap(), vec![14; 256]);
        // Same code, different name: separate entry.
        let renamed = affine_kernel("cache_probe_2", 1, 1);
        dev.dispatch(&renamed, &[buf.arg()], g).unwrap();
        assert_eq!(dev.cached_pipeline_count(), 3);

        // A cached lookup must be far cheaper than the first compile of a new kernel.
        let fresh = affine_kernel("cache_timing", 3, 1);
        let t0 = std::time::Instant::now();
        dev.batch().dispatch(&fresh, &[buf.arg()], g).unwrap();
        let first = t0.elapsed();
        let t1 = std::time::Instant::now();
        for _ in 0..10 {
            dev.batch().dispatch(&fresh, &[buf.arg()], g).unwrap();
        }
        let cached = t1.elapsed() / 10;
        println!("{dev:?}: first record {first:?}, cached record {cached:?}");
        assert!(
            cached < first,
            "{dev:?}: cached {cached:?} vs first {first:?}"
        );
        assert_eq!(dev.cached_pipeline_count(), 4);
        assert_validation_clean(&dev);
    }
}

const SUBGROUP_PROBE: &str = "enable subgroups;
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>,
        @builtin(subgroup_size) sg: u32) {
    let total = subgroupAdd(1u);
    out[gid.x * 2u] = sg;
    out[gid.x * 2u + 1u] = total;
}";

fn subgroup_probe(required: Option<u32>) -> cohort_runtime::KernelArtifact {
    artifact(
        "subgroup_probe",
        SUBGROUP_PROBE,
        vec![binding(0, BindingKind::StorageReadWrite, "out")],
        [64, 1, 1],
        KernelFeatures {
            subgroups: true,
            required_subgroup_size: required,
            ..Default::default()
        },
    )
}

#[test]
fn subgroup_size_matches_device_info() {
    for dev in devices() {
        let info = dev.info().clone();
        // The WGSL starts with `enable subgroups;`, which the wgpu backend must cope with.
        let kernel = subgroup_probe(None);
        let out: GpuBuffer<u32> = dev.alloc(2 * 256).unwrap();
        dev.dispatch(&kernel, &[out.arg()], Dispatch::Groups([4, 1, 1]))
            .unwrap();
        let got = dev.read(&out).unwrap();
        for pair in got.chunks(2) {
            assert_eq!(pair[0], info.subgroup_size, "{dev:?} subgroup_size builtin");
            assert_eq!(
                pair[1], info.subgroup_size,
                "{dev:?} subgroupAdd(1) over a full subgroup"
            );
        }

        // Requiring the default size works wherever the size is pinned or fixed.
        if info.supports_required_subgroup_size || info.subgroup_size_min == info.subgroup_size_max
        {
            let pinned = subgroup_probe(Some(info.subgroup_size));
            let out2: GpuBuffer<u32> = dev.alloc(2 * 256).unwrap();
            dev.dispatch(&pinned, &[out2.arg()], Dispatch::Groups([4, 1, 1]))
                .unwrap();
            assert_eq!(dev.read(&out2).unwrap(), got, "{dev:?}");
        }
        if info.backend == BackendKind::Vulkan {
            assert!(
                info.supports_required_subgroup_size
                    || info.subgroup_size_min == info.subgroup_size_max
            );
        }
        assert_validation_clean(&dev);
    }
}

#[test]
fn devices_and_buffers_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Device>();
    check::<GpuBuffer<f32>>();
    // And really usable from another thread.
    for dev in devices() {
        let buf = dev.upload(&[1u32, 2, 3]).unwrap();
        let back = std::thread::scope(|s| s.spawn(|| dev.read(&buf).unwrap()).join().unwrap());
        assert_eq!(back, vec![1, 2, 3]);
    }
}

#[test]
fn best_prefers_vulkan_then_a_real_gpu_over_the_software_driver() {
    if devices().len() < 2 {
        return;
    }
    assert_eq!(
        Device::best_gpu().unwrap().info().backend,
        BackendKind::Vulkan
    );
    // `best` tells the software driver without opening it (`VkDevice::peek_best`): its
    // choice must be the one the opened device gives, and its note must name that device.
    let (best, why) = Device::best_explained().unwrap();
    let vk = Device::new(BackendKind::Vulkan).unwrap();
    let expected = if vk.info().software_driver {
        BackendKind::Cpu
    } else {
        BackendKind::Vulkan
    };
    assert_eq!(best.info().backend, expected, "{:?}", best.info());
    match why {
        Some(why) => assert!(why.contains(&vk.info().adapter_name), "{why}"),
        None => assert_eq!(expected, BackendKind::Vulkan),
    }
}
