//! Mitsuba `plastic`'s constants as the kernels compute them, against the values the
//! `mitsuba` package (3.9.1) reports: `mi.fresnel_diffuse_reflectance(eta)` and a default
//! `plastic`'s `fdr_int`, `fdr_ext` and `specular_sampling_weight` (its `repr`).

use cohort_kernels::sampling::{fresnel_diffuse_reflectance, plastic_specular_probability};
use glam::Vec3;

#[test]
fn diffuse_fresnel_reflectance_is_mitsubas() {
    for (eta, mitsuba) in [
        (1.000277f32 / 1.49, 0.590_478_96f32),
        (1.49 / 1.000277, 0.090_239),
        (1.1, 0.025_179_69),
        (1.9, 0.147_484_14),
        (0.7, 0.550_336_2),
    ] {
        let ours = fresnel_diffuse_reflectance(eta);
        assert!(
            (ours - mitsuba).abs() < 2e-6,
            "eta {eta}: {ours} vs Mitsuba's {mitsuba}"
        );
    }
}

#[test]
fn specular_sampling_follows_the_mean_albedos() {
    // Mitsuba's default plastic: specular_sampling_weight = 1 / (1 + 0.5) = 0.666667; with
    // f_i = 0.5 the specular lobe is then taken with probability 2/3 / (2/3 + 1/3 * 1).
    let p = plastic_specular_probability(0.5, Vec3::splat(0.5), Vec3::ONE);
    assert!((p - 2.0 / 3.0).abs() < 1e-6, "{p}");
    // No specular reflectance: never the coating; no diffuse: always.
    assert_eq!(
        plastic_specular_probability(0.3, Vec3::splat(0.5), Vec3::ZERO),
        0.0
    );
    assert_eq!(
        plastic_specular_probability(0.3, Vec3::ZERO, Vec3::ONE),
        1.0
    );
}
