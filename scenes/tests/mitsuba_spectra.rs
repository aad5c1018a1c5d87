//! Sampled spectra become the linear sRGB colours that Mitsuba 3.9.1's RGB variants give
//! them: as a reflectance (under D65, clamped to [0, 1]) and as an emitter's intensity or
//! radiance (no illuminant, clamped at 0). The oracle, `data/mitsuba_spectra.txt`, was
//! written by `scripts/cie_tables.py` from the `mitsuba` package itself.

use cohort_scenes::{load_mitsuba_str, Bsdf, Light, Loaded};
use glam::Vec3;

fn load(body: &str) -> Result<Loaded, String> {
    let xml = format!(r#"<scene version="3.0.0">{body}</scene>"#);
    load_mitsuba_str(&xml, ".").map_err(|e| e.to_string())
}

fn reflectance(spectrum: &str) -> (Vec3, usize) {
    let l = load(&format!(
        r#"<shape type="rectangle"><bsdf type="diffuse"><spectrum name="reflectance" value="{spectrum}"/></bsdf></shape>"#
    ))
    .unwrap();
    let Bsdf::Diffuse { reflectance } = l.scene.materials[0].bsdf else {
        panic!("diffuse expected");
    };
    let clamped = l
        .warnings
        .iter()
        .filter(|w| w.to_string().contains("out-of-gamut"))
        .count();
    (reflectance, clamped)
}

fn intensity(spectrum: &str) -> Vec3 {
    let l = load(&format!(
        r#"<emitter type="point"><spectrum name="intensity" value="{spectrum}"/></emitter>"#
    ))
    .unwrap();
    match l.scene.lights[0] {
        Light::Point { intensity, .. } => intensity,
        ref other => panic!("point light expected, got {other:?}"),
    }
}

fn area_radiance(spectrum: &str) -> Vec3 {
    let l = load(&format!(
        r#"<shape type="rectangle"><emitter type="area"><spectrum name="radiance" value="{spectrum}"/></emitter></shape>"#
    ))
    .unwrap();
    l.scene.materials[0].emission.expect("an emitting material")
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 2e-5 * (1.0 + b.abs().max_element())
}

#[test]
fn sampled_spectra_match_mitsubas_colours() {
    let data = include_str!("data/mitsuba_spectra.txt");
    let mut checked = 0;
    for line in data
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let parts: Vec<&str> = line.split('|').map(str::trim).collect();
        let [kind, spectrum, rgb] = parts[..] else {
            panic!("bad oracle line {line}");
        };
        let v: Vec<f32> = rgb.split_whitespace().map(|x| x.parse().unwrap()).collect();
        let want = Vec3::new(v[0], v[1], v[2]);
        match kind {
            "reflectance" => {
                let (got, _) = reflectance(spectrum);
                assert!(
                    close(got, want),
                    "reflectance {spectrum}: {got} vs Mitsuba's {want}"
                );
            }
            "emitter" => {
                let got = intensity(spectrum);
                assert!(
                    close(got, want),
                    "intensity {spectrum}: {got} vs Mitsuba's {want}"
                );
                let got = area_radiance(spectrum);
                assert!(
                    close(got, want),
                    "radiance {spectrum}: {got} vs Mitsuba's {want}"
                );
            }
            other => panic!("unknown kind {other}"),
        }
        checked += 1;
    }
    assert!(checked >= 16, "the oracle has {checked} cases");
}

#[test]
fn a_flat_reflectance_spectrum_is_grey() {
    let (c, warnings) = reflectance("360:0.5, 830:0.5");
    assert!((c - Vec3::splat(0.5)).abs().max_element() < 1e-3, "{c}");
    assert_eq!(warnings, 0);
}

#[test]
fn out_of_gamut_spectra_are_clamped_with_a_warning() {
    // A narrow green band lies outside the sRGB gamut (negative blue).
    let (c, warnings) = reflectance("550:0.5, 560:0.5");
    assert_eq!(c.z, 0.0);
    assert_eq!(warnings, 1);
}

#[test]
fn malformed_spectra_are_located_errors() {
    for (value, expect) in [
        ("500:0.5, 400:0.5", "must increase"),
        ("500:0.5", "at least two"),
        ("500 0.5, 600:1", "wavelength:value"),
        ("500:x, 600:1", "not a finite number"),
    ] {
        let e = load(&format!(
            r#"<shape type="rectangle"><bsdf type="diffuse">
<spectrum name="reflectance" value="{value}"/></bsdf></shape>"#
        ))
        .unwrap_err();
        assert!(e.contains(expect) && e.contains(":2:"), "{value}: {e}");
    }
}
