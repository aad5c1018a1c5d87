//! Host side of the path tracer. Data flow: `cohort-scenes` Scene → [`gpu_scene`]
//! (BVH + triangles + materials on the device) → [`Renderer`] (path-state buffers and
//! the iteration loop over the kernels of `cohort-kernels`) → [`Image`] → [`output`]
//! (EXR / PNG files, written atomically). A render can be split into [`shard`]s, whose
//! EXRs ([`provenance`] in the header, path counts per pixel) [`input`] reads back and
//! [`merge`] combines; [`multi_device`] does both in one process, on several devices.

pub mod bvh_cache;
mod design;
mod error;
pub mod gpu_scene;
pub mod image;
pub mod input;
mod iteration;
mod kernels;
pub mod lights;
pub mod merge;
pub mod multi_device;
mod options;
pub mod output;
mod paths;
pub mod provenance;
mod queues;
pub mod renderer;
pub mod roulette;
pub mod shard;
mod stats;
pub mod validate;
pub mod wavefront;

pub use cohort_kernels::shading;
pub use gpu_scene::{GpuScene, PreparedScene, SceneBvh};
pub use image::Image;
pub use renderer::{
    Algorithm, Budget, HostTimes, InPatch, IntegratorKind, KernelTimes, RenderError, RenderOptions,
    RenderStats, Renderer, Shading,
};
pub use roulette::Roulette;
pub use shard::Shard;
