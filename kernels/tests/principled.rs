//! Mitsuba `principled` and `principledthin` as the kernels compute them (host Rust),
//! against Mitsuba 3.9.1's own BSDFs: values, densities and samples at random directions,
//! recorded by `scripts/principled_cases.py` in `data/principled_mitsuba.txt`.

use cohort_kernels::bsdf::principled::{eval, sample, thin_eval, thin_sample};
use cohort_kernels::layout::Principled;
use glam::{Vec2, Vec3};

struct Set {
    thin: bool,
    p: Principled,
    cases: Vec<Vec<f32>>,
}

fn sets() -> Vec<Set> {
    let text = include_str!("data/principled_mitsuba.txt");
    let mut sets: Vec<Set> = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        let tag = words.next().unwrap();
        let v: Vec<f32> = words.map(|w| w.parse().unwrap()).collect();
        if tag == "P" {
            sets.push(Set {
                thin: v[0] == 1.0,
                p: Principled {
                    base_color: Vec3::new(v[1], v[2], v[3]),
                    roughness: v[4],
                    anisotropic: v[5],
                    metallic: v[6],
                    spec_trans: v[7],
                    spec_tint: v[8],
                    sheen: v[9],
                    sheen_tint: v[10],
                    clearcoat: v[11],
                    clearcoat_gloss: v[12],
                    flatness: v[13],
                    diff_trans: v[14],
                    eta: v[15],
                    rate_a: 1.0,
                    rate_b: 1.0,
                    rate_c: 1.0,
                    rate_d: 1.0,
                    pad: 0,
                },
                cases: Vec::new(),
            });
        } else {
            sets.last_mut().unwrap().cases.push(v);
        }
    }
    sets
}

fn v3(c: &[f32], at: usize) -> Vec3 {
    Vec3::new(c[at], c[at + 1], c[at + 2])
}

/// Equal to a relative 2e-3 (single-precision arithmetic in a different order), or
/// absolutely where both are tiny.
fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 2e-3 * a.abs().max(b.abs()) + 1e-6
}

#[test]
fn values_and_densities_are_mitsubas() {
    let mut nonzero = 0;
    for (k, s) in sets().iter().enumerate() {
        for c in &s.cases {
            let (wi, wo) = (v3(c, 0), v3(c, 3));
            let e = if s.thin {
                thin_eval(s.p, wi, wo)
            } else {
                eval(s.p, wi, wo)
            };
            let (value, pdf) = (v3(c, 6), c[9]);
            let ok = close(e.x, value.x) && close(e.y, value.y) && close(e.z, value.z);
            assert!(
                ok,
                "set {k}, wi {wi}, wo {wo}: value {} vs Mitsuba's {value}",
                e.truncate()
            );
            assert!(
                close(e.w, pdf),
                "set {k}, wi {wi}, wo {wo}: pdf {} vs Mitsuba's {pdf}",
                e.w
            );
            if pdf > 0.0 {
                nonzero += 1;
            }
        }
    }
    assert!(nonzero > 150, "only {nonzero} cases with a density");
}

#[test]
fn samples_are_mitsubas() {
    let mut sampled = 0;
    for (k, s) in sets().iter().enumerate() {
        for c in &s.cases {
            let wi = v3(c, 0);
            let (choice, u) = (c[10], Vec2::new(c[11], c[12]));
            let want = v3(c, 13);
            let weight = v3(c, 16);
            let wo = if s.thin {
                thin_sample(s.p, wi, u, choice)
            } else {
                sample(s.p, wi, u, choice)
            };
            if weight.max_element() <= 0.0 {
                // Mitsuba's sample failed; so must ours, or carry no weight.
                let w = if wo == Vec3::ZERO {
                    Vec3::ZERO
                } else {
                    let e = if s.thin {
                        thin_eval(s.p, wi, wo)
                    } else {
                        eval(s.p, wi, wo)
                    };
                    if e.w > 0.0 {
                        e.truncate() / e.w
                    } else {
                        Vec3::ZERO
                    }
                };
                assert!(
                    w.max_element() <= 1e-6,
                    "set {k}, wi {wi}: sampled {wo} (weight {w}) where Mitsuba failed"
                );
                continue;
            }
            sampled += 1;
            assert!(
                (wo - want).abs().max_element() < 2e-3,
                "set {k}, wi {wi}, u {u}, choice {choice}: {wo} vs Mitsuba's {want}"
            );
            let e = if s.thin {
                thin_eval(s.p, wi, wo)
            } else {
                eval(s.p, wi, wo)
            };
            let w = e.truncate() / e.w;
            assert!(
                close(w.x, weight.x) && close(w.y, weight.y) && close(w.z, weight.z),
                "set {k}, wi {wi}: weight {w} vs Mitsuba's {weight}"
            );
        }
    }
    assert!(sampled > 200, "only {sampled} successful samples");
}
