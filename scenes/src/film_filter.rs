//! Mitsuba's reconstruction filters (`<rfilter>`), as the renderer samples them.
//!
//! Mitsuba splats every sample into the pixels within the filter's radius with the weight
//! `f(dx) f(dy)` and divides each pixel by its sum of weights. In its scalar variants (the
//! reference, `scalar_rgb`) `f` is the tabulated form `eval_discretized`: the filter's value at
//! `radius * i / 31` held constant on `[radius * i / 31, radius * (i + 1) / 31)`, so `f` is a
//! step function of 62 steps over `[-radius, radius]`. A pixel's expected value is the mean of
//! the radiance over the sampled film area weighted by `f` around the pixel's centre.
//!
//! The renderer gets the same expectation without splatting (filter importance sampling): a
//! pixel's camera rays are placed at offsets drawn in proportion to `|f|` from its centre,
//! restricted to the sampled film area, each weighted by the sign of `f` times
//! `integral |f| / integral f` over that area (1 for a filter without negative lobes).
//! [`FilmFilter::table`] is what the kernels read (`cohort_kernels::extend::film_sample`).

/// Steps of Mitsuba's tabulated filter on each side of the centre (`MI_FILTER_RESOLUTION`).
pub const FILTER_STEPS: usize = 31;

/// Bins of [`FilmFilter::table`] across `[-radius, radius]`.
pub const FILTER_BINS: usize = 2 * FILTER_STEPS;

/// A reconstruction filter other than the box (the box is `Camera::filter = None`: each
/// sample counts in its own pixel only, uniformly over it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmFilter {
    /// Mitsuba's plugin name, for messages.
    pub kind: FilterKind,
    pub radius: f32,
    /// `eval(radius * i / 31)` for i in 0..31 (Mitsuba's `m_values`; beyond the last the
    /// filter is 0).
    pub values: [f32; FILTER_STEPS],
    /// Mitsuba's `sample_border`: samples also land up to `border()` pixels outside the
    /// film (or crop window), so that edge pixels see the whole filter.
    pub sample_border: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterKind {
    Gaussian { stddev: f32 },
    Tent,
    Mitchell { b: f32, c: f32 },
    CatmullRom,
    Lanczos { lobes: u32 },
}

impl FilterKind {
    pub fn name(&self) -> &'static str {
        match self {
            FilterKind::Gaussian { .. } => "gaussian",
            FilterKind::Tent => "tent",
            FilterKind::Mitchell { .. } => "mitchell",
            FilterKind::CatmullRom => "catmullrom",
            FilterKind::Lanczos { .. } => "lanczos",
        }
    }
}

impl FilmFilter {
    /// Mitsuba's `gaussian` (its default filter): `max(0, exp(-x^2 / (2 stddev^2)) - bias)`
    /// cut at 4 standard deviations.
    pub fn gaussian(stddev: f32) -> FilmFilter {
        let radius = 4.0 * stddev;
        let alpha = -1.0 / (2.0 * stddev * stddev);
        let bias = (alpha * radius * radius).exp();
        FilmFilter::tabulate(FilterKind::Gaussian { stddev }, radius, |x| {
            ((alpha * x * x).exp() - bias).max(0.0)
        })
    }

    /// Mitsuba's `tent`: `max(0, 1 - |x| / radius)`.
    pub fn tent(radius: f32) -> FilmFilter {
        let inv = 1.0 / radius;
        FilmFilter::tabulate(FilterKind::Tent, radius, |x| {
            (1.0 - (x * inv).abs()).max(0.0)
        })
    }

    /// Mitsuba's `mitchell` (Mitchell-Netravali cubic, radius 2).
    pub fn mitchell(b: f32, c: f32) -> FilmFilter {
        FilmFilter::tabulate(FilterKind::Mitchell { b, c }, 2.0, |x| cubic(x, b, c))
    }

    /// Mitsuba's `catmullrom`: the cubic with B = 0, C = 1/2.
    pub fn catmull_rom() -> FilmFilter {
        FilmFilter::tabulate(FilterKind::CatmullRom, 2.0, |x| cubic(x, 0.0, 0.5))
    }

    /// Mitsuba's `lanczos`: the windowed sinc with `lobes` lobes (its radius).
    pub fn lanczos(lobes: u32) -> FilmFilter {
        let radius = lobes as f32;
        FilmFilter::tabulate(FilterKind::Lanczos { lobes }, radius, |x| {
            let x = x.abs();
            let x1 = core::f32::consts::PI * x;
            let x2 = x1 / radius;
            if x < f32::EPSILON {
                1.0
            } else if x > radius {
                0.0
            } else {
                (x1.sin() * x2.sin()) / (x1 * x2)
            }
        })
    }

    fn tabulate(kind: FilterKind, radius: f32, eval: impl Fn(f32) -> f32) -> FilmFilter {
        let mut values = [0.0; FILTER_STEPS];
        for (i, v) in values.iter_mut().enumerate() {
            *v = eval(radius * i as f32 / FILTER_STEPS as f32);
        }
        FilmFilter {
            kind,
            radius,
            values,
            sample_border: false,
        }
    }

    /// Pixels sampled beyond each edge of the film with `sample_border` (Mitsuba's
    /// `border_size`), else 0.
    pub fn border(&self) -> u32 {
        if self.sample_border {
            (self.radius - 0.5 - 2.0 * ray_epsilon()).ceil().max(0.0) as u32
        } else {
            0
        }
    }

    /// The filter's value at offset `x` (pixels) from a pixel's centre, as Mitsuba's
    /// `eval_discretized` gives it.
    pub fn eval_discretized(&self, x: f32) -> f32 {
        let i = (x * (FILTER_STEPS as f32 / self.radius)).abs() as usize;
        self.values.get(i).copied().unwrap_or(0.0)
    }

    /// Value of bin `k` of `[-radius, radius]` split in [`FILTER_BINS`] equal bins.
    fn bin(&self, k: usize) -> f32 {
        if k >= FILTER_STEPS {
            self.values[k - FILTER_STEPS]
        } else {
            self.values[FILTER_STEPS - 1 - k]
        }
    }

    /// What the kernels read: the cumulative integral of `|f|` at the edges of the
    /// [`FILTER_BINS`] bins over `[-radius, radius]` (`FILTER_BINS + 1` values from 0), then
    /// the same for the signed `f`.
    pub fn table(&self) -> Vec<f32> {
        let h = self.radius / FILTER_STEPS as f32;
        let mut abs = vec![0.0f32; FILTER_BINS + 1];
        let mut signed = vec![0.0f32; FILTER_BINS + 1];
        for k in 0..FILTER_BINS {
            abs[k + 1] = abs[k] + self.bin(k).abs() * h;
            signed[k + 1] = signed[k] + self.bin(k) * h;
        }
        abs.extend(signed);
        abs
    }
}

/// Mitsuba's `math::RayEpsilon<float>`.
fn ray_epsilon() -> f32 {
    f32::EPSILON / 2.0 * 1500.0
}

/// The Mitchell-Netravali cubic with parameters `b`, `c`, as Mitsuba evaluates it.
fn cubic(x: f32, b: f32, c: f32) -> f32 {
    let x = x.abs();
    let x2 = x * x;
    let x3 = x2 * x;
    let r = if x < 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * x3 + (-18.0 + 12.0 * b + 6.0 * c) * x2 + (6.0 - 2.0 * b)
    } else {
        (-b - 6.0 * c) * x3
            + (6.0 * b + 30.0 * c) * x2
            + (-12.0 * b - 48.0 * c) * x
            + (8.0 * b + 24.0 * c)
    };
    if x < 2.0 {
        r / 6.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gaussian_table_is_mitsubas() {
        let f = FilmFilter::gaussian(0.5);
        assert_eq!(f.radius, 2.0);
        // eval(0) = 1 - exp(-8).
        assert!((f.values[0] - (1.0 - (-8.0f32).exp())).abs() < 1e-6);
        // The step holds its left value: f(0.06) = f(0) (one step is 2/31 wide).
        assert_eq!(f.eval_discretized(0.06), f.values[0]);
        assert_eq!(f.eval_discretized(-0.07), f.values[1]);
        assert_eq!(f.eval_discretized(2.0), 0.0);
        let t = f.table();
        assert_eq!(t.len(), 2 * (FILTER_BINS + 1));
        // A positive filter: both halves agree, and the table is symmetric around the centre.
        assert_eq!(t[..FILTER_BINS + 1], t[FILTER_BINS + 1..]);
        let total = t[FILTER_BINS];
        assert!((t[FILTER_STEPS] - total / 2.0).abs() < 1e-6 * total);
    }

    #[test]
    fn negative_lobes_show_in_the_signed_table_only() {
        let f = FilmFilter::lanczos(3);
        let t = f.table();
        let (abs, signed) = t.split_at(FILTER_BINS + 1);
        assert!(abs[FILTER_BINS] > signed[FILTER_BINS]);
        assert!(signed[FILTER_BINS] > 0.0);
        assert!(abs.windows(2).all(|w| w[1] >= w[0]));
    }

    #[test]
    fn the_border_is_mitsubas() {
        let mut f = FilmFilter::gaussian(0.5);
        assert_eq!(f.border(), 0);
        f.sample_border = true;
        assert_eq!(f.border(), 2);
        let mut t = FilmFilter::tent(1.0);
        t.sample_border = true;
        assert_eq!(t.border(), 1);
    }
}
