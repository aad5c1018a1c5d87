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

/// Configurations whose groups share draws retire where the draws are keyed by slot (each
/// invocation computes its group's: the thread level, and warp and block groups on the CPU
/// backend) or where one group holds every slot (grid): the image is the one of the same
/// render with every slot kept listed, bit for bit. Elsewhere (warp and block groups on a
/// GPU, whose leaders share the draws) nothing is retired.
#[test]
fn coherent_renders_retire_where_the_draws_follow_the_slot() {
    use cohort::Group;
    let base = RenderOptions {
        algorithm: Algorithm::parse("warp").unwrap(),
        budget: Budget::PathsPerPixel(6),
        size: Some((32, 32)),
        seed: 9,
        compact: false,
        integrator: IntegratorKind::Nee,
        ..Default::default()
    };
    let variants = [
        base.clone(),
        RenderOptions {
            algorithm: Algorithm::parse("block_256").unwrap(),
            group_rr: true,
            coherent_light: true,
            ..base.clone()
        },
        RenderOptions {
            algorithm: Algorithm::parse("grid").unwrap(),
            ..base.clone()
        },
        // `normal` with the group roulette: a group of one invocation, keyed by slot.
        RenderOptions {
            algorithm: Algorithm::NORMAL,
            group_rr: true,
            ..base.clone()
        },
    ];
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        for opts in &variants {
            let kept = RenderOptions {
                retire: false,
                ..opts.clone()
            };
            let (reference, none) = render(&dev, &kept);
            assert_eq!(none, 0.0, "a render told to keep its slots retired some");
            let (retiring, compact_time) = render(&dev, opts);
            let what = format!("{}, {}", kind.name(), opts.algorithm.name());
            let per_lane = kind == BackendKind::Cpu;
            let retires = match opts.algorithm.group {
                Group::Warp | Group::Block(_) => per_lane,
                _ => true,
            };
            assert_eq!(
                compact_time > 0.0,
                retires,
                "{what}: retired {compact_time} s"
            );
            let differ = reference
                .iter()
                .zip(&retiring)
                .filter(|(a, b)| a != b)
                .count();
            assert_eq!(differ, 0, "{what}: {differ} pixels differ");
        }
    }
}
