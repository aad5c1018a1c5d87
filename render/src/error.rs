//! The renderer's error type.

use cohort::runtime::RuntimeError;

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    #[error(transparent)]
    Kernel(#[from] cohort::Error),
    #[error(transparent)]
    Compile(#[from] cohort::emit::CompileError),
    #[error("cannot build the BVH: {0}")]
    Bvh(String),
    #[error("{0}")]
    Options(String),
}
