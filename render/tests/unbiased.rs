//! Unbiasedness of every configuration under light sampling: each of
//! the paper's group levels (`normal`, `warp`, `block_256`, `block_512`, `block_1024`,
//! `grid`) crossed with every option that changes the estimator (`--rr group`,
//! `--rr whole` for warp and block groups, `--coherent-light`, `--coherent-glossy`, the
//! in-patch variants `cosine` and `equal-area`, and all of them at once) renders the same
//! image in expectation as `normal` with the same integrator (next-event estimation),
//! roulette and budget.
//!
//! The scene is the embedded `cornell` with its tall box made a rough conductor (GGX,
//! alpha 0.2), so that coherent glossy sampling has a glossy surface to act on; diffuse
//! walls, the small area light and multiple bounces make every other option matter.
//!
//! # The statistic
//! For seeds s = 1..n, the configuration and the reference render with seed s; the
//! per-seed image means m_c(s), m_r(s) (all pixels, the three channels summed) are
//! independent across seeds, so the paired differences d(s) = m_c(s) - m_r(s) are
//! independent and identically distributed whatever the correlations between paths within
//! one render (a grid-wide roulette, a block's shared direction patch, whole-group ends).
//! The relative bias is mean(d) / mean(m_r), its standard error sd(d) / sqrt(n) / mean(m_r)
//! (the spread across seeds, nothing assumed about the estimator's variance), and its
//! p-value comes from Student's t with n - 1 degrees of freedom. A configuration fails when
//! |bias| exceeds `k` standard errors, k = max(4, the two-sided t quantile of a Sidak
//! correction at a family-wise false-alarm rate of 1 % over all configurations): with
//! fixed seeds the test is deterministic, and an unbiased renderer changed elsewhere still
//! fails it only with probability 1 %. The *resolution* of a configuration, printed and
//! named in a failure, is k standard errors: the smallest relative bias it detects.
//!
//! # Budgets
//! - CPU backend, the default (what CI runs, a debug build on 2 cores: 3.4 minutes measured
//!   on 2 cores shared with other builds, about 3 CPU-minutes): 16x16 pixels, 16 paths per
//!   pixel, 16 seeds; k = 4.76 standard errors. Resolution about 0.3 % for
//!   `normal --coherent-light`, 2-4 % for the warp and block levels with per-path roulette,
//!   8-10 % on the grid, and much coarser (8-66 %) for `--rr whole` and the grid's group
//!   roulette, where a block- or grid-wide draw per bounce makes each image mean noisy.
//! - A real GPU (Vulkan and wgpu, where present; about 2.5 minutes per backend on an H200):
//!   128x128, 1024 paths per pixel, 32 seeds; resolution 0.01-0.06 % with per-path
//!   roulette, 0.1-0.7 % with `--rr whole`, 1-4 % on the grid.
//! - Environment variables raise (or lower) any of them: `COHORT_UNBIASED_PATHS` (paths per
//!   pixel), `COHORT_UNBIASED_SEEDS`, `COHORT_UNBIASED_SIZE` (image side), and
//!   `COHORT_UNBIASED_ONLY` (comma-separated configuration names, e.g.
//!   `block_256 --rr whole`, to spend a budget on a few). `block_256 --rr whole` at the
//!   0.1 % level takes `COHORT_UNBIASED_PATHS=8192 COHORT_UNBIASED_SEEDS=64` on a GPU
//!   (128x128: about 35-50 s per backend on an H200; the result is in docs/VALIDATION.md).
//!   The CPU backend cannot reach it in minutes: a release build on 2 cores renders about
//!   5x faster than a debug one, still about 10^5 paths per second.
//!
//! GPU backends on a software driver (lavapipe, llvmpipe) are skipped: they compute what
//! the CPU backend computes, bit for bit (`nee.rs`, `backends_agree_with_light_sampling`),
//! at a third of its speed.
//!
//! The result on record (docs/VALIDATION.md, "Unbiasedness of every configuration").

use std::sync::Arc;
use std::time::Instant;

use cohort::runtime::{BackendKind, Device};
use cohort_render::{
    Algorithm, Budget, GpuScene, InPatch, IntegratorKind, RenderOptions, Renderer,
};
use cohort_scenes::{Material, Scene};
use glam::Vec3;

/// Family-wise false-alarm rate over all configurations of one run.
const FAMILY_ALPHA: f64 = 0.01;
/// The fewest standard errors a bias must exceed to fail, whatever the correction.
const MIN_K: f64 = 4.0;

/// A budget: image side, paths per pixel, seeds.
#[derive(Clone, Copy, Debug)]
struct Plan {
    size: u32,
    paths: u32,
    seeds: u32,
}

impl Plan {
    /// The default for `device`, overridden by the environment.
    fn for_device(device: &Device) -> Plan {
        let gpu = device.info().backend != BackendKind::Cpu && !device.info().software_driver;
        let default = if gpu {
            Plan {
                size: 128,
                paths: 1024,
                seeds: 32,
            }
        } else {
            Plan {
                size: 16,
                paths: 16,
                seeds: 16,
            }
        };
        let env = |name: &str, d: u32| {
            std::env::var(name)
                .ok()
                .map(|v| {
                    v.trim()
                        .parse::<u32>()
                        .unwrap_or_else(|_| panic!("{name}={v}: expected a positive integer"))
                })
                .filter(|&v| v > 0)
                .unwrap_or(d)
        };
        Plan {
            size: env("COHORT_UNBIASED_SIZE", default.size),
            paths: env("COHORT_UNBIASED_PATHS", default.paths),
            seeds: env("COHORT_UNBIASED_SEEDS", default.seeds).max(3),
        }
    }
}

/// The embedded cornell box with its tall box a rough conductor (so that
/// `--coherent-glossy` has something to sample).
fn scene() -> Scene {
    let mut scene = cohort_scenes::embedded::load("cornell").expect("embedded cornell");
    let glossy = scene.materials.len() as u32;
    scene
        .materials
        .push(Material::rough_conductor(0.2, Vec3::splat(0.8)));
    let tall = scene
        .objects
        .iter_mut()
        .find(|o| o.name == "tall box")
        .expect("cornell has a tall box");
    tall.material = glossy;
    for t in tall.triangles.clone() {
        scene.triangles.materials[t as usize] = glossy;
    }
    scene
}

/// The reference: `normal` (independent cosine sampling, per-path roulette, independent
/// light samples) with next-event estimation; every configuration differs from it only
/// in the named options.
fn reference() -> RenderOptions {
    RenderOptions {
        integrator: IntegratorKind::Nee,
        ..Default::default()
    }
}

/// Every configuration under test, named as the command line names it.
fn configurations() -> Vec<(String, RenderOptions)> {
    let levels = [
        "normal",
        "warp",
        "block_256",
        "block_512",
        "block_1024",
        "grid",
    ];
    let mut out = Vec::new();
    for level in levels {
        let algorithm = Algorithm::parse(level).expect("a paper level");
        let base = RenderOptions {
            algorithm,
            ..reference()
        };
        let coherent = algorithm.coherent;
        let grid = level == "grid";
        let mut add = |suffix: &str, o: RenderOptions| {
            let name = if suffix.is_empty() {
                level.to_string()
            } else {
                format!("{level} {suffix}")
            };
            out.push((name, o));
        };
        if coherent {
            add("", base.clone());
            add(
                "--rr group",
                RenderOptions {
                    group_rr: true,
                    ..base.clone()
                },
            );
            if !grid {
                // The command line's --rr whole: group roulette plus whole-group ends
                // with its default --end-continue 0.5.
                add(
                    "--rr whole",
                    RenderOptions {
                        group_rr: true,
                        whole_group_end: Some(0.5),
                        ..base.clone()
                    },
                );
            }
        }
        add(
            "--coherent-light",
            RenderOptions {
                coherent_light: true,
                ..base.clone()
            },
        );
        if coherent {
            add(
                "--coherent-glossy",
                RenderOptions {
                    coherent_glossy: true,
                    ..base.clone()
                },
            );
            add(
                "--in-patch cosine",
                RenderOptions {
                    in_patch: InPatch::Cosine,
                    ..base.clone()
                },
            );
            add(
                "--in-patch equal-area",
                RenderOptions {
                    in_patch: InPatch::EqualArea,
                    ..base.clone()
                },
            );
            add(
                if grid {
                    "--rr group --coherent-light --coherent-glossy --in-patch equal-area"
                } else {
                    "--rr whole --coherent-light --coherent-glossy --in-patch equal-area"
                },
                RenderOptions {
                    group_rr: true,
                    whole_group_end: (!grid).then_some(0.5),
                    coherent_light: true,
                    coherent_glossy: true,
                    in_patch: InPatch::EqualArea,
                    ..base.clone()
                },
            );
        }
    }
    out
}

/// One configuration's comparison with the reference.
#[derive(Clone, Debug)]
struct Bias {
    name: String,
    /// mean(m_c - m_r) / mean(m_r).
    relative: f64,
    /// Its standard error, from the spread across seeds.
    se: f64,
    /// Two-sided p-value (Student's t, seeds - 1 degrees of freedom).
    p: f64,
}

impl Bias {
    fn t(&self) -> f64 {
        if self.se > 0.0 {
            self.relative / self.se
        } else if self.relative == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    }
}

/// Image mean (all pixels, the three channels summed), in f64.
fn image_mean(pixels: &[Vec3]) -> f64 {
    pixels
        .iter()
        .map(|p| p.x as f64 + p.y as f64 + p.z as f64)
        .sum::<f64>()
        / pixels.len().max(1) as f64
}

/// The per-seed image means of `opts` on `device` (seeds 1..=plan.seeds): one renderer,
/// reconfigured for each seed.
fn seed_means(
    device: &Device,
    scene: &Scene,
    gpu: &Arc<GpuScene>,
    plan: Plan,
    opts: &RenderOptions,
) -> Vec<f64> {
    let with_seed = |seed: u32| RenderOptions {
        seed,
        budget: Budget::PathsPerPixel(plan.paths),
        size: Some((plan.size, plan.size)),
        ..opts.clone()
    };
    let mut r = Renderer::with_scene(device, scene, gpu.clone(), with_seed(1))
        .unwrap_or_else(|e| panic!("{opts:?}: {e}"));
    (1..=plan.seeds)
        .map(|seed| {
            if seed > 1 {
                r.reconfigure(with_seed(seed)).unwrap();
            }
            let (img, stats) = r.render(|_, _| {}).unwrap();
            assert_eq!(
                stats.completed_paths,
                plan.paths as u64 * img.pixels.len() as u64,
                "every pixel completes exactly its paths"
            );
            image_mean(&img.pixels)
        })
        .collect()
}

/// Relative bias of `c` against the reference `r` (per-seed means, paired by seed).
fn compare(name: &str, c: &[f64], r: &[f64]) -> Bias {
    assert_eq!(c.len(), r.len());
    let n = c.len() as f64;
    let d: Vec<f64> = c.iter().zip(r).map(|(a, b)| a - b).collect();
    let mean_d = d.iter().sum::<f64>() / n;
    let var_d = d.iter().map(|x| (x - mean_d).powi(2)).sum::<f64>() / (n - 1.0);
    let mean_r = r.iter().sum::<f64>() / n;
    let relative = mean_d / mean_r;
    let se = (var_d / n).sqrt() / mean_r;
    let t = if se > 0.0 {
        relative / se
    } else if relative == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    Bias {
        name: name.to_string(),
        relative,
        se,
        p: t_two_sided_p(t, n - 1.0),
    }
}

/// ln Γ(x), x > 0 (Lanczos, g = 7, n = 9; about 15 digits).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised incomplete beta function I_x(a, b) (continued fraction, modified Lentz).
fn incomplete_beta(x: f64, a: f64, b: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front =
        (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x > (a + 1.0) / (a + b + 2.0) {
        return 1.0 - incomplete_beta(1.0 - x, b, a);
    }
    let tiny = 1e-300;
    let (mut c, mut d) = (1.0, 1.0 - (a + b) * x / (a + 1.0));
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut f = d;
    for m in 1..500 {
        let m = m as f64;
        let num = m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m));
        for num in [
            num,
            -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0)),
        ] {
            d = 1.0 + num * d;
            if d.abs() < tiny {
                d = tiny;
            }
            c = 1.0 + num / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            f *= c * d;
        }
        if (c * d - 1.0).abs() < 1e-15 {
            break;
        }
    }
    front * f / a
}

/// Two-sided p-value of Student's t with `nu` degrees of freedom: P(|T| >= |t|).
fn t_two_sided_p(t: f64, nu: f64) -> f64 {
    if !t.is_finite() {
        return 0.0;
    }
    incomplete_beta(nu / (nu + t * t), nu / 2.0, 0.5)
}

/// The |t| whose two-sided p-value is `alpha` (bisection).
fn t_quantile(alpha: f64, nu: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e3f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if t_two_sided_p(mid, nu) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// How many standard errors fail a configuration when `m` are tested with `seeds` seeds.
fn threshold(m: usize, seeds: u32) -> f64 {
    let per_test = 1.0 - (1.0 - FAMILY_ALPHA).powf(1.0 / m.max(1) as f64);
    t_quantile(per_test, seeds as f64 - 1.0).max(MIN_K)
}

/// Renders every configuration (or those `COHORT_UNBIASED_ONLY` names) on `device`, prints
/// the table and asserts unbiasedness at the plan's resolution.
fn check(device: &Device) {
    let plan = Plan::for_device(device);
    let scene = scene();
    let gpu = GpuScene::prepare(device, &scene).unwrap();
    let only: Option<Vec<String>> = std::env::var("COHORT_UNBIASED_ONLY").ok().map(|v| {
        v.split(',')
            .map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "))
            .filter(|s| !s.is_empty())
            .collect()
    });
    let configs: Vec<_> = configurations()
        .into_iter()
        .filter(|(name, _)| only.as_ref().is_none_or(|o| o.contains(name)))
        .collect();
    assert!(
        !configs.is_empty(),
        "COHORT_UNBIASED_ONLY={only:?} names no configuration; they are: {:?}",
        configurations()
            .iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
    );
    let k = threshold(configs.len(), plan.seeds);
    let info = device.info();
    println!(
        "unbiasedness on {} ({}): embedded cornell with a glossy tall box, nee, {s}x{s}, {} paths/pixel, {} seeds; \
         fail at |bias| > {k:.2} se (Sidak, family-wise alpha {FAMILY_ALPHA}, t with {} dof)",
        info.adapter_name,
        info.backend.name(),
        plan.paths,
        plan.seeds,
        plan.seeds - 1,
        s = plan.size,
    );
    let started = Instant::now();
    let reference = seed_means(device, &scene, &gpu, plan, &reference());
    println!(
        "{:<78} {:>9} {:>8} {:>7} {:>8} {:>9}",
        "configuration", "bias %", "se %", "z", "p", "resol. %"
    );
    let mut failed = Vec::new();
    for (name, opts) in &configs {
        let b = compare(
            name,
            &seed_means(device, &scene, &gpu, plan, opts),
            &reference,
        );
        println!(
            "{:<78} {:>+9.4} {:>8.4} {:>+7.2} {:>8.2e} {:>9.3}",
            b.name,
            100.0 * b.relative,
            100.0 * b.se,
            b.t(),
            b.p,
            100.0 * k * b.se
        );
        // A NaN statistic fails too.
        if b.t().is_nan() || b.t().abs() > k {
            failed.push(b);
        }
    }
    println!(
        "{} configurations and the reference in {:.1} s",
        configs.len(),
        started.elapsed().as_secs_f64()
    );
    assert!(
        failed.is_empty(),
        "biased on {} ({}), {}x{} at {} paths/pixel, {} seeds: {}",
        info.adapter_name,
        info.backend.name(),
        plan.size,
        plan.size,
        plan.paths,
        plan.seeds,
        failed
            .iter()
            .map(|b| format!(
                "`{}` {:+.4} +- {:.4} % (z = {:+.2} > {k:.2}: more than this run's resolution of {:.3} %, p = {:.1e})",
                b.name,
                100.0 * b.relative,
                100.0 * b.se,
                b.t(),
                100.0 * k * b.se,
                b.p
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
}

/// CPU backend, every configuration: CI's budget resolves about 2-4 % with per-path
/// roulette on warp and block groups (8-66 % for whole-group ends and the grid); see the
/// module docs for more.
#[test]
fn every_configuration_is_unbiased_on_the_cpu_backend() {
    let device = Device::new(BackendKind::Cpu).expect("the CPU backend always opens");
    check(&device);
}

/// Vulkan and wgpu on a real GPU, with the GPU budget (about 0.1 %); software drivers are
/// left to the CPU backend, which they match bit for bit.
#[test]
fn every_configuration_is_unbiased_on_a_gpu() {
    for kind in [BackendKind::Vulkan, BackendKind::Wgpu] {
        let Some(device) = Device::for_tests(kind) else {
            continue;
        };
        if device.info().software_driver {
            println!(
                "skipping {} on {}: a software driver (the CPU backend test covers it)",
                kind.name(),
                device.info().adapter_name
            );
            continue;
        }
        check(&device);
    }
}

#[test]
fn the_statistics_are_right() {
    // Student's t: two-sided 5 % points.
    for (nu, t) in [(1.0, 12.706), (5.0, 2.571), (15.0, 2.131), (1e6, 1.960)] {
        let p = t_two_sided_p(t, nu);
        assert!((p - 0.05).abs() < 2e-4, "nu {nu}: p({t}) = {p}");
        assert!((t_quantile(0.05, nu) - t).abs() < 2e-3 * t);
    }
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
    // The threshold never falls below MIN_K, and grows with fewer seeds.
    assert_eq!(threshold(1, 1000), MIN_K);
    assert!(threshold(40, 16) > threshold(40, 64));
    // Paired seeds: the relative bias is the mean difference over the reference mean.
    let b = compare("x", &[1.1, 2.2, 3.3], &[1.0, 2.0, 3.0]);
    assert!((b.relative - 0.1).abs() < 1e-12);
}
