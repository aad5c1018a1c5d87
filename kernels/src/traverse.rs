//! Closest-hit BVH traversal (Aila & Laine 2009 style: one ray per invocation, a stack
//! in a local array, both child boxes tested per node fetch, nearer child first) with a
//! watertight ray/triangle test (Woop, Benthin & Wald 2013).
//!
//! The traversal kernels here and in [`crate::traverse_wide`] and [`crate::traverse_cw`]
//! are `loops = finite`: a ray visits each node of the (finite, acyclic) tree at most
//! once, a leaf holds at most 8 triangles, and a ray whose direction or origin would send
//! it through invalid references (NaN, zero) stops before its first node. naga's
//! loop-bound counters cost 8 % of the renderer's paths/s (BENCHMARKS.md, 2026-11-27,
//! d2bc83f and 807cf8c).

use crate::layout::*;
use crate::shadow::finish_slot;
use crate::traverse_wide::{AnyHit, Closest, HitQuery};
use cohort::prelude::*;

/// Entry distance of the ray into a box, or a huge number when it misses within
/// [0, tmax]. The far distance is widened by 1 + 2γ(3) so rounding never loses a hit.
#[kernel_fn]
pub fn slab(org: Vec3, inv_dir: Vec3, bmin: Vec3, bmax: Vec3, tmax: f32) -> f32 {
    let t0 = (bmin - org) * inv_dir;
    let t1 = (bmax - org) * inv_dir;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(tmax) * 1.0000004;
    if near <= far {
        near
    } else {
        3.0e38
    }
}

/// Watertight ray/triangle intersection (Woop, Benthin & Wald 2013) in the ray's
/// sheared space. Vertices are rotated into the ray's axis order (kx, ky, kz) with
/// [`rotate`], the origin once per ray (`org_r = rotate(org, kz)`): a cyclic rotation is
/// two vector selects per vertex, where a dot product with a one-hot axis vector was three
/// multiply-adds per component (and would turn an infinite coordinate into NaN). Returns
/// (t, u, v) in xyz and 1 in w on a hit within (tmin, tmax), else w = 0.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn intersect(
    org_r: Vec3,
    kz: u32,
    shear: Vec3,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    tmin: f32,
    tmax: f32,
) -> Vec4 {
    let a = rotate(v0, kz) - org_r;
    let b = rotate(v1, kz) - org_r;
    let c = rotate(v2, kz) - org_r;
    let ax = a.x - shear.x * a.z;
    let ay = a.y - shear.y * a.z;
    let bx = b.x - shear.x * b.z;
    let by = b.y - shear.y * b.z;
    let cx = c.x - shear.x * c.z;
    let cy = c.y - shear.y * c.z;
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let mut result = Vec4::ZERO;
    // `|` and `&` rather than `||` and `&&`: all operands are cheap and safe to evaluate,
    // and non-short-circuit logic compiles to straight-line code in the innermost loop.
    let mixed = ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0));
    let det = u + v + w;
    if !mixed & (det != 0.0) {
        let t = (u * (shear.z * a.z) + v * (shear.z * b.z) + w * (shear.z * c.z)) / det;
        if (t > tmin) & (t < tmax) {
            result = Vec4::new(t, v / det, w / det, 1.0);
        }
    }
    result
}

/// `v` in the axis order (kx, ky, kz) of a ray whose dominant axis is `kz`, with
/// kx = kz + 1 and ky = kz + 2 (mod 3): a cyclic rotation of the components.
#[kernel_fn]
pub fn rotate(v: Vec3, kz: u32) -> Vec3 {
    if kz == 0 {
        Vec3::new(v.y, v.z, v.x)
    } else if kz == 1 {
        Vec3::new(v.z, v.x, v.y)
    } else {
        v
    }
}

/// Intersects the ray with triangles `first..first + cnt` and returns `best` updated: the
/// closest hit so far as (t, u, v, triangle index as bits), t in x also when there is
/// none (then w keeps `best.w`). For `AnyHit` it returns at the first hit.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn leaf_hits<Q: HitQuery>(
    org_r: Vec3,
    kz: u32,
    shear: Vec3,
    first: u32,
    cnt: u32,
    tmin: f32,
    best: Vec4,
    tris: &[Triangle],
) -> Vec4 {
    let mut b = best;
    for k in first..first + cnt {
        let t = tris[k as usize];
        let h = intersect(org_r, kz, shear, t.v0, t.v1, t.v2, tmin, b.x);
        if h.w != 0.0 {
            b = Vec4::new(h.x, h.y, h.z, f32::from_bits(k));
            if Q::ANY {
                break;
            }
        }
    }
    b
}

/// The ray's dominant axis kz (Woop et al.): 0, 1 or 2.
#[kernel_fn]
pub fn dominant_axis(dir: Vec3) -> u32 {
    let ad = dir.abs();
    let mut kz = 2u32;
    if (ad.x >= ad.y) & (ad.x >= ad.z) {
        kz = 0;
    } else if ad.y >= ad.z {
        kz = 1;
    }
    kz
}

/// Traces the ray (`org`, `dir`) over (`tmin`, `tmax`) through the BVH2: (t, u, v,
/// triangle index as bits) of the closest hit (or, for `AnyHit`, of the first found), or
/// w = MISS.
#[kernel_fn]
#[allow(clippy::manual_swap, clippy::too_many_arguments)] // std::mem::swap is not kernel code
pub fn trace2<Q: HitQuery>(
    org: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
    f: &Frame,
    nodes: &[BvhNode],
    tris: &[Triangle],
) -> Vec4 {
    let inv = dir.recip();
    let kz = dominant_axis(dir);
    let d_r = rotate(dir, kz);
    let org_r = rotate(org, kz);
    let shear = Vec3::new(d_r.x / d_r.z, d_r.y / d_r.z, 1.0 / d_r.z);
    let mut best_t = tmax;
    let mut best = Vec4::new(best_t, 0.0, 0.0, f32::from_bits(MISS));
    // Every entry is pushed before it is popped: no zero fill (`uninit`).
    let mut stack: [u32; 64] = uninit();
    let mut sp = 0usize;
    let mut node = 0u32;
    // A ray with a NaN or zero direction, or a NaN or huge origin, misses (dot products
    // propagate NaN into an ordered compare, which min/max would not): its box tests would
    // enter every child (NaN compares false both ways), empty slots included, and send the
    // loop through invalid node references (a GPU hang on the H100).
    let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
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
                    best = leaf_hits::<Q>(org_r, kz, shear, first, cnt, tmin, best, tris);
                    best_t = best.x;
                    if Q::ANY {
                        if best.w.to_bits() != MISS {
                            go = false;
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
        if Q::ANY {
            if !go {
                next_a = 0xffff_ffff;
                next_b = 0xffff_ffff;
                sp = 0;
            }
        }
        if (next_a != 0xffff_ffff) & (next_b != 0xffff_ffff) {
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
    best
}

/// Traces ray slot `r` through the BVH and writes its closest hit to `hits[r]`:
/// (t, u, v, triangle index as bits), or w = MISS. Shared by both traversal kernels.
#[kernel_fn]
pub fn trace_ray(
    r: u32,
    f: &Frame,
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[BvhNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let ri = r as usize;
    let o4 = ray_o[ri];
    hits[ri] = trace2::<Closest>(
        o4.truncate(),
        ray_d[ri].truncate(),
        o4.w,
        3.0e38,
        f,
        nodes,
        tris,
    );
}

/// Closest hit of every live ray. `hits[r]` = (t, u, v, triangle index as bits), or
/// w = MISS.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
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
    let r = live_slot(gi, count, idrays, state);
    if r != NO_SLOT {
        trace_ray(r, f, ray_o, ray_d, nodes, tris, hits);
    }
}

/// No live ray slot for this invocation (see [`live_slot`]).
pub const NO_SLOT: u32 = 0xffff_ffff;

/// The ray slot that invocation `gi` of a traversal traces: entry `gi` of the id list
/// when it is within the `count[0]` listed and its path is not done, else [`NO_SLOT`].
#[kernel_fn]
pub fn live_slot(gi: u32, count: &[u32], idrays: &[u32], state: &[UVec4]) -> u32 {
    let mut r = NO_SLOT;
    if gi < count[0] {
        let s = idrays[gi as usize];
        if state[s as usize].w & DONE == 0 {
            r = s;
        }
    }
    r
}

/// Persistent-threads traversal (Aila & Laine 2009): a fixed number of invocations
/// fetch rays from an atomic counter (`next[0]`, zeroed by the caller) until all
/// `count[0]` rays are traced, which evens out the work of long and short rays. Launch it
/// with a few invocations per GPU core rather than one per ray.
///
/// Each invocation claims its own ray. Claiming a chunk per workgroup (invocation 0
/// claims, the others read it through workgroup memory between barriers) traced wrong
/// or no hits for about 0.3% of the rays on lavapipe, although the protocol is race-free
/// on paper; per-invocation claims are exact on every device we have.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn traverse_persistent(
    f: &Frame,
    count: &[u32],
    next: &[AtomicU32],
    idrays: &[u32],
    state: &[UVec4],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[BvhNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let n = count[0];
    loop {
        let i = next[0].fetch_add(1, Ordering::Relaxed);
        if i >= n {
            break;
        }
        let r = idrays[i as usize];
        if state[r as usize].w & DONE == 0 {
            trace_ray(r, f, ray_o, ray_d, nodes, tris, hits);
        }
    }
}

/// The shadow pass of next-event estimation over the BVH2 (trees too deep for the 8-wide
/// kernel's stack): as `crate::traverse_wide::trace_shadow8`.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn trace_shadow(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    shadow_o: &[Vec4],
    shadow_d: &[Vec4],
    nee: &[Vec4],
    nodes: &[BvhNode],
    tris: &[Triangle],
    radiance: &mut [Vec4],
    accum: &mut [Vec4],
) {
    if gi < count[0] {
        let r = idrays[gi as usize] as usize;
        let d = shadow_d[r];
        if d.w != SLOT_IDLE {
            let ld = nee[r].truncate();
            let mut visible = false;
            if ld != Vec3::ZERO {
                let o = shadow_o[r];
                visible = trace2::<AnyHit>(o.truncate(), d.truncate(), 0.0, o.w, f, nodes, tris)
                    .w
                    .to_bits()
                    == MISS;
            }
            finish_slot(r as u32, d.w, ld, visible, radiance, accum);
        }
    }
}
