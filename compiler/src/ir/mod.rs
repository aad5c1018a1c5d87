//! The IR builder: typed handles over naga IR that the rewritten kernel code calls.
//! Front end (`cohort-macros`) → here → `naga::Module` → [`crate::compile`] (validated,
//! compacted, target-neutral) → a backend of `cohort-runtime`, which lowers it.

pub(crate) mod builder;
pub mod control;
mod fold;
pub mod function;
pub mod group;
pub mod intrinsics;
pub mod kernel;
pub mod math;
pub mod ops;
pub mod print;
pub mod types;
pub mod val;

pub use control::{
    and, break_, continue_, discard, diverged, for_range, for_range_rev, if_, if_else, if_value,
    loop_, or, return_, return_value, while_, BranchValue,
};
pub use function::{function, inlined};
pub use kernel::{
    build_kernel, builtin, place, Buffer, BuiltKernel, Uniform, Workgroup, LENGTHS_BINDING,
};
pub use ops::{cast, eq, ge, gt, le, lt, ne};
pub use types::{
    assert_uniform, storage_element_ok, struct_type, ConstValue, GpuType, HostRepr, MemberDesc,
    ScalarType,
};
pub use val::{
    array, array_repeat, compose, field, field_init, index, konst, lit, name, place_field,
    place_index, spec_constant, zero, AsPlace, AutoDeref, FieldInit, MethodNeedsKernelFn, Place,
    RtArray, SpecConstant, ToVal, Val, Var,
};
