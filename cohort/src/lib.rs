//! Cohort: GPU kernels written in a subset of Rust.
//!
//! Data flow of a kernel: `#[kernel]` (crate `cohort-macros`, the front end) keeps the
//! function as plain Rust for the host and generates a module of the same name whose
//! `build` rewrites the body into calls on [`ir`] (typed handles over naga IR); the
//! compiler (crate `cohort-compiler`, which knows no GPU API) validates and compacts the
//! module into a target-neutral compiled kernel; [`emit`] wraps it with the kernel's Rust
//! function; the `launch` functions hand that to [`runtime`], whose backends lower it (wgpu:
//! WGSL; raw Vulkan through ash: SPIR-V; the CPU backend runs the Rust function).
//!
//! This crate is what kernel authors depend on: the attributes, the [`intrinsics`] with
//! their host meaning, and the launch glue.

pub mod emit;
pub mod host;
pub mod intrinsics;
pub mod launch;

pub use cohort_compiler as compiler;
pub use cohort_compiler::{ir, spec};

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
