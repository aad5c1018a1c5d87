//! Coherent light sampling against independent light sampling at equal time (the equal-time
//! work against Mitsuba 3): for each scene, a long reference with independent light
//! sampling, then each configuration for the same kernel time, round-robin and repeated,
//! reporting paths/s and the RMS error against the reference (relative to the reference's
//! mean).
//!
//! `cargo run --release -p cohort-render --example light_sampling -- [scene[,scene...]]
//! [seconds] [reference seconds]` (defaults: `cornell,confroom`, 1, 20). Scenes are
//! embedded names or Mitsuba XML files; 1024x1024, NEE, no compaction.

use std::time::Duration;

use cohort::runtime::Device;
use cohort_render::{Algorithm, Budget, GpuScene, Image, IntegratorKind, RenderOptions, Renderer};
use cohort_scenes::{embedded, Scene};

fn load(name: &str) -> Scene {
    embedded::load(name).unwrap_or_else(|| {
        cohort_scenes::load_mitsuba(name)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .scene
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scenes = args
        .get(1)
        .map(String::as_str)
        .unwrap_or("cornell,confroom");
    let seconds: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let reference_seconds: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(20.0);
    let device = Device::best().expect("device");
    println!(
        "device: {} [{}]",
        device.info().adapter_name,
        device.info().backend.name()
    );
    // (label, algorithm, coherent light)
    let configs: Vec<(String, Algorithm, bool)> = ["normal", "warp", "block_256"]
        .iter()
        .flat_map(|a| {
            let alg = Algorithm::parse(a).unwrap();
            let mut v = vec![(a.to_string(), alg, false)];
            if *a != "normal" {
                v.push((format!("{a} + coherent light"), alg, true));
            }
            v
        })
        .collect();
    for name in scenes.split(',') {
        let scene = load(name);
        let gpu = GpuScene::prepare(&device, &scene).expect("scene");
        let opts = |alg: Algorithm, coherent_light: bool, t: f64, seed: u32| RenderOptions {
            algorithm: alg,
            integrator: IntegratorKind::Nee,
            coherent_light,
            compact: false,
            size: Some((1024, 1024)),
            budget: Budget::KernelTime(Duration::from_secs_f64(t)),
            seed,
            ..Default::default()
        };
        let render = |o: RenderOptions| -> (Image, f64) {
            let mut r = Renderer::with_scene(&device, &scene, gpu.clone(), o).expect("renderer");
            let (img, stats) = r.render(|_, _| {}).expect("render");
            (img, stats.paths_per_second())
        };
        let (reference, _) = render(opts(Algorithm::NORMAL, false, reference_seconds, 1000));
        let mean = reference.mean().dot(glam::Vec3::ONE) / 3.0;
        println!("{name}: reference {reference_seconds} s, mean {mean:.4}");
        // Round-robin, twice: clock drift hits every configuration alike.
        let mut rows: Vec<(f64, f64, u32)> = vec![(0.0, 0.0, 0); configs.len()];
        for rep in 0..2u32 {
            for (i, (_, alg, cl)) in configs.iter().enumerate() {
                let (img, pps) = render(opts(*alg, *cl, seconds, 1 + rep * 100 + i as u32));
                let rms = img.rms_diff(&reference) / mean;
                rows[i].0 += rms as f64;
                rows[i].1 += pps;
                rows[i].2 += 1;
            }
        }
        let base = rows[0].0 / rows[0].2 as f64;
        for ((label, _, _), (rms, pps, n)) in configs.iter().zip(&rows) {
            let (rms, pps) = (rms / *n as f64, pps / *n as f64);
            println!(
                "{name} {seconds} s {label:<28} {:>8.1} M paths/s  RMS {:>6.2} %  ({:.2}x normal's RMS)",
                pps / 1e6,
                100.0 * rms,
                rms / base
            );
        }
    }
}
