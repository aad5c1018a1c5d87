//! The emitters of a scene as next-event estimation samples them: an alias table over the
//! emitter triangles (in BVH leaf order) and the delta lights (point, spot, directional,
//! projector),
//! each chosen in proportion to its power, and the probability of sampling the
//! environment (constant or map) instead (half the samples when there are other lights).
//!
//! Powers are estimates that only steer the choice (any positive choice probabilities
//! keep the estimator unbiased): a one-sided Lambertian emitter of radiance L and area A
//! emits pi L A; a point light of intensity I, 4 pi I; a spot, I times the solid angle of
//! its cone out to the middle of its falloff; a directional light of irradiance E, E
//! times the cross-section pi R^2 of the scene's bounding sphere.

use cohort_kernels::layout::{
    DeltaLight, LightEntry, Triangle, DELTA_LIGHT, DIRECTIONAL_LIGHT, POINT_LIGHT, PROJECTOR_LIGHT,
    SPOT_LIGHT,
};
use cohort_scenes::{Light, Scene};
use glam::{Mat3, Vec3};
use std::f64::consts::PI;

/// What `extend` needs to sample lights: the table, its length, and the environment's share.
pub struct LightTable {
    /// Never empty (one unused entry when the scene has no emitter triangle), so it can be bound.
    pub entries: Vec<LightEntry>,
    /// Entries in use (0: no area or delta light).
    pub count: u32,
    /// Probability of sampling the environment (0: none; 1: no other light).
    pub env_light: f32,
    /// The delta lights the entries with `DELTA_LIGHT` set refer to; never empty (one unused
    /// entry when there is none), so it can be bound.
    pub delta: Vec<DeltaLight>,
}

/// Relative luminance of linear sRGB.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Radius of the bounding sphere of the scene's triangles (1 for a scene without any).
fn scene_radius(tris: &[Triangle]) -> f64 {
    let (lo, hi) = tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let r = 0.5 * (hi - lo).length() as f64;
    if r.is_finite() && r > 0.0 {
        r
    } else {
        1.0
    }
}

/// The kernel's form of a delta light (its selection probability filled in later) and
/// its estimated power; `starts`: where each texture starts in the kernels' array.
fn delta_light(light: &Light, radius: f64, starts: &[u32]) -> (DeltaLight, f64) {
    let header = |t: Option<u32>| t.map_or(0, |t| starts[t as usize] + 1);
    match *light {
        Light::Point {
            position,
            intensity,
        } => (
            DeltaLight {
                kind: POINT_LIGHT,
                position,
                intensity,
                ..Default::default()
            },
            4.0 * PI * luminance(intensity) as f64,
        ),
        Light::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
            texture,
        } => {
            let inv = Mat3::from_mat4(to_world).inverse();
            let mid = 0.5 * (cutoff_angle + beam_width) as f64;
            (
                DeltaLight {
                    kind: SPOT_LIGHT,
                    position: to_world.transform_point3(Vec3::ZERO),
                    intensity,
                    to_local_x: inv.row(0),
                    to_local_y: inv.row(1),
                    to_local_z: inv.row(2),
                    cos_cutoff: cutoff_angle.cos(),
                    cos_beam: beam_width.cos(),
                    cutoff: cutoff_angle,
                    inv_transition: if cutoff_angle > beam_width {
                        1.0 / (cutoff_angle - beam_width)
                    } else {
                        0.0
                    },
                    texture: header(texture),
                    uv_factor: cutoff_angle.tan(),
                    ..Default::default()
                },
                2.0 * PI * (1.0 - mid.cos()) * luminance(intensity) as f64,
            )
        }
        Light::Projector {
            to_world,
            irradiance,
            texture,
            tan_half_fov,
            aspect,
        } => {
            let inv = Mat3::from_mat4(to_world).inverse();
            // The pyramid's solid angle is about its image area (2 t)^2 / aspect at unit
            // distance; the image's mean is unknown here, so its scale stands in.
            let area = 4.0 * (tan_half_fov * tan_half_fov / aspect) as f64;
            (
                DeltaLight {
                    kind: PROJECTOR_LIGHT,
                    position: to_world.transform_point3(Vec3::ZERO),
                    intensity: irradiance,
                    to_local_x: inv.row(0),
                    to_local_y: inv.row(1),
                    to_local_z: inv.row(2),
                    direction: to_world.transform_vector3(Vec3::Z),
                    texture: header(texture),
                    uv_factor: tan_half_fov,
                    aspect,
                    ..Default::default()
                },
                PI * area * luminance(irradiance) as f64,
            )
        }
        Light::Directional {
            direction,
            irradiance,
        } => (
            DeltaLight {
                kind: DIRECTIONAL_LIGHT,
                direction,
                intensity: irradiance,
                ..Default::default()
            },
            PI * radius * radius * luminance(irradiance) as f64,
        ),
    }
}

/// Builds the table over `tris` (BVH leaf order) and the scene's delta lights, and writes
/// each emitter triangle's selection probability per unit area into its `light_pdf` (0 for
/// the others).
pub fn build(scene: &Scene, tris: &mut [Triangle]) -> LightTable {
    let radius = scene_radius(tris);
    // (light id, power, area or 0 for a delta light)
    let mut power: Vec<(u32, f64, f64)> = Vec::new();
    for (k, t) in tris.iter_mut().enumerate() {
        t.light_pdf = 0.0;
        let m = &scene.materials[t.material as usize];
        if let Some(e) = m.emission {
            let area = 0.5 * (t.v1 - t.v0).cross(t.v2 - t.v0).length();
            let sides = if m.two_sided { 2.0 } else { 1.0 };
            let p = PI * (luminance(e) * area * sides) as f64;
            // Triangles too small for the kernels' f32 normal (which would be NaN) are left out.
            if p > 0.0 && p.is_finite() && area > 1e-15 {
                power.push((k as u32, p, area as f64));
            }
        }
    }
    let mut delta = Vec::new();
    let starts = cohort_scenes::texture::gpu_texture_starts(&scene.textures);
    for light in &scene.lights {
        let (d, p) = delta_light(light, radius, &starts);
        if p > 0.0 && p.is_finite() {
            power.push((DELTA_LIGHT | delta.len() as u32, p, 0.0));
            delta.push(d);
        }
    }
    // The environment gets half the samples when there are other lights, all of them
    // otherwise. Its power (pi L over the bounding sphere's 4 pi R^2) is no guide: in an
    // interior, walls block most of it, and sampling it by that power starves the lights
    // that do reach the surfaces (measured on the hide_emitters test scene: the variance
    // rose above Mitsuba's, which picks each emitter with the same probability).
    let has_env = luminance(scene.environment) > 0.0
        || scene
            .environment_map
            .as_ref()
            .is_some_and(|m| !m.is_black());
    let env_light = match (has_env, power.is_empty()) {
        (false, _) => 0.0,
        (true, true) => 1.0,
        (true, false) => 0.5,
    };
    let others: f64 = power.iter().map(|&(_, p, _)| p).sum();
    if power.is_empty() {
        return LightTable {
            entries: vec![LightEntry::default()],
            count: 0,
            env_light,
            delta: vec![DeltaLight::default()],
        };
    }
    for &(id, p, area) in &power {
        let select = (1.0 - env_light as f64) * p / others;
        if id & DELTA_LIGHT != 0 {
            delta[(id & !DELTA_LIGHT) as usize].select = select as f32;
        } else {
            tris[id as usize].light_pdf = (select / area) as f32;
        }
    }
    if delta.is_empty() {
        delta.push(DeltaLight::default());
    }
    LightTable {
        entries: alias_table(
            &power
                .iter()
                .map(|&(k, p, _)| (k, p / others))
                .collect::<Vec<_>>(),
        ),
        count: power.len() as u32,
        env_light,
        delta,
    }
}

/// The alias table (`cohort_scenes::alias`) over `(light id, probability)` pairs.
fn alias_table(items: &[(u32, f64)]) -> Vec<LightEntry> {
    let weights: Vec<f64> = items.iter().map(|&(_, p)| p).collect();
    cohort_scenes::alias::alias_table(&weights)
        .into_iter()
        .zip(items)
        .map(|(e, &(k, _))| LightEntry {
            tri: k,
            alias_tri: items[e.alias as usize].0,
            prob: e.prob,
            pad: 0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table picks each triangle with its probability: summed over entries.
    #[test]
    fn alias_table_reproduces_the_probabilities() {
        let items = [(7u32, 0.5), (3, 0.25), (9, 0.125), (1, 0.0625), (4, 0.0625)];
        let t = alias_table(&items);
        let n = t.len() as f64;
        for &(k, p) in &items {
            let got: f64 = t
                .iter()
                .map(|e| {
                    (if e.tri == k { e.prob as f64 } else { 0.0 })
                        + if e.alias_tri == k {
                            1.0 - e.prob as f64
                        } else {
                            0.0
                        }
                })
                .sum::<f64>()
                / n;
            assert!((got - p).abs() < 1e-6, "triangle {k}: {got} vs {p}");
        }
    }
}
