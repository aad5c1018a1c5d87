//! Shards of a render (`RenderOptions::shard`) merge into the render they split: the
//! unsplit image up to float summation order for per-path sampling, and an unbiased
//! estimate of it for coherent configurations, whose group draws each shard takes from
//! its own seed.

use cohort::runtime::{BackendKind, Device};
use cohort_render::merge::{merge, merge_tolerance};
use cohort_render::{
    Algorithm, Budget, GpuScene, Image, IntegratorKind, RenderOptions, Renderer, Shard,
};
use cohort_scenes::Scene;

fn cornell() -> Scene {
    cohort_scenes::embedded::load("cornell").unwrap()
}

fn render(d: &Device, scene: &Scene, gpu: &std::sync::Arc<GpuScene>, opts: RenderOptions) -> Image {
    let mut r = Renderer::with_scene(d, scene, gpu.clone(), opts).unwrap();
    r.render(|_, _| {}).unwrap().0
}

/// Per-path sampling under a paths budget: shard K of N renders paths K*P/N..(K+1)*P/N
/// of every pixel with the unsplit run's random numbers, so the merged shards are the
/// unsplit image: bit for bit with one shard, and otherwise within `merge_tolerance(P)`
/// relative per channel, because the unsplit run sums a pixel's P paths in one f32
/// (`accum += l` in path order) while a merge sums each shard's paths and then the
/// shards (both sums are within (P - 1) * 2^-24 of the exact one).
#[test]
fn shards_merge_into_the_unsplit_render() {
    let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
        return;
    };
    let scene = cornell();
    let gpu = GpuScene::prepare(&d, &scene).unwrap();
    let paths = 14;
    let tol = merge_tolerance(paths);
    for integrator in [IntegratorKind::Nee, IntegratorKind::Path] {
        let opts = RenderOptions {
            budget: Budget::PathsPerPixel(paths),
            size: Some((24, 20)),
            seed: 3,
            integrator,
            ..Default::default()
        };
        assert!(opts.per_path_sampling());
        let whole = render(&d, &scene, &gpu, opts.clone());
        assert!(whole.paths.iter().all(|&p| p == paths));
        for n in [1, 2, 3, 7] {
            let parts: Vec<Image> = (0..n)
                .map(|k| {
                    let shard = Shard::new(k, n).unwrap();
                    let part = render(
                        &d,
                        &scene,
                        &gpu,
                        RenderOptions {
                            shard,
                            ..opts.clone()
                        },
                    );
                    let own = shard.paths(paths).len() as u32;
                    assert!(
                        part.paths.iter().all(|&p| p == own),
                        "{integrator:?} shard {shard}: {own} paths per pixel"
                    );
                    part
                })
                .collect();
            if n > 1 {
                assert!(
                    parts[0].rms_diff(&whole) > 0.0,
                    "{integrator:?} {n} shards: a shard alone is not the whole"
                );
            }
            let merged = merge(&parts).unwrap();
            assert_eq!(merged.paths, whole.paths);
            let mut exact = 0;
            for (i, (m, w)) in merged.pixels.iter().zip(&whole.pixels).enumerate() {
                for c in 0..3 {
                    let (a, b) = (m[c], w[c]);
                    if a.to_bits() == b.to_bits() {
                        exact += 1;
                    } else {
                        assert!(
                            n > 1,
                            "{integrator:?}: one shard is bit-identical: pixel {i} {a} vs {b}"
                        );
                        assert!(
                            (a - b).abs() <= tol * a.abs().max(b.abs()),
                            "{integrator:?} {n} shards: pixel {i} channel {c}: merged {a} vs unsplit {b} (relative tolerance {tol})"
                        );
                    }
                }
            }
            eprintln!(
                "{integrator:?}, {n} shards: {exact} of {} channels bit-identical",
                3 * merged.pixels.len()
            );
        }
    }
}

/// Coherent configurations share group draws keyed by iteration; each shard draws them
/// from its own seed, so the merged shards are an independent unbiased estimate: over
/// seeds, their mean agrees with the unsplit runs' within the seed-to-seed spread.
#[test]
fn coherent_shards_merge_without_bias() {
    let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
        return;
    };
    let scene = cornell();
    let gpu = GpuScene::prepare(&d, &scene).unwrap();
    let seeds = 6u32;
    let shards = 4;
    let configs = [
        RenderOptions {
            algorithm: Algorithm::parse("warp").unwrap(),
            group_rr: true,
            integrator: IntegratorKind::Path,
            ..Default::default()
        },
        RenderOptions {
            algorithm: Algorithm::parse("block_64").unwrap(),
            group_rr: true,
            whole_group_end: Some(0.5),
            integrator: IntegratorKind::Nee,
            coherent_light: true,
            ..Default::default()
        },
    ];
    for config in configs {
        assert!(!config.per_path_sampling());
        let stats = |split: bool| -> (f64, f64) {
            let means: Vec<f64> = (0..seeds)
                .map(|s| {
                    let opts = RenderOptions {
                        patches_n: 8,
                        budget: Budget::PathsPerPixel(24),
                        seed: 2000 + s,
                        size: Some((16, 16)),
                        ..config.clone()
                    };
                    let img = if split {
                        let parts: Vec<Image> = (0..shards)
                            .map(|k| {
                                render(
                                    &d,
                                    &scene,
                                    &gpu,
                                    RenderOptions {
                                        shard: Shard::new(k, shards).unwrap(),
                                        ..opts.clone()
                                    },
                                )
                            })
                            .collect();
                        merge(&parts).unwrap()
                    } else {
                        render(&d, &scene, &gpu, opts)
                    };
                    let m = img.mean();
                    ((m.x + m.y + m.z) / 3.0) as f64
                })
                .collect();
            let mean = means.iter().sum::<f64>() / seeds as f64;
            let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
            (mean, var / seeds as f64)
        };
        let (m0, v0) = stats(false);
        let (m1, v1) = stats(true);
        let se = (v0 + v1).sqrt();
        assert!(
            (m1 - m0).abs() < 5.0 * se + 0.01 * m0,
            "{} rr_group={} whole={:?}: merged shards {m1:.4} vs unsplit {m0:.4} (se {se:.4})",
            config.algorithm.name(),
            config.group_rr,
            config.whole_group_end
        );
    }
}

/// A time budget splits too: shard K starts its paths 2^32 K / N apart, so shards never
/// render the same path, and a shard's own paths per pixel are what it completed.
#[test]
fn time_budget_shards_render_their_own_paths() {
    let Some(d) = Device::for_tests(BackendKind::Vulkan) else {
        return;
    };
    let scene = cornell();
    let gpu = GpuScene::prepare(&d, &scene).unwrap();
    let opts = RenderOptions {
        budget: Budget::KernelTime(std::time::Duration::from_millis(5)),
        size: Some((16, 16)),
        ..Default::default()
    };
    let a = render(
        &d,
        &scene,
        &gpu,
        RenderOptions {
            shard: Shard::new(0, 2).unwrap(),
            ..opts.clone()
        },
    );
    let b = render(
        &d,
        &scene,
        &gpu,
        RenderOptions {
            shard: Shard::new(1, 2).unwrap(),
            ..opts.clone()
        },
    );
    assert!(a.rms_diff(&b) > 0.0, "different paths, different images");
    let merged = merge(&[a.clone(), b.clone()]).unwrap();
    for i in 0..merged.paths.len() {
        assert_eq!(merged.paths[i], a.paths[i] + b.paths[i]);
        assert!(merged.pixels[i].is_finite());
    }
    // An empty shard of a paths budget is refused, not rendered forever.
    let empty = RenderOptions {
        budget: Budget::PathsPerPixel(2),
        shard: Shard::new(0, 3).unwrap(),
        ..opts
    };
    let err = Renderer::with_scene(&d, &scene, gpu, empty)
        .err()
        .expect("0/3 of 2 paths is empty");
    assert!(err.to_string().contains("no path"), "{err}");
}
