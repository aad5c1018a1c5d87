//! Dealing paths to finished slots (`cohort_kernels::deal`, `RenderOptions::deal`): on
//! every backend, a render that deals traces as many paths per pixel as one that does
//! not, its image is the same up to the float rounding of a sum in another order where
//! the draws are keyed by path (another sample of the same estimator where coherent groups
//! key them by slot), it deals at all, and it is the same image bit for bit when rendered
//! again.

use cohort::runtime::{BackendKind, Device};
use cohort_render::merge::merge_tolerance;
use cohort_render::{
    Algorithm, Budget, Deal, Image, IntegratorKind, RenderOptions, RenderStats, Renderer,
};

const BACKENDS: [BackendKind; 3] = [BackendKind::Cpu, BackendKind::Vulkan, BackendKind::Wgpu];

fn render(dev: &Device, opts: &RenderOptions) -> (Image, RenderStats) {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let mut r = Renderer::new(dev, &scene, opts.clone()).expect("renderer");
    r.render(|_, _| {}).expect("render")
}

#[test]
fn a_render_that_deals_traces_the_same_paths() {
    let base = RenderOptions {
        algorithm: Algorithm::NORMAL,
        budget: Budget::PathsPerPixel(12),
        size: Some((32, 32)),
        seed: 3,
        compact: false,
        integrator: IntegratorKind::Nee,
        // One slot per pixel, tracing all its paths (by default a small image takes
        // copies of itself, each of few paths).
        wavefront: Some(32 * 32),
        ..Default::default()
    };
    let variants = [
        base.clone(),
        // Two copies of the image: a slot traces every second path, then every fourth...
        RenderOptions {
            wavefront: Some(2 * 32 * 32),
            ..base.clone()
        },
        // Implicit paths, and a budget of paths not a multiple of any stride.
        RenderOptions {
            integrator: IntegratorKind::Path,
            budget: Budget::PathsPerPixel(7),
            ..base.clone()
        },
        // Warp groups whose draws follow the slot (the CPU backend computes them per
        // lane); on a GPU, whose leaders share them, nothing is retired or dealt.
        RenderOptions {
            algorithm: Algorithm::parse("warp").unwrap(),
            ..base.clone()
        },
    ];
    for kind in BACKENDS {
        let Some(dev) = Device::for_tests(kind) else {
            continue;
        };
        for opts in &variants {
            let what = format!(
                "{}, {}, {:?}, wavefront {:?}",
                kind.name(),
                opts.algorithm.name(),
                opts.integrator,
                opts.wavefront
            );
            let Budget::PathsPerPixel(paths) = opts.budget else {
                unreachable!()
            };
            let off = RenderOptions {
                deal: Deal::Off,
                ..opts.clone()
            };
            let on = RenderOptions {
                deal: Deal::On,
                ..opts.clone()
            };
            let (kept, kept_stats) = render(&dev, &off);
            let (dealt, stats) = render(&dev, &on);
            assert_eq!(kept_stats.dealt, 0, "{what}: dealt with Deal::Off");
            let deals = !(opts.algorithm.coherent && kind != BackendKind::Cpu);
            assert_eq!(stats.dealt > 0, deals, "{what}: {} deals", stats.dealt);
            assert!(
                dealt.paths.iter().all(|&p| p == paths),
                "{what}: a pixel's path count is not {paths}"
            );
            assert_eq!(stats.completed_paths, kept_stats.completed_paths, "{what}");
            if opts.algorithm.coherent {
                // Group draws keyed by slot: a dealt path draws its group's numbers from
                // the slot that traces it, so the image is another sample of the same
                // estimator.
                let mean = |img: &Image| img.pixels.iter().map(|p| p.x).sum::<f32>();
                let (a, b) = (mean(&kept), mean(&dealt));
                assert!((a - b).abs() < 0.03 * a, "{what}: red sums {a} and {b}");
            } else {
                let tol = merge_tolerance(paths);
                for (i, (a, b)) in kept.pixels.iter().zip(&dealt.pixels).enumerate() {
                    for (x, y) in a.to_array().into_iter().zip(b.to_array()) {
                        assert!(
                            (x - y).abs() <= tol * x.abs().max(y.abs()),
                            "{what}: pixel {i}: {a} without dealing, {b} with"
                        );
                    }
                }
            }
            if deals {
                let (again, _) = render(&dev, &on);
                assert_eq!(
                    again.pixels, dealt.pixels,
                    "{what}: dealt twice, two images"
                );
            }
        }
    }
}

/// A renderer that dealt renders its next run's budget, larger or smaller, with every
/// pixel's paths, and a time budget never deals.
#[test]
fn dealing_follows_the_budget_of_each_run() {
    let Some(dev) = Device::for_tests(BackendKind::Cpu) else {
        return;
    };
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let opts = RenderOptions {
        budget: Budget::PathsPerPixel(2),
        size: Some((24, 24)),
        compact: false,
        integrator: IntegratorKind::Nee,
        deal: Deal::On,
        wavefront: Some(24 * 24),
        ..Default::default()
    };
    let mut r = Renderer::new(&dev, &scene, opts.clone()).expect("renderer");
    let (img, _) = r.render(|_, _| {}).expect("render");
    assert!(img.paths.iter().all(|&p| p == 2), "a pixel without 2 paths");
    r.set_budget(Budget::PathsPerPixel(10)).unwrap();
    let (img, large) = r.render(|_, _| {}).expect("render");
    assert!(
        img.paths.iter().all(|&p| p == 10),
        "a pixel without 10 paths"
    );
    assert!(large.dealt > 0, "no deal at 10 paths per pixel");
    r.set_budget(Budget::KernelTime(std::time::Duration::from_millis(5)))
        .unwrap();
    let (_, timed) = r.render(|_, _| {}).expect("render");
    assert_eq!(timed.dealt, 0, "a time budget dealt");
}

/// `display` sums each pixel's own slots: a run that dealt refuses it rather than show
/// an image without the dealt paths.
#[test]
fn display_refuses_a_run_that_dealt() {
    let Some(dev) = Device::for_tests(BackendKind::Cpu) else {
        return;
    };
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let opts = RenderOptions {
        budget: Budget::PathsPerPixel(8),
        size: Some((24, 24)),
        compact: false,
        integrator: IntegratorKind::Nee,
        deal: Deal::On,
        wavefront: Some(24 * 24),
        ..Default::default()
    };
    let mut r = Renderer::new(&dev, &scene, opts).expect("renderer");
    let (_, stats) = r.render(|_, _| {}).expect("render");
    assert!(stats.dealt > 0);
    let out = dev.alloc::<u32>(24 * 24).unwrap();
    let err = r.display(&out, 0.0, 0..24).unwrap_err().to_string();
    assert!(err.contains("deal Off"), "{err}");
}
