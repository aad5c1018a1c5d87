//! Renderers created and dropped on one device run in constant memory (the Mitsuba-scene
//! work's "nothing grows"): a live viewer or a long sweep that switches configurations
//! makes a renderer per configuration, and whatever one renderer keeps after it is dropped
//! adds up.
//!
//! The measure is the process's resident set (Linux `/proc/self/statm`), which is what
//! runs out on a laptop or a CI runner. The first renderers compile the pipelines and fill
//! the driver's and the allocator's pools, so growth is measured after a warm-up, over
//! `ROUNDS` more renderers, each rendering the embedded Cornell box at 24 x 24.
//!
//! This file holds one test so that no other test of the binary allocates beside it.

use cohort::runtime::{BackendKind, Device};
use cohort_render::{Budget, RenderOptions, Renderer};

/// Renderers made before the baseline is read: pipelines, pools and caches fill here.
const WARM_UP: usize = 4;
/// Renderers made between the two readings.
const ROUNDS: usize = 16;
/// Growth allowed over `ROUNDS` renderers: allocators round, and the C library keeps
/// freed pages in its arenas. A leak of one renderer's buffers and descriptor state is
/// several MB per renderer on the software driver (measured before the fix: 16 MB), so
/// this bound fails on any leak of a renderer's own resources within a few rounds.
const ALLOWED_GROWTH: u64 = 24 << 20;

fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").expect("Linux /proc/self/statm");
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .expect("resident pages in /proc/self/statm");
    pages * 4096
}

fn render_once(device: &Device, scene: &cohort_scenes::Scene) {
    let opts = RenderOptions {
        budget: Budget::PathsPerPixel(4),
        size: Some((24, 24)),
        seed: 7,
        ..Default::default()
    };
    let mut r = Renderer::new(device, scene, opts).expect("renderer");
    let (img, _) = r.render(|_, _| {}).expect("render");
    assert_eq!(img.pixels.len(), 24 * 24);
}

#[test]
fn renderers_created_in_a_loop_run_in_flat_memory() {
    let scene = cohort_scenes::embedded::load("cornell").expect("embedded cornell box");
    use cohort::runtime::cpu::simd::Forms;
    // The CPU backend with each form of its kernels. Vector forms compile during the
    // warm-up (LLVM's own memory, once per process, is not a renderer's); with measured
    // forms they would compile whenever a kernel gets hot, in the middle of the rounds.
    let devices = [
        (BackendKind::Wgpu, Device::for_tests(BackendKind::Wgpu)),
        (BackendKind::Vulkan, Device::for_tests(BackendKind::Vulkan)),
        (BackendKind::Cpu, Device::cpu_with(Forms::Host).ok()),
        (BackendKind::Cpu, Device::cpu_with(Forms::Vector).ok()),
    ];
    for (kind, device) in devices {
        let Some(device) = device else {
            continue;
        };
        for _ in 0..WARM_UP {
            render_once(&device, &scene);
        }
        let before = resident_bytes();
        let mut readings = Vec::with_capacity(ROUNDS);
        for _ in 0..ROUNDS {
            render_once(&device, &scene);
            readings.push(resident_bytes());
        }
        let after = resident_bytes();
        let growth = after.saturating_sub(before);
        let mb = |b: u64| b as f64 / (1 << 20) as f64;
        println!(
            "{} ({}): resident {:.1} MB after warm-up, {:.1} MB after {ROUNDS} more renderers (+{:.1} MB); per round: {:?}",
            kind.name(),
            device.info().driver,
            mb(before),
            mb(after),
            mb(growth),
            readings.iter().map(|&b| mb(b).round() as i64).collect::<Vec<_>>()
        );
        assert!(
            growth <= ALLOWED_GROWTH,
            "{}: {ROUNDS} renderers created and dropped grew the process by {:.1} MB (allowed {:.1} MB)",
            kind.name(),
            mb(growth),
            mb(ALLOWED_GROWTH)
        );
    }
}
