//! Next-event estimation (`IntegratorKind::Nee`): it converges to what implicit path
//! tracing converges to (both are unbiased estimators of the same image), with much less
//! noise where lights are small; coherent light sampling keeps it unbiased; the white
//! furnace holds with light sampling on every wall; both backends agree bit for bit.

use cohort::runtime::{BackendKind, Device};
use cohort::Group;
use cohort_render::{Algorithm, Budget, Image, IntegratorKind, RenderOptions, Renderer};
use cohort_scenes::{Bsdf, Camera, FovAxis, Material, Scene, SceneBuilder, Shading};
use glam::{Mat4, Vec3};

fn devices() -> Vec<Device> {
    [BackendKind::Wgpu, BackendKind::Vulkan]
        .into_iter()
        .filter_map(Device::for_tests)
        .collect()
}

/// Where the statistical tests render: a real GPU if there is one, else the CPU backend
/// (about 3x the software Vulkan driver on CI's two cores; what the GPU backends compute is
/// tied to it by `backends_agree_with_light_sampling`).
fn first_device() -> Option<Device> {
    Some(Device::best().expect("the CPU backend always opens"))
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

fn opts(integrator: IntegratorKind, size: u32, paths: u32, seed: u32) -> RenderOptions {
    RenderOptions {
        integrator,
        budget: Budget::PathsPerPixel(paths),
        seed,
        size: Some((size, size)),
        ..Default::default()
    }
}

fn render(d: &Device, scene: &Scene, o: RenderOptions) -> Image {
    let paths = match o.budget {
        Budget::PathsPerPixel(p) => p,
        Budget::KernelTime(_) => unreachable!(),
    };
    let (img, stats) = Renderer::new(d, scene, o)
        .unwrap()
        .render(|_, _| {})
        .unwrap();
    assert_eq!(
        stats.completed_paths,
        paths as u64 * img.pixels.len() as u64,
        "every pixel completes exactly its paths"
    );
    assert!(
        img.paths.iter().all(|&p| p == paths),
        "the shadow pass counts every ended path once"
    );
    img
}

/// Mean over b x b-pixel blocks: a coarse image whose pixels average many paths, to
/// compare two estimators' expectations without the noise of single pixels.
fn blocks(img: &Image, b: u32) -> Vec<Vec3> {
    let (w, h) = (img.width / b, img.height / b);
    let mut out = vec![Vec3::ZERO; (w * h) as usize];
    for y in 0..img.height {
        for x in 0..img.width {
            out[((y / b) * w + x / b) as usize] +=
                img.pixels[(y * img.width + x) as usize] / (b * b) as f32;
        }
    }
    out
}

/// RMS difference over the pixels whose reference value is below 1 in every channel
/// (not the emitter itself, whose radiance is 17 on cornell-box).
fn rms_off_lights(img: &Image, reference: &Image) -> f32 {
    let (mut s, mut n) = (0.0f64, 0usize);
    for (a, r) in img.pixels.iter().zip(&reference.pixels) {
        if r.max_element() < 1.0 {
            s += (*a - *r).length_squared() as f64;
            n += 3;
        }
    }
    (s / n.max(1) as f64).sqrt() as f32
}

/// On both shared scenes (area light, diffuse walls; glossy, mirror and glass objects):
/// light sampling converges to the image of implicit path tracing, block by block, and its
/// error against a long render falls as 1/sqrt(paths); on cornell-box, at equal paths, its
/// error is a fraction of implicit path tracing's.
#[test]
fn nee_converges_to_the_implicit_image_with_less_noise() {
    let Some(d) = first_device() else { return };
    for name in ["cornell-box", "stanford-like"] {
        let scene = shared(name);
        // 128x128 (the size), 256-path references, 8x8-pixel blocks.
        let size = 128;
        let reference = render(&d, &scene, opts(IntegratorKind::Nee, size, 256, 99));
        let implicit = render(&d, &scene, opts(IntegratorKind::Path, size, 1024, 98));
        let (rb, ib) = (blocks(&reference, 8), blocks(&implicit, 8));
        let mean = reference.mean().max_element();
        assert!(mean > 0.01, "{name}: reference is black");
        for (k, (a, b)) in rb.iter().zip(&ib).enumerate() {
            // 64 pixels x 256 paths per block; implicit path tracing is the noisy side.
            assert!(
                (*a - *b).abs().max_element() < 0.12 * a.max_element().max(mean),
                "{name}: block {k}: nee {a} vs implicit {b}"
            );
        }
        let m_nee = reference.mean();
        let m_path = implicit.mean();
        assert!(
            (m_nee - m_path).abs().max_element() < 0.02 * mean,
            "{name}: image mean nee {m_nee} vs implicit {m_path}"
        );

        let e4 = render(&d, &scene, opts(IntegratorKind::Nee, size, 4, 1)).rms_diff(&reference);
        let e64 = render(&d, &scene, opts(IntegratorKind::Nee, size, 64, 2)).rms_diff(&reference);
        // Against a 256-path reference the expected ratio is
        // sqrt((1/64 + 1/256) / (1/4 + 1/256)) = 0.28 rather than 1/4.
        let ratio = e64 / e4;
        assert!(
            ratio > 0.15 && ratio < 0.4,
            "{name}: nee rms {e4} at 4 paths, {e64} at 64 (ratio {ratio})"
        );
        if name == "cornell-box" {
            // Pixels that see the light itself are as noisy with both integrators (their
            // noise is the pixel footprint straddling the light's edge): compare the others.
            let lit = render(&d, &scene, opts(IntegratorKind::Nee, size, 64, 2));
            let dark = render(&d, &scene, opts(IntegratorKind::Path, size, 64, 2));
            let (n64, p64) = (
                rms_off_lights(&lit, &reference),
                rms_off_lights(&dark, &reference),
            );
            assert!(
                n64 < 0.4 * p64,
                "{name}: at 64 paths nee rms {n64} is not well below implicit's {p64}"
            );
        }
    }
}

/// A closed box whose walls all emit `le` and reflect with albedo `a`: every pixel
/// converges to le / (1 - a). With light sampling every wall is also a light, so both
/// MIS strategies carry weight everywhere.
#[test]
fn white_furnace_with_light_sampling() {
    let (a, le) = (0.5f32, 1.0f32);
    let cam = Camera::look_at(
        Vec3::new(0.1, 0.2, 0.3),
        Vec3::new(1.0, 0.3, -0.2),
        Vec3::Y,
        70.0,
        FovAxis::X,
        32,
        32,
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
    for d in devices()
        .into_iter()
        .chain(Device::for_tests(BackendKind::Cpu))
    {
        let img = render(&d, &scene, opts(IntegratorKind::Nee, 32, 32, 3));
        for c in img.mean().to_array() {
            assert!(
                (c - expect).abs() < 0.02 * expect,
                "furnace mean {} vs {expect} on {:?}",
                img.mean(),
                d.info().backend
            );
        }
    }
}

/// A diffuse floor and box under a constant sky (no area light): light sampling draws
/// environment directions by cosine and agrees with implicit path tracing.
#[test]
fn environment_light_sampling_agrees_with_implicit() {
    let Some(d) = first_device() else { return };
    let cam = Camera::look_at(
        Vec3::new(0.0, 1.5, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        60.0,
        FovAxis::X,
        24,
        24,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam);
    let grey = b.material(Material::diffuse(Vec3::splat(0.7)));
    b.add_mesh(
        "floor",
        &cohort_scenes::shapes::rectangle(),
        &(Mat4::from_scale(Vec3::splat(3.0)) * Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2)),
        grey,
        Shading::Flat,
    );
    b.add_mesh(
        "box",
        &cohort_scenes::shapes::cube(),
        &(Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0)) * Mat4::from_scale(Vec3::splat(0.5))),
        grey,
        Shading::Flat,
    );
    b.set_environment(Vec3::new(0.9, 0.95, 1.0));
    let scene = b.finish();
    let nee = render(&d, &scene, opts(IntegratorKind::Nee, 24, 512, 5));
    let implicit = render(&d, &scene, opts(IntegratorKind::Path, 24, 512, 6));
    let mean = nee.mean().max_element();
    for (k, (a, b)) in blocks(&nee, 4)
        .iter()
        .zip(&blocks(&implicit, 4))
        .enumerate()
    {
        assert!(
            (*a - *b).abs().max_element() < 0.06 * mean,
            "block {k}: nee {a} vs implicit {b}"
        );
    }
}

/// Coherent light sampling (a group shares its light pick and stratum) at every group
/// level, with coherent diffuse sampling, is unbiased: its image mean agrees with
/// independent light sampling within the spread of independent seeds.
#[test]
fn coherent_light_sampling_is_unbiased() {
    let Some(d) = first_device() else { return };
    let scene = shared("cornell-box");
    let seeds = 6u32;
    let run = |algorithm: Algorithm, coherent_light: bool, light_cells: u32| -> (f64, f64) {
        let means: Vec<f64> = (0..seeds)
            .map(|s| {
                let o = RenderOptions {
                    algorithm,
                    coherent_light,
                    light_cells,
                    patches_n: 8,
                    ..opts(IntegratorKind::Nee, 16, 48, 2000 + s)
                };
                let m = render(&d, &scene, o).mean();
                ((m.x + m.y + m.z) / 3.0) as f64
            })
            .collect();
        let mean = means.iter().sum::<f64>() / seeds as f64;
        let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
        (mean, var / seeds as f64)
    };
    let (m0, v0) = run(Algorithm::NORMAL, false, 4);
    for (group, cells) in [
        (Group::Thread, 4),
        (Group::Warp, 4),
        (Group::Block(256), 2),
        (Group::Grid, 8),
        (Group::Warp, 1),
    ] {
        let algorithm = if group == Group::Thread {
            Algorithm::NORMAL
        } else {
            Algorithm {
                group,
                coherent: true,
            }
        };
        let (m, v) = run(algorithm, true, cells);
        let se = (v + v0).sqrt();
        assert!(
            (m - m0).abs() < 5.0 * se + 0.01 * m0,
            "{group:?} K={cells}: mean {m:.4} vs independent {m0:.4} (se {se:.4})"
        );
    }
}

/// The GPU backends run the same light-sampling kernels and give the same image, bit for
/// bit; the CPU backend gives it up to float rounding (fused multiply-adds, the last ulp of
/// transcendentals), which may send a path another way: the image means agree to 1e-3 and
/// at most 5 % of the pixel channels differ by more than 1e-3 relative.
#[test]
fn backends_agree_with_light_sampling() {
    let scene = shared("stanford-like");
    let cpu = Device::for_tests(BackendKind::Cpu).expect("the CPU backend always opens");
    let imgs: Vec<Image> = devices()
        .iter()
        .chain([&cpu])
        .map(|d| {
            render(
                d,
                &scene,
                RenderOptions {
                    coherent_light: true,
                    ..opts(IntegratorKind::Nee, 24, 8, 7)
                },
            )
        })
        .collect();
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * a.abs().max(b.abs()).max(1e-3);
    let (gpu, cpu) = imgs.split_at(imgs.len() - 1);
    for img in gpu {
        let differ = img
            .pixels
            .iter()
            .zip(&cpu[0].pixels)
            .map(|(a, b)| (0..3).filter(|&c| !close(a[c], b[c])).count())
            .sum::<usize>();
        let (ma, mb) = (img.mean(), cpu[0].mean());
        assert!(
            differ * 20 <= 3 * img.pixels.len() && (0..3).all(|c| close(ma[c], mb[c])),
            "{differ} of {} pixel channels differ between a GPU backend and the CPU backend (mean {ma} vs {mb})",
            3 * img.pixels.len()
        );
    }
    let imgs = gpu;
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
