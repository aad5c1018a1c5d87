//! obvhs BVH2 → [`GpuBvh`]. The pipeline is obvhs's own `build_bvh2` with its `medium_build`
//! preset (PLOC search distance 14, reinsertion 5 % of nodes, SAH-driven leaf collapse to at most
//! 8 triangles with traversal cost 3, a second reinsertion pass after collapse), written out here
//! because the helper re-validates the whole tree in debug builds, which costs more than the build
//! itself in tests. Spatial pre-splits stay off: they would put one triangle in several leaves.

use glam::{Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::leaf_collapser::collapse;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

use super::{leaf_ref, GpuBvh, MAX_LEAF_TRIANGLES, MAX_TRIANGLES};
use crate::layout;
use crate::scene::Triangles;

#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BvhError {
    #[error("{count} triangles exceed the GPU BVH's limit of {max}")]
    TooManyTriangles { count: usize, max: u32 },
}

const REINSERTION_RATIO: f32 = 0.05;
const POST_COLLAPSE_REINSERTION_RATIO: f32 = 0.10;
const COLLAPSE_TRAVERSAL_COST: f32 = 3.0;

pub(super) fn build(tris: &Triangles) -> Result<GpuBvh, BvhError> {
    build_with(tris, MAX_LEAF_TRIANGLES, COLLAPSE_TRAVERSAL_COST)
}

/// [`build`] with another leaf collapse: at most `max_leaf` (1..=8) triangles per leaf, SAH
/// traversal cost `traversal_cost` (relative to one triangle test; higher gives larger leaves).
pub(super) fn build_with(
    tris: &Triangles,
    max_leaf: u32,
    traversal_cost: f32,
) -> Result<GpuBvh, BvhError> {
    let max_leaf = max_leaf.clamp(1, MAX_LEAF_TRIANGLES);
    let n = tris.len();
    if n == 0 {
        return Ok(GpuBvh::default());
    }
    if n > MAX_TRIANGLES as usize {
        return Err(BvhError::TooManyTriangles {
            count: n,
            max: MAX_TRIANGLES,
        });
    }
    let aabbs: Vec<Aabb> = (0..n)
        .map(|i| {
            let [a, b, c] = tris.vertices(i).map(Vec3A::from);
            Aabb::new(a.min(b).min(c), a.max(b).max(c))
        })
        .collect();

    let mut bvh = PlocBuilder::with_capacity(n).build(
        PlocSearchDistance::Medium,
        &aabbs,
        (0..n as u32).collect(),
        SortPrecision::U64,
        3,
    );
    let mut reinsertion = ReinsertionOptimizer::default();
    reinsertion.run(&mut bvh, REINSERTION_RATIO, None);
    collapse(&mut bvh, max_leaf, traversal_cost);
    reinsertion.run(&mut bvh, POST_COLLAPSE_REINSERTION_RATIO, None);

    let mut out = Flattener {
        src: &bvh,
        tris,
        aabbs: &aabbs,
        nodes: Vec::new(),
        triangles: Vec::new(),
        depth: 0,
    };
    let root = &bvh.nodes[0];
    if root.is_leaf() {
        // A single leaf has no interior node to hold its box: give it a root whose two children are
        // that same leaf (testing it twice cannot change a closest hit).
        out.nodes.push(layout::BvhNode::default());
        let (child, lo, hi) = out.child(0, 1);
        out.nodes[0] = node(child, lo, hi, child, lo, hi);
        out.depth = out.depth.max(1);
    } else {
        out.interior(0, 1);
    }
    let bounds = aabbs.iter().fold(Aabb::INVALID, |acc, b| acc.union(b));
    Ok(GpuBvh {
        nodes: out.nodes,
        triangles: out.triangles,
        depth: out.depth,
        bounds_min: Vec3::from(bounds.min),
        bounds_max: Vec3::from(bounds.max),
    })
}

fn node(left: u32, lmin: Vec3, lmax: Vec3, right: u32, rmin: Vec3, rmax: Vec3) -> layout::BvhNode {
    layout::BvhNode {
        lmin,
        left,
        lmax,
        right,
        rmin,
        pad0: 0,
        rmax,
        pad1: 0,
    }
}

struct Flattener<'a> {
    src: &'a Bvh2,
    tris: &'a Triangles,
    aabbs: &'a [Aabb],
    nodes: Vec<layout::BvhNode>,
    triangles: Vec<layout::Triangle>,
    depth: u32,
}

impl Flattener<'_> {
    /// Emits obvhs interior node `id` (depth `depth`) and its subtree; returns its index.
    fn interior(&mut self, id: usize, depth: u32) -> u32 {
        self.depth = self.depth.max(depth);
        let index = self.nodes.len() as u32;
        self.nodes.push(layout::BvhNode::default());
        let first = self.src.nodes[id].first_index as usize;
        let (l, lmin, lmax) = self.child(first, depth + 1);
        let (r, rmin, rmax) = self.child(first + 1, depth + 1);
        self.nodes[index as usize] = node(l, lmin, lmax, r, rmin, rmax);
        index
    }

    /// Emits child `id`; returns its reference and box.
    fn child(&mut self, id: usize, depth: u32) -> (u32, Vec3, Vec3) {
        let n = self.src.nodes[id];
        let lo = Vec3::from(n.aabb().min);
        let hi = Vec3::from(n.aabb().max);
        if !n.is_leaf() {
            return (self.interior(id, depth), lo, hi);
        }
        let prims: Vec<u32> = (n.first_index..n.first_index + n.prim_count)
            .map(|i| self.src.primitive_indices[i as usize])
            .collect();
        let (r, _, _) = self.leaf(&prims, depth);
        (r, lo, hi)
    }

    /// A leaf of original triangles `prims`; split into a small subtree if obvhs left more than fit
    /// in one reference (collapse is told the same limit, so this is only a safety net).
    fn leaf(&mut self, prims: &[u32], depth: u32) -> (u32, Vec3, Vec3) {
        let bounds = prims
            .iter()
            .fold(Aabb::INVALID, |acc, &p| acc.union(&self.aabbs[p as usize]));
        let (lo, hi) = (Vec3::from(bounds.min), Vec3::from(bounds.max));
        if prims.len() as u32 <= MAX_LEAF_TRIANGLES {
            let first = self.triangles.len() as u32;
            for &p in prims {
                let [v0, v1, v2] = self.tris.vertices(p as usize);
                self.triangles.push(layout::Triangle {
                    v0,
                    material: self.tris.materials[p as usize],
                    v1,
                    original: p,
                    v2,
                    light_pdf: 0.0,
                });
            }
            return (leaf_ref(first, prims.len() as u32), lo, hi);
        }
        self.depth = self.depth.max(depth);
        let index = self.nodes.len() as u32;
        self.nodes.push(layout::BvhNode::default());
        let (a, b) = prims.split_at(prims.len() / 2);
        let (l, lmin, lmax) = self.leaf(a, depth + 1);
        let (r, rmin, rmax) = self.leaf(b, depth + 1);
        self.nodes[index as usize] = node(l, lmin, lmax, r, rmin, rmax);
        (index, lo, hi)
    }
}
