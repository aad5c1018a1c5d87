//! Merging the images of disjoint sets of paths of one render (shards, or the parts
//! rendered on several devices): per pixel, the mean over all their paths, each part's
//! mean weighted by its path count.
//!
//! The renderer sums a pixel's paths in order into an f32 (`accum += l`), so a merge of
//! shards, which sums each shard's paths separately and then the shards, is the unsplit
//! image only up to float summation order: both sums are within (P - 1) * 2^-24 of the
//! exact sum of P nonnegative path values, so they differ by at most about
//! 2 * P * 2^-24 relative (`merge_tolerance`). One part merges bit-exactly. The merge
//! itself adds in f64, where the weights and the sum of at most 2^24 paths are exact
//! enough not to matter.

use glam::Vec3;

use crate::Image;

/// Merges `parts` (all of one size) into one image, weighting each pixel of each part by
/// its path count; a pixel with no path anywhere is black.
pub fn merge(parts: &[Image]) -> Result<Image, String> {
    let first = parts.first().ok_or("nothing to merge")?;
    let (w, h) = (first.width, first.height);
    let n = (w * h) as usize;
    if let Some(p) = parts.iter().find(|p| (p.width, p.height) != (w, h)) {
        return Err(format!(
            "cannot merge a {}x{} image with a {w}x{h} one",
            p.width, p.height
        ));
    }
    let mut sums = vec![[0f64; 3]; n];
    let mut paths = vec![0u32; n];
    for part in parts {
        for (i, (m, &c)) in part.pixels.iter().zip(&part.paths).enumerate() {
            paths[i] = paths[i]
                .checked_add(c)
                .ok_or("more than 2^32 paths in a pixel")?;
            for (s, v) in sums[i].iter_mut().zip(m.to_array()) {
                *s += v as f64 * c as f64;
            }
        }
    }
    let pixels = sums
        .iter()
        .zip(&paths)
        .map(|(s, &c)| {
            if c == 0 {
                Vec3::ZERO
            } else {
                Vec3::new(
                    (s[0] / c as f64) as f32,
                    (s[1] / c as f64) as f32,
                    (s[2] / c as f64) as f32,
                )
            }
        })
        .collect();
    Ok(Image {
        width: w,
        height: h,
        pixels,
        paths,
    })
}

/// The largest relative difference between a merge of shards and the unsplit render of
/// `paths` paths per pixel that float summation order explains (see the module docs):
/// 2 (P - 1) units of 2^-24 for the two orders of summation, plus a few roundings for
/// the divisions into means and the merge's conversions.
pub fn merge_tolerance(paths: u32) -> f32 {
    (2.0 * paths as f32 + 4.0) * f32::EPSILON / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(pixels: Vec<Vec3>, paths: Vec<u32>) -> Image {
        Image {
            width: pixels.len() as u32,
            height: 1,
            pixels,
            paths,
        }
    }

    #[test]
    fn weights_by_path_count() {
        let a = img(vec![Vec3::splat(1.0), Vec3::ZERO], vec![1, 0]);
        let b = img(vec![Vec3::splat(4.0), Vec3::ZERO], vec![3, 0]);
        let m = merge(&[a, b]).unwrap();
        assert_eq!(m.paths, vec![4, 0]);
        assert_eq!(m.pixels, vec![Vec3::splat(3.25), Vec3::ZERO]);
    }

    #[test]
    fn one_part_is_unchanged() {
        let a = img(vec![Vec3::new(0.1, 1.0 / 3.0, 7.7e-5)], vec![13]);
        let m = merge(std::slice::from_ref(&a)).unwrap();
        assert_eq!(
            m.pixels[0].to_array().map(f32::to_bits),
            a.pixels[0].to_array().map(f32::to_bits)
        );
    }

    #[test]
    fn sizes_must_match() {
        let a = img(vec![Vec3::ZERO], vec![1]);
        let b = img(vec![Vec3::ZERO; 2], vec![1; 2]);
        assert!(merge(&[a, b]).unwrap_err().contains("2x1"));
        assert!(merge(&[]).is_err());
    }
}
