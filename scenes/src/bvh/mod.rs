//! Scene → GPU acceleration structure: an obvhs PLOC BVH2 flattened into the layout the renderer's
//! traversal kernel reads, plus the host reference traversal that kernel is tested against.
//!
//! # GPU layout
//! Two storage buffers, both arrays of 16-byte-aligned `#[repr(C)]` structs that are valid std430
//! and WGSL structs as written (every `Vec3` is followed by a 4-byte scalar, i.e. WGSL
//! `vec3<f32>` + `u32` filling one 16-byte slot).
//!
//! **Nodes** ([`layout::BvhNode`], 64 bytes): a BVH2 whose interior node holds BOTH children's boxes, so one
//! node fetch lets a thread test two boxes and pick the nearer child. Node 0 is the root. The root's
//! own box is not stored (see [`GpuBvh::bounds_min`]).
//!
//! | offset | field | |
//! |---|---|---|
//! | 0 | `lmin: Vec3` | left child box min |
//! | 12 | `left: u32` | left child reference |
//! | 16 | `lmax: Vec3` | left child box max |
//! | 28 | `right: u32` | right child reference |
//! | 32 | `rmin: Vec3` | right child box min |
//! | 44 | `pad0: u32` | zero |
//! | 48 | `rmax: Vec3` | right child box max |
//! | 60 | `pad1: u32` | zero |
//!
//! **Child reference** (`u32`): bit 31 clear = interior node, the value is its index in `nodes`.
//! Bit 31 set = leaf: bits 28..=30 hold `count - 1` (1 to [`MAX_LEAF_TRIANGLES`] = 8 triangles) and
//! bits 0..=27 the index of its first triangle in `triangles`; the leaf's triangles are consecutive.
//! A reference is self-contained, so a traversal stack of plain `u32` can hold leaves too.
//! (See [`leaf_ref`], [`decode_leaf`].) Up to 2^28 - 1 triangles.
//!
//! **Triangles** ([`layout::Triangle`], 48 bytes), reordered into leaf order:
//!
//! | offset | field | |
//! |---|---|---|
//! | 0 | `v0: Vec3` | vertex 0 |
//! | 12 | `material: u32` | index into the material table ([`crate::layout::Material`]) |
//! | 16 | `v1: Vec3` | vertex 1 |
//! | 28 | `original: u32` | index of the triangle in [`crate::Scene::triangles`] (normals, objects) |
//! | 32 | `v2: Vec3` | vertex 2 |
//! | 44 | `light_pdf: f32` | zero here; the renderer's light table fills it |
//!
//! Vertices rather than precomputed edges: the watertight test (Woop, Benthin, Wald 2013) needs the
//! exact vertices, because `v0 + e1` rounds differently in neighbouring triangles and would reopen
//! the cracks along shared edges that the test exists to close.

mod build;
pub mod compressed;
mod traverse;
pub mod wide;

use crate::layout;
use glam::Vec3;

pub use build::BvhError;
pub use compressed::GpuCwBvh;
pub use traverse::{brute_force_closest_hit, closest_hit, intersect_triangle, BruteForce, Hit};
pub use wide::{closest_hit8, GpuBvh8, WideBvhError};

// The node and triangle types are declared once, in `cohort-layout`, and read by the
// kernels as written here.
const _: () = assert!(std::mem::size_of::<layout::BvhNode>() == 64);
const _: () = assert!(std::mem::size_of::<layout::Triangle>() == 48);

/// Bit 31 of a child reference: the child is a leaf.
pub const LEAF_BIT: u32 = 1 << 31;
/// Largest triangle count of one leaf (3 bits of count - 1).
pub const MAX_LEAF_TRIANGLES: u32 = 8;
const COUNT_SHIFT: u32 = 28;
/// Largest first-triangle index a leaf reference can hold.
pub const MAX_TRIANGLES: u32 = (1 << COUNT_SHIFT) - 1;

/// Reference to a leaf of `count` (1..=8) triangles starting at `first`.
pub const fn leaf_ref(first: u32, count: u32) -> u32 {
    LEAF_BIT | ((count - 1) << COUNT_SHIFT) | first
}

pub const fn is_leaf(child: u32) -> bool {
    child & LEAF_BIT != 0
}

/// `(first, count)` of a leaf reference.
pub const fn decode_leaf(child: u32) -> (u32, u32) {
    (child & MAX_TRIANGLES, ((child >> COUNT_SHIFT) & 7) + 1)
}

/// The flattened BVH and reordered triangles. Empty scene: both arrays empty (the renderer must then
/// skip traversal: there is nothing to hit).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuBvh {
    pub nodes: Vec<layout::BvhNode>,
    pub triangles: Vec<layout::Triangle>,
    /// Most interior nodes on one root-to-leaf path: a near-first traversal stack never holds more
    /// entries than this.
    pub depth: u32,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}

impl GpuBvh {
    /// Builds with obvhs (PLOC + reinsertion + SAH leaf collapse) and flattens; see `build.rs`.
    pub fn build(scene: &crate::Scene) -> Result<GpuBvh, BvhError> {
        build::build(&scene.triangles)
    }

    /// [`GpuBvh::build`] with another SAH leaf collapse: at most `max_leaf` (1..=8) triangles
    /// per leaf, traversal cost `traversal_cost` relative to a triangle test (the default build
    /// uses 8 and 3).
    pub fn build_with_leaves(
        scene: &crate::Scene,
        max_leaf: u32,
        traversal_cost: f32,
    ) -> Result<GpuBvh, BvhError> {
        build::build_with(&scene.triangles, max_leaf, traversal_cost)
    }

    pub fn node_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.nodes)
    }

    pub fn triangle_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.triangles)
    }
}
