//! Sampled spectra (`<spectrum value="400:0.1, 500:0.8, ..."/>`) to linear sRGB, as Mitsuba
//! 3's RGB variants convert them when a scene is loaded (`spectrum_list_to_srgb`): the
//! piecewise-linear spectrum is integrated against the CIE 1931 observer at 1000 evenly
//! spaced wavelengths from 360 to 830 nm (zero outside the given range), under Mitsuba's D65
//! for a reflectance (a flat spectrum of 0.5 is grey 0.5) and as is for an emitter (a flat
//! spectrum of 1 has luminance 1), then mapped from XYZ to linear sRGB. A reflectance is
//! clamped to [0, 1] and an emission to >= 0, with a warning, as Mitsuba does. The tables come
//! from the `mitsuba` package (`scripts/cie_tables.py`), which also wrote the test's oracle
//! (`scenes/tests/mitsuba_spectra.rs`).

use glam::Vec3;

use super::cie_tables::{CIE_MAX, CIE_MIN, CIE_XYZ_D65, CIE_Y_NORMALIZATION};

/// What the spectrum describes, which decides the illuminant and the clamping.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum SpectrumUse {
    Reflectance,
    Emission,
}

/// Mitsuba's `xyz_to_srgb` (linear sRGB, D65 white).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.240479, -1.537150, -0.498535],
    [-0.969256, 1.875991, 0.041556],
    [0.055648, -0.204043, 1.057311],
];

/// Quadrature points, as Mitsuba takes them.
const STEPS: usize = 1000;

/// The observer and D65 at `w` nm, linearly interpolated between whole nanometres.
fn observer(w: f64) -> [f64; 4] {
    let t = w - CIE_MIN;
    if t < 0.0 || w > CIE_MAX {
        return [0.0; 4];
    }
    let i = (t.floor() as usize).min(CIE_XYZ_D65.len() - 2);
    let f = t - i as f64;
    let (a, b) = (CIE_XYZ_D65[i], CIE_XYZ_D65[i + 1]);
    std::array::from_fn(|k| a[k] as f64 * (1.0 - f) + b[k] as f64 * f)
}

/// The colour of the piecewise-linear spectrum through `samples` (wavelengths increasing, at
/// least two), and whether it had to be clamped into range.
pub(crate) fn to_srgb(samples: &[(f64, f64)], used_as: SpectrumUse) -> (Vec3, bool) {
    debug_assert!(samples.len() >= 2);
    let (first, last) = (samples[0].0, samples[samples.len() - 1].0);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // The last sample whose wavelength is <= w, leaving room for its right neighbour.
        let k = samples
            .partition_point(|s| s.0 <= w)
            .saturating_sub(1)
            .min(samples.len() - 2);
        let ((w0, v0), (w1, v1)) = (samples[k], samples[k + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let [x, y, z, d65] = observer(w);
        let weight = match used_as {
            SpectrumUse::Reflectance => v * d65,
            SpectrumUse::Emission => v,
        };
        xyz[0] += x * weight;
        xyz[1] += y * weight;
        xyz[2] += z * weight;
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * CIE_Y_NORMALIZATION;
    let rgb: [f64; 3] =
        std::array::from_fn(|r| (0..3).map(|c| XYZ_TO_SRGB[r][c] * xyz[c] * scale).sum());
    let rgb = Vec3::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32);
    let clamped = match used_as {
        SpectrumUse::Reflectance => rgb.clamp(Vec3::ZERO, Vec3::ONE),
        SpectrumUse::Emission => rgb.max(Vec3::ZERO),
    };
    (clamped, clamped != rgb)
}
