//! The emitters of a scene as next-event estimation samples them: an alias table over the
//! emitter triangles (in BVH leaf order), each chosen in proportion to its power, and the
//! probability of sampling the constant environment instead.

use cohort_kernels::layout::{LightEntry, Triangle};
use cohort_scenes::Scene;
use glam::Vec3;

/// What `extend` needs to sample lights: the table, its length, and the environment's share.
pub struct LightTable {
    /// Never empty (one unused entry when the scene has no emitter triangle), so it can be bound.
    pub entries: Vec<LightEntry>,
    /// Entries in use (0: no area light).
    pub count: u32,
    /// Probability of sampling the environment (0: none; 1: no area light).
    pub env_light: f32,
}

/// Relative luminance of linear sRGB.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Builds the table over `tris` (BVH leaf order) and writes each emitter triangle's
/// selection probability per unit area into its `light_pdf` (0 for the others).
pub fn build(scene: &Scene, tris: &mut [Triangle]) -> LightTable {
    let mut power = Vec::new();
    for (k, t) in tris.iter_mut().enumerate() {
        t.light_pdf = 0.0;
        let m = &scene.materials[t.material as usize];
        if let Some(e) = m.emission {
            let area = 0.5 * (t.v1 - t.v0).cross(t.v2 - t.v0).length();
            let sides = if m.two_sided { 2.0 } else { 1.0 };
            let p = luminance(e) * area * sides;
            // Triangles too small for the kernels' f32 normal (which would be NaN) are left out.
            if p > 0.0 && p.is_finite() && area > 1e-15 {
                power.push((k as u32, p, area));
            }
        }
    }
    let has_env = luminance(scene.environment) > 0.0;
    // With both kinds of light, half the samples go to each: a simple rule that never
    // starves either (the environment's power has no meaningful area to compare with).
    let env_light = match (has_env, power.is_empty()) {
        (false, _) => 0.0,
        (true, true) => 1.0,
        (true, false) => 0.5,
    };
    if power.is_empty() {
        return LightTable {
            entries: vec![LightEntry::default()],
            count: 0,
            env_light,
        };
    }
    let total: f64 = power.iter().map(|&(_, p, _)| p as f64).sum();
    for &(k, p, area) in &power {
        let select = (1.0 - env_light as f64) * p as f64 / total;
        tris[k as usize].light_pdf = (select / area as f64) as f32;
    }
    LightTable {
        entries: alias_table(
            &power
                .iter()
                .map(|&(k, p, _)| (k, p as f64 / total))
                .collect::<Vec<_>>(),
        ),
        count: power.len() as u32,
        env_light,
    }
}

/// Vose's alias method over `(triangle, probability)` pairs whose probabilities sum to 1.
fn alias_table(items: &[(u32, f64)]) -> Vec<LightEntry> {
    let n = items.len();
    let mut scaled: Vec<f64> = items.iter().map(|&(_, p)| p * n as f64).collect();
    let mut entries: Vec<LightEntry> = items
        .iter()
        .map(|&(k, _)| LightEntry {
            tri: k,
            alias_tri: k,
            prob: 1.0,
            pad: 0,
        })
        .collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(s), Some(&l)) = (small.pop(), large.last()) {
        entries[s].prob = scaled[s] as f32;
        entries[s].alias_tri = items[l].0;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left is 1 up to rounding.
    entries
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
