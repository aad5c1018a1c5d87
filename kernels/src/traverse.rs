//! Closest-hit BVH traversal (Aila & Laine 2009 style: one ray per invocation, a stack
//! in a local array, both child boxes tested per node fetch, nearer child first) with a
//! watertight ray/triangle test (Woop, Benthin & Wald 2013).

use crate::layout::*;
use cohort::prelude::*;

/// Entry distance of the ray into a box, or a huge number when it misses within
/// [0, tmax]. The far distance is widened by 1 + 2γ(3) so rounding never loses a hit.
#[kernel_fn]
pub fn slab(org: Vec3, inv_dir: Vec3, bmin: Vec3, bmax: Vec3, tmax: f32) -> f32 {
    let t0 = (bmin - org) * inv_dir;
    let t1 = (bmax - org) * inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(tmax) * 1.0000004;
    if near <= far { near } else { 3.0e38 }
}

/// Watertight ray/triangle intersection in the ray's sheared space. Returns (t, u, v)
/// in xyz and 1 in w on a hit within (tmin, tmax), else w = 0.
#[kernel_fn]
pub fn intersect(org: Vec3, kz: u32, shear: Vec3, v0: Vec3, v1: Vec3, v2: Vec3, tmin: f32, tmax: f32) -> Vec4 {
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    let a = v0 - org;
    let b = v1 - org;
    let c = v2 - org;
    let ax = a[kx as usize] - shear.x * a[kz as usize];
    let ay = a[ky as usize] - shear.y * a[kz as usize];
    let bx = b[kx as usize] - shear.x * b[kz as usize];
    let by = b[ky as usize] - shear.y * b[kz as usize];
    let cx = c[kx as usize] - shear.x * c[kz as usize];
    let cy = c[ky as usize] - shear.y * c[kz as usize];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let mut result = Vec4::ZERO;
    let mixed = (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0);
    let det = u + v + w;
    if !mixed && det != 0.0 {
        let az = shear.z * a[kz as usize];
        let bz = shear.z * b[kz as usize];
        let cz = shear.z * c[kz as usize];
        let t = (u * az + v * bz + w * cz) / det;
        if t > tmin && t < tmax {
            result = Vec4::new(t, v / det, w / det, 1.0);
        }
    }
    result
}

/// Shear constants of a ray: the dominant axis `kz` (returned in w as a float) and
/// (Sx, Sy, Sz).
#[kernel_fn]
pub fn shear_of(dir: Vec3) -> Vec4 {
    let ad = dir.abs();
    let mut kz = 2u32;
    if ad.x >= ad.y && ad.x >= ad.z {
        kz = 0;
    } else if ad.y >= ad.z {
        kz = 1;
    }
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    let dz = dir[kz as usize];
    Vec4::new(dir[kx as usize] / dz, dir[ky as usize] / dz, 1.0 / dz, kz as f32)
}

/// Closest hit of every live ray. `hits[r]` = (t, u, v, triangle index as bits), or
/// w = MISS.
#[kernel(workgroup = 64)]
pub fn traverse(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[BvhNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let i = gi as usize;
    if gi >= count[0] {
        return;
    }
    let r = idrays[i] as usize;
    if state[r].w & DONE != 0 {
        return;
    }
    let org = ray_o[r].truncate();
    let dir = ray_d[r].truncate();
    let tmin = ray_o[r].w;
    let inv = dir.recip();
    let sh = shear_of(dir);
    let kz = sh.w as u32;
    let shear = sh.truncate();
    let mut best_t = 3.0e38f32;
    let mut best = Vec4::new(best_t, 0.0, 0.0, f32::from_bits(MISS));
    let mut stack = [0u32; 64];
    let mut sp = 0usize;
    let mut node = 0u32;
    let mut go = f.has_geometry != 0;
    while go {
        let n = nodes[node as usize];
        let tl = slab(org, inv, n.lmin, n.lmax, best_t);
        let tr = slab(org, inv, n.rmin, n.rmax, best_t);
        let mut next_a = 0xffff_ffffu32;
        let mut next_b = 0xffff_ffffu32;
        let mut ta = 0.0f32;
        let mut tb = 0.0f32;
        // Leaves are intersected as soon as their box is hit; interior children are
        // collected for the near-first descent.
        for side in 0..2u32 {
            let child = if side == 0 { n.left } else { n.right };
            let tc = if side == 0 { tl } else { tr };
            if tc < best_t {
                if child & 0x8000_0000 != 0 {
                    let first = child & 0x0fff_ffff;
                    let cnt = ((child >> 28) & 7) + 1;
                    for k in first..first + cnt {
                        let t = tris[k as usize];
                        let h = intersect(org, kz, shear, t.v0, t.v1, t.v2, tmin, best_t);
                        if h.w != 0.0 {
                            best_t = h.x;
                            best = Vec4::new(h.x, h.y, h.z, f32::from_bits(k));
                        }
                    }
                } else if next_a == 0xffff_ffff {
                    next_a = child;
                    ta = tc;
                } else {
                    next_b = child;
                    tb = tc;
                }
            }
        }
        if next_a != 0xffff_ffff && next_b != 0xffff_ffff {
            if tb < ta {
                let tmp = next_a;
                next_a = next_b;
                next_b = tmp;
            }
            stack[sp] = next_b;
            sp += 1;
            node = next_a;
        } else if next_a != 0xffff_ffff {
            node = next_a;
        } else if sp > 0 {
            sp -= 1;
            node = stack[sp];
        } else {
            go = false;
        }
    }
    hits[r] = best;
}
