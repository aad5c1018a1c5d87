//! Writing a new sampling strategy: one `impl` of `DiffuseSampler`, tested on the host
//! (the same Rust runs there) and then rendered on the GPU, where `extend::<S>` is
//! compiled for it.
//!
//! The strategy: the group shares an azimuth stratum (one of 4N slices of the
//! hemisphere around the normal); each ray samples cosine-weighted inside the slice.
//! Since the slice is uniform and cosine sampling is separable in azimuth, every ray's
//! pdf is exactly cos/pi: weight 1, unbiased, and coherent within the group.
//!
//! `cargo run --release -p cohort-render --example custom_sampler`

use cohort::prelude::*;
use cohort::runtime::Device;
use cohort::Group;
use cohort_kernels::rng::{hash, stream, uniform};
use cohort_kernels::sampling::{cosine_hemisphere, frame, DiffuseSampler};
use cohort_render::{output, Algorithm, Budget, RenderOptions, Renderer};

pub struct SharedAzimuth;

#[kernel_impl]
impl DiffuseSampler for SharedAzimuth {
    fn group_value(key: u32, _patches_n: u32) -> u32 {
        hash(key)
    }
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4 {
        let strata = 4 * patches_n;
        let k = group_value % strata;
        let v = Vec2::new(u.x, (k as f32 + u.y) / strata as f32);
        let d = frame(n) * cosine_hemisphere(v);
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

fn main() {
    // 1. On the host: E[cos theta] under the pdf cos/pi is 2/3, whatever the group draw.
    let n = 200_000u32;
    let mut sum = 0.0f64;
    for k in 0..n {
        let group = SharedAzimuth::group_value(stream(1, k / 32, 0, 0), 16);
        let key = stream(2, k, 0, 0);
        let d = SharedAzimuth::sample(
            Vec3::Z,
            Vec2::new(uniform(key, 0), uniform(key, 1)),
            group,
            16,
        );
        sum += d.z as f64 * d.w as f64;
    }
    let mean = sum / n as f64;
    println!("host check: E[cos] = {mean:.4} (expected 0.6667)");
    assert!((mean - 2.0 / 3.0).abs() < 0.01);

    // 2. On the GPU: render the default scene with it, groups of one warp.
    let device =
        Device::best().expect("a Vulkan device (scripts/install-deps.sh installs lavapipe)");
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let opts = RenderOptions {
        algorithm: Algorithm {
            group: Group::Warp,
            coherent: true,
        },
        patches_n: 16,
        budget: Budget::PathsPerPixel(32),
        size: Some((128, 128)),
        ..Default::default()
    };
    let mut renderer = Renderer::new(&device, &scene, opts).unwrap();
    let (image, stats) = renderer.render_custom::<SharedAzimuth>(|_, _| {}).unwrap();
    output::write_png(std::path::Path::new("custom_sampler.png"), &image, 0.0).unwrap();
    println!(
        "rendered {} paths/pixel, mean radiance {}; wrote custom_sampler.png",
        stats.paths_per_pixel(),
        image.mean()
    );
}
