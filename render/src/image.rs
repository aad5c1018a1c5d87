//! A rendered image: linear RGB per pixel (row-major, top row first) and the number
//! of completed paths behind each pixel.

use glam::Vec3;

#[derive(Clone, Debug)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
    pub paths: Vec<u32>,
}

impl Image {
    pub fn mean(&self) -> Vec3 {
        self.pixels.iter().copied().sum::<Vec3>() / self.pixels.len().max(1) as f32
    }

    /// Root-mean-square difference to `other` over pixels and channels.
    pub fn rms_diff(&self, other: &Image) -> f32 {
        assert_eq!((self.width, self.height), (other.width, other.height));
        let s: f64 = self
            .pixels
            .iter()
            .zip(&other.pixels)
            .map(|(a, b)| {
                let d = *a - *b;
                (d.x as f64).powi(2) + (d.y as f64).powi(2) + (d.z as f64).powi(2)
            })
            .sum();
        (s / (3 * self.pixels.len()) as f64).sqrt() as f32
    }
}
