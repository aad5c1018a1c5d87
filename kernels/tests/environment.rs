//! Mitsuba `envmap` as the kernels read it (`cohort_kernels::environment`, run here as host
//! Rust): radiance equal to the scenes crate's lookup, a sampling density that integrates to
//! one and agrees with the directions drawn, and light sampling that integrates the map.

use cohort_kernels::environment::{env_map_pdf, env_map_radiance, env_map_sample};
use cohort_scenes::EnvironmentMap;
use glam::{Mat3, Vec2, Vec3, Vec4};
use std::f64::consts::PI;

/// A 24 x 12 map with smooth colour, a black band and a bright 2 x 2 sun, turned.
fn map() -> EnvironmentMap {
    let (w, h) = (24u32, 12u32);
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut c = Vec3::new(
                0.5 + 0.4 * (x as f32 * 0.5).sin(),
                0.2 + y as f32 * 0.05,
                0.8,
            );
            if y == 8 {
                c = Vec3::ZERO;
            }
            if (3..5).contains(&y) && (15..17).contains(&x) {
                c = Vec3::new(40.0, 35.0, 30.0);
            }
            texels.push(c);
        }
    }
    let to_world = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
    EnvironmentMap::new(w, h, &texels, 1.5, to_world)
}

fn layout(m: &EnvironmentMap) -> Vec<Vec4> {
    m.gpu_layout().into_iter().map(Vec4::from).collect()
}

/// A reproducible uniform number stream.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// Directions on a (theta, phi) grid of the world sphere with their solid angles.
fn sphere_grid(n_theta: usize) -> Vec<(Vec3, f64)> {
    let n_phi = 2 * n_theta;
    let mut out = Vec::new();
    for i in 0..n_theta {
        let t0 = PI * i as f64 / n_theta as f64;
        let t1 = PI * (i + 1) as f64 / n_theta as f64;
        let theta = 0.5 * (t0 + t1);
        let area = (t0.cos() - t1.cos()) * 2.0 * PI / n_phi as f64;
        for j in 0..n_phi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / n_phi as f64;
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                theta.cos() as f32,
                (theta.sin() * phi.sin()) as f32,
            );
            out.push((d, area));
        }
    }
    out
}

fn lum(c: Vec3) -> f64 {
    (c.x * 0.2126 + c.y * 0.7152 + c.z * 0.0722) as f64
}

#[test]
fn radiance_is_the_scenes_lookup() {
    let m = map();
    let t = layout(&m);
    let mut rng = Lcg(1);
    for _ in 0..2000 {
        let d = Vec3::new(
            rng.next() * 2.0 - 1.0,
            rng.next() * 2.0 - 1.0,
            rng.next() * 2.0 - 1.0,
        );
        if d.length() < 0.1 {
            continue;
        }
        let d = d.normalize();
        let got = env_map_radiance(&t, 0, d);
        let want = m.eval(d);
        assert!(
            (got - want).abs().max_element() <= 1e-4 * (1.0 + want.max_element()),
            "{d}: {got} vs {want}"
        );
    }
}

#[test]
fn density_integrates_to_one() {
    let t = layout(&map());
    let integral: f64 = sphere_grid(400)
        .iter()
        .map(|&(d, a)| env_map_pdf(&t, 0, d) as f64 * a)
        .sum();
    assert!(
        (integral - 1.0).abs() < 2e-3,
        "integral of the density: {integral}"
    );
}

#[test]
fn samples_carry_their_density_and_integrate_the_map() {
    let m = map();
    let t = layout(&m);
    let mut rng = Lcg(7);
    let n = 400_000;
    let mut estimate = 0.0f64;
    // Histogram over 6 x 12 (theta, phi) bins of the world sphere, against the density.
    let (bt, bp) = (6usize, 12usize);
    let mut counts = vec![0u32; bt * bp];
    let bin = |d: Vec3| {
        let theta = d.y.clamp(-1.0, 1.0).acos() as f64;
        let phi = (d.z as f64).atan2(d.x as f64).rem_euclid(2.0 * PI);
        let i = ((theta / PI * bt as f64) as usize).min(bt - 1);
        let j = ((phi / (2.0 * PI) * bp as f64) as usize).min(bp - 1);
        i * bp + j
    };
    for _ in 0..n {
        let s = env_map_sample(&t, 0, Vec2::new(rng.next(), rng.next()));
        let d = s.truncate();
        assert!((d.length() - 1.0).abs() < 1e-4, "{s}");
        assert!(s.w > 0.0, "a drawn direction has density {}", s.w);
        let p = env_map_pdf(&t, 0, d);
        // Away from the poles the density a sample reports is the density of its direction.
        let sin_theta = (m.to_world.inverse() * d).y.abs();
        if sin_theta < 0.99 {
            assert!(
                (p - s.w).abs() <= 2e-3 * s.w.max(p) + 1e-6,
                "{d}: sampled {} vs pdf {p}",
                s.w
            );
        }
        estimate += lum(env_map_radiance(&t, 0, d)) / s.w as f64;
        counts[bin(d)] += 1;
    }
    estimate /= n as f64;
    let grid = sphere_grid(400);
    let exact: f64 = grid
        .iter()
        .map(|&(d, a)| lum(env_map_radiance(&t, 0, d)) * a)
        .sum();
    assert!(
        (estimate - exact).abs() < 0.01 * exact,
        "importance-sampled integral {estimate} vs quadrature {exact}"
    );
    let mut expected = vec![0.0f64; bt * bp];
    for &(d, a) in &grid {
        expected[bin(d)] += env_map_pdf(&t, 0, d) as f64 * a * n as f64;
    }
    for (k, (&c, &e)) in counts.iter().zip(&expected).enumerate() {
        // Poisson counts: within 5 standard deviations (plus the quadrature's own error).
        let tol = 5.0 * e.sqrt() + 0.01 * e + 5.0;
        assert!(
            (c as f64 - e).abs() <= tol,
            "bin {k}: {c} samples, density says {e:.0}"
        );
    }
}

/// A black region is never sampled and has density 0 (the black row's own band).
#[test]
fn black_texels_get_no_samples_between_them() {
    let (w, h) = (8u32, 6u32);
    let texels: Vec<Vec3> = (0..w * h)
        .map(|i| if i / w >= 3 { Vec3::ZERO } else { Vec3::ONE })
        .collect();
    let m = EnvironmentMap::new(w, h, &texels, 1.0, Mat3::IDENTITY);
    let t = layout(&m);
    let mut rng = Lcg(3);
    for _ in 0..20_000 {
        let s = env_map_sample(&t, 0, Vec2::new(rng.next(), rng.next()));
        // Rows 3.. are black: the density vanishes from row 3 (colatitude 3/5 pi) down.
        assert!(
            s.y > (0.6 * std::f32::consts::PI).cos() - 1e-4,
            "sampled below the lit rows: {s}"
        );
    }
    assert_eq!(
        env_map_pdf(&t, 0, Vec3::new(0.0, -1.0, 0.2).normalize()),
        0.0
    );
}
