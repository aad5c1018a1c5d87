//! Direction sampling. Diffuse bounces go through a [`DiffuseSampler`] strategy (the
//! extension kernel is generic over it, so a new strategy is an `impl`, not a copied
//! kernel); glossy, mirror and glass bounces sample their BSDF here.

use cohort::prelude::*;

/// Orthonormal frame around `n` (columns: tangent, bitangent, n), continuous in `n`
/// everywhere except one point (Duff et al. 2017), so nearby normals map a local
/// direction to nearby world directions.
#[kernel_fn]
pub fn frame(n: Vec3) -> Mat3 {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    Mat3::from_cols(t, bt, n)
}

/// Cosine-weighted direction in the local frame (z up).
#[kernel_fn]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * core::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// A strategy for diffuse bounces. Coherent strategies draw one value per group of
/// invocations (`group_value`, computed by the group's leader, or by the host for the
/// grid) and every ray of the group samples with it.
#[kernel_trait]
pub trait DiffuseSampler {
    /// Whether `sample` reads `group_value`: where it does not, `extend` leaves the
    /// group's draw out (a sampler that shares nothing sets it to false).
    const GROUP_VALUE: bool = true;
    /// The group's draw from the random stream `key` (e.g. a hemisphere patch index).
    fn group_value(key: u32, patches_n: u32) -> u32;
    /// World direction for a bounce at shading normal `n` from random numbers `u`, in
    /// `xyz`; in `w` the factor by which the path throughput is multiplied on top of the
    /// albedo (f·cos/pdf divided by the albedo: 1 for exact cosine sampling).
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4;
    /// Whether the sampler derives values from the group's draw alone ([`group_params`];
    /// read only with `GROUP_VALUE`):
    /// where it does, a backend that keeps each group's draws in a table (the CPU
    /// backend's warp and block levels) computes them once per group and calls
    /// [`sample_grouped`] instead of `sample`.
    ///
    /// [`group_params`]: DiffuseSampler::group_params
    /// [`sample_grouped`]: DiffuseSampler::sample_grouped
    const GROUP_PARAMS: bool = false;
    /// What `sample` computes from `group_value` and `patches_n` alone, e.g. the bounds of
    /// the group's patch: the same in every ray of the group.
    fn group_params(_group_value: u32, _patches_n: u32) -> Vec4 {
        Vec4::ZERO
    }
    /// `sample` given `params = group_params(group_value, patches_n)`: the same direction
    /// and weight, bit for bit (`cohort check` tests it), without recomputing `params`.
    fn sample_grouped(n: Vec3, u: Vec2, group_value: u32, _params: Vec4, patches_n: u32) -> Vec4 {
        Self::sample(n, u, group_value, patches_n)
    }
}

/// The paper's `normal` algorithm: independent cosine sampling per path.
pub struct Cosine;

#[kernel_impl]
impl DiffuseSampler for Cosine {
    const GROUP_VALUE: bool = false;
    fn group_value(_key: u32, _patches_n: u32) -> u32 {
        0
    }
    fn sample(n: Vec3, u: Vec2, _group_value: u32, _patches_n: u32) -> Vec4 {
        let d = frame(n) * cosine_hemisphere(u);
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

/// Patch (i, j) of the N x 4N split of the hemisphere that contains a cosine-distributed
/// point: patches are chosen with probability proportional to their cosine-weighted
/// solid angle P(i, j).
#[kernel_fn]
pub fn cosine_patch(key: u32, patches_n: u32) -> u32 {
    let u1 = crate::rng::uniform(key, 0);
    let u2 = crate::rng::uniform(key, 1);
    let cos_t = (1.0 - u1).max(0.0).sqrt();
    let theta = cos_t.min(1.0).acos();
    let m = 4 * patches_n;
    let dt = core::f32::consts::FRAC_PI_2 / patches_n as f32;
    let i = ((theta / dt) as u32).min(patches_n - 1);
    let j = ((u2 * m as f32) as u32).min(m - 1);
    i * m + j
}

/// Bounds of patch `patch` of the N x 4N split: cos of its lower and upper polar angle
/// (x = cos(i dT), y = cos((i+1) dT)), in z its azimuth band's index j and in w the band's
/// width dP: the patch's azimuths run from j dP to (j + 1) dP ([`patch_azimuth`]).
#[kernel_fn]
pub fn patch_bounds(patch: u32, patches_n: u32) -> Vec4 {
    let m = 4 * patches_n;
    let i = patch / m;
    let j = patch % m;
    let dt = core::f32::consts::FRAC_PI_2 / patches_n as f32;
    let dp = 2.0 * core::f32::consts::PI / m as f32;
    Vec4::new(
        (i as f32 * dt).cos(),
        ((i + 1) as f32 * dt).cos(),
        j as f32,
        dp,
    )
}

/// The azimuth at fraction `v` of the azimuth band of a patch with bounds `b`
/// ([`patch_bounds`]).
#[kernel_fn]
pub fn patch_azimuth(b: Vec4, v: f32) -> f32 {
    (b.z + v) * b.w
}

/// Local direction (z up) with polar cosine `cos_t` and azimuth `phi`.
#[kernel_fn]
pub fn polar_dir(cos_t: f32, phi: f32) -> Vec3 {
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// The paper's coherent sampler: the group shares a patch; each ray draws its direction
/// uniformly by solid angle inside it, in its own tangent frame, weighted by its exact
/// pdf P(i,j)/A(i,j).
pub struct CoherentUniform;

#[kernel_impl]
impl DiffuseSampler for CoherentUniform {
    const GROUP_PARAMS: bool = true;
    fn group_value(key: u32, patches_n: u32) -> u32 {
        cosine_patch(key, patches_n)
    }
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4 {
        let params = Self::group_params(group_value, patches_n);
        Self::sample_grouped(n, u, group_value, params, patches_n)
    }
    fn group_params(group_value: u32, patches_n: u32) -> Vec4 {
        patch_bounds(group_value, patches_n)
    }
    fn sample_grouped(n: Vec3, u: Vec2, _group_value: u32, b: Vec4, _patches_n: u32) -> Vec4 {
        let c0 = b.x;
        let c1 = b.y;
        let cos_t = c0 - u.x * (c0 - c1);
        let d = frame(n) * polar_dir(cos_t, patch_azimuth(b, u.y));
        // f cos / pdf over the albedo: (cos / pi) / (P / A), P = dp/2pi (c0^2 - c1^2),
        // A = dp (c0 - c1), so P / A = (c0 + c1) / 2pi and the factor is 2 cos / (c0 + c1).
        let w = 2.0 * cos_t / (c0 + c1);
        Vec4::new(d.x, d.y, d.z, w)
    }
}

/// Beyond the paper: cosine-weighted sampling inside the shared patch. Each ray's pdf is
/// then exactly cos/pi, so the weight is the albedo and in-patch variance disappears.
pub struct CoherentCosine;

#[kernel_impl]
impl DiffuseSampler for CoherentCosine {
    const GROUP_PARAMS: bool = true;
    fn group_value(key: u32, patches_n: u32) -> u32 {
        cosine_patch(key, patches_n)
    }
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4 {
        let params = Self::group_params(group_value, patches_n);
        Self::sample_grouped(n, u, group_value, params, patches_n)
    }
    fn group_params(group_value: u32, patches_n: u32) -> Vec4 {
        patch_bounds(group_value, patches_n)
    }
    fn sample_grouped(n: Vec3, u: Vec2, _group_value: u32, b: Vec4, _patches_n: u32) -> Vec4 {
        let c0 = b.x;
        let c1 = b.y;
        // cos^2 uniform in [c1^2, c0^2] gives density proportional to cos inside the band.
        let cos2 = c0 * c0 - u.x * (c0 * c0 - c1 * c1);
        let d = frame(n) * polar_dir(cos2.max(0.0).sqrt(), patch_azimuth(b, u.y));
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

/// Shirley–Chiu concentric map of the unit square onto the unit disk: area-preserving,
/// and continuous, so square cells map to compact disk cells.
#[kernel_fn]
pub fn concentric_disk(p: Vec2) -> Vec2 {
    let a = 2.0 * p.x - 1.0;
    let b = 2.0 * p.y - 1.0;
    let mut r = 0.0f32;
    let mut phi = 0.0f32;
    if a * a > b * b {
        r = a;
        phi = core::f32::consts::FRAC_PI_4 * (b / a);
    } else if b != 0.0 {
        r = b;
        phi = core::f32::consts::FRAC_PI_2 - core::f32::consts::FRAC_PI_4 * (a / b);
    }
    Vec2::new(r * phi.cos(), r * phi.sin())
}

/// Cell `cell` of a `k` x `k` grid over the unit square: its column and row in x and y,
/// `k` in z ([`grid_point`]).
#[kernel_fn]
pub fn grid_cell(cell: u32, k: u32) -> Vec4 {
    Vec4::new((cell % k) as f32, (cell / k) as f32, k as f32, 0.0)
}

/// Point of the grid cell `c` ([`grid_cell`]) at offset `u` in it.
#[kernel_fn]
pub fn grid_point(c: Vec4, u: Vec2) -> Vec2 {
    Vec2::new((c.x + u.x) / c.z, (c.y + u.y) / c.z)
}

/// Point of cell `cell` of a `k` x `k` grid over the unit square, at offset `u` in it.
#[kernel_fn]
pub fn cell_point(cell: u32, k: u32, u: Vec2) -> Vec2 {
    grid_point(grid_cell(cell, k), u)
}

/// Beyond the paper: equal-area patches. The unit square is cut into 2N x 2N cells
/// (as many patches as N x 4N) and mapped to the hemisphere by the concentric disk map
/// and Malley's projection, which together carry uniform area to the cosine-weighted
/// hemisphere. Every patch then has the same probability, the group picks one uniformly,
/// and each ray's direction has pdf exactly cos/pi (weight 1).
pub struct CoherentEqualArea;

#[kernel_impl]
impl DiffuseSampler for CoherentEqualArea {
    fn group_value(key: u32, patches_n: u32) -> u32 {
        let k = 2 * patches_n;
        crate::rng::hash(key) % (k * k)
    }
    const GROUP_PARAMS: bool = true;
    fn sample(n: Vec3, u: Vec2, group_value: u32, patches_n: u32) -> Vec4 {
        let params = Self::group_params(group_value, patches_n);
        Self::sample_grouped(n, u, group_value, params, patches_n)
    }
    fn group_params(group_value: u32, patches_n: u32) -> Vec4 {
        grid_cell(group_value, 2 * patches_n)
    }
    fn sample_grouped(n: Vec3, u: Vec2, _group_value: u32, c: Vec4, _patches_n: u32) -> Vec4 {
        let d2 = concentric_disk(grid_point(c, u));
        let z = (1.0 - d2.x * d2.x - d2.y * d2.y).max(0.0).sqrt();
        let d = frame(n) * Vec3::new(d2.x, d2.y, z);
        Vec4::new(d.x, d.y, d.z, 1.0)
    }
}

/// Smith masking G1 for GGX, with `cos` the cosine to the macro normal.
#[kernel_fn]
pub fn smith_g1(cos: f32, alpha: f32) -> f32 {
    let c2 = (cos * cos).max(1e-12);
    let tan2 = (1.0 - c2).max(0.0) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// GGX normal distribution D(m) of a microfacet normal at cosine `cos_m` to the macro
/// normal.
#[kernel_fn]
pub fn ggx_d(cos_m: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let t = cos_m * cos_m * (a2 - 1.0) + 1.0;
    a2 / (core::f32::consts::PI * t * t)
}

/// Beckmann normal distribution D(m) (isotropic) of a microfacet normal at cosine `cos_m` to
/// the macro normal.
#[kernel_fn]
pub fn beckmann_d(cos_m: f32, alpha: f32) -> f32 {
    let c2 = (cos_m * cos_m).max(1e-12);
    let tan2 = (1.0 - c2).max(0.0) / c2;
    let a2 = alpha * alpha;
    (-tan2 / a2).exp() / (core::f32::consts::PI * a2 * c2 * c2)
}

/// Smith's masking for the Beckmann distribution at cosine `cos` to the macro normal, by the
/// rational approximation Mitsuba evaluates (under 0.35 % relative error).
#[kernel_fn]
pub fn beckmann_g1(cos: f32, alpha: f32) -> f32 {
    let c2 = (cos * cos).max(1e-12);
    let tan2 = (1.0 - c2).max(0.0) / c2;
    let mut g = 1.0f32;
    if tan2 > 0.0 {
        let a = 1.0 / (alpha * tan2.sqrt());
        if a < 1.6 {
            g = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
        }
    }
    g
}

/// A Beckmann microfacet normal (z up) drawn with density D(m) cos(m): the distribution of
/// normals, not only the visible ones (`microfacet_eval` gives the matching density).
#[kernel_fn]
pub fn beckmann_sample(alpha: f32, u: Vec2) -> Vec3 {
    let tan2 = -alpha * alpha * (1.0 - u.x).ln();
    let cos = 1.0 / (1.0 + tan2).sqrt();
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * core::f32::consts::PI * u.y;
    Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)
}

/// A rough conductor's microfacet normal for the local outgoing direction `wo` (z up): GGX's
/// visible normals ([`ggx_vndf`]), or Beckmann's normals ([`beckmann_sample`]).
#[kernel_fn]
pub fn microfacet_sample(wo: Vec3, alpha: f32, beckmann: bool, u: Vec2) -> Vec3 {
    if beckmann {
        beckmann_sample(alpha, u)
    } else {
        ggx_vndf(wo, alpha, u)
    }
}

/// The rough conductor (isotropic GGX or Beckmann, separable Smith masking) for local
/// directions `wo`, `wi` (z up): x = f·cos without the Fresnel factor and the specular
/// reflectance, D G / (4 wo.z); y = the density with which [`microfacet_sample`] and
/// reflection produce `wi`; z = the cosine between `wo` and the half vector (the Fresnel
/// factor's angle). Zero below either horizon.
#[kernel_fn]
pub fn microfacet_eval(wo: Vec3, wi: Vec3, alpha: f32, beckmann: bool) -> Vec4 {
    let mut r = Vec4::ZERO;
    if (wo.z > 0.0) & (wi.z > 0.0) {
        let m = (wo + wi).normalize();
        let cos_h = wo.dot(m).max(1e-12);
        if beckmann {
            let d = beckmann_d(m.z, alpha);
            let g = beckmann_g1(wo.z, alpha) * beckmann_g1(wi.z, alpha);
            r = Vec4::new(d * g / (4.0 * wo.z), d * m.z / (4.0 * cos_h), cos_h, 0.0);
        } else {
            let d = ggx_d(m.z, alpha);
            let pdf = smith_g1(wo.z, alpha) * d / (4.0 * wo.z);
            r = Vec4::new(pdf * smith_g1(wi.z, alpha), pdf, cos_h, 0.0);
        }
    }
    r
}

/// Fresnel reflectance of a conductor of complex index `eta + i k` (per channel) at incident
/// cosine `cos_i`, unpolarised, as Mitsuba computes it (`fresnel_conductor`, after Moeller's
/// "Optics"). eta 0, k 1 (Mitsuba's `material` = none) gives 1.
#[kernel_fn]
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let mut f = Vec3::ONE;
    // Mitsuba's default `material = none` reflects everything: skip the arithmetic.
    let perfect = (eta.abs().max_element() == 0.0) & ((k - Vec3::ONE).abs().max_element() == 0.0);
    if !perfect {
        f = Vec3::new(
            fresnel_conductor1(cos_i, eta.x, k.x),
            fresnel_conductor1(cos_i, eta.y, k.y),
            fresnel_conductor1(cos_i, eta.z, k.z),
        );
    }
    f
}

/// [`fresnel_conductor`] of one channel.
#[kernel_fn]
pub fn fresnel_conductor1(cos_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = cos_i * cos_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - s2;
    let a2b2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2b2 + t1)).max(0.0).sqrt();
    let term1 = a2b2 + c2;
    let term2 = 2.0 * cos_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2b2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    0.5 * (rs + rp)
}

/// GGX visible-normal sampling (Heitz 2018): a microfacet normal for the local
/// outgoing direction `wo` (z up).
#[kernel_fn]
pub fn ggx_vndf(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1v = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2v = vh.cross(t1v);
    let r = u.x.sqrt();
    let phi = 2.0 * core::f32::consts::PI * u.y;
    let t1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let t2 = (1.0 - s) * (1.0 - t1 * t1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1v * t1 + t2v * t2 + vh * (1.0 - t1 * t1 - t2 * t2).max(0.0).sqrt();
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Fresnel reflectance of a dielectric interface; `eta` = transmitted / incident index.
#[kernel_fn]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        1.0
    } else {
        let cos_t = (1.0 - sin2_t).sqrt();
        let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        0.5 * (rs * rs + rp * rp)
    }
}

/// Mitsuba's fit of the hemispherical average of the Fresnel reflectance for relative index
/// `eta` (`fresnel_diffuse_reflectance`: Egan and Hilgeman 1973 below 1, d'Eon and Irving
/// 2011 above), which its `plastic` uses for light reflected back into the coating.
#[kernel_fn]
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        let inv2 = inv * inv;
        let inv3 = inv2 * inv;
        0.919317 - 3.4793 * inv + 6.75335 * inv2 - 7.80989 * inv3 + 4.98554 * inv3 * inv
            - 1.36881 * inv3 * inv2
    }
}

/// Mitsuba `plastic`: the probability of sampling the coating's specular reflection for an
/// incident Fresnel reflectance `f_i`, from the lobes' mean albedos (the diffuse lobe takes
/// the rest).
#[kernel_fn]
pub fn plastic_specular_probability(f_i: f32, diffuse: Vec3, specular: Vec3) -> f32 {
    let d_mean = (diffuse.x + diffuse.y + diffuse.z) / 3.0;
    let s_mean = (specular.x + specular.y + specular.z) / 3.0;
    let weight = s_mean / (d_mean + s_mean);
    let ps = f_i * weight;
    let pd = (1.0 - f_i) * (1.0 - weight);
    ps / (ps + pd)
}

/// Mitsuba `plastic`'s diffuse lobe without the cosine and the Fresnel transmissions: the
/// base's albedo over (1 - the internal reflections), scaled by 1 / eta^2 (radiance
/// compression on entering, expansion on leaving).
#[kernel_fn]
pub fn plastic_base(diffuse: Vec3, eta: f32, nonlinear: bool) -> Vec3 {
    let fdr_int = fresnel_diffuse_reflectance(1.0 / eta);
    let mut denominator = Vec3::splat(1.0 - fdr_int);
    if nonlinear {
        denominator = Vec3::ONE - diffuse * fdr_int;
    }
    diffuse / denominator / (eta * eta)
}
