//! The emitters of a scene as next-event estimation samples them: an alias table over the
//! emitter triangles (in BVH leaf order) and the delta lights (point, spot, directional,
//! projector), and the probability of sampling the environment (constant or map) instead.
//!
//! Each emitter is chosen with the same probability, as Mitsuba 3 chooses them (its
//! `Scene::sample_emitter`): an emitting shape, a delta light and the environment count one
//! each, and a shape's triangles share its probability in proportion to their area (its
//! `sample_position` by area). Choosing by power instead was measured against Mitsuba's own
//! test scene with eight emitters of very different powers (`various_emitters`): the dim
//! spot lights got a third of Mitsuba's samples, and the image failed Mitsuba's render test
//! there (383 pixel channels beyond chance, 245 allowed; 94 with this choice).
//!
//! Powers are still estimated, to leave out emitters that emit nothing: a one-sided
//! Lambertian emitter of radiance L and area A emits pi L A; a point light of intensity I,
//! 4 pi I; a spot, I times the solid angle of its cone out to the middle of its falloff; a
//! directional light of irradiance E, E times the cross-section pi R^2 of the scene's
//! bounding sphere.

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
    // The object each original triangle belongs to: an emitting object is one emitter.
    let mut object_of = vec![u32::MAX; scene.triangles.len()];
    for (o, object) in scene.objects.iter().enumerate() {
        for t in object.triangles.clone() {
            if let Some(slot) = object_of.get_mut(t as usize) {
                *slot = o as u32;
            }
        }
    }
    // (light id, emitter, area or 0 for a delta light)
    let mut candidates: Vec<(u32, usize, f64)> = Vec::new();
    // Each emitting object's summed area, by emitter number.
    let mut emitter_area: Vec<f64> = Vec::new();
    let mut emitter_of_object = std::collections::HashMap::new();
    for (k, t) in tris.iter_mut().enumerate() {
        t.light_pdf = 0.0;
        let m = &scene.materials[t.material as usize];
        if let Some(e) = m.emission {
            let area = 0.5 * (t.v1 - t.v0).cross(t.v2 - t.v0).length();
            let p = PI * (luminance(e) * area) as f64;
            // Triangles too small for the kernels' f32 normal (which would be NaN) are left out.
            if p > 0.0 && p.is_finite() && area > 1e-15 {
                // A triangle outside every object (not made by the scene loaders) is an
                // emitter of its own.
                let object = object_of
                    .get(t.original as usize)
                    .copied()
                    .filter(|&o| o != u32::MAX)
                    .map_or(usize::MAX - k, |o| o as usize);
                let next = emitter_area.len();
                let emitter = *emitter_of_object.entry(object).or_insert(next);
                if emitter == next {
                    emitter_area.push(0.0);
                }
                emitter_area[emitter] += area as f64;
                candidates.push((k as u32, emitter, area as f64));
            }
        }
    }
    let mut delta = Vec::new();
    let starts = cohort_scenes::texture::gpu_texture_starts(&scene.textures);
    for light in &scene.lights {
        let (d, p) = delta_light(light, radius, &starts);
        if p > 0.0 && p.is_finite() {
            candidates.push((DELTA_LIGHT | delta.len() as u32, emitter_area.len(), 0.0));
            emitter_area.push(0.0);
            delta.push(d);
        }
    }
    let emitters = emitter_area.len();
    let has_env = luminance(scene.environment) > 0.0
        || scene
            .environment_map
            .as_ref()
            .is_some_and(|m| !m.is_black());
    let env_light = if has_env {
        1.0 / (emitters + 1) as f32
    } else {
        0.0
    };
    if candidates.is_empty() {
        return LightTable {
            entries: vec![LightEntry::default()],
            count: 0,
            env_light,
            delta: vec![DeltaLight::default()],
        };
    }
    // The probability of each entry among the non-environment lights.
    let share: Vec<(u32, f64)> = candidates
        .iter()
        .map(|&(id, emitter, area)| {
            let within = if id & DELTA_LIGHT != 0 {
                1.0
            } else {
                area / emitter_area[emitter]
            };
            (id, within / emitters as f64)
        })
        .collect();
    for (&(id, p), &(_, _, area)) in share.iter().zip(&candidates) {
        let select = (1.0 - env_light as f64) * p;
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
        entries: alias_table(&share),
        count: share.len() as u32,
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

    /// The probability that the table picks `id`: summed over its entries.
    fn picked(t: &LightTable, id: u32) -> f64 {
        let n = t.entries.len() as f64;
        t.entries
            .iter()
            .map(|e| {
                (if e.tri == id { e.prob as f64 } else { 0.0 })
                    + if e.alias_tri == id {
                        1.0 - e.prob as f64
                    } else {
                        0.0
                    }
            })
            .sum::<f64>()
            / n
    }

    /// Mitsuba's choice: each emitter (shape, delta light, environment) equally likely
    /// whatever its power, a shape's triangles by area; `light_pdf` and `select` agree with
    /// the table.
    #[test]
    fn each_emitter_is_chosen_as_often_whatever_its_power() {
        let xml = r#"<scene version="3.0.0">
            <shape type="rectangle">
                <transform name="to_world"><scale value="3"/></transform>
                <emitter type="area"><rgb name="radiance" value="50"/></emitter>
            </shape>
            <shape type="rectangle">
                <transform name="to_world"><scale x="0.1" y="0.2"/><translate z="2"/></transform>
                <emitter type="area"><rgb name="radiance" value="0.01"/></emitter>
            </shape>
            <emitter type="point"><point name="position" value="0, 0, 1"/><rgb name="intensity" value="0.001"/></emitter>
            <emitter type="constant"><rgb name="radiance" value="100"/></emitter>
        </scene>"#;
        let scene = cohort_scenes::load_mitsuba_str(xml, ".").unwrap().scene;
        let bvh = cohort_scenes::GpuBvh::build(&scene).unwrap();
        let mut tris: Vec<Triangle> = bvh.triangles.clone();
        let t = build(&scene, &mut tris);
        // Two rectangles, the point light, the environment: a quarter each (the table
        // draws among the first three, once the environment is not chosen).
        assert!((t.env_light - 0.25).abs() < 1e-6, "{}", t.env_light);
        assert!(
            (t.delta[0].select - 0.25).abs() < 1e-6,
            "{}",
            t.delta[0].select
        );
        assert!((picked(&t, DELTA_LIGHT) - 1.0 / 3.0).abs() < 1e-6);
        let mut per_rectangle = [0.0f64; 2];
        for (k, tri) in tris.iter().enumerate() {
            let area = 0.5 * (tri.v1 - tri.v0).cross(tri.v2 - tri.v0).length() as f64;
            let p = picked(&t, k as u32);
            // Within a rectangle, its two triangles by area: the same density per area.
            assert!(
                (tri.light_pdf as f64 * area / 0.75 - p).abs() < 1e-6,
                "triangle {k}: light_pdf {} x area {area} vs picked {p}",
                tri.light_pdf
            );
            per_rectangle[usize::from(tri.v0.z > 1.0)] += p;
        }
        for p in per_rectangle {
            assert!((p - 1.0 / 3.0).abs() < 1e-6, "{per_rectangle:?}");
        }
    }

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
