//! Statistical tests of sampling routines, run on any device by compiling the routine's own
//! kernel (docs/VALIDATION.md): [`sampler`] for a diffuse strategy (`DiffuseSampler`) at
//! each group level, [`bsdf`] for the renderer's BSDFs. Both return a [`Report`]:
//! [`Report::passed`], and a table a person reads (`Display`).
//!
//! - [`stats`]: the statistics (regularised incomplete gamma, Pearson's test with pooling,
//!   the test of weighted means, Sidak);
//! - [`sampler`](mod@sampler), [`bsdf`](mod@bsdf): the tests;
//! - [`report`]: the results, their table and images.

pub mod bsdf;
pub mod report;
pub mod sampler;
pub mod stats;

pub use bsdf::{bsdf, builtin_bsdfs, BsdfCase, BsdfOptions};
/// The built-in strategies, for callers without the kernels crate (`cohort check`).
pub use cohort_kernels::sampling::{
    CoherentCosine, CoherentEqualArea, CoherentUniform, Cosine, DiffuseSampler,
};
pub use report::{Report, Table, TestResult};
pub use sampler::{sampler, SamplerOptions};

use cohort::runtime::{Device, RuntimeError};

/// Why a test could not run (a failed test is a [`Report`] that did not pass).
#[derive(Debug, thiserror::Error)]
pub enum ValidateError {
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error(transparent)]
    Kernel(#[from] cohort::Error),
    #[error("cannot write the images: {0}")]
    Io(#[from] std::io::Error),
    #[error("{0}")]
    Options(String),
}

/// The device in words: backend and adapter.
pub fn device_name(device: &Device) -> String {
    let info = device.info();
    format!("{} backend, {}", info.backend.name(), info.adapter_name)
}
