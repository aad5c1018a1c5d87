//! Scene data for the Cohort path tracer (host only, no GPU code).
//!
//! Data flow:
//! ```text
//! Mitsuba XML (mitsuba/) ─┐   OBJ (obj.rs), PLY (ply.rs), analytic shapes (shapes.rs)
//!                         ├─► TriMesh ─► SceneBuilder ─► Scene (scene.rs: camera, triangles, materials)
//! embedded generators ────┘                                  │
//!                                                            ▼
//!                                  bvh/: obvhs PLOC BVH2 ─► GpuBvh { nodes, triangles } + materials
//!                                                            │  (bytemuck, std430/WGSL layouts)
//!                                                            ▼
//!                                  renderer kernels (other crates); host reference traversal here
//! ```
//! `morton.rs` gives the pixel order the renderer lays its rays out in.

/// The GPU types this crate writes (BVH nodes, triangles, materials and their constants),
/// declared once for the scene builder and the kernels.
pub use cohort_layout as layout;

pub mod alias;
pub mod builder;
pub mod bvh;
pub mod camera;
pub mod embedded;
pub mod environment_map;
pub mod error;
pub mod film_filter;
mod image_bmp;
pub mod image_file;
mod image_hdr;
pub mod material;
pub mod mesh;
pub mod mitsuba;
pub mod morton;
pub mod obj;
pub mod ply;
mod ply_attributes;
pub mod rough_plastic;
pub mod scene;
pub mod serialized;
pub mod shapes;
pub mod texture;

pub use builder::{Added, SceneBuilder, Shading};
pub use bvh::{
    brute_force_closest_hit, closest_hit, intersect_triangle, BruteForce, BvhError, GpuBvh, Hit,
};
pub use bvh::{closest_hit8, GpuBvh8, GpuCwBvh, WideBvhError};
pub use camera::{Camera, CameraFrame, CropWindow, FovAxis, Projection};
pub use environment_map::EnvironmentMap;
pub use error::{ErrorKind, Location, Position, SceneError, Warning};
pub use film_filter::{FilmFilter, FilterKind};
pub use material::{Bsdf, Mask, Material, Perturb, PerturbKind, Principled, Roughness};
pub use mesh::{MeshAttribute, TriMesh};
pub use mitsuba::{
    load_mitsuba, load_mitsuba_str, load_mitsuba_str_with, load_mitsuba_with,
    load_mitsuba_with_params, LoadOptions, Loaded,
};
pub use morton::{morton2d_decode, morton2d_encode, morton_pixel_order};
pub use scene::{Integrator, Light, Object, Scene, SceneStats, Triangles};
pub use texture::Texture;
