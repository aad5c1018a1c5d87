//! Retiring finished slots from the live list (`cohort_kernels::retire`): a render that
//! retires them is the render that keeps every slot listed, bit for bit, on every
//! backend: with one kernel and with material queues, with ray reordering (which sorts
//! the shorter list), and with copies of the image left idle from the start by a small
//! budget (retired at once).

use cohort::runtime::{BackendKind, Device};
use cohort_render::{Algorithm, Budget, IntegratorKind, RenderOptions, Renderer, Shading};

const BACKENDS: [BackendKind; 3] = [BackendKind::Cpu, BackendKind::Vulkan, BackendKind::Wgpu];

/// The image, and the kernel time of the compaction stage (where retiring is counted).
fn render(dev: &Device, opts: &RenderOptions) -> (Vec<[f32; 3]>, f64) {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let mut r = Renderer::new(dev, &scene, opts.clone()).expect("renderer");
    let (img, stats) = r.render(|_, _| {}).expect("render");
    let pixels = img.pixels.iter().map(|p| p.to_array()).collect();
    (pixels, stats.kernel.compact.as_secs_f64())
}

#[test]
fn a_render_that_retires_finished_slots_is_the_same_image() {
    let base = RenderOptions {
        algorithm: Algorithm::NORMAL,
        budget: Budget::PathsPerPixel(6),
        size: Some((32, 32)),
        seed: 5,
        // Compaction keeps every slot listed: the reference.
        compact: true,
        integrator: IntegratorKind::Nee,
        ..Default::default()
    };
    let variants = [
        base.clone(),
        RenderOptions {
            shading: Shading::Queues,
            ..base.clone()
        },
        RenderOptions {
            reorder: 2,
            ..base.clone()
        },
        // Four copies of the image and two paths per pixel: half the slots start done.
        RenderOptions {
            budget: Budget::PathsPerPixel(2),
            wavefront: Some(4 * 32 * 32),
            ..base.clone()
        },
    ];
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        for opts in &variants {
            let (kept, _) = render(&dev, opts);
            assert!(kept.iter().any(|p| p[0] > 0.0), "a black image");
            let retiring = RenderOptions {
                compact: false,
                ..opts.clone()
            };
            let (retired, compact_time) = render(&dev, &retiring);
            let what = format!(
                "{}, shading {:?}, reorder {}, wavefront {:?}",
                kind.name(),
                opts.shading,
                opts.reorder,
                opts.wavefront
            );
            assert!(compact_time > 0.0, "{what}: no slot was retired");
            let differ = kept.iter().zip(&retired).filter(|(a, b)| a != b).count();
            assert_eq!(differ, 0, "{what}: {differ} pixels differ");
        }
    }
}
