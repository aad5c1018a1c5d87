//! Statistical tests of the diffuse sampling strategies, run on the host through the
//! same Rust source the kernels are built from (fast, fixed seeds):
//! - patch choices follow P(i, j) (chi-square);
//! - P sums to 1 and each strategy's stated pdf integrates to 1 over the hemisphere;
//! - each strategy's directions follow its stated pdf (chi-square over a theta x phi grid);
//! - weighted by their throughput factor, directions estimate cosine-weighted integrals
//!   without bias.

use cohort_kernels::rng::{stream, uniform};
use cohort_kernels::sampling::{
    cosine_patch, CoherentCosine, CoherentEqualArea, CoherentUniform, Cosine, DiffuseSampler,
};
use glam::{Vec2, Vec3};
use std::f64::consts::PI;

const N: u32 = 4;

fn p_patch(i: u32, n: u32) -> f64 {
    // P(i, j) = (dphi / 2pi) (cos^2(i dT) - cos^2((i+1) dT)), dphi / 2pi = 1 / M.
    let dt = PI / 2.0 / n as f64;
    let (c0, c1) = ((i as f64 * dt).cos(), ((i + 1) as f64 * dt).cos());
    (c0 * c0 - c1 * c1) / (4 * n) as f64
}

fn area_patch(i: u32, n: u32) -> f64 {
    let dt = PI / 2.0 / n as f64;
    let dp = 2.0 * PI / (4 * n) as f64;
    dp * ((i as f64 * dt).cos() - ((i + 1) as f64 * dt).cos())
}

/// Chi-square statistic must stay under dof + 6 sqrt(2 dof) (far in the tail).
fn assert_chi2(observed: &[f64], expected: &[f64], what: &str) {
    let mut chi2 = 0.0;
    let mut dof = 0;
    for (o, e) in observed.iter().zip(expected) {
        if *e > 0.0 {
            chi2 += (o - e) * (o - e) / e;
            dof += 1;
        } else {
            assert_eq!(*o, 0.0, "{what}: samples in a cell of zero probability");
        }
    }
    let dof = (dof - 1) as f64;
    let limit = dof + 6.0 * (2.0 * dof).sqrt();
    assert!(
        chi2 < limit,
        "{what}: chi2 = {chi2:.1} over {dof} degrees of freedom (limit {limit:.1})"
    );
}

#[test]
fn patch_probabilities_sum_to_one_and_are_followed() {
    for n in [1, 4, 16, 100] {
        let total: f64 = (0..n).map(|i| p_patch(i, n) * (4 * n) as f64).sum();
        assert!((total - 1.0).abs() < 1e-12, "N = {n}: sum of P = {total}");
    }
    let m = 4 * N;
    let samples = 400_000u32;
    let mut counts = vec![0.0; (N * m) as usize];
    for k in 0..samples {
        counts[cosine_patch(stream(7, k, 0, 0), N) as usize] += 1.0;
    }
    let expected: Vec<f64> = (0..N * m)
        .map(|p| p_patch(p / m, N) * samples as f64)
        .collect();
    assert_chi2(&counts, &expected, "patch choice");
}

/// Stated pdf of each strategy in the local frame (z up).
fn pdf(strategy: &str, dir: Vec3) -> f64 {
    let cos_t = dir.z.clamp(0.0, 1.0) as f64;
    match strategy {
        "cosine" | "coherent_cosine" | "coherent_equal_area" => cos_t / PI,
        "coherent_uniform" => {
            let theta = cos_t.acos();
            let i = ((theta / (PI / 2.0 / N as f64)) as u32).min(N - 1);
            p_patch(i, N) / area_patch(i, N)
        }
        _ => unreachable!(),
    }
}

/// Sample `k`; samples `k` with equal `k / group` share their group's draw.
fn sample(strategy: &str, k: u32, group: u32) -> (Vec3, f32) {
    let key = stream(11, k, 0, 0);
    let g = stream(13, k / group, 0, 0);
    let u = Vec2::new(uniform(key, 2), uniform(key, 3));
    let n = Vec3::Z;
    let s = match strategy {
        "cosine" => Cosine::sample(n, u, Cosine::group_value(g, N), N),
        "coherent_uniform" => CoherentUniform::sample(n, u, CoherentUniform::group_value(g, N), N),
        "coherent_cosine" => CoherentCosine::sample(n, u, CoherentCosine::group_value(g, N), N),
        "coherent_equal_area" => {
            CoherentEqualArea::sample(n, u, CoherentEqualArea::group_value(g, N), N)
        }
        _ => unreachable!(),
    };
    (s.truncate(), s.w)
}

#[test]
fn stated_pdfs_integrate_to_one() {
    for strategy in [
        "cosine",
        "coherent_uniform",
        "coherent_cosine",
        "coherent_equal_area",
    ] {
        // Midpoint rule over (cos theta, phi); the pdfs are constant in phi.
        let steps = 20_000;
        let mut total = 0.0;
        for k in 0..steps {
            let c = (k as f64 + 0.5) / steps as f64;
            let s = (1.0 - c * c).sqrt();
            total += pdf(strategy, Vec3::new(s as f32, 0.0, c as f32)) * 2.0 * PI / steps as f64;
        }
        assert!(
            (total - 1.0).abs() < 1e-3,
            "{strategy}: pdf integrates to {total}"
        );
    }
}

#[test]
fn directions_follow_their_pdf() {
    // Grid: 2 theta cells per patch band, 2 phi cells per patch column.
    let (nt, np) = (2 * N, 2 * 4 * N);
    let samples = 300_000u32;
    for strategy in [
        "cosine",
        "coherent_uniform",
        "coherent_cosine",
        "coherent_equal_area",
    ] {
        let mut counts = vec![0.0; (nt * np) as usize];
        for k in 0..samples {
            // One sample per group: chi-square needs independent samples (members of a
            // group are correlated by design; their marginal is the same).
            let (d, _) = sample(strategy, k, 1);
            assert!(
                d.z >= -1e-6 && (d.length() - 1.0).abs() < 1e-4,
                "{strategy}: bad direction {d}"
            );
            let theta = (d.z.clamp(0.0, 1.0) as f64).acos();
            let phi = (d.y as f64).atan2(d.x as f64).rem_euclid(2.0 * PI);
            let ti = ((theta / (PI / 2.0) * nt as f64) as u32).min(nt - 1);
            let pi_ = ((phi / (2.0 * PI) * np as f64) as u32).min(np - 1);
            counts[(ti * np + pi_) as usize] += 1.0;
        }
        // Expected mass of each cell: integrate the pdf over it (midpoint in cos theta).
        let mut expected = vec![0.0; (nt * np) as usize];
        for ti in 0..nt {
            let (t0, t1) = (
                ti as f64 * PI / 2.0 / nt as f64,
                (ti + 1) as f64 * PI / 2.0 / nt as f64,
            );
            let sub = 200;
            let mut mass = 0.0;
            for k in 0..sub {
                let c = t1.cos() + (t0.cos() - t1.cos()) * (k as f64 + 0.5) / sub as f64;
                let s = (1.0 - c * c).sqrt();
                mass += pdf(strategy, Vec3::new(s as f32, 0.0, c as f32)) * (t0.cos() - t1.cos())
                    / sub as f64;
            }
            for p in 0..np {
                expected[(ti * np + p) as usize] = mass * 2.0 * PI / np as f64 * samples as f64;
            }
        }
        assert_chi2(&counts, &expected, strategy);
    }
}

#[test]
fn weighted_estimates_are_unbiased() {
    // E[w * g(dir)] = integral of g cos / pi, for a g that is not constant.
    let g = |d: Vec3| 1.0 + d.x as f64 * 0.5 + d.z as f64 * d.z as f64 * 2.0;
    // Exact: integral (1 + x/2 + 2 z^2) cos/pi = 1 + 0 + 2 * E[z^2] = 1 + 2 * 1/2 = 2.
    let exact = 2.0;
    let samples = 400_000u32;
    for strategy in [
        "cosine",
        "coherent_uniform",
        "coherent_cosine",
        "coherent_equal_area",
    ] {
        let mut sum = 0.0;
        let mut sq = 0.0;
        for k in 0..samples {
            let (d, w) = sample(strategy, k, 32);
            let v = w as f64 * g(d);
            sum += v;
            sq += v * v;
        }
        let mean = sum / samples as f64;
        let var = sq / samples as f64 - mean * mean;
        // Groups of 32 share a patch: the effective sample count is that of groups.
        let se = (var / (samples / 32) as f64).sqrt();
        assert!(
            (mean - exact).abs() < 5.0 * se + 1e-3,
            "{strategy}: mean {mean} vs {exact} (se {se})"
        );
    }
}

/// Equal-area cells map into the upper hemisphere with unit directions and weight 1;
/// that their union follows cos/pi exactly is checked by `directions_follow_their_pdf`,
/// so every cell, drawn uniformly, carries the same cosine-weighted measure.
#[test]
fn equal_area_cells_give_hemisphere_directions() {
    let k = 2 * N;
    for cell in [0, 3, k + 1, k * k / 2, k * k - 1] {
        for s in 0..200 {
            let key = stream(5, s, 0, 0);
            let d = CoherentEqualArea::sample(
                Vec3::Z,
                Vec2::new(uniform(key, 0), uniform(key, 1)),
                cell,
                N,
            );
            assert!(
                d.z >= 0.0 && (d.truncate().length() - 1.0).abs() < 1e-4 && d.w == 1.0,
                "cell {cell}: {d}"
            );
        }
    }
    // Cells are drawn uniformly.
    let mut counts = vec![0.0; (k * k) as usize];
    let draws = 200_000u32;
    for g in 0..draws {
        counts[CoherentEqualArea::group_value(stream(9, g, 0, 0), N) as usize] += 1.0;
    }
    let expected = vec![draws as f64 / (k * k) as f64; (k * k) as usize];
    assert_chi2(&counts, &expected, "equal-area cell choice");
}
