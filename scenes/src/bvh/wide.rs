//! An 8-wide BVH for the GPU, collapsed from the flattened BVH2 ([`GpuBvh`]) and sharing its
//! triangle array, leaf references and exact f32 boxes: only the interior nodes change, so the
//! closest hit is the same as the BVH2's (up to ties in t) with the same watertight triangle test
//! and the same conservative slab test.
//!
//! # GPU layout
//! [`GpuBvh8::nodes`] is an array of 128-byte records ([`layout::WideNode`]); one 8-wide node is two
//! consecutive records, slots 0..=3 in the first and 4..=7 in the second. A record is four child
//! boxes in structure-of-arrays form (`lo_x[i]`, `hi_x[i]`, ... of child slot i), so that a thread
//! tests four boxes with vector-shaped arithmetic and 16-byte loads:
//!
//! | offset | field | |
//! |---|---|---|
//! | 0 | `lo_x: [f32; 4]` | box min x of the 4 children |
//! | 16 | `hi_x: [f32; 4]` | box max x |
//! | 32 | `lo_y`, 48 `hi_y`, 64 `lo_z`, 80 `hi_z` | likewise |
//! | 96 | `child: [u32; 4]` | child references, as in [`GpuBvh`] (bit 31 = leaf); an interior child is the index of its first record; [`EMPTY_SLOT`] where a node has fewer than 8 children |
//! | 112 | `meta: [u32; 4]` | first record only: `meta[0]` bytes 0..=3 and `meta[1]` bytes 0..=3 are the leaf-child masks of ray octants 0..=7 (see below); the rest zero |
//!
//! An empty slot has the box lo = +inf, hi = -inf, which the sign-ordered slab test never hits.
//! Node 0 (records 0 and 1) is the root; the root's own box is not stored.
//!
//! **Child order (Ylitie, Karras & Laine 2017).** The ray's octant is `oct = (dir.x < 0) | (dir.y
//! < 0) << 1 | (dir.z < 0) << 2`. A traversal visits the hit children in the order of `slot ^ oct`
//! (ascending), which is roughly front to back because the builder puts in slot s the child whose
//! centroid lies furthest towards the direction with the signs of octant s. The leaf mask of
//! octant `oct` has bit `slot ^ oct` set for each leaf child, so a kernel separates leaf and
//! interior hits in that order without permuting bits itself.

use glam::{UVec4, Vec3, Vec4};

use crate::layout;

use super::{is_leaf, GpuBvh};

/// Child reference of an unused slot.
pub const EMPTY_SLOT: u32 = u32::MAX;
/// Children per node.
pub const WIDTH: usize = 8;
/// Stack entries a traversal kernel has (it pushes at most `interior children - 1` per node).
pub const STACK_SIZE: u32 = 64;

const _: () = assert!(std::mem::size_of::<layout::WideNode>() == 128);

/// The 8-wide node records; triangles are the BVH2's ([`GpuBvh::triangles`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuBvh8 {
    pub nodes: Vec<layout::WideNode>,
    /// Most 8-wide nodes on one root-to-leaf path.
    pub depth: u32,
    /// Most stack entries an ordered traversal that pushes every hit interior child but the
    /// first can hold: at most [`STACK_SIZE`] (the build checks).
    pub stack_bound: u32,
}

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum WideBvhError {
    #[error("the 8-wide BVH may need {need} stack entries, more than the kernel's {STACK_SIZE}")]
    StackTooDeep { need: u32 },
}

#[derive(Clone, Copy)]
struct Child {
    r: u32,
    lo: Vec3,
    hi: Vec3,
}

impl Child {
    fn area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// Leaf collapse of a BVH2 that is to be widened: at most this many triangles per leaf ...
pub const WIDE_MAX_LEAF: u32 = 4;
/// ... at this SAH traversal cost (relative to one triangle test). Smaller leaves than the
/// default BVH2's (8, 3) measured faster for both traversal kernels on an H200 (8-wide:
/// 1.22x primary and 1.42x diffuse over the default BVH2 kernel on confroom, against 1.11x and
/// 1.16x on the default leaves; see docs/results/traversal_wide_h200.txt).
pub const WIDE_TRAVERSAL_COST: f32 = 1.5;

impl GpuBvh8 {
    /// The BVH2 with [`WIDE_MAX_LEAF`] / [`WIDE_TRAVERSAL_COST`] leaves and its 8-wide form;
    /// where that tree may need more than [`STACK_SIZE`] stack entries, the default BVH2
    /// ([`GpuBvh::build`]) and its 8-wide form; where that one does too, the default BVH2
    /// alone (a renderer then uses the BVH2 kernel). Both trees share the returned BVH2's
    /// triangle array.
    pub fn build_scene(scene: &crate::Scene) -> Result<(GpuBvh, Option<GpuBvh8>), super::BvhError> {
        let small = GpuBvh::build_with_leaves(scene, WIDE_MAX_LEAF, WIDE_TRAVERSAL_COST)?;
        if let Ok(wide) = GpuBvh8::build(&small) {
            return Ok((small, Some(wide)));
        }
        let bvh = GpuBvh::build(scene)?;
        let wide = GpuBvh8::build(&bvh).ok();
        Ok((bvh, wide))
    }

    /// Collapses `bvh`'s BVH2 into 8-wide nodes: each node takes its BVH2 node's two children and
    /// repeatedly opens the interior child of largest surface area until it has 8 children or
    /// only leaves.
    pub fn build(bvh: &GpuBvh) -> Result<GpuBvh8, WideBvhError> {
        let mut out = GpuBvh8::default();
        if bvh.nodes.is_empty() {
            return Ok(out);
        }
        let (_, bound) = out.node(bvh, 0, 1);
        out.stack_bound = bound;
        if bound > STACK_SIZE {
            return Err(WideBvhError::StackTooDeep { need: bound });
        }
        Ok(out)
    }

    pub fn node_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.nodes)
    }

    fn children2(bvh: &GpuBvh, i: u32) -> [Child; 2] {
        let n = &bvh.nodes[i as usize];
        [
            Child {
                r: n.left,
                lo: n.lmin,
                hi: n.lmax,
            },
            Child {
                r: n.right,
                lo: n.rmin,
                hi: n.rmax,
            },
        ]
    }

    /// Emits the 8-wide node for BVH2 interior node `i`; returns its first record and the stack
    /// bound of its subtree.
    fn node(&mut self, bvh: &GpuBvh, i: u32, depth: u32) -> (u32, u32) {
        self.depth = self.depth.max(depth);
        let mut kids: Vec<Child> = Self::children2(bvh, i).to_vec();
        while kids.len() < WIDTH {
            let best = kids
                .iter()
                .enumerate()
                .filter(|(_, c)| !is_leaf(c.r))
                .max_by(|a, b| a.1.area().total_cmp(&b.1.area()))
                .map(|(k, _)| k);
            let Some(k) = best else { break };
            let c = kids.swap_remove(k);
            kids.extend(Self::children2(bvh, c.r));
        }
        let slots = assign_slots(&kids);
        let index = self.nodes.len() as u32;
        let empty = layout::WideNode {
            lo_x: Vec4::INFINITY,
            hi_x: Vec4::NEG_INFINITY,
            lo_y: Vec4::INFINITY,
            hi_y: Vec4::NEG_INFINITY,
            lo_z: Vec4::INFINITY,
            hi_z: Vec4::NEG_INFINITY,
            child: UVec4::splat(EMPTY_SLOT),
            meta: UVec4::ZERO,
        };
        self.nodes.push(empty);
        self.nodes.push(empty);
        let mut leaf_slots = 0u32;
        let interior = kids.iter().filter(|c| !is_leaf(c.r)).count() as u32;
        let mut bound = 0;
        for (s, k) in slots.iter().enumerate() {
            let Some(k) = *k else { continue };
            let c = kids[k];
            let r = if is_leaf(c.r) {
                leaf_slots |= 1 << s;
                c.r
            } else {
                let (r, b) = self.node(bvh, c.r, depth + 1);
                bound = bound.max(interior - 1 + b);
                r
            };
            let rec = &mut self.nodes[index as usize + s / 4];
            let j = s % 4;
            rec.lo_x[j] = c.lo.x;
            rec.hi_x[j] = c.hi.x;
            rec.lo_y[j] = c.lo.y;
            rec.hi_y[j] = c.hi.y;
            rec.lo_z[j] = c.lo.z;
            rec.hi_z[j] = c.hi.z;
            rec.child[j] = r;
        }
        let mut meta = [0u32; 2];
        for oct in 0..8u32 {
            let m = (0..8u32)
                .filter(|s| leaf_slots & (1 << s) != 0)
                .fold(0u32, |m, s| m | 1 << (s ^ oct));
            meta[oct as usize / 4] |= m << (8 * (oct % 4));
        }
        self.nodes[index as usize].meta = UVec4::new(meta[0], meta[1], 0, 0);
        (index, bound)
    }
}

/// The ray-octant signs of slot `s`: bit set = negative.
fn slot_dir(s: usize) -> Vec3 {
    Vec3::new(
        if s & 1 != 0 { -1.0 } else { 1.0 },
        if s & 2 != 0 { -1.0 } else { 1.0 },
        if s & 4 != 0 { -1.0 } else { 1.0 },
    )
}

/// Which child (index into `kids`) each of the 8 slots holds: greedily, the (child, slot) pair
/// whose child centroid lies furthest back along the slot's octant direction first.
fn assign_slots(kids: &[Child]) -> [Option<usize>; WIDTH] {
    let centroid = |c: &Child| 0.5 * (c.lo + c.hi);
    let (lo, hi) = kids.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), c| (lo.min(c.lo), hi.max(c.hi)),
    );
    let pc = 0.5 * (lo + hi);
    let mut pairs: Vec<(f32, usize, usize)> = Vec::with_capacity(kids.len() * WIDTH);
    for (k, c) in kids.iter().enumerate() {
        for s in 0..WIDTH {
            pairs.push(((centroid(c) - pc).dot(slot_dir(s)), k, s));
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut slots = [None; WIDTH];
    let mut used = vec![false; kids.len()];
    for (_, k, s) in pairs {
        if !used[k] && slots[s].is_none() {
            used[k] = true;
            slots[s] = Some(k);
        }
    }
    slots
}

/// Octant of a direction: bit 0/1/2 set when x/y/z is negative.
pub fn octant(dir: Vec3) -> u32 {
    (dir.x < 0.0) as u32 | ((dir.y < 0.0) as u32) << 1 | ((dir.z < 0.0) as u32) << 2
}

/// Closest hit through the 8-wide BVH (host reference of the GPU kernel's order: leaves of a node
/// first, then the nearest-in-octant-order interior child, the others on a stack), with
/// `tmin < t < tmax`. `bvh` provides the triangles.
pub fn closest_hit8(
    wide: &GpuBvh8,
    bvh: &GpuBvh,
    origin: Vec3,
    dir: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<super::Hit> {
    if wide.nodes.is_empty() {
        return None;
    }
    let inv = dir.recip();
    let shear = super::traverse::Shear::new(origin, dir);
    let oct = octant(dir);
    let mut best: Option<super::Hit> = None;
    let mut best_t = tmax;
    let mut stack: Vec<u32> = Vec::new();
    let mut node = Some(0u32);
    while let Some(n) = node {
        let mut hits = [false; WIDTH];
        let recs = [wide.nodes[n as usize], wide.nodes[n as usize + 1]];
        for (s, h) in hits.iter_mut().enumerate() {
            let rec = &recs[s / 4];
            let j = s % 4;
            if rec.child[j] == EMPTY_SLOT {
                continue;
            }
            let lo = [rec.lo_x[j], rec.lo_y[j], rec.lo_z[j]];
            let hi = [rec.hi_x[j], rec.hi_y[j], rec.hi_z[j]];
            *h = super::traverse::slab(origin, inv, lo.into(), hi.into(), tmin, best_t).is_some();
        }
        let child = |s: usize| recs[s / 4].child[s % 4];
        // Leaves in octant order, then interior children in octant order.
        for p in 0..WIDTH {
            let s = p ^ oct as usize;
            if hits[s] && is_leaf(child(s)) {
                if let Some(h) = super::traverse::leaf_closest(bvh, &shear, child(s), tmin, best_t)
                {
                    best_t = h.t;
                    best = Some(h);
                }
            }
        }
        let mut next = Vec::new();
        for p in 0..WIDTH {
            let s = p ^ oct as usize;
            if hits[s] && !is_leaf(child(s)) {
                next.push(child(s));
            }
        }
        node = if next.is_empty() {
            stack.pop()
        } else {
            stack.extend(next[1..].iter().rev());
            Some(next[0])
        };
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embedded::{self, Rng};

    /// The 8-wide traversal finds the BVH2's closest hit (same triangle or same t) on random
    /// rays over every embedded scene; the layout invariants hold.
    #[test]
    fn wide_matches_bvh2() {
        for name in embedded::names() {
            let scene = embedded::load(name).unwrap();
            for (m, c) in [(8, 3.0), (WIDE_MAX_LEAF, WIDE_TRAVERSAL_COST)] {
                let bvh = GpuBvh::build_with_leaves(&scene, m, c).unwrap();
                let wide = match GpuBvh8::build(&bvh) {
                    Ok(w) => w,
                    // Only the small leaves may exceed the stack (fairyforest: 65).
                    Err(e) => {
                        assert!(m < 8, "{name}: {e}");
                        eprintln!("{name} (leaves <= {m}): {e}");
                        continue;
                    }
                };
                eprintln!(
                    "{name} (leaves <= {m}): {} triangles, {} BVH2 nodes (depth {}), {} 8-wide nodes (depth {}), stack bound {}",
                    bvh.triangles.len(),
                    bvh.nodes.len(),
                    bvh.depth,
                    wide.nodes.len() / 2,
                    wide.depth,
                    wide.stack_bound
                );
                assert!(wide.nodes.len().is_multiple_of(2));
                // Every leaf of the BVH2 appears exactly once.
                let mut seen = vec![0u32; bvh.triangles.len()];
                for rec in &wide.nodes {
                    for c in rec.child.to_array() {
                        if c != EMPTY_SLOT && is_leaf(c) {
                            let (first, count) = super::super::decode_leaf(c);
                            for i in first..first + count {
                                seen[i as usize] += 1;
                            }
                        } else if c != EMPTY_SLOT {
                            assert!(c.is_multiple_of(2) && (c as usize) < wide.nodes.len());
                        }
                    }
                }
                assert!(
                    seen.iter().all(|&s| s == 1),
                    "{name}: a triangle is not in exactly one leaf"
                );
                let lo = bvh.bounds_min;
                let hi = bvh.bounds_max;
                let mut rng = Rng::new(7);
                for k in 0..2000 {
                    let o = if k % 2 == 0 {
                        scene.camera.origin()
                    } else {
                        lo + (hi - lo) * Vec3::new(rng.f32(), rng.f32(), rng.f32())
                    };
                    let d = Vec3::new(
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                        rng.range(-1.0, 1.0),
                    )
                    .normalize_or(Vec3::Y);
                    let a = super::super::closest_hit(&bvh, o, d, 0.0, 3.0e38);
                    let b = closest_hit8(&wide, &bvh, o, d, 0.0, 3.0e38);
                    let same = match (a, b) {
                        (None, None) => true,
                        (Some(a), Some(b)) => a.triangle_index == b.triangle_index || a.t == b.t,
                        _ => false,
                    };
                    assert!(same, "{name} ray {k}: {a:?} vs {b:?}");
                }
            }
        }
    }
}
