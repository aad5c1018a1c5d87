//! Correctness of the path tracer on small images (lavapipe in CI): the white
//! furnace, backend agreement, GPU traversal against the host BVH traversal, and
//! convergence on the shared reference scenes.

use cohort::runtime::{BackendKind, Device};
use cohort_render::{Budget, Image, RenderOptions, Renderer};
use cohort_scenes::{Bsdf, Camera, FovAxis, Material, Scene, SceneBuilder, Shading};
use glam::{Mat4, Vec3};

fn devices() -> Vec<Device> {
    [BackendKind::Wgpu, BackendKind::Vulkan]
        .into_iter()
        .filter_map(Device::for_tests)
        .collect()
}

fn render(d: &Device, scene: &Scene, size: u32, paths: u32, seed: u32) -> Image {
    let opts = RenderOptions {
        budget: Budget::PathsPerPixel(paths),
        seed,
        size: Some((size, size)),
        ..Default::default()
    };
    let mut r = Renderer::new(d, scene, opts).unwrap();
    let (img, stats) = r.render(|_, _| {}).unwrap();
    assert_eq!(
        stats.completed_paths,
        paths as u64 * (size * size) as u64,
        "every pixel completes exactly its paths"
    );
    assert!(img.paths.iter().all(|&p| p == paths));
    img
}

/// Inside a closed box whose walls all emit `le` and reflect with albedo `a`, every
/// pixel converges to le / (1 - a).
#[test]
fn white_furnace() {
    let (a, le) = (0.5f32, 1.0f32);
    let cam = Camera::look_at(
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(1.0, 0.3, -0.2),
        Vec3::Y,
        70.0,
        FovAxis::X,
        64,
        64,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam);
    let m = b.material(Material {
        bsdf: Bsdf::Diffuse {
            reflectance: Vec3::splat(a),
        },
        two_sided: true,
        emission: Some(Vec3::splat(le)),
        emission_texture: None,
        texture: None,
        mask: None,
        blend: None,
        perturb: None,
    });
    b.add_mesh(
        "box",
        &cohort_scenes::shapes::cube(),
        &Mat4::from_scale(Vec3::splat(2.0)),
        m,
        Shading::Flat,
    );
    let scene = b.finish();
    let expect = le / (1.0 - a);
    for d in devices() {
        let img = render(&d, &scene, 64, 24, 3);
        let mean = img.mean();
        for c in mean.to_array() {
            assert!(
                (c - expect).abs() < 0.02 * expect,
                "furnace mean {mean} vs {expect} on {:?}",
                d.info().backend
            );
        }
        // Every 8x8 block of pixels (1536 paths) is within 6% of the expectation.
        for by in 0..8 {
            for bx in 0..8 {
                let mut s = Vec3::ZERO;
                for y in 0..8 {
                    for x in 0..8 {
                        s += img.pixels[((by * 8 + y) * 64 + bx * 8 + x) as usize];
                    }
                }
                let m = s / 64.0;
                assert!(
                    (m.x - expect).abs() < 0.06 * expect,
                    "furnace block ({bx},{by}) mean {m} vs {expect}"
                );
            }
        }
    }
}

/// A reference scene of the repository (`render/tests/scenes/NAME`), so that the test needs
/// no folder beside the clone.
fn shared(name: &str) -> Scene {
    let path = format!(
        "{}/tests/scenes/{name}/scene.xml",
        env!("CARGO_MANIFEST_DIR")
    );
    cohort_scenes::load_mitsuba(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .scene
}

/// The two GPU backends run the same kernels on the same inputs and produce identical
/// images, bit for bit (wgpu compiles the WGSL, ash runs the SPIR-V; naga writes both
/// from one module).
#[test]
fn backends_agree() {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let imgs: Vec<Image> = devices()
        .iter()
        .map(|d| render(d, &scene, 32, 8, 7))
        .collect();
    if imgs.len() == 2 {
        let differ = imgs[0]
            .pixels
            .iter()
            .zip(&imgs[1].pixels)
            .filter(|(x, y)| x.to_array().map(f32::to_bits) != y.to_array().map(f32::to_bits))
            .count();
        assert_eq!(
            differ,
            0,
            "{differ} of {} pixels differ between wgpu and Vulkan",
            imgs[0].pixels.len()
        );
    }
}

/// The CPU backend runs the kernels' Rust functions, whose float operations the GPU
/// compilers may contract or reorder, so its image is not bit-identical: it must agree
/// statistically. Same seed, so the paths are the same up to rounding: the images are
/// compared by their means (within 0.5 %) and by the RMS of their difference against the
/// noise of two renders with different seeds.
#[test]
fn cpu_backend_agrees_with_the_gpu_backends() {
    let scene = cohort_scenes::embedded::load("cornell").unwrap();
    let Some(cpu) = Device::for_tests(BackendKind::Cpu) else {
        return;
    };
    let Some(gpu) = devices().into_iter().next() else {
        return;
    };
    let on_cpu = render(&cpu, &scene, 32, 8, 7);
    let on_gpu = render(&gpu, &scene, 32, 8, 7);
    let other_seed = render(&gpu, &scene, 32, 8, 8);
    let (mc, mg) = (on_cpu.mean(), on_gpu.mean());
    assert!(
        (mc - mg).abs().max_element() <= 0.005 * mg.max_element(),
        "means differ: CPU {mc} vs GPU {mg}"
    );
    let same_paths = on_cpu.rms_diff(&on_gpu);
    let noise = other_seed.rms_diff(&on_gpu);
    assert!(
        same_paths < 0.5 * noise,
        "CPU vs GPU with the same seed: rms {same_paths}, more than half the noise between seeds ({noise})"
    );
}

/// RMS error against a long render falls like 1/sqrt(paths).
#[test]
fn converges_on_shared_scenes() {
    let d = match devices().into_iter().next() {
        Some(d) => d,
        None => return,
    };
    for name in ["cornell-box", "stanford-like"] {
        let scene = shared(name);
        let reference = render(&d, &scene, 24, 1024, 99);
        let e4 = render(&d, &scene, 24, 4, 1).rms_diff(&reference);
        let e64 = render(&d, &scene, 24, 64, 2).rms_diff(&reference);
        // 16x the paths: error / 4 expected; allow for the reference's own noise.
        let ratio = e64 / e4;
        assert!(
            ratio > 0.15 && ratio < 0.4,
            "{name}: rms {e4} at 4 paths, {e64} at 64 (ratio {ratio})"
        );
        assert!(
            reference.mean().max_element() > 0.01,
            "{name}: reference is black"
        );
    }
}

/// Every coherent configuration is unbiased: its image mean on the shared stanford-like
/// scene agrees with `normal`'s within the confidence interval estimated from independent
/// seeds (coherent pixels are correlated inside a group, so the spread across whole
/// renders, not across pixels, measures the error).
#[test]
fn coherent_configurations_converge_to_normal() {
    // The first GPU backend, and the CPU backend (whose group operations are its lane
    // scheduler's, not a GPU's).
    let devices: Vec<Device> = devices()
        .into_iter()
        .take(1)
        .chain(Device::for_tests(BackendKind::Cpu))
        .collect();
    for d in &devices {
        coherent_configurations_on(d);
    }
}

fn coherent_configurations_on(d: &Device) {
    use cohort::Group;
    use cohort_render::{Algorithm, InPatch};
    let scene = shared("stanford-like");
    let seeds = 6u32;
    let run = |algorithm: Algorithm,
               in_patch: InPatch,
               group_rr: bool,
               compact: bool,
               coherent_glossy: bool,
               whole_group_end: Option<f32>|
     -> (f64, f64) {
        let means: Vec<f64> = (0..seeds)
            .map(|s| {
                let opts = RenderOptions {
                    algorithm,
                    in_patch,
                    group_rr,
                    compact,
                    coherent_glossy,
                    whole_group_end,
                    patches_n: 8,
                    budget: Budget::PathsPerPixel(48),
                    seed: 1000 + s,
                    size: Some((16, 16)),
                    ..Default::default()
                };
                let mut r = Renderer::new(d, &scene, opts).unwrap();
                let (img, _) = r.render(|_, _| {}).unwrap();
                let m = img.mean();
                ((m.x + m.y + m.z) / 3.0) as f64
            })
            .collect();
        let mean = means.iter().sum::<f64>() / seeds as f64;
        let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
        (mean, var / seeds as f64)
    };
    let (m0, v0) = run(
        Algorithm::NORMAL,
        InPatch::Uniform,
        false,
        true,
        false,
        None,
    );
    let configs = [
        (Group::Warp, InPatch::Uniform, false, true, false, None),
        (
            Group::Block(256),
            InPatch::Uniform,
            false,
            true,
            false,
            None,
        ),
        (Group::Grid, InPatch::Uniform, false, true, false, None),
        (Group::Warp, InPatch::Uniform, true, false, false, None),
        (Group::Block(256), InPatch::Cosine, true, false, false, None),
        (Group::Warp, InPatch::EqualArea, false, true, true, None),
        // Whole-group termination (a path that ends triggers a shared roulette).
        (Group::Warp, InPatch::Uniform, true, true, false, Some(0.5)),
        (
            Group::Block(64),
            InPatch::Uniform,
            true,
            false,
            false,
            Some(0.3),
        ),
    ];
    for (group, in_patch, rr, compact, glossy, whole) in configs {
        let (m, v) = run(
            Algorithm {
                group,
                coherent: true,
            },
            in_patch,
            rr,
            compact,
            glossy,
            whole,
        );
        let se = (v + v0).sqrt();
        assert!(
            (m - m0).abs() < 5.0 * se + 0.01 * m0,
            "{:?}: {group:?} {in_patch:?} rr={rr} compact={compact} whole={whole:?}: mean {m:.4} vs normal {m0:.4} (se {se:.4})",
            d.info().backend
        );
    }
}
