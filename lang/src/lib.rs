//! Cohort: GPU kernels written in a subset of Rust.
//!
//! Data flow of a kernel: `#[kernel]` (crate `cohort-macros`, the front end) keeps the
//! function as plain Rust for the host and generates a module of the same name whose
//! `build` rewrites the body into calls on [`ir`] (typed handles over naga IR); [`emit`]
//! validates, compacts and writes WGSL and SPIR-V; the `launch` functions hand the
//! artifact to [`runtime`] (wgpu or raw Vulkan through ash).

pub mod emit;
pub mod host;
pub mod intrinsics;
pub mod ir;
pub mod launch;
pub mod spec;

pub use cohort_macros::{kernel, kernel_fn, kernel_impl, kernel_trait, GpuType};
pub use cohort_runtime as runtime;
pub use launch::{Error, Grid, Result};
pub use spec::{Group, KernelInfo, Spec};
pub use {bytemuck, glam, naga};

/// What kernel source files `use`: the attributes, the intrinsics, glam's types and the
/// atomics.
pub mod prelude {
    pub use crate::intrinsics::*;
    pub use crate::{kernel, kernel_fn, kernel_impl, kernel_trait, GpuType, Group};
    pub use glam::{IVec2, IVec3, IVec4, Mat3, Mat4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};
    pub use std::sync::atomic::{AtomicI32, AtomicU32, Ordering};
}
