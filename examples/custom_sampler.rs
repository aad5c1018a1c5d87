//! Writing a new sampling strategy: one `impl` of `DiffuseSampler`, validated by the
//! statistical test of `cohort_render::validate` (its own kernel, run on the device, at
//! every group level), then rendered with, `extend::<S>` compiled for it.
//!
//! The strategy: the group shares an azimuth stratum (one of 4N slices of the
//! hemisphere around the normal); each ray samples cosine-weighted inside the slice.
//! Since the slice is uniform and cosine sampling is separable in azimuth, every ray's
//! pdf over the group's draws is exactly cos/pi: weight 1, unbiased, and coherent within
//! the group.
//!
//! `cargo run --release -p cohort-render --example custom_sampler` (on a GPU if there is
//! one, else on the CPU backend; it says which).

use cohort::prelude::*;
use cohort::runtime::Device;
use cohort::Group;
use cohort_kernels::rng::hash;
use cohort_kernels::sampling::{cosine_hemisphere, frame, DiffuseSampler};
use cohort_render::validate::{self, Report, SamplerOptions};
use cohort_render::{output, Algorithm, Budget, Image, RenderOptions, Renderer};

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

/// How much work the example does.
pub struct Settings {
    /// Rays per group level of the validation.
    pub samples: u32,
    /// Image size and paths per pixel of the render.
    pub size: u32,
    pub paths: u32,
}

/// Validates `SharedAzimuth` on `device` at every group level (the report), and when it
/// passes renders the Cornell box with it in groups of one warp (the image).
pub fn run(device: &Device, settings: &Settings) -> Result<(Report, Option<Image>), String> {
    let opts = SamplerOptions {
        samples: settings.samples,
        ..Default::default()
    };
    let report = validate::sampler::<SharedAzimuth>(device, &opts).map_err(|e| e.to_string())?;
    if !report.passed() {
        return Ok((report, None));
    }
    let scene = cohort_scenes::embedded::load("cornell").ok_or("no embedded scene `cornell`")?;
    let opts = RenderOptions {
        algorithm: Algorithm {
            group: Group::Warp,
            coherent: true,
        },
        patches_n: 16,
        budget: Budget::PathsPerPixel(settings.paths),
        size: Some((settings.size, settings.size)),
        ..Default::default()
    };
    let mut renderer = Renderer::new(device, &scene, opts).map_err(|e| e.to_string())?;
    let (image, _) = renderer
        .render_custom::<SharedAzimuth>(|_, _| {})
        .map_err(|e| e.to_string())?;
    Ok((report, Some(image)))
}

#[allow(dead_code)]
fn main() {
    let (device, why) = Device::best_explained().expect("no device, not even the CPU backend");
    println!("device: {}", validate::device_name(&device));
    if let Some(why) = why {
        println!("(the CPU backend: {why})");
    }
    let settings = Settings {
        samples: 1 << 18,
        size: 128,
        paths: 32,
    };
    // 1. Validate: the weighted directions over the group's draws follow cos/pi, at every
    //    group level (docs/VALIDATION.md).
    let (report, image) = run(&device, &settings).unwrap_or_else(|e| panic!("{e}"));
    println!("{report}");
    let Some(image) = image else {
        eprintln!("SharedAzimuth failed its validation: not rendering with it");
        std::process::exit(1);
    };
    // 2. Render the default scene with it, groups of one warp.
    output::write_png(std::path::Path::new("custom_sampler.png"), &image, 0.0).unwrap();
    println!(
        "rendered {} paths/pixel on {}, mean radiance {}; wrote custom_sampler.png",
        settings.paths,
        validate::device_name(&device),
        image.mean()
    );
}
