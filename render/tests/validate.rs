//! `cohort_render::validate` on the CPU backend: the example's strategy and a correct one
//! pass, a deliberately wrong one (a density off by 10 % in two quarters of the azimuth,
//! with the right mean of cos theta) fails, as does one whose grouped form disagrees with
//! its `sample`, BSDFs pass, and the example runs end to end.
//! Fixed seeds: every run draws the same numbers.

use cohort::prelude::*;
use cohort::runtime::{BackendKind, Device};
use cohort_kernels::rng::hash;
use cohort_kernels::sampling::{cosine_hemisphere, frame, CoherentUniform, DiffuseSampler};
use cohort_render::validate::{self, builtin_bsdfs, BsdfOptions, SamplerOptions};

#[allow(dead_code, unused_imports)]
#[path = "../../examples/custom_sampler.rs"]
mod custom_sampler;

fn cpu() -> Device {
    Device::new(BackendKind::Cpu).expect("the CPU backend")
}

/// Cosine sampling with its azimuth skewed: the first quarter gets 10 % more of the rays,
/// the second 10 % fewer. Weight 1, so the mean of cos theta is still 2/3.
pub struct SkewedAzimuth;

#[kernel_impl]
impl DiffuseSampler for SkewedAzimuth {
    fn group_value(_key: u32, _patches_n: u32) -> u32 {
        0
    }
    fn sample(n: Vec3, u: Vec2, _group_value: u32, _patches_n: u32) -> Vec4 {
        let mut t = u.y;
        if u.y < 0.275 {
            t = u.y / 0.275 * 0.25;
        } else if u.y < 0.5 {
            t = 0.25 + (u.y - 0.275) / 0.225 * 0.25;
        }
        let d = frame(n) * cosine_hemisphere(Vec2::new(u.x, t));
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

/// Cosine sampling in the group's sector of azimuth, with a `group_params` one sector off
/// the one its `sample` uses: its directions are right, the renderer's grouped form of it is
/// not.
pub struct StaleParams;

/// The group's sector of azimuth: its index in x, the number of sectors in y.
#[kernel_fn]
pub fn sector(group_value: u32, patches_n: u32) -> Vec4 {
    let sectors = 4 * patches_n;
    Vec4::new((group_value % sectors) as f32, sectors as f32, 0.0, 0.0)
}

#[kernel_impl]
impl DiffuseSampler for StaleParams {
    const GROUP_PARAMS: bool = true;
    fn group_value(key: u32, _patches_n: u32) -> u32 {
        hash(key)
    }
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4 {
        Self::sample_grouped(n, u, group_value, sector(group_value, patches_n), patches_n)
    }
    fn group_params(group_value: u32, patches_n: u32) -> Vec4 {
        sector(group_value, patches_n) + Vec4::X
    }
    fn sample_grouped(n: Vec3, u: Vec2, _group_value: u32, s: Vec4, _patches_n: u32) -> Vec4 {
        let d = frame(n) * cosine_hemisphere(Vec2::new(u.x, (s.x + u.y) / s.y));
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

fn small() -> SamplerOptions {
    SamplerOptions {
        levels: vec![Group::Thread, Group::Warp],
        samples: 1 << 16,
        ..Default::default()
    }
}

#[test]
fn the_correct_sampler_passes() {
    let r = validate::sampler::<cohort_kernels::sampling::Cosine>(&cpu(), &small()).unwrap();
    println!("{r}");
    assert!(r.passed(), "{r}");
}

/// A strategy with group parameters is tested for its grouped form too: the paper's passes,
/// one whose parameters disagree with its `sample` fails that test alone.
#[test]
fn a_grouped_form_that_disagrees_fails() {
    // One level: the grouped test does not depend on it.
    let opts = SamplerOptions {
        levels: vec![Group::Thread],
        samples: 1 << 14,
        ..small()
    };
    let r = validate::sampler::<CoherentUniform>(&cpu(), &opts).unwrap();
    assert!(r.passed(), "{r}");
    assert!(r.tests.iter().any(|t| t.test == "grouped"), "{r}");
    let r = validate::sampler::<StaleParams>(&cpu(), &opts).unwrap();
    let failed: Vec<_> = r.failures().iter().map(|t| t.test.clone()).collect();
    assert_eq!(failed, ["grouped"], "{r}");
}

#[test]
fn the_wrong_sampler_fails() {
    let dir = std::env::temp_dir().join(format!("cohort-validate-{}", std::process::id()));
    let opts = SamplerOptions {
        out: Some(dir.clone()),
        ..small()
    };
    let r = validate::sampler::<SkewedAzimuth>(&cpu(), &opts).unwrap();
    println!("{r}");
    assert!(!r.passed(), "{r}");
    // Every marginal test sees it, at both levels and every normal.
    assert_eq!(r.failures().len(), r.counted(), "{r}");
    // Its mean of cos theta is right: the old check of the example could not see it.
    let images: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(images.len(), r.counted());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_examples_sampler_passes_at_every_level() {
    let opts = SamplerOptions {
        samples: 1 << 18,
        ..Default::default()
    };
    let r = validate::sampler::<custom_sampler::SharedAzimuth>(&cpu(), &opts).unwrap();
    println!("{r}");
    assert!(r.passed(), "{r}");
    assert_eq!(r.counted(), 4 * opts.normals.len());
}

#[test]
fn bsdfs_pass() {
    let cases: Vec<_> = builtin_bsdfs()
        .into_iter()
        .filter(|c| {
            c.name.starts_with("roughconductor ggx")
                || c.name.starts_with("roughdielectric ggx a=0.4")
        })
        .collect();
    let opts = BsdfOptions {
        samples: 1 << 15,
        incident: vec![0.7],
        cos_bins: 8,
        phi_bins: 16,
        sub: 8,
        ..Default::default()
    };
    let r = validate::bsdf(&cpu(), &cases, &opts).unwrap();
    println!("{r}");
    assert!(r.passed(), "{r}");
}

#[test]
fn the_example_validates_then_renders() {
    let settings = custom_sampler::Settings {
        samples: 1 << 16,
        size: 16,
        paths: 2,
    };
    let (report, image) = custom_sampler::run(&cpu(), &settings).unwrap();
    assert!(report.passed(), "{report}");
    let image = image.expect("an image after the validation passed");
    assert_eq!((image.width, image.height), (16, 16));
    assert!(image.mean().max_element() > 0.0);
}

/// The rough dielectric at the settings that once failed: Beckmann at cos wo = 0.9 (a 16 x 16
/// quadrature overestimated the sharp transmitted lobe's integral) and 0.5 (the reported
/// density has Mitsuba's rational G1, 0.29 % off the sampling's: a known deviation, tested
/// against the exact density and said so), GGX at 0.5 with 32768 samples (a cell expecting
/// 11 samples got 1, and the sample variance made that p = 8.7e-13).
#[test]
fn rough_dielectrics_pass_where_they_failed() {
    let cases: Vec<_> = builtin_bsdfs()
        .into_iter()
        .filter(|c| {
            c.name == "roughdielectric beckmann a=0.4 eta=1.5"
                || c.name == "roughdielectric ggx a=0.4 eta=1.5"
        })
        .collect();
    assert_eq!(cases.len(), 2);
    let opts = BsdfOptions {
        samples: 1 << 15,
        incident: vec![0.9, 0.5],
        seed: 1,
        ..Default::default()
    };
    let r = validate::bsdf(&cpu(), &cases, &opts).unwrap();
    println!("{r}");
    assert!(r.passed(), "{r}");
    let beckmann_05: Vec<_> = r
        .tests
        .iter()
        .filter(|t| t.subject.contains("beckmann") && t.config == "cos wo=0.5")
        .collect();
    assert_eq!(beckmann_05.len(), 2);
    assert!(
        beckmann_05
            .iter()
            .all(|t| t.note.contains("known deviation")),
        "{r}"
    );
}
