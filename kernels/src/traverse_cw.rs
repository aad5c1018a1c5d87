//! Closest-hit and any-hit traversal of the compressed 8-wide BVH
//! (`cohort_scenes::GpuCwBvh`): the same tree, slots and octant order as
//! [`crate::traverse_wide`], but one 80-byte node per step instead of two 128-byte records.
//! Child boxes are 8-bit grid planes: a plane's ray distance is one multiply-add,
//! `q * (scale * inv) + (p - org) * inv`, with the two factors computed once per node.
//! Interior children are consecutive nodes and a node's leaf triangles are consecutive, so a
//! child is found from the node's two base indices and its slot's rank in a bit mask.

/// The nodes this traversal reads (declared in `cohort-layout`).
pub use crate::layout::CwNode;
use crate::layout::*;
use crate::traverse::{dominant_axis, leaf_hits, live_slot, rotate, NO_SLOT};
use crate::traverse_wide::{permute8, HitQuery, STACK_SIZE};
use cohort::prelude::*;

/// The four bytes of `w` as floats (byte 0 first).
#[kernel_fn]
pub fn bytes4(w: u32) -> Vec4 {
    Vec4::new(
        (w & 0xff) as f32,
        ((w >> 8) & 0xff) as f32,
        ((w >> 16) & 0xff) as f32,
        (w >> 24) as f32,
    )
}

/// Ray distances of four planes of one axis: `q * s + b`.
#[kernel_fn]
pub fn planes4(w: u32, s: f32, b: f32) -> Vec4 {
    bytes4(w) * Vec4::splat(s) + Vec4::splat(b)
}

/// Bits (slot order) of the eight children of `n` whose boxes the ray enters within
/// [0, tmax]. `sa` and `sb` per axis: the plane distance is `q * sa + sb`.
#[kernel_fn]
pub fn hit_cw(n: CwNode, sa: Vec3, sb: Vec3, neg: UVec3, tmax: f32) -> u32 {
    // Near planes: the low ones where the inverse direction is positive.
    let xn = if neg.x != 0 { 2 } else { 0 };
    let yn = if neg.y != 0 { 2 } else { 0 };
    let zn = if neg.z != 0 { 2 } else { 0 };
    let mut bits = 0u32;
    for half in 0..2u32 {
        let near = planes4(word(n.qx, xn + half), sa.x, sb.x)
            .max(planes4(word(n.qy, yn + half), sa.y, sb.y))
            .max(planes4(word(n.qz, zn + half), sa.z, sb.z))
            .max(Vec4::ZERO);
        let far = planes4(word(n.qx, (2 - xn) + half), sa.x, sb.x)
            .min(planes4(word(n.qy, (2 - yn) + half), sa.y, sb.y))
            .min(planes4(word(n.qz, (2 - zn) + half), sa.z, sb.z))
            .min(Vec4::splat(tmax))
            * Vec4::splat(1.0000004);
        let h = (near.x <= far.x) as u32
            | ((near.y <= far.y) as u32) << 1
            | ((near.z <= far.z) as u32) << 2
            | ((near.w <= far.w) as u32) << 3;
        bits |= h << (4 * half);
    }
    bits
}

/// Component `i` (0..4) of `v`.
#[kernel_fn]
pub fn word(v: UVec4, i: u32) -> u32 {
    let lo = if (i & 1) != 0 { v.y } else { v.x };
    let hi = if (i & 1) != 0 { v.w } else { v.z };
    if (i & 2) != 0 {
        hi
    } else {
        lo
    }
}

/// The power of two with biased exponent `e` (byte `k` of `packed`).
#[kernel_fn]
pub fn step(packed: u32, k: u32) -> f32 {
    f32::from_bits(((packed >> (8 * k)) & 0xff) << 23)
}

/// A direction component with its zero replaced by a tiny number of the same sign, so that
/// `q * (scale * inv)` is never 0 * inf.
#[kernel_fn]
pub fn nonzero(d: f32) -> f32 {
    if d.abs() < 1.0e-30 {
        if d.to_bits() >> 31 != 0 {
            -1.0e-30
        } else {
            1.0e-30
        }
    } else {
        d
    }
}

/// Traces the ray (`org`, `dir`) over (`tmin`, `tmax`) through the compressed 8-wide BVH:
/// (t, u, v, triangle index as bits) of the closest hit (or, for `AnyHit`, of the first
/// found), or w = MISS. Same hits as `traverse_wide::trace8` up to ties in t.
#[kernel_fn]
#[allow(clippy::too_many_arguments)]
pub fn trace_cw<Q: HitQuery>(
    org: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
    f: &Frame,
    nodes: &[CwNode],
    tris: &[Triangle],
) -> Vec4 {
    let inv = Vec3::new(nonzero(dir.x), nonzero(dir.y), nonzero(dir.z)).recip();
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
    let mut best_t = tmax;
    let mut best = Vec4::new(best_t, 0.0, 0.0, f32::from_bits(MISS));
    // Every entry is pushed before it is popped: no zero fill (`uninit`).
    let mut stack: [u32; STACK_SIZE] = uninit();
    let mut sp = 0usize;
    let mut node = 0u32;
    // As in trace8: a NaN or zero direction, or a NaN or huge origin, misses.
    let mut go = (f.has_geometry != 0) & (dir.dot(dir) > 0.0) & (org.dot(org) < 1.0e36);
    while go {
        let n = nodes[node as usize];
        let p = Vec3::new(
            f32::from_bits(n.a.x),
            f32::from_bits(n.a.y),
            f32::from_bits(n.a.z),
        );
        let scale = Vec3::new(step(n.a.w, 0), step(n.a.w, 1), step(n.a.w, 2));
        let sa = scale * inv;
        let sb = (p - org) * inv;
        let leaf_slots = n.a.w >> 24;
        let hits8 = hit_cw(n, sa, sb, neg, best_t) & (leaf_slots | n.b.w);
        let ordered = permute8(hits8, oct);
        let leaf_mask = permute8(leaf_slots, oct);
        let mut leaves = ordered & leaf_mask;
        let mut inner = ordered & !leaf_mask;
        while leaves != 0 {
            let s = leaves.trailing_zeros() ^ oct;
            leaves &= leaves - 1;
            // Triangles of the leaf slots below s come first: sum their 4-bit counts.
            let below = n.b.z & ((1u32 << (4 * s)) - 1);
            let pairs = (below & 0x0f0f_0f0f) + ((below >> 4) & 0x0f0f_0f0f);
            let first = n.b.y + (pairs.wrapping_mul(0x0101_0101) >> 24);
            let cnt = (n.b.z >> (4 * s)) & 15;
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
            let s = inner.trailing_zeros() ^ oct;
            inner &= inner - 1;
            node = n.b.x + (n.b.w & ((1u32 << s) - 1)).count_ones();
            while inner != 0 {
                let q = 31 - inner.leading_zeros();
                inner ^= 1u32 << q;
                let c = q ^ oct;
                stack[sp] = n.b.x + (n.b.w & ((1u32 << c) - 1)).count_ones();
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

/// Closest hit of every live ray through the compressed 8-wide BVH: a drop-in for
/// `traverse_wide::traverse8` with `nodes` from `cohort_scenes::GpuCwBvh`.
#[kernel(workgroup = 64, loops = finite)]
#[allow(clippy::too_many_arguments)]
pub fn traverse_cw(
    #[builtin(global_index)] gi: u32,
    f: &Frame,
    count: &[u32],
    idrays: &[u32],
    state: &[UVec4],
    ray_o: &[Vec4],
    ray_d: &[Vec4],
    nodes: &[CwNode],
    tris: &[Triangle],
    hits: &mut [Vec4],
) {
    let r = live_slot(gi, count, idrays, state);
    if r != NO_SLOT {
        let o4 = ray_o[r as usize];
        hits[r as usize] = trace_cw::<crate::traverse_wide::Closest>(
            o4.truncate(),
            ray_d[r as usize].truncate(),
            o4.w,
            3.0e38,
            f,
            nodes,
            tris,
        );
    }
}
