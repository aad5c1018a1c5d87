//! The references the points are compared with: a long `normal` render per scene and
//! size, cached in the out dir as `reference_<scene>_<w>x<h>.exr` (so later runs, and the
//! shards of a sweep that share the out dir, reuse it), read back from that EXR; the RMS
//! error against it; and a checksum that lets the merge see shards that measured against
//! different references.

use std::path::{Path, PathBuf};

use cohort_render::{output, Algorithm, Budget, Image, RenderOptions};
use glam::Vec3;

use super::measure::{LoadedScene, Sweep};

/// The seed of the reference: different from every point's, so that the reference's noise
/// is independent of theirs (with the same seed `normal` would repeat its first paths).
fn reference_seed(seed: u32) -> u32 {
    seed ^ 0x5eed_5eed
}

/// Where the reference of a scene at a size is cached. Not by budget, seed or integrator:
/// a reference is an estimate of the same image whatever made it.
pub fn reference_path(out_dir: &Path, label: &str, (w, h): (u32, u32)) -> PathBuf {
    out_dir.join(format!("reference_{label}_{w}x{h}.exr"))
}

/// The scene's reference: read from the out dir if a file of the right size is there,
/// else rendered under `--reference-time` and written there.
pub fn reference_image(sweep: &Sweep, scene: &LoadedScene) -> Result<Image, String> {
    let (plan, spec, (w, h)) = (sweep.plan, scene.spec, scene.size);
    let path = reference_path(&plan.out_dir, &spec.label, (w, h));
    if path.exists() {
        match read_exr(&path) {
            Ok(img) if (img.width, img.height) == (w, h) => {
                sweep.log(format!(
                    "{}: reusing the reference {}",
                    spec.label,
                    path.display()
                ));
                return Ok(img);
            }
            Ok(img) => sweep.log(format!(
                "{}: {} is {}x{}, not {w}x{h}: rendering it again",
                spec.label,
                path.display(),
                img.width,
                img.height
            )),
            Err(e) => sweep.log(format!(
                "{}: cannot read {} ({e}): rendering it again",
                spec.label,
                path.display()
            )),
        }
    }
    let opts = RenderOptions {
        algorithm: Algorithm::NORMAL,
        budget: Budget::KernelTime(plan.reference_time),
        seed: reference_seed(plan.seed),
        size: Some((w, h)),
        // Both integrators converge to the same image; light sampling gets there sooner.
        integrator: plan.integrator,
        ..Default::default()
    };
    let (image, stats) = sweep
        .render(scene, opts)
        .map_err(|e| format!("{} reference: {e}", spec.label))?;
    output::write_exr(&path, &image, &[]).map_err(|e| e.to_string())?;
    sweep.log(format!(
        "{}: reference {:.1} paths/pixel in {:.2} s kernel time, wrote {}",
        spec.label,
        stats.paths_per_pixel(),
        stats.kernel.total().as_secs_f64(),
        path.display()
    ));
    Ok(image)
}

/// Reads an RGB(A) EXR written by `output::write_exr` (alpha, if any, is ignored).
fn read_exr(path: &Path) -> Result<Image, String> {
    struct Pixels {
        width: usize,
        data: Vec<Vec3>,
    }
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| Pixels {
            width: size.width(),
            data: vec![Vec3::ZERO; size.width() * size.height()],
        },
        |p: &mut Pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            p.data[pos.y() * p.width + pos.x()] = Vec3::new(r, g, b)
        },
    )
    .map_err(|e| e.to_string())?;
    let size = img.layer_data.size;
    let pixels = img.layer_data.channel_data.pixels.data;
    Ok(Image {
        width: size.width() as u32,
        height: size.height() as u32,
        paths: vec![0; pixels.len()],
        pixels,
    })
}

/// Names a reference's pixels: its size and an FNV-1a hash of their bits. The EXR holds
/// the same f32 values as the rendered image, so a reference reads back to the checksum
/// it was rendered with, and shards that shared one file agree on it.
pub fn checksum(img: &Image) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for p in &img.pixels {
        for c in p.to_array() {
            for byte in c.to_bits().to_le_bytes() {
                hash = (hash ^ byte as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    format!("{}x{} fnv1a-64:{hash:016x}", img.width, img.height)
}

/// RMS error in percent: the root mean square of (image - reference) over all pixels and
/// RGB channels, divided by the root mean square of the reference over the same, x 100.
pub fn rms_percent(img: &Image, reference: &Image) -> f64 {
    let (mut diff, mut norm) = (0f64, 0f64);
    for (a, r) in img.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (a, r) = (a[c] as f64, r[c] as f64);
            diff += (a - r) * (a - r);
            norm += r * r;
        }
    }
    100.0 * (diff / norm).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(v: f32) -> Image {
        Image {
            width: 2,
            height: 1,
            pixels: vec![Vec3::splat(v); 2],
            paths: vec![1; 2],
        }
    }

    #[test]
    fn rms_percent_is_relative_to_the_reference() {
        assert_eq!(rms_percent(&img(1.0), &img(1.0)), 0.0);
        assert!((rms_percent(&img(1.1), &img(1.0)) - 10.0).abs() < 1e-4);
        assert!((rms_percent(&img(0.0), &img(2.0)) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn checksums_tell_pixels_apart() {
        assert_eq!(checksum(&img(1.0)), checksum(&img(1.0)));
        assert_ne!(checksum(&img(1.0)), checksum(&img(1.0 + f32::EPSILON)));
        assert!(checksum(&img(1.0)).starts_with("2x1 "));
    }
}
