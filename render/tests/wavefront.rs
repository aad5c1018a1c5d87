//! The wavefront sized to the device (`cohort_render::wavefront`): several paths of a pixel
//! in flight change nothing but the order of float sums. Each pixel's n-th path draws from
//! (seed, pixel, n) whatever the number of copies, each pixel completes exactly its budget,
//! a pixel's slots are summed in slot order (not in the order they finished), and copies
//! left without a path by a smaller budget idle.

use cohort::runtime::{BackendKind, Device};
use cohort_render::{Algorithm, Budget, Image, IntegratorKind, RenderOptions, Renderer};

fn cpu() -> Device {
    Device::new(BackendKind::Cpu).expect("the CPU backend always opens")
}

fn opts(paths: u32, wavefront: u32, integrator: IntegratorKind) -> RenderOptions {
    RenderOptions {
        algorithm: Algorithm::NORMAL,
        budget: Budget::PathsPerPixel(paths),
        size: Some((24, 16)),
        integrator,
        wavefront: Some(wavefront),
        seed: 7,
        ..Default::default()
    }
}

fn render(d: &Device, o: RenderOptions) -> (Image, u64) {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let mut r = Renderer::new(d, &scene, o).unwrap();
    let (image, stats) = r.render(|_, _| {}).unwrap();
    (image, stats.slots)
}

/// The largest difference between two images relative to the brighter pixel.
fn largest_relative(a: &Image, b: &Image) -> f32 {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(x, y)| ((*x - *y).abs().max_element()) / x.max(*y).max_element().max(1e-6))
        .fold(0.0, f32::max)
}

#[test]
fn copies_change_only_the_order_of_sums() {
    let d = cpu();
    let pixels = 24 * 16;
    for integrator in [IntegratorKind::Path, IntegratorKind::Nee] {
        let (one, slots) = render(&d, opts(8, 1, integrator));
        assert_eq!(slots, pixels);
        // One copy per path: each slot traces one path, summed in path order, as one
        // slot per pixel sums them: the same bits.
        let (eight, slots) = render(&d, opts(8, 8 * pixels as u32, integrator));
        assert_eq!(slots, 8 * pixels);
        assert_eq!(one.paths, eight.paths);
        assert!(one.paths.iter().all(|&p| p == 8));
        assert_eq!(one.pixels, eight.pixels, "{integrator:?}");
        // Three copies of eight paths: 3 + 3 + 2 paths, the same paths in another sum.
        let (three, slots) = render(&d, opts(8, 3 * pixels as u32 - 5, integrator));
        assert_eq!(slots, 3 * pixels);
        assert_eq!(one.paths, three.paths);
        let rel = largest_relative(&one, &three);
        assert!(rel < 1e-5, "{integrator:?}: {rel}");
    }
}

#[test]
fn copies_never_outnumber_the_paths_of_the_budget() {
    let d = cpu();
    let (image, slots) = render(&d, opts(2, 1 << 20, IntegratorKind::Nee));
    assert_eq!(slots, 2 * 24 * 16);
    assert!(image.paths.iter().all(|&p| p == 2));
}

#[test]
fn copies_beyond_a_smaller_budget_idle() {
    let d = cpu();
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let mut r = Renderer::new(&d, &scene, opts(8, 1 << 20, IntegratorKind::Path)).unwrap();
    r.set_budget(Budget::PathsPerPixel(3)).unwrap();
    let (image, stats) = r.render(|_, _| {}).unwrap();
    assert_eq!(stats.slots, 8 * 24 * 16);
    assert!(
        image.paths.iter().all(|&p| p == 3),
        "{:?}",
        &image.paths[..8]
    );
    let (fresh, _) = render(&d, opts(3, 1, IntegratorKind::Path));
    assert_eq!(image.pixels, fresh.pixels);
}

#[test]
fn the_device_chooses_when_no_size_is_given() {
    let d = cpu();
    let o = RenderOptions {
        wavefront: None,
        ..opts(1000, 1, IntegratorKind::Path)
    };
    let pixels = 24 * 16u64;
    let k = cohort_render::wavefront::copies(&d, &o, pixels) as u64;
    assert_eq!(k, cohort_render::wavefront::auto_slots(&d).div_ceil(pixels));
}
