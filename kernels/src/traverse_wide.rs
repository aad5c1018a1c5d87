//! Closest-hit traversal of the 8-wide BVH (`cohort_scenes::GpuBvh8`): one ray per
//! invocation; each step fetches one 8-wide node (two 128-byte records of four child boxes
//! in structure-of-arrays form), tests all eight boxes, intersects the triangles of the hit
//! leaf children at once, continues with the first hit interior child in the ray-octant
//! order of Ylitie, Karras & Laine 2017 and pushes the others. Triangles, leaf references
//! and the watertight triangle test are those of the BVH2 kernel ([`crate::traverse`]); the
//! box test is the same conservative slab test (far distance scaled by 1 + 2γ(3)), with the
//! slab ends ordered by the sign of the inverse direction instead of a min/max.

/// The node records this traversal reads (declared in `cohort-layout`).
pub use crate::layout::WideNode;
use crate::layout::*;
use crate::shadow::finish_slot;
use crate::traverse::{dominant_axis, leaf_hits, live_slot, rotate, NO_SLOT};
use cohort::prelude::*;

/// Stack entries per invocation (the builder checks its bound against this:
/// `cohort_scenes::bvh::wide::STACK_SIZE`).
pub const STACK_SIZE: usize = 64;

/// Bits (slot order) of the four children of record `n` whose boxes the ray enters within
/// [0, tmax]. `neg` = 1 per axis where the inverse direction is negative: the slab's near
/// end is then the box max.
#[kernel_fn]
pub fn hit4(org: Vec3, inv: Vec3, neg: UVec3, n: WideNode, tmax: f32) -> u32 {
    let nx = neg.x != 0;
    let ny = neg.y != 0;
    let nz = neg.z != 0;
    let ax = if nx { n.hi_x } else { n.lo_x };
    let bx = if nx { n.lo_x } else { n.hi_x };
    let ay = if ny { n.hi_y } else { n.lo_y };
    let by = if ny { n.lo_y } else { n.hi_y };
    let az = if nz { n.hi_z } else { n.lo_z };
    let bz = if nz { n.lo_z } else { n.hi_z };
    let ox = Vec4::splat(org.x);
    let oy = Vec4::splat(org.y);
    let oz = Vec4::splat(org.z);
    let ix = Vec4::splat(inv.x);
    let iy = Vec4::splat(inv.y);
    let iz = Vec4::splat(inv.z);
    let near = ((ax - ox) * ix)
        .max((ay - oy) * iy)
        .max((az - oz) * iz)
        .max(Vec4::ZERO);
    let far = ((bx - ox) * ix)
        .min((by - oy) * iy)
        .min((bz - oz) * iz)
        .min(Vec4::splat(tmax))
        * Vec4::splat(1.0000004);
    (near.x <= far.x) as u32
        | ((near.y <= far.y) as u32) << 1
        | ((near.z <= far.z) as u32) << 2
        | ((near.w <= far.w) as u32) << 3
}

/// Child reference of slot `s` (0..8) of the node whose records hold `a` and `b`.
#[kernel_fn]
pub fn pick(a: UVec4, b: UVec4, s: u32) -> u32 {
    let c = if s >= 4 { b } else { a };
    let odd = (s & 1) != 0;
    let lo = if odd { c.y } else { c.x };
    let hi = if odd { c.w } else { c.z };
    if (s & 2) != 0 {
        hi
    } else {
        lo
    }
}

/// Moves bit `s` of an 8-bit mask to bit `s ^ oct`.
#[kernel_fn]
pub fn permute8(m: u32, oct: u32) -> u32 {
    let mut r = m;
    if (oct & 1) != 0 {
        r = ((r & 0x55) << 1) | ((r >> 1) & 0x55);
    }
    if (oct & 2) != 0 {
        r = ((r & 0x33) << 2) | ((r >> 2) & 0x33);
    }
    if (oct & 4) != 0 {
        r = ((r & 0x0f) << 4) | ((r >> 4) & 0x0f);
    }
    r
}

/// What a traversal looks for, decided when the kernel is built (an associated constant,
/// so the closest-hit kernel contains no early exit).
pub trait HitQuery: 'static {
    /// Stop at the first hit within (tmin, tmax): occlusion (shadow) rays.
    const ANY: bool;
}

/// The closest hit (path rays).
pub struct Closest;
impl HitQuery for Closest {
    const ANY: bool = false;
}

/// Any hit, with early exit (shadow rays of light sampling).
pub struct AnyHit;
impl HitQuery for AnyHit {
    const ANY: bool = true;
}

/// Traces the ray (`org`, `dir`) over (`tmin`, `tmax`) through the 8-wide BVH: (t, u, v,
/// triangle index as bits) of the closest hit (or, for [`AnyHit`], of the first found),
/// or w = MISS.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn trace8<Q: HitQuery>(
    org: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
    f: &Frame,
    nodes: &[WideNode],
    tris: &[Triangle],
) -> Vec4 {
    let inv = dir.recip();
    let kz = dominant_axis(dir);
    let d_r = rotate(dir, kz);
    let org_r = rotate(org, kz);
    let shear = Vec3::new(d_r.x / d_r.z, d_r.y / d_r.z, 1.0 / d_r.z);
    let neg = UVec3::new(
        (inv.x < 0.0) as u32,
        (inv.y < 0.0) as u32,
        (inv.z < 0.0) as u32,
    );
    let oct = neg.x | (neg.y << 1) | (neg.z << 2);
    // Byte `oct & 3` of meta.x (octants 0..3) or meta.y (4..7).
    let meta_shift = (oct & 3) * 8;
    let mut best_t = tmax;
    let mut best = Vec4::new(best_t, 0.0, 0.0, f32::from_bits(MISS));
    // Every entry is pushed before it is popped: no zero fill (`uninit`).
    let mut stack: [u32; STACK_SIZE] = uninit();
    let mut sp = 0usize;
    let mut node = 0u32;
    // A ray with a NaN or zero direction, or a NaN or huge origin, misses (dot products
    // propagate NaN into an ordered compare, which min/max would not): its box tests would
    // enter every child (NaN compares false both ways), empty slots included, and send the
    // loop through invalid node references (a GPU hang on the H100).
    let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
    while go {
        // Both records are fetched at once: testing the second one only when it holds a
        // child (one more dependent fetch per node) measured 10% slower on primary rays.
        let a = nodes[node as usize];
        let b = nodes[node as usize + 1];
        let hits8 = hit4(org, inv, neg, a, best_t) | (hit4(org, inv, neg, b, best_t) << 4);
        let ordered = permute8(hits8, oct);
        let leaf_mask = ((if oct >= 4 { a.meta.y } else { a.meta.x }) >> meta_shift) & 0xff;
        let mut leaves = ordered & leaf_mask;
        let mut inner = ordered & !leaf_mask;
        while leaves != 0 {
            let p = leaves.trailing_zeros();
            leaves &= leaves - 1;
            let child = pick(a.child, b.child, p ^ oct);
            let first = child & 0x0fff_ffff;
            let cnt = ((child >> 28) & 7) + 1;
            best = leaf_hits::<Q>(org_r, kz, shear, first, cnt, tmin, best, tris);
            best_t = best.x;
            if Q::ANY {
                if best.w.to_bits() != MISS {
                    leaves = 0;
                    go = false;
                }
            }
        }
        if Q::ANY {
            if !go {
                inner = 0;
                sp = 0;
            }
        }
        if inner != 0 {
            // Nearest (first in octant order) next; the others are pushed far to near.
            let p = inner.trailing_zeros();
            inner &= inner - 1;
            node = pick(a.child, b.child, p ^ oct);
            while inner != 0 {
                let q = 31 - inner.leading_zeros();
                inner ^= 1u32 << q;
                stack[sp] = pick(a.child, b.child, q ^ oct);
                sp += 1;
            }
        } else if sp > 0 {
            sp -= 1;
            node = stack[sp];
        } else {
            go = false;
        }
    }
    best
}

/// Traces ray slot `r` through the 8-wide BVH and writes its closest hit to `hits[r]`:
/// (t, u, v, triangle index as bits), or w = MISS.
#[kernel_fn]
pub fn trace_ray8(
    r: u32,
    f: &Frame,
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let ri = r as usize;
    let o4 = ray_o[ri];
    hits[ri] = trace8::<Closest>(
        o4.truncate(),
        ray_d[ri].truncate(),
        o4.w,
        3.0e38,
        f,
        nodes,
        tris,
    );
}

/// Closest hit of every live ray through the 8-wide BVH: a drop-in for
/// [`crate::traverse::traverse`] with `nodes` from `cohort_scenes::GpuBvh8`. On the CPU
/// backend a dispatch traces its rays as one stream ([`crate::traverse_stream`]).
#[kernel(workgroup = 64, loops = finite, cpu_dispatch = crate::traverse_stream::traverse8_whole)]
#[allow(clippy::too_many_arguments)]
pub fn traverse8(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[WideNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let r = live_slot(gi, count, idrays, state);
    if r != NO_SLOT {
        trace_ray8(r, f, ray_o, ray_d, nodes, tris, hits);
    }
}

/// The shadow pass of next-event estimation over the 8-wide BVH: for every live slot,
/// trace its light sample's shadow ray (any hit, early exit) and finish the slot
/// (`crate::shadow::finish_slot`). On the CPU backend a dispatch traces its shadow rays as
/// one stream ([`crate::traverse_stream`]).
#[kernel(workgroup = 64, loops = finite, cpu_dispatch = crate::traverse_stream::trace_shadow8_whole)]
#[allow(clippy::too_many_arguments)]
pub fn trace_shadow8(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    shadow_o: &[Vec4],
    shadow_d: &[Vec4],
    nee: &[Vec4],
    nodes: &[WideNode],
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
                visible = trace8::<AnyHit>(o.truncate(), d.truncate(), 0.0, o.w, f, nodes, tris)
                    .w
                    .to_bits()
                    == MISS;
            }
            finish_slot(r as u32, d.w, ld, visible, radiance, accum);
        }
    }
}
