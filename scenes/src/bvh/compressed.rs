//! The 8-wide BVH in compressed form (after Ylitie, Karras & Laine 2017, "Efficient
//! Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"): one 80-byte node per
//! 8-wide node instead of 256 bytes, child boxes quantised to 8 bits per plane relative to the
//! node's own grid. Built from [`GpuBvh8`]: the same children in the same slots, so a
//! traversal visits them in the same octant order; only the storage changes.
//!
//! # GPU layout ([`layout::CwNode`], five 16-byte words)
//! | word | contents |
//! |---|---|
//! | `a` | `p.x, p.y, p.z` (f32 bits): the grid origin; `a.w`: the grid's power-of-two scale per axis as biased f32 exponents in bytes 0, 1, 2, and the leaf-slot mask in byte 3 |
//! | `b` | `b.x`: index of the first interior child (interior children are consecutive nodes, in slot order); `b.y`: first triangle of the leaf children (their triangles are consecutive, in slot order); `b.z`: triangle count of slot s in bits 4s..4s+4 (0 for interior and empty slots); `b.w`: the interior-slot mask |
//! | `qx` | bytes of slot s: `qx.x`/`qx.y` the low x plane of slots 0..=3 / 4..=7, `qx.z`/`qx.w` the high x plane |
//! | `qy`, `qz` | likewise for y and z |
//!
//! A child's box is `p + scale * q` per plane. The quantisation rounds outwards with a margin
//! of a thousandth of a grid step, and the grid starts one step below the node's box, so a
//! decoded box contains the exact one with room for the rounding of the kernel's slab test.
//! An empty slot has low planes 255 and high planes 0 on every axis, but a kernel must mask it
//! out (it is in neither the leaf nor the interior mask): a flat grid makes its box a point.
//!
//! Triangles are reordered so that each node's leaf triangles are consecutive
//! ([`GpuCwBvh::from_wide`] rewrites the BVH2's and the 8-wide BVH's leaf references to match,
//! so all three trees share one triangle array).

use glam::Vec3;

use super::wide::{EMPTY_SLOT, WIDTH};
use super::{decode_leaf, is_leaf, leaf_ref, GpuBvh, GpuBvh8};
use crate::layout;

// One compressed 8-wide node (`layout::CwNode`) is 80 bytes.
const _: () = assert!(std::mem::size_of::<layout::CwNode>() == 80);

/// The compressed nodes; node 0 is the root. Triangles are the (reordered) BVH2's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuCwBvh {
    pub nodes: Vec<layout::CwNode>,
}

/// Margin of the outward rounding, in grid steps (see the module docs).
const MARGIN: f64 = 1e-3;

impl GpuCwBvh {
    /// Compresses `wide` (built from `bvh`) and reorders the shared triangle array so that every
    /// node's leaf triangles are consecutive; the leaf references of `bvh` and `wide` are
    /// rewritten to the new order.
    pub fn from_wide(bvh: &mut GpuBvh, wide: &mut GpuBvh8) -> GpuCwBvh {
        let mut out = GpuCwBvh::default();
        if wide.nodes.is_empty() {
            return out;
        }
        let mut triangles: Vec<layout::Triangle> = Vec::with_capacity(bvh.triangles.len());
        // Old leaf reference -> new one.
        let mut moved = std::collections::HashMap::new();
        // Breadth first: a node's interior children get consecutive indices when it is emitted.
        let mut queue = std::collections::VecDeque::from([0u32]);
        out.nodes.push(layout::CwNode::default());
        let mut next = 0usize;
        while let Some(w) = queue.pop_front() {
            let slots = wide_slots(wide, w);
            let index = next;
            next += 1;
            let mut node = layout::CwNode::default();
            let (lo, hi) = slots.iter().flatten().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), c| (lo.min(c.1), hi.max(c.2)),
            );
            let grid = Grid::new(lo, hi);
            node.a = glam::UVec4::new(
                grid.p.x.to_bits(),
                grid.p.y.to_bits(),
                grid.p.z.to_bits(),
                0,
            );
            node.b = glam::UVec4::new(out.nodes.len() as u32, triangles.len() as u32, 0, 0);
            let mut leaf_mask = 0u32;
            let mut exps = 0u32;
            for (axis, e) in grid.exponent.iter().enumerate() {
                exps |= e << (8 * axis);
            }
            for (s, slot) in slots.iter().enumerate() {
                let (q_lo, q_hi) = match slot {
                    None => ([255u32; 3], [0u32; 3]),
                    Some((r, lo, hi)) => {
                        if is_leaf(*r) {
                            let (first, count) = decode_leaf(*r);
                            let new = leaf_ref(triangles.len() as u32, count);
                            moved.insert(*r, new);
                            triangles.extend_from_slice(
                                &bvh.triangles[first as usize..(first + count) as usize],
                            );
                            leaf_mask |= 1 << s;
                            node.b[2] |= count << (4 * s);
                        } else {
                            node.b[3] |= 1 << s;
                            queue.push_back(*r);
                            out.nodes.push(layout::CwNode::default());
                        }
                        grid.quantise(*lo, *hi)
                    }
                };
                let (word, shift) = (s / 4, 8 * (s % 4));
                for (axis, q) in [&mut node.qx, &mut node.qy, &mut node.qz]
                    .into_iter()
                    .enumerate()
                {
                    q[word] |= q_lo[axis] << shift;
                    q[2 + word] |= q_hi[axis] << shift;
                }
            }
            node.a[3] = exps | leaf_mask << 24;
            out.nodes[index] = node;
        }
        debug_assert_eq!(triangles.len(), bvh.triangles.len());
        bvh.triangles = triangles;
        let remap = |r: &mut u32| {
            if is_leaf(*r) && *r != EMPTY_SLOT {
                *r = moved[r];
            }
        };
        for n in &mut bvh.nodes {
            remap(&mut n.left);
            remap(&mut n.right);
        }
        for rec in &mut wide.nodes {
            rec.child.as_mut().iter_mut().for_each(remap);
        }
        out
    }

    pub fn node_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.nodes)
    }

    /// The decoded box of slot `s` of node `n` (empty slots: low > high), for tests.
    pub fn child_box(&self, n: usize, s: usize) -> (Vec3, Vec3) {
        let node = &self.nodes[n];
        let p = Vec3::new(
            f32::from_bits(node.a[0]),
            f32::from_bits(node.a[1]),
            f32::from_bits(node.a[2]),
        );
        let scale = |axis: usize| f32::from_bits(((node.a[3] >> (8 * axis)) & 0xff) << 23);
        let byte = |q: &glam::UVec4, w: usize| ((q[w + s / 4] >> (8 * (s % 4))) & 0xff) as f32;
        let lo = Vec3::new(byte(&node.qx, 0), byte(&node.qy, 0), byte(&node.qz, 0));
        let hi = Vec3::new(byte(&node.qx, 2), byte(&node.qy, 2), byte(&node.qz, 2));
        let s3 = Vec3::new(scale(0), scale(1), scale(2));
        (p + s3 * lo, p + s3 * hi)
    }
}

/// The children of 8-wide node `w` by slot: (reference, box low, box high).
fn wide_slots(wide: &GpuBvh8, w: u32) -> [Option<(u32, Vec3, Vec3)>; WIDTH] {
    let mut out = [None; WIDTH];
    for (s, o) in out.iter_mut().enumerate() {
        let rec = &wide.nodes[w as usize + s / 4];
        let j = s % 4;
        if rec.child[j] != EMPTY_SLOT {
            *o = Some((
                rec.child[j],
                Vec3::new(rec.lo_x[j], rec.lo_y[j], rec.lo_z[j]),
                Vec3::new(rec.hi_x[j], rec.hi_y[j], rec.hi_z[j]),
            ));
        }
    }
    out
}

/// A node's quantisation grid: origin `p` and a power-of-two step per axis.
struct Grid {
    p: Vec3,
    step: [f64; 3],
    exponent: [u32; 3],
}

impl Grid {
    fn new(lo: Vec3, hi: Vec3) -> Grid {
        let mut p = [0f32; 3];
        let mut step = [0f64; 3];
        let mut exponent = [0u32; 3];
        for axis in 0..3 {
            let (l, h) = (lo[axis] as f64, hi[axis] as f64);
            // 253 steps for the box, one below and one above it as the margin's room.
            // A flat box (a wall) still gets a step that moves a plane: a millionth of its
            // coordinates' magnitude.
            let want = ((h - l) / 253.0)
                .max((l.abs() + h.abs()) * 2f64.powi(-20))
                .max(f64::from(f32::MIN_POSITIVE));
            let e = want.log2().ceil() as i32;
            let s = 2f64.powi(e);
            // f32 with biased exponent e + 127 is exactly 2^e.
            exponent[axis] = (e + 127).clamp(1, 254) as u32;
            step[axis] = 2f64.powi(exponent[axis] as i32 - 127);
            // One step below the box, rounded down to an f32.
            let origin = l - s;
            let mut o = origin as f32;
            if o as f64 > origin {
                o = o.next_down();
            }
            p[axis] = o;
        }
        Grid {
            p: Vec3::from(p),
            step,
            exponent,
        }
    }

    /// Grid planes of the box (`lo`, `hi`), rounded outwards with the margin.
    fn quantise(&self, lo: Vec3, hi: Vec3) -> ([u32; 3], [u32; 3]) {
        let mut q_lo = [0u32; 3];
        let mut q_hi = [0u32; 3];
        for axis in 0..3 {
            let p = self.p[axis] as f64;
            let l = ((lo[axis] as f64 - p) / self.step[axis] - MARGIN).floor();
            let h = ((hi[axis] as f64 - p) / self.step[axis] + MARGIN).ceil();
            q_lo[axis] = l.clamp(0.0, 255.0) as u32;
            q_hi[axis] = h.clamp(0.0, 255.0) as u32;
        }
        (q_lo, q_hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decoded_boxes_contain_the_exact_ones_and_every_triangle_is_kept() {
        for name in ["cornell", "fairyforest"] {
            check(name);
        }
    }

    fn check(name: &str) {
        let scene = crate::embedded::load(name).unwrap();
        let (mut bvh, wide) = GpuBvh8::build_scene(&scene).unwrap();
        let mut wide = wide.expect("an 8-wide BVH");
        let before: std::collections::BTreeSet<u32> =
            bvh.triangles.iter().map(|t| t.original).collect();
        let reference_wide = wide.clone();
        let cw = GpuCwBvh::from_wide(&mut bvh, &mut wide);
        let after: std::collections::BTreeSet<u32> =
            bvh.triangles.iter().map(|t| t.original).collect();
        assert_eq!(before, after);
        assert_eq!(wide.nodes.len() / 2, cw.nodes.len());
        // Breadth-first order of the 8-wide nodes = compressed node order.
        let mut queue = std::collections::VecDeque::from([0u32]);
        let mut n = 0;
        let mut assigned = 1u32;
        while let Some(w) = queue.pop_front() {
            let node = cw.nodes[n];
            let mut tri = node.b[1];
            for (s, slot) in wide_slots(&reference_wide, w).iter().enumerate() {
                let (lo, hi) = cw.child_box(n, s);
                match slot {
                    // The kernel masks empty slots out (node.a.w byte 3 | node.b.w).
                    None => assert_eq!((node.a[3] >> 24 | node.b[3]) & (1 << s), 0),
                    Some((r, l, h)) => {
                        assert!(
                            lo.cmple(*l).all() && hi.cmpge(*h).all(),
                            "node {n} slot {s}: {lo} {hi} vs {l} {h}"
                        );
                        if is_leaf(*r) {
                            let count = (node.b[2] >> (4 * s)) & 15;
                            assert_eq!(count, decode_leaf(*r).1);
                            tri += count;
                        } else {
                            assert!(node.b[3] & (1 << s) != 0);
                            // The kernel's child index: first interior child + interior slots below s.
                            assert_eq!(
                                node.b[0] + (node.b[3] & ((1 << s) - 1)).count_ones(),
                                assigned
                            );
                            assigned += 1;
                            queue.push_back(*r);
                        }
                    }
                }
            }
            assert!(tri as usize <= bvh.triangles.len());
            n += 1;
        }
    }
}
