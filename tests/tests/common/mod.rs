//! Shared pieces of the GPU test suites: the devices to run on, deterministic inputs and
//! comparisons with a stated tolerance.
#![allow(dead_code)]

use cohort::runtime::{BackendKind, Device};

/// Every backend with an adapter here (wgpu and Vulkan on lavapipe or a GPU), and the
/// native CPU backend. With `CI=true` a missing adapter fails the test instead of
/// skipping it.
///
/// The CPU backend comes with every kernel's host form, and with its vector form wherever it
/// has one (`cpu::simd`) at each block width the lowering takes, so that each suite checks
/// every form against the host run.
pub fn devices() -> Vec<Device> {
    use cohort::runtime::cpu::simd::Forms;
    let mut out: Vec<Device> = [BackendKind::Wgpu, BackendKind::Vulkan]
        .into_iter()
        .filter_map(Device::for_tests)
        .collect();
    if std::env::var("CI").as_deref() == Ok("true") {
        if let Err(e) = cohort::runtime::cpu::simd::llvm_library() {
            panic!("CI=true and the CPU backend's vector form cannot compile: {e}");
        }
    }
    out.push(Device::cpu_with(Forms::Host).expect("the CPU backend always opens"));
    for lanes in cohort::runtime::cpu::simd::WIDTHS {
        out.push(
            Device::cpu_with_lanes(Forms::Vector, lanes).expect("the CPU backend always opens"),
        );
    }
    out
}

/// Whether `d` is the native CPU backend, which runs the kernel's own Rust function: its
/// results equal the host run's exactly, where the GPUs' are compared within a bound.
pub fn is_cpu(d: &Device) -> bool {
    d.info().backend == BackendKind::Cpu
}

/// The outputs of the GPU backends among `outs` (one per device of `devs`).
pub fn gpu_outputs<'a, T>(devs: &[Device], outs: &'a [T]) -> Vec<&'a T> {
    devs.iter()
        .zip(outs)
        .filter(|(d, _)| !is_cpu(d))
        .map(|(_, o)| o)
        .collect()
}

/// Asserts that the CPU backend's output among `outs` is exactly `host` (compared by
/// `Debug` text, so that NaN and -0.0 count as themselves).
pub fn assert_cpu_is_host<T: std::fmt::Debug>(what: &str, devs: &[Device], outs: &[T], host: &T) {
    for (d, o) in devs.iter().zip(outs) {
        if is_cpu(d) {
            assert_eq!(
                format!("{o:?}"),
                format!("{host:?}"),
                "{what}: the CPU backend differs from the host run of the same function"
            );
        }
    }
}

/// xorshift32: reproducible inputs without a dependency.
pub struct Rng(pub u32);
impl Rng {
    pub fn next_u32(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }
    pub fn f32(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * (self.next_u32() >> 8) as f32 / 16777216.0
    }
}

/// Distance in units in the last place between two floats (0 when both are equal,
/// including equal NaN bit patterns).
pub fn ulps(a: f32, b: f32) -> u32 {
    if a.to_bits() == b.to_bits() {
        return 0;
    }
    if a.is_nan() || b.is_nan() {
        return u32::MAX;
    }
    let key = |x: f32| {
        let b = x.to_bits() as i32;
        if b < 0 {
            i32::MIN - b
        } else {
            b
        }
    };
    (key(a) as i64 - key(b) as i64)
        .unsigned_abs()
        .min(u32::MAX as u64) as u32
}

/// Asserts that two float slices agree within `max_ulps` (or `abs` absolute error,
/// for results near zero where ulps are meaningless).
pub fn assert_close(what: &str, a: &[f32], b: &[f32], max_ulps: u32, abs: f32) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let ok = ulps(*x, *y) <= max_ulps || (x - y).abs() <= abs;
        assert!(ok, "{what}: element {i} differs: {x} vs {y} ({} ulps; bound {max_ulps} ulps or {abs} absolute)", ulps(*x, *y));
    }
}

pub fn flatten_vec4(v: &[glam::Vec4]) -> Vec<f32> {
    v.iter().flat_map(|x| x.to_array()).collect()
}

/// What the IR builder needs of a thread-level kernel of 64-invocation workgroups built
/// without Rust source (`cohort::ir::build_kernel`), named `name` at `file`:`line`.
pub const fn ir_kernel_info(
    name: &'static str,
    file: &'static str,
    line: u32,
) -> cohort::KernelInfo {
    cohort::KernelInfo {
        name,
        file,
        line,
        column: 1,
        workgroup_size: 64,
        group: cohort::Group::Thread,
        finite_loops: false,
    }
}

/// The CPU backend's vector form of `module` as LLVM IR (what its object cache compiles),
/// or why the lowering gives it none, in which case the kernel runs its host form.
pub fn vector_form(
    module: &cohort::compiler::ir::BuiltKernel,
    name: &str,
) -> Result<String, String> {
    let compiled = cohort::compiler::compile(module, name.into()).unwrap();
    cohort::runtime::cpu::simd::lower_to_llvm_ir(&compiled)
}
