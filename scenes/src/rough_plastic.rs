//! What Mitsuba's `roughplastic` precomputes when it is loaded: the rough coating's
//! transmittance into the plastic as a table over the incident cosine, and its mean
//! reflectance from inside (light the base sends back into the coating). The kernels read
//! the table as a 64 x 1 texture (`Material::table`), so it goes through the same
//! interpolation as Mitsuba's `lerp_gather`.
//!
//! Mitsuba integrates over visible microfacet normals with a Gauss-Legendre grid in the
//! space of its visible-normal sampling; this integrates the same integrals over the
//! normals' spherical coordinates on a finer grid, so the values agree closely (the tests
//! compare them with Mitsuba's own).

use glam::DVec3;

/// Entries of the transmittance table (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`), at
/// cos θ = k / (TABLE_SIZE - 1).
pub const TABLE_SIZE: usize = 64;

/// Midpoint grid of the microfacet integrals: polar and azimuthal steps.
const GRID_THETA: usize = 256;
const GRID_PHI: usize = 128;

/// The precomputed quantities of one `roughplastic`.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlasticTables {
    /// Fraction of light arriving at cos θ_k = k / 63 that the rough interface lets into
    /// the plastic.
    pub external_transmittance: [f32; TABLE_SIZE],
    /// 2 × the mean over the table's cosines of (reflectance from inside × cos θ).
    pub internal_reflectance: f32,
}

/// Mitsuba's dielectric Fresnel reflectance with the refracted cosine (signed as the
/// opposite of `cos_i`) and the index ratio `eta_ti` of the refraction.
fn fresnel(cos_i: f64, eta: f64) -> (f64, f64, f64) {
    let eta_ti = if cos_i >= 0.0 { 1.0 / eta } else { eta };
    let eta_it = 1.0 / eta_ti;
    let cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * eta_ti * eta_ti;
    if cos_t2 <= 0.0 {
        return (1.0, 0.0, eta_ti);
    }
    let (ci, ct) = (cos_i.abs(), cos_t2.sqrt());
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    let r = if ci == 0.0 {
        1.0
    } else {
        0.5 * (a_s * a_s + a_p * a_p)
    };
    (r, if cos_i >= 0.0 { -ct } else { ct }, eta_ti)
}

/// Smith's masking of direction `v` for microfacet normal `m` (Mitsuba's `smith_g1`: zero
/// where `v` sees the microfacet's back).
fn smith_g1(v: DVec3, m: DVec3, alpha: f64, beckmann: bool) -> f64 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    let tan2_alpha2 = alpha * alpha * (v.x * v.x + v.y * v.y) / (v.z * v.z);
    if tan2_alpha2 <= 0.0 {
        return 1.0;
    }
    if beckmann {
        let a = 1.0 / tan2_alpha2.sqrt();
        if a >= 1.6 {
            1.0
        } else {
            (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
        }
    } else {
        2.0 / (1.0 + (1.0 + tan2_alpha2).sqrt())
    }
}

/// The means of the coating's transmittance (light from `wi` refracted through at index
/// ratio `eta`) and of its reflectance from inside (from `wi` at `1 / eta`) over the
/// microfacet normals visible from `wi` (density D(m) G1(wi, m) max(0, wi·m) / wi.z), on
/// a midpoint grid in φ (`phis`: its cosines and sines) and in s = t / (1 + t),
/// t = tan θ_m / alpha: dense where D is, and reaching grazing normals, whose weight
/// (wi·m) is large for oblique `wi` (a grid uniform in D(m) cos θ_m misses them: 1 % low
/// at 80°). Both means take the same normals, so one pass computes them.
fn visible_normal_means(
    wi: DVec3,
    alpha: f64,
    beckmann: bool,
    eta: f64,
    phis: &[(f64, f64)],
) -> (f64, f64) {
    let inside = 1.0 / eta;
    let (mut transmitted, mut reflected, mut norm) = (0.0, 0.0, 0.0);
    for i in 0..GRID_THETA {
        let s = (i as f64 + 0.5) / GRID_THETA as f64;
        let t = s / (1.0 - s);
        let theta = (alpha * t).atan();
        // dθ/ds = alpha / (1 + alpha² t²) · dt/ds, dt/ds = 1 / (1 - s)².
        let dtheta = alpha / (1.0 + alpha * alpha * t * t) / ((1.0 - s) * (1.0 - s));
        let (sin_m, cos_m) = theta.sin_cos();
        let d = distribution(cos_m, alpha, beckmann);
        for &(cos_phi, sin_phi) in phis {
            let m = DVec3::new(sin_m * cos_phi, sin_m * sin_phi, cos_m);
            let wm = wi.dot(m);
            if wm <= 0.0 {
                continue;
            }
            let visible = d * smith_g1(wi, m, alpha, beckmann) * wm / wi.z * sin_m * dtheta;
            transmitted += visible * transmittance(wi, m, alpha, beckmann, eta);
            reflected += visible * reflectance(wi, m, alpha, beckmann, inside);
            norm += visible;
        }
    }
    // The visible normals' density integrates to 1 with the exact G1, which Mitsuba's
    // sampling follows; Beckmann's G1 is an approximation (0.35 %), so normalise.
    (transmitted / norm, reflected / norm)
}

/// The normal distribution D(m) at cos θ_m.
fn distribution(cos_m: f64, alpha: f64, beckmann: bool) -> f64 {
    let c2 = cos_m * cos_m;
    let tan2 = (1.0 - c2) / c2;
    let a2 = alpha * alpha;
    if beckmann {
        (-tan2 / a2).exp() / (std::f64::consts::PI * a2 * c2 * c2)
    } else {
        let t = c2 * (a2 - 1.0) + 1.0;
        a2 / (std::f64::consts::PI * t * t)
    }
}

/// Mitsuba's `eval_reflectance` at microfacet normal `m`: what the rough interface
/// reflects from `wi` (index ratio `eta`) and lets out unmasked.
fn reflectance(wi: DVec3, m: DVec3, alpha: f64, beckmann: bool, eta: f64) -> f64 {
    let wo = 2.0 * wi.dot(m) * m - wi;
    if wo.z <= 0.0 {
        return 0.0;
    }
    fresnel(wi.dot(m), eta).0 * smith_g1(wo, m, alpha, beckmann)
}

/// Mitsuba's `eval_transmittance` at microfacet normal `m`: the fraction of light from
/// `wi` refracted through unmasked.
fn transmittance(wi: DVec3, m: DVec3, alpha: f64, beckmann: bool, eta: f64) -> f64 {
    let cos_i = wi.dot(m);
    let (f, cos_t, eta_ti) = fresnel(cos_i, eta);
    let wt = m * (cos_i * eta_ti + cos_t) - wi * eta_ti;
    if wt.z * wi.z >= 0.0 {
        return 0.0;
    }
    (1.0 - f) * smith_g1(wt, m, alpha, beckmann)
}

/// The tables of a `roughplastic` with roughness `alpha`, distribution Beckmann (else
/// GGX) and relative index `eta` (int_ior / ext_ior).
pub fn tables(alpha: f32, beckmann: bool, eta: f32) -> RoughPlasticTables {
    let (alpha, eta) = (alpha as f64, eta as f64);
    let phis: Vec<(f64, f64)> = (0..GRID_PHI)
        .map(|j| {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / GRID_PHI as f64;
            (phi.cos(), phi.sin())
        })
        .collect();
    // Each cosine's integrals on a thread of their own (a scene load waits for them: 0.2 s
    // per material on one core), gathered in table order so the sum below is the same
    // whatever the thread count.
    let entry = |k: usize| {
        let mu = (k as f64 / (TABLE_SIZE - 1) as f64).max(1e-6);
        let wi = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let (t, r) = visible_normal_means(wi, alpha, beckmann, eta, &phis);
        (mu, t, r)
    };
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = TABLE_SIZE.div_ceil(threads.clamp(1, TABLE_SIZE));
    let entries: Vec<(f64, f64, f64)> = std::thread::scope(|scope| {
        let parts: Vec<_> = (0..TABLE_SIZE)
            .step_by(chunk)
            .map(|from| {
                let entry = &entry;
                scope.spawn(move || {
                    (from..(from + chunk).min(TABLE_SIZE))
                        .map(entry)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        parts
            .into_iter()
            .flat_map(|p| p.join().expect("a table thread panicked"))
            .collect()
    });
    let mut external_transmittance = [0f32; TABLE_SIZE];
    let mut internal = 0.0;
    for (k, &(mu, t, r)) in entries.iter().enumerate() {
        external_transmittance[k] = t as f32;
        internal += r * mu;
    }
    RoughPlasticTables {
        external_transmittance,
        internal_reflectance: (2.0 * internal / TABLE_SIZE as f64) as f32,
    }
}
