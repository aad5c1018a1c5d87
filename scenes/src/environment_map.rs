//! Mitsuba's `envmap` emitter: a latitude-longitude image of the radiance arriving from
//! every direction, and the data the kernels sample it with (`cohort_kernels::environment`).
//!
//! Mapping (Mitsuba 3.9, `envmap.cpp`): a direction `d` in the emitter's frame
//! (`to_world`'s inverse applied to the world direction) has longitude
//! u = atan2(d.x, -d.z) / 2 pi and colatitude v = acos(d.y) / pi. Columns are texel-centred
//! and periodic in u (column x at u = (x + 0.5) / W); rows run from v = 0 (row 0) to v = 1
//! (row H - 1), corner-aligned. Radiance is the bilinear interpolation of the texels times
//! `scale`.
//!
//! Sampling draws (u, v) with a density proportional to the bilinear interpolation of
//! luminance x sin(theta) over the same grid of texel centres (W + 1 columns, the last the
//! first again, by H rows): Mitsuba's own density, so the variance per sample is Mitsuba's.
//! A cell between four texel centres is chosen through an alias table, then a point in it
//! by inverting the bilinear density (linear in x, then linear in y given x).

use glam::{Mat3, Vec3};

use crate::alias::alias_table;

/// Entries of the kernels' header before the texels: (W, H) as bits, then the three rows
/// of the world-to-map rotation, then the three rows of the map-to-world one.
pub const ENV_HEADER: usize = 7;

/// An environment map: `width * height` linear RGB radiance texels (scale applied), row 0
/// at the top (v = 0, the map's +y pole).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    /// Map frame to world (Mitsuba's `to_world`, its linear part).
    pub to_world: Mat3,
}

/// Mitsuba's luminance, in double precision for the sums below.
fn luminance(c: Vec3) -> f64 {
    crate::texture::luminance(c) as f64
}

impl EnvironmentMap {
    /// The map of an image (`width * height` texels, row 0 at the top) times `scale`, under
    /// `to_world`. Like Mitsuba, an image narrower than 2 or lower than 3 texels is first
    /// padded by repeating its last column and row.
    pub fn new(width: u32, height: u32, texels: &[Vec3], scale: f32, to_world: Mat3) -> Self {
        let w = width.max(2);
        let h = height.max(3);
        let mut out = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            let sy = y.min(height - 1);
            for x in 0..w {
                let sx = x.min(width - 1);
                out.push(texels[(sy * width + sx) as usize] * scale);
            }
        }
        EnvironmentMap {
            width: w,
            height: h,
            texels: out,
            to_world,
        }
    }

    /// Whether the map emits anything (else it is no light at all).
    pub fn is_black(&self) -> bool {
        self.texels.iter().all(|t| luminance(*t) <= 0.0)
    }

    /// Mean radiance over the sphere's directions (a power estimate for the light choice).
    pub fn mean_radiance(&self) -> Vec3 {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut sum = glam::DVec3::ZERO;
        let mut weight = 0.0;
        for y in 0..h {
            let s = (std::f64::consts::PI * y as f64 / (h - 1) as f64).sin();
            for x in 0..w {
                sum += self.texels[y * w + x].as_dvec3() * s;
                weight += s;
            }
        }
        (sum / weight.max(1e-30)).as_vec3()
    }

    /// Continuous texel coordinates of world direction `d`: x in [0, W) along the longitude
    /// (texel centres at integers, periodic), y in [0, H - 1] along the colatitude.
    fn texel_coords(&self, d: Vec3) -> (f32, f32) {
        let l = (self.to_world.inverse() * d).normalize();
        let u = l.x.atan2(-l.z) * (0.5 * std::f32::consts::FRAC_1_PI);
        let v = l.y.clamp(-1.0, 1.0).acos() * std::f32::consts::FRAC_1_PI;
        let w = self.width as f32;
        let x = u * w - 0.5;
        let x = x - w * (x / w).floor();
        (x, v * (self.height - 1) as f32)
    }

    /// Radiance arriving from world direction `d` (the direction a ray leaves the scene
    /// in), as Mitsuba's `eval`.
    pub fn eval(&self, d: Vec3) -> Vec3 {
        let (x, y) = self.texel_coords(d);
        let (w, h) = (self.width, self.height);
        let x0 = (x.floor() as u32).min(w - 1);
        let y0 = (y.floor() as u32).min(h - 2);
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let x1 = (x0 + 1) % w;
        let t = |x: u32, y: u32| self.texels[(y * w + x) as usize];
        let top = t(x0, y0) * (1.0 - fx) + t(x1, y0) * fx;
        let bottom = t(x0, y0 + 1) * (1.0 - fx) + t(x1, y0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The sampling density's values at the (W + 1) x H texel centres (column W is column
    /// 0 again), normalised so that their bilinear interpolation integrates to 1 over the
    /// (u, v) unit square; and the cells' weights (the mean of their four corners).
    fn density(&self) -> (Vec<f64>, Vec<f64>) {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut vertex = vec![0.0f64; (w + 1) * h];
        for y in 0..h {
            let s = (std::f64::consts::PI * y as f64 / (h - 1) as f64)
                .sin()
                .max(0.0);
            for x in 0..=w {
                vertex[y * (w + 1) + x] = luminance(self.texels[y * w + x % w]).max(0.0) * s;
            }
        }
        let mut cells = vec![0.0f64; w * (h - 1)];
        for y in 0..h - 1 {
            for x in 0..w {
                let v = |x: usize, y: usize| vertex[y * (w + 1) + x];
                cells[y * w + x] = 0.25 * (v(x, y) + v(x + 1, y) + v(x, y + 1) + v(x + 1, y + 1));
            }
        }
        // The bilinear function's integral over the unit square: each cell covers
        // 1 / (W (H - 1)) of it.
        let integral = cells.iter().sum::<f64>() / (w * (h - 1)) as f64;
        if integral > 0.0 {
            vertex.iter_mut().for_each(|v| *v /= integral);
        }
        (vertex, cells)
    }

    /// The map in the kernels' layout (`cohort_kernels::environment`): the header
    /// ([`ENV_HEADER`] entries), the texels row by row, then (W + 1) x H entries whose z is
    /// the normalised density at a texel centre and, for the first W (H - 1), x and y (as
    /// bits) the alias table over the cells (cell index = row W + column).
    pub fn gpu_layout(&self) -> Vec<[f32; 4]> {
        let bits = f32::from_bits;
        let mut data = Vec::with_capacity(ENV_HEADER + self.texels.len() * 2 + 2);
        data.push([bits(self.width), bits(self.height), 0.0, 0.0]);
        let inv = self.to_world.inverse();
        for r in 0..3 {
            data.push(inv.row(r).extend(0.0).to_array());
        }
        for r in 0..3 {
            data.push(self.to_world.row(r).extend(0.0).to_array());
        }
        data.extend(self.texels.iter().map(|t| t.extend(0.0).to_array()));
        let (vertex, cells) = self.density();
        let table = if cells.iter().sum::<f64>() > 0.0 {
            alias_table(&cells)
        } else {
            Vec::new()
        };
        for (i, v) in vertex.iter().enumerate() {
            let (prob, alias) = table.get(i).map_or((1.0, 0), |e| (e.prob, e.alias));
            data.push([prob, bits(alias), *v as f32, 0.0]);
        }
        data
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map() -> EnvironmentMap {
        let texels: Vec<Vec3> = (0..8 * 4)
            .map(|i| Vec3::new(i as f32, (i % 8) as f32, 1.0))
            .collect();
        EnvironmentMap::new(8, 4, &texels, 2.0, Mat3::IDENTITY)
    }

    /// Texel centres: column x at longitude (x + 0.5) / W, row y at colatitude y / (H - 1).
    #[test]
    fn texel_centres_are_where_mitsuba_puts_them() {
        let m = map();
        for (x, y) in [(0u32, 0u32), (3, 1), (7, 2), (5, 3)] {
            let u = (x as f32 + 0.5) / 8.0;
            let v = y as f32 / 3.0;
            let (theta, phi) = (v * std::f32::consts::PI, u * 2.0 * std::f32::consts::PI);
            let d = Vec3::new(
                phi.sin() * theta.sin(),
                theta.cos(),
                -phi.cos() * theta.sin(),
            );
            let got = m.eval(d);
            let want = m.texels[(y * 8 + x) as usize];
            // At the poles every longitude meets: only the row matters there.
            if y == 0 || y == 3 {
                assert!((got.z - want.z).abs() < 1e-4, "({x}, {y}): {got} vs {want}");
            } else {
                assert!(
                    (got - want).abs().max_element() < 1e-3,
                    "({x}, {y}): {got} vs {want}"
                );
            }
        }
    }

    /// Longitude wraps: halfway between the last column and the first is their mean.
    #[test]
    fn longitude_is_periodic() {
        let m = map();
        let theta = std::f32::consts::PI / 3.0;
        let d = Vec3::new(0.0, theta.cos(), -theta.sin());
        let want = (m.texels[8 + 7] + m.texels[8]) * 0.5;
        assert!((m.eval(d) - want).abs().max_element() < 1e-3);
    }

    /// The normalised density integrates to 1 over the unit square.
    #[test]
    fn density_is_normalised() {
        let m = map();
        let (vertex, _) = m.density();
        let (w, h) = (9usize, 4usize);
        let mut integral = 0.0;
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                let v = |x: usize, y: usize| vertex[y * w + x];
                integral += 0.25 * (v(x, y) + v(x + 1, y) + v(x, y + 1) + v(x + 1, y + 1));
            }
        }
        integral /= ((w - 1) * (h - 1)) as f64;
        assert!((integral - 1.0).abs() < 1e-9, "{integral}");
    }

    #[test]
    fn small_images_are_padded_as_mitsuba_pads_them() {
        let m = EnvironmentMap::new(1, 1, &[Vec3::ONE], 3.0, Mat3::IDENTITY);
        assert_eq!((m.width, m.height), (2, 3));
        assert!(m.texels.iter().all(|t| *t == Vec3::splat(3.0)));
    }
}
