//! One render on several devices at once: the options' shard is split into one part per
//! device ([`Shard::split`]), each part is rendered by its own thread on its own device,
//! and the parts are merged by path count ([`crate::merge`]) — the same split and merge
//! as shards on separate machines, in one process. The BVH is built once on the host and
//! uploaded to every device.

use std::sync::Arc;

use cohort::runtime::Device;
use cohort_scenes::{GpuBvh8, Scene};

use crate::{merge, GpuScene, Image, RenderError, RenderOptions, RenderStats, Renderer};

/// Renders `opts` on every device of `devices`; `progress(device, fraction, stats)` is
/// called from the device's thread. Returns the merged image and each device's
/// statistics. With one device this is a plain render of `opts`.
pub fn render_on_devices(
    devices: &[Device],
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize, f64, &RenderStats) + Sync),
) -> Result<(Image, Vec<RenderStats>), RenderError> {
    let parts = opts
        .shard
        .split(devices.len() as u32)
        .map_err(RenderError::Options)?;
    let (bvh, wide) = GpuBvh8::build_scene(scene).map_err(|e| RenderError::Bvh(e.to_string()))?;
    let results: Vec<Result<(Image, RenderStats), RenderError>> = std::thread::scope(|s| {
        let threads: Vec<_> = devices
            .iter()
            .zip(parts)
            .enumerate()
            .map(|(i, (device, shard))| {
                let (bvh, wide) = (&bvh, wide.as_ref());
                let opts = RenderOptions {
                    shard,
                    ..opts.clone()
                };
                s.spawn(move || {
                    let gpu = Arc::new(GpuScene::upload_with(device, scene, bvh, wide)?);
                    let mut r = Renderer::with_scene(device, scene, gpu, opts)?;
                    r.render(|f, stats| progress(i, f, stats))
                })
            })
            .collect();
        threads
            .into_iter()
            .map(|t| {
                t.join().unwrap_or_else(|_| {
                    Err(RenderError::Options(
                        "a device's render thread panicked".into(),
                    ))
                })
            })
            .collect()
    });
    let mut images = Vec::with_capacity(results.len());
    let mut stats = Vec::with_capacity(results.len());
    for (i, r) in results.into_iter().enumerate() {
        let (image, s) = r.map_err(|e| match e {
            RenderError::Options(m) if devices.len() > 1 => {
                RenderError::Options(format!("device {i}: {m}"))
            }
            e => e,
        })?;
        images.push(image);
        stats.push(s);
    }
    let image = if images.len() == 1 {
        images.pop().unwrap()
    } else {
        merge::merge(&images).map_err(RenderError::Options)?
    };
    Ok((image, stats))
}

/// The statistics of a render on several devices: paths, rays and kernel time summed
/// (so paths per kernel second is per device; slots in flight too), iterations and wall
/// time of the slowest.
pub fn combined_stats(per_device: &[RenderStats]) -> RenderStats {
    let mut all = RenderStats::default();
    for s in per_device {
        all.iterations = all.iterations.max(s.iterations);
        all.completed_paths += s.completed_paths;
        all.rays += s.rays;
        all.kernel += s.kernel;
        all.queued_iterations = all.queued_iterations.max(s.queued_iterations);
        all.wall = all.wall.max(s.wall);
        all.host.record += s.host.record;
        all.host.submit += s.host.submit;
        all.host.wait += s.host.wait;
        all.host.batches += s.host.batches;
        all.pixels = s.pixels;
        all.slots += s.slots;
    }
    all
}
