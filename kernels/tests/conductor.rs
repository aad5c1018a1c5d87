//! Conductor pieces as the kernels compute them, against the `mitsuba` package (3.9.1,
//! scalar_rgb): `mi.fresnel_conductor(cos, Complex2f(eta, k))`, and a Beckmann
//! `mi.MicrofacetDistribution(Beckmann, 0.3)`'s `smith_g1` and `eval`.

use cohort_kernels::sampling::{
    beckmann_d, beckmann_g1, beckmann_sample, fresnel_conductor, microfacet_eval,
};
use glam::{Vec2, Vec3};

#[test]
fn conductor_fresnel_is_mitsubas() {
    for (cos, eta, k, mitsuba) in [
        (1.0f32, 0.143036f32, 3.983f32, 0.966_679_33f32),
        (0.5, 0.375307, 2.38556, 0.804_371_2),
        (0.1, 1.44205, 1.60336, 0.718_890_3),
        (0.8, 0.2, 3.0, 0.922_402_86),
        (0.3, 1.5, 0.0, 0.207_756_33),
    ] {
        let f = fresnel_conductor(cos, Vec3::splat(eta), Vec3::splat(k));
        assert!(
            (f.x - mitsuba).abs() < 2e-6,
            "cos {cos} eta {eta} k {k}: {f} vs {mitsuba}"
        );
        assert_eq!((f.x, f.x), (f.y, f.z));
    }
    // Mitsuba's material none: eta 0, k 1 reflects everything at every angle.
    for cos in [1.0, 0.7, 0.2, 0.01] {
        let f = fresnel_conductor(cos, Vec3::ZERO, Vec3::ONE);
        assert!((f - Vec3::ONE).abs().max_element() < 1e-6, "{f}");
    }
}

#[test]
fn beckmann_is_mitsubas() {
    let alpha = 0.3;
    for (cos, g1, d) in [(0.9f32, 1.0f32, 0.397_861_03f32), (0.2, 0.912_688_25, 0.0)] {
        assert!((beckmann_g1(cos, alpha) - g1).abs() < 1e-6, "G1({cos})");
        assert!((beckmann_d(cos, alpha) - d).abs() < 1e-6, "D({cos})");
    }
}

/// The Beckmann sampler's density is what `microfacet_eval` reports: the mean of f·cos / pdf
/// over sampled directions equals the directional albedo integrated by quadrature.
#[test]
fn beckmann_sampling_density_matches_its_pdf() {
    let alpha = 0.4;
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let n = 400;
    let mut sampled = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let m = beckmann_sample(alpha, u);
            let wi = m * (2.0 * wo.dot(m)) - wo;
            let e = microfacet_eval(wo, wi, alpha, true);
            if wi.z > 0.0 && e.y > 0.0 {
                sampled += (e.x / e.y) as f64;
            }
        }
    }
    sampled /= (n * n) as f64;
    // Quadrature of f·cos over the hemisphere (uniform in cos theta and phi).
    let q = 800;
    let mut direct = 0.0f64;
    for i in 0..q {
        for j in 0..q {
            let c = (i as f32 + 0.5) / q as f32;
            let phi = 2.0 * std::f32::consts::PI * (j as f32 + 0.5) / q as f32;
            let s = (1.0 - c * c).sqrt();
            let wi = Vec3::new(s * phi.cos(), s * phi.sin(), c);
            direct += microfacet_eval(wo, wi, alpha, true).x as f64;
        }
    }
    direct *= 2.0 * std::f64::consts::PI / (q * q) as f64;
    assert!(
        (sampled - direct).abs() < 5e-3,
        "sampled {sampled} vs quadrature {direct}"
    );
}
