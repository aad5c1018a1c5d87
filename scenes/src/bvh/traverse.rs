//! Host reference traversal of a [`GpuBvh`], written the way the GPU kernel should be (stack of
//! child references, both child boxes tested per node fetch, nearer child first), and a brute-force
//! closest hit over the scene's triangles with the same triangle test, which tests use as ground
//! truth. [`BruteForce`] is the same search with a conservative per-group bounding-sphere cull, so
//! that thousands of rays over a 250k-triangle scene stay affordable in a debug build; it shares no
//! code with the BVH path except the triangle test.
//!
//! Robustness, so that the BVH never loses a hit the brute force finds:
//! - triangles: watertight test of Woop, Benthin & Wald (JCGT 2013), with the paper's fallback to
//!   double precision when an edge function is exactly zero (a GPU kernel without f64 may skip the
//!   fallback; it only matters for rays through a vertex or along an edge);
//! - boxes: slab test with the far distance scaled by 1 + 2 gamma(3) (Ize 2013, "Robust BVH ray
//!   traversal"), and NaNs from 0 * inf (ray in a slab plane) ignored, so rounding can only make a
//!   box test pass, never fail.

use glam::Vec3;

use super::{decode_leaf, is_leaf, GpuBvh};
use crate::scene::Triangles;

/// A closest hit. The hit point is `(1 - u - v) v0 + u v1 + v v2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Index in [`crate::Scene::triangles`] (not in the reordered GPU array).
    pub triangle_index: u32,
    pub u: f32,
    pub v: f32,
}

/// Per-ray constants of the watertight test: the axis permutation and shear.
#[derive(Clone, Copy)]
pub(super) struct Shear {
    origin: Vec3,
    k: [usize; 3],
    s: Vec3,
}

impl Shear {
    pub(super) fn new(origin: Vec3, dir: Vec3) -> Shear {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding of the projected triangle when looking down -kz.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Shear {
            origin,
            k: [kx, ky, kz],
            s: Vec3::new(dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]),
        }
    }

    fn hit(&self, v0: Vec3, v1: Vec3, v2: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
        let [kx, ky, kz] = self.k;
        let (a, b, c) = (v0 - self.origin, v1 - self.origin, v2 - self.origin);
        let ax = a[kx] - self.s.x * a[kz];
        let ay = a[ky] - self.s.y * a[kz];
        let bx = b[kx] - self.s.x * b[kz];
        let by = b[ky] - self.s.y * b[kz];
        let cx = c[kx] - self.s.x * c[kz];
        let cy = c[ky] - self.s.y * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.s.z * a[kz];
        let bz = self.s.z * b[kz];
        let cz = self.s.z * c[kz];
        let t = (u * az + v * bz + w * cz) / det;
        if !(t > tmin && t < tmax) {
            return None;
        }
        Some((t, v / det, w / det))
    }
}

/// Watertight ray/triangle test: `(t, u, v)` for a hit with `tmin < t < tmax`, either side.
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    v: [Vec3; 3],
    tmin: f32,
    tmax: f32,
) -> Option<(f32, f32, f32)> {
    Shear::new(origin, dir).hit(v[0], v[1], v[2], tmin, tmax)
}

/// 1 + 2 gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24.
const FAR_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Entry distance of the ray into box [lo, hi] within (tmin, tmax), or None.
pub(super) fn slab(
    origin: Vec3,
    inv: Vec3,
    lo: Vec3,
    hi: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let mut near = tmin;
    let mut far = tmax;
    for k in 0..3 {
        let t0 = (lo[k] - origin[k]) * inv[k];
        let t1 = (hi[k] - origin[k]) * inv[k];
        // f32::min/max return the other operand for NaN: an undefined slab does not cull.
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1) * FAR_SCALE);
    }
    (near <= far).then_some(near)
}

/// Closest hit among the triangles of leaf reference `r`, with `tmin < t < tmax` (the first of
/// equal distances in leaf order).
pub(super) fn leaf_closest(
    bvh: &GpuBvh,
    shear: &Shear,
    r: u32,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let (first, count) = decode_leaf(r);
    let mut best = None;
    let mut best_t = tmax;
    for i in first..first + count {
        let t = &bvh.triangles[i as usize];
        let v = [t.v0, t.v1, t.v2];
        if let Some((t_hit, u, w)) = shear.hit(v[0], v[1], v[2], tmin, best_t) {
            best_t = t_hit;
            best = Some(Hit {
                t: t_hit,
                triangle_index: t.original,
                u,
                v: w,
            });
        }
    }
    best
}

/// Closest hit through the BVH, with `tmin < t < tmax`.
pub fn closest_hit(bvh: &GpuBvh, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
    if bvh.nodes.is_empty() {
        return None;
    }
    let shear = Shear::new(origin, dir);
    let inv = dir.recip();
    let mut best: Option<Hit> = None;
    let mut best_t = tmax;
    let mut stack: Vec<u32> = Vec::with_capacity(bvh.depth as usize + 1);
    stack.push(0);
    while let Some(r) = stack.pop() {
        if is_leaf(r) {
            if let Some(h) = leaf_closest(bvh, &shear, r, tmin, best_t) {
                best_t = h.t;
                best = Some(h);
            }
            continue;
        }
        let n = &bvh.nodes[r as usize];
        let l = slab(origin, inv, n.lmin, n.lmax, tmin, best_t);
        let rt = slab(origin, inv, n.rmin, n.rmax, tmin, best_t);
        match (l, rt) {
            (Some(tl), Some(tr)) => {
                let (near, far) = if tl <= tr {
                    (n.left, n.right)
                } else {
                    (n.right, n.left)
                };
                stack.push(far);
                stack.push(near);
            }
            (Some(_), None) => stack.push(n.left),
            (None, Some(_)) => stack.push(n.right),
            (None, None) => {}
        }
    }
    best
}

/// Closest hit by testing every triangle (ground truth for tests). Among hits at exactly the same
/// distance the lowest triangle index wins.
pub fn brute_force_closest_hit(
    tris: &Triangles,
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<Hit> {
    let shear = Shear::new(origin, dir);
    let mut best: Option<Hit> = None;
    let mut best_t = tmax;
    for (i, v) in tris.positions.chunks_exact(3).enumerate() {
        if let Some((t, u, w)) = shear.hit(v[0], v[1], v[2], tmin, best_t) {
            best_t = t;
            best = Some(Hit {
                t,
                triangle_index: i as u32,
                u,
                v: w,
            });
        }
    }
    best
}

/// Triangles per bounding sphere of [`BruteForce`].
const GROUP: usize = 32;

/// Exhaustive closest-hit search in the scene's own triangle order, skipping a group of
/// consecutive triangles only when its bounding sphere, inflated well beyond f32 rounding, cannot
/// be hit within the current closest distance. Returns exactly what [`brute_force_closest_hit`]
/// returns.
pub struct BruteForce<'a> {
    tris: &'a Triangles,
    spheres: Vec<(Vec3, f32)>,
}

impl<'a> BruteForce<'a> {
    pub fn new(tris: &'a Triangles) -> Self {
        let spheres = tris
            .positions
            .chunks(3 * GROUP)
            .map(|vs| {
                let (lo, hi) = vs.iter().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), v| (lo.min(*v), hi.max(*v)),
                );
                let c = 0.5 * (lo + hi);
                let r = vs.iter().map(|v| v.distance(c)).fold(0.0f32, f32::max);
                (c, r * (1.0 + 1e-4) + 1e-6 * c.abs().max_element())
            })
            .collect();
        BruteForce { tris, spheres }
    }

    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        let shear = Shear::new(origin, dir);
        let len = dir.length();
        let dn = dir / len;
        let mut best: Option<Hit> = None;
        let mut best_t = tmax;
        for (g, &(c, r)) in self.spheres.iter().enumerate() {
            let oc = c - origin;
            // Slack for the rounding of the distances themselves, relative to how far away we are.
            let r = r + 1e-5 * (oc.length() + r);
            let along = oc.dot(dn);
            if oc.cross(dn).length() > r || (along + r) / len < tmin || (along - r) / len > best_t {
                continue;
            }
            let first = g * GROUP;
            let last = (first + GROUP).min(self.tris.len());
            for i in first..last {
                let v = &self.tris.positions[3 * i..3 * i + 3];
                if let Some((t, u, w)) = shear.hit(v[0], v[1], v[2], tmin, best_t) {
                    best_t = t;
                    best = Some(Hit {
                        t,
                        triangle_index: i as u32,
                        u,
                        v: w,
                    });
                }
            }
        }
        best
    }
}
