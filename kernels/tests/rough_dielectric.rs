//! Mitsuba `roughdielectric` in the kernels: what `sample` weighs a direction by is what
//! `eval` says (f·cos over the density), and the density `eval` reports integrates to 1
//! over the sphere of directions, for both distributions, both sides of the interface and
//! total internal reflection, isotropic and anisotropic.

use cohort_kernels::bsdf::rough_dielectric::{eval, sample};
use glam::{Mat3, Vec2, Vec3};

struct Rng(u32);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / 16777216.0
    }
}

fn direction(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// (eta, (alpha_u, alpha_v), Beckmann).
const CASES: [(f32, Vec2, bool); 6] = [
    (1.5, Vec2::new(0.2, 0.2), false),
    (1.0 / 1.5, Vec2::new(0.3, 0.3), false),
    (1.33, Vec2::new(0.4, 0.4), true),
    (1.0 / 1.7, Vec2::new(0.15, 0.15), true),
    (1.5, Vec2::new(0.05, 0.4), false),
    (1.0 / 1.33, Vec2::new(0.35, 0.1), true),
];

#[test]
fn sample_weights_are_eval_over_pdf() {
    let n = Mat3::IDENTITY;
    let mut rng = Rng(7);
    for (eta, alpha, beckmann) in CASES {
        for theta in [0.1f32, 0.7, 1.2, 1.5] {
            let wo = direction(theta, 0.3);
            for _ in 0..2000 {
                let s = sample(
                    wo,
                    n,
                    eta,
                    alpha,
                    beckmann,
                    Vec2::new(rng.f(), rng.f()),
                    rng.f(),
                );
                if s.w <= 0.0 {
                    continue;
                }
                let wi = s.truncate();
                let e = eval(wo, wi, n, eta, alpha, beckmann);
                let expected = e.x / e.y;
                let got = s.w;
                assert!(
                    e.y > 0.0 && (got - expected).abs() <= 2e-3 * expected.max(1e-3),
                    "eta {eta} alpha {alpha:?} beckmann {beckmann} theta {theta}: weight {got} vs f cos / pdf {expected} ({e})"
                );
            }
        }
    }
}

#[test]
fn eval_density_integrates_to_one() {
    let n = Mat3::IDENTITY;
    for (eta, alpha, beckmann) in CASES {
        for theta in [0.2f32, 1.0] {
            let wo = direction(theta, 0.0);
            // Midpoint rule over the sphere in (cos θ, φ).
            let (nc, np) = (1200, 240);
            let mut total = 0.0f64;
            for i in 0..nc {
                let c = -1.0 + 2.0 * (i as f32 + 0.5) / nc as f32;
                for j in 0..np {
                    let phi = std::f32::consts::TAU * (j as f32 + 0.5) / np as f32;
                    let s = (1.0 - c * c).max(0.0).sqrt();
                    let wi = Vec3::new(s * phi.cos(), s * phi.sin(), c);
                    total += eval(wo, wi, n, eta, alpha, beckmann).y as f64;
                }
            }
            total *= 4.0 * std::f64::consts::PI / (nc * np) as f64;
            // Below 1 by what the sampler loses: normals whose reflection or refraction
            // lands on the wrong side (and Beckmann's back-facing draws).
            assert!(
                total <= 1.02 && total > 0.85,
                "eta {eta} alpha {alpha:?} beckmann {beckmann} theta {theta}: {total}"
            );
        }
    }
}
