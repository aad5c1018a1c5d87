//! `cohort-compiler`: the Cohort compiler, which knows no GPU API.
//!
//! Layers, as in naga: the front end is the `#[kernel]` proc macro (crate `cohort-macros`),
//! whose generated `build` calls [`ir`] (typed handles over naga IR) to make a
//! `naga::Module`; [`compile`] validates and compacts it into a target-neutral
//! [`CompiledKernel`](compile::CompiledKernel) with its binding layout and needs
//! ([`abi`]); each backend of `cohort-runtime` lowers that module itself. [`spec`] says
//! which specialisation of a kernel is built for a [`Target`](spec::Target).

pub mod abi;
pub mod compile;
pub mod ir;
pub mod spec;

pub use compile::{compile, CompileError, CompiledKernel};
/// The naga this compiler builds on, for code that `#[derive(GpuType)]` generates in crates
/// that use the compiler without the `cohort` facade (`cohort-layout`).
#[doc(hidden)]
pub use naga;
pub use spec::{Group, KernelInfo, Spec, Target};

#[cfg(test)]
mod tests {
    /// The compiler knows no GPU API: its dependencies are naga and the math and byte
    /// crates (the compiler split from the GPU API). A dependency on a runtime or GPU crate
    /// would turn the layers around again.
    #[test]
    fn depends_on_no_gpu_api() {
        let manifest = include_str!("../Cargo.toml");
        let deps = manifest
            .split("[dependencies]")
            .nth(1)
            .expect("a [dependencies] table");
        let names: Vec<&str> = deps
            .lines()
            .take_while(|l| !l.starts_with('['))
            .filter_map(|l| l.split(['=', '.']).next())
            .map(str::trim)
            .filter(|n| !n.is_empty() && !n.starts_with('#'))
            .collect();
        assert_eq!(names, ["naga", "glam", "bytemuck", "thiserror"]);
    }
}
