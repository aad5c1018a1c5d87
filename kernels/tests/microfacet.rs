//! Mitsuba's microfacet distribution as the kernels compute it (host Rust,
//! `cohort_kernels::microfacet`), against Mitsuba 3.9.1's own `MicrofacetDistribution` and
//! `roughconductor`: the visible normal drawn from the same sample, its density, and the
//! conductor's f·cos and density, anisotropic GGX and Beckmann, recorded by
//! `scripts/microfacet_cases.py` in `data/microfacet_mitsuba.txt`.

use cohort_kernels::microfacet::{conductor_eval, erf, erfinv, visible_pdf, visible_sample};
use glam::{Vec2, Vec3};

fn v3(c: &[f32], at: usize) -> Vec3 {
    Vec3::new(c[at], c[at + 1], c[at + 2])
}

/// Equal to a relative `rel`, or absolutely where both are tiny.
fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-6
}

#[test]
fn samples_densities_and_values_are_mitsubas() {
    let text = include_str!("data/microfacet_mitsuba.txt");
    let (mut beckmann, mut a) = (false, Vec2::ONE);
    let mut cases = 0;
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let tag = words.next().unwrap();
        let v: Vec<f32> = words.map(|w| w.parse().unwrap()).collect();
        if tag == "D" {
            beckmann = v[0] == 1.0;
            a = Vec2::new(v[1], v[2]);
            continue;
        }
        let (wi, wo, u) = (v3(&v, 0), v3(&v, 3), Vec2::new(v[6], v[7]));
        let (m, pdf_m, value, pdf) = (v3(&v, 8), v[11], v[12], v[13]);
        let what = format!("beckmann {beckmann}, alpha {a}, wi {wi}, wo {wo}, u {u}");
        // Beckmann's sampler inverts erf numerically: Mitsuba's erf and erfinv differ from
        // ours in the last digits, so its normals agree to 1e-3.
        let mk = visible_sample(wi, a, beckmann, u);
        assert!((mk - m).length() < 1e-3, "normal {mk} vs {m}: {what}");
        let pk = visible_pdf(wi, m, a, beckmann);
        assert!(close(pk, pdf_m, 2e-3), "density {pk} vs {pdf_m}: {what}");
        let e = conductor_eval(wi, wo, a, beckmann);
        assert!(close(e.x, value, 2e-3), "f·cos {} vs {value}: {what}", e.x);
        assert!(close(e.y, pdf, 2e-3), "pdf {} vs {pdf}: {what}", e.y);
        cases += 1;
    }
    assert_eq!(cases, 480);
}

/// The sampler's normals have the density `visible_pdf` states: it integrates to 1 over
/// the hemisphere, and the mean of stratified samples matches a quadrature of m pdf(m).
#[test]
fn sampled_normals_have_the_stated_density() {
    for (beckmann, a) in [
        (false, Vec2::new(0.4, 0.2)),
        (true, Vec2::new(0.5, 0.15)),
        (true, Vec2::splat(0.8)),
    ] {
        for wi in [
            Vec3::new(0.3, 0.2, 0.93).normalize(),
            Vec3::new(0.8, -0.5, 0.2).normalize(),
        ] {
            let n = 256;
            let mut mean = Vec3::ZERO;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    mean += visible_sample(wi, a, beckmann, u);
                }
            }
            mean /= (n * n) as f32;
            // Quadrature over the hemisphere of m * pdf(m) dω.
            let k = 512;
            let mut quad = Vec3::ZERO;
            let mut total = 0.0f32;
            for i in 0..k {
                for j in 0..4 * k {
                    let ct = (i as f32 + 0.5) / k as f32;
                    let st = (1.0 - ct * ct).sqrt();
                    let phi = (j as f32 + 0.5) / (4 * k) as f32 * std::f32::consts::TAU;
                    let m = Vec3::new(st * phi.cos(), st * phi.sin(), ct);
                    let w = visible_pdf(wi, m, a, beckmann) / (k * 4 * k) as f32
                        * std::f32::consts::TAU;
                    quad += m * w;
                    total += w;
                }
            }
            assert!((total - 1.0).abs() < 0.02, "density integrates to {total}");
            assert!(
                (mean - quad).length() < 0.01,
                "mean sampled normal {mean} vs {quad} (beckmann {beckmann}, {a}, {wi})"
            );
        }
    }
}

#[test]
fn erf_and_its_inverse() {
    for &(x, e) in &[
        (0.0f32, 0.0f32),
        (0.5, 0.520_499_9),
        (-1.2, -0.910_314),
        (2.5, 0.999_593),
    ] {
        assert!((erf(x) - e).abs() < 2e-7, "erf({x}) = {}", erf(x));
    }
    for i in 1..200 {
        let y = -1.0 + i as f32 / 100.0;
        assert!((erf(erfinv(y)) - y).abs() < 1e-6, "erf(erfinv({y}))");
    }
}
