//! Building one kernel specialisation: the entry point, its resources (buffers,
//! uniforms, workgroup memory) and invocation builtins.
//!
//! The `build` function that `#[kernel]` generates calls [`build_kernel`] with a closure
//! that declares the parameters (in source order, which is binding order) and then runs
//! the rewritten body. The result is a plain `naga::Module` plus the binding table the
//! runtime needs; nothing here knows about WGSL or SPIR-V.

use naga::{
    AddressSpace, ArraySize, Binding, BuiltIn, Expression, FunctionArgument, GlobalVariable,
    Handle, ResourceBinding, ShaderStage, Span, StorageAccess, TypeInner,
};
use std::marker::PhantomData;

use super::builder::{self, with, Ctx, FnState, InstallGuard};
use super::types::GpuType;
use super::val::{AsPlace, Place, RtArray, Val};
use crate::abi::{Binding as RtBinding, BindingKind};
use crate::spec::{Group, KernelInfo, Spec};

/// The result of building a kernel, before validation and emission.
pub struct BuiltKernel {
    pub module: naga::Module,
    pub bindings: Vec<RtBinding>,
    pub uses_subgroups: bool,
    /// Whether invocations wait for each other on the CPU backend (`Ctx::synchronises`).
    pub synchronises: bool,
    /// Operations this specialisation cannot lower; `emit` turns them into an error.
    pub unsupported: Vec<String>,
    /// The kernel's print sites (`crate::abi::PrintSite`), in site order.
    pub prints: Vec<crate::abi::PrintSite>,
    pub spec: Spec,
    pub info: &'static KernelInfo,
}

/// Builds the kernel: `declare_and_run` declares parameters and records the body.
pub fn build_kernel(
    info: &'static KernelInfo,
    spec: Spec,
    declare_and_run: impl FnOnce(),
) -> BuiltKernel {
    validate_spec(info, &spec);
    let mut ctx = Ctx::new(info, spec);
    ctx.fns.push(FnState::new(info.name));
    builder::install(ctx);
    let guard = InstallGuard;
    prologue();
    declare_and_run();
    let mut ctx = builder::uninstall().expect("builder state vanished");
    std::mem::forget(guard);
    let func = ctx.fns.pop().expect("entry function").finish();
    ctx.module.entry_points.push(naga::EntryPoint {
        name: info.name.to_string(),
        stage: ShaderStage::Compute,
        early_depth_test: None,
        workgroup_size: [spec.workgroup_size, 1, 1],
        workgroup_size_overrides: None,
        function: func,
        mesh_info: None,
        task_payload: None,
        incoming_ray_payload: None,
    });
    BuiltKernel {
        module: ctx.module,
        bindings: ctx.bindings,
        uses_subgroups: ctx.uses_subgroups,
        synchronises: ctx.synchronises,
        unsupported: ctx.unsupported,
        prints: ctx.prints,
        spec,
        info,
    }
}

fn validate_spec(info: &KernelInfo, spec: &Spec) {
    assert!(
        spec.workgroup_size >= 1 && spec.workgroup_size <= 1024,
        "kernel `{}`: workgroup size {} is outside 1..=1024",
        info.name,
        spec.workgroup_size
    );
    if spec.group == Group::Warp {
        assert!(
            spec.workgroup_size.is_multiple_of(crate::spec::WARP),
            "kernel `{}`: group = Warp needs a workgroup size that is a multiple of 32, not {}",
            info.name,
            spec.workgroup_size
        );
    }
}

fn builtin_arg(name: &str, b: BuiltIn, inner: TypeInner) -> Handle<Expression> {
    with(|c| {
        let ty = c.ty(inner);
        let f = c.f();
        let existing = f
            .func
            .arguments
            .iter()
            .position(|a| a.binding == Some(Binding::BuiltIn(b)));
        let idx = match existing {
            Some(i) => i,
            None => {
                f.func.arguments.push(FunctionArgument {
                    name: Some(name.to_string()),
                    ty,
                    binding: Some(Binding::BuiltIn(b)),
                });
                f.func.arguments.len() - 1
            }
        };
        if matches!(
            b,
            BuiltIn::SubgroupSize
                | BuiltIn::SubgroupInvocationId
                | BuiltIn::SubgroupId
                | BuiltIn::NumSubgroups
        ) {
            c.uses_subgroups = true;
        }
        c.expr(Expression::FunctionArgument(idx as u32))
    })
}

const U32: TypeInner = TypeInner::Scalar(naga::Scalar::U32);
const UVEC3: TypeInner = TypeInner::Vector {
    size: naga::VectorSize::Tri,
    scalar: naga::Scalar::U32,
};

/// Values every specialisation may need are computed at the top of the entry point, so
/// they dominate every later use (naga rejects uses outside the emitting block).
fn prologue() {
    let local = builtin_arg("local_index", BuiltIn::LocalInvocationIndex, U32);
    let wid = builtin_arg("workgroup_id", BuiltIn::WorkGroupId, UVEC3);
    let nwg = builtin_arg("num_workgroups", BuiltIn::NumWorkGroups, UVEC3);
    let (wg_linear, global) = with(|c| {
        let wgs = c.spec.workgroup_size;
        // Workgroups are numbered x fastest, then y, then z:
        // wx + nx * (wy + ny * wz).
        let wx = c.expr(Expression::AccessIndex {
            base: wid,
            index: 0,
        });
        let wy = c.expr(Expression::AccessIndex {
            base: wid,
            index: 1,
        });
        let wz = c.expr(Expression::AccessIndex {
            base: wid,
            index: 2,
        });
        let nx = c.expr(Expression::AccessIndex {
            base: nwg,
            index: 0,
        });
        let ny = c.expr(Expression::AccessIndex {
            base: nwg,
            index: 1,
        });
        let zy = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left: wz,
            right: ny,
        });
        let row = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Add,
            left: wy,
            right: zy,
        });
        let t = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left: row,
            right: nx,
        });
        let wg_linear = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Add,
            left: wx,
            right: t,
        });
        let size = c.expr(Expression::Literal(naga::Literal::U32(wgs)));
        let base = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Multiply,
            left: wg_linear,
            right: size,
        });
        let global = c.expr(Expression::Binary {
            op: naga::BinaryOperator::Add,
            left: base,
            right: local,
        });
        (wg_linear, global)
    });
    with(|c| {
        c.prologue.local_index = Some(local);
        c.prologue.workgroup_linear = Some(wg_linear);
        c.prologue.global_index = Some(global);
    });
    let warp_sg = with(|c| c.spec.group == Group::Warp && c.spec.warp_via_subgroup);
    if warp_sg {
        let lane = builtin_arg("subgroup_lane", BuiltIn::SubgroupInvocationId, U32);
        with(|c| c.prologue.subgroup_lane = Some(lane));
    }
}

/// Invocation builtins, as kernel parameters marked `#[builtin(...)]`.
pub mod builtin {
    use super::*;
    use glam::UVec3;

    fn u32v(h: Handle<Expression>) -> Val<u32> {
        Val::from_handle(h)
    }
    fn uvec3(h: Handle<Expression>) -> Val<UVec3> {
        Val::from_handle(h)
    }
    /// Linear index of the invocation in the dispatch: `workgroup_index * workgroup_size +
    /// local_index`, unique in 1-D, 2-D and 3-D dispatches (dispatches of more than 65535
    /// workgroups are laid out in rows).
    pub fn global_index() -> Val<u32> {
        u32v(with(|c| c.prologue.global_index.expect("prologue")))
    }
    pub fn local_index() -> Val<u32> {
        u32v(with(|c| c.prologue.local_index.expect("prologue")))
    }
    /// Linear index of the workgroup in the dispatch: x fastest, then y, then z.
    pub fn workgroup_index() -> Val<u32> {
        u32v(with(|c| c.prologue.workgroup_linear.expect("prologue")))
    }
    pub fn global_id() -> Val<UVec3> {
        uvec3(builtin_arg("global_id", BuiltIn::GlobalInvocationId, UVEC3))
    }
    pub fn local_id() -> Val<UVec3> {
        uvec3(builtin_arg("local_id", BuiltIn::LocalInvocationId, UVEC3))
    }
    pub fn workgroup_id() -> Val<UVec3> {
        uvec3(builtin_arg("workgroup_id", BuiltIn::WorkGroupId, UVEC3))
    }
    pub fn num_workgroups() -> Val<UVec3> {
        uvec3(builtin_arg("num_workgroups", BuiltIn::NumWorkGroups, UVEC3))
    }
    /// The workgroup size of this specialisation (a constant).
    pub fn workgroup_size() -> Val<u32> {
        let n = with(|c| c.spec.workgroup_size);
        crate::ir::val::lit(n)
    }
    pub fn subgroup_size() -> Val<u32> {
        u32v(builtin_arg("subgroup_size", BuiltIn::SubgroupSize, U32))
    }
    pub fn subgroup_lane() -> Val<u32> {
        u32v(builtin_arg(
            "subgroup_lane",
            BuiltIn::SubgroupInvocationId,
            U32,
        ))
    }
    pub fn subgroup_id() -> Val<u32> {
        u32v(builtin_arg("subgroup_id", BuiltIn::SubgroupId, U32))
    }
    pub fn num_subgroups() -> Val<u32> {
        u32v(builtin_arg("num_subgroups", BuiltIn::NumSubgroups, U32))
    }
}

fn round_up(x: usize, a: usize) -> usize {
    x.div_ceil(a) * a
}

pub(crate) fn add_global(
    name: &str,
    space: AddressSpace,
    ty: Handle<naga::Type>,
    kind: Option<BindingKind>,
) -> Handle<GlobalVariable> {
    with(|c| {
        let binding = kind.map(|k| {
            let b = c.next_binding;
            c.next_binding += 1;
            c.bindings.push(RtBinding {
                binding: b,
                kind: k,
                name: name.to_string(),
            });
            ResourceBinding {
                group: 0,
                binding: b,
            }
        });
        c.module.global_variables.append(
            GlobalVariable {
                name: Some(name.to_string()),
                space,
                binding,
                ty,
                init: None,
                memory_decorations: Default::default(),
            },
            Span::UNDEFINED,
        )
    })
}

/// Where a uniform parameter lives: a uniform buffer, or a read-only storage buffer where
/// the specialisation asks for one (`Spec::uniforms_as_storage`).
pub(crate) fn uniform_space() -> (AddressSpace, BindingKind) {
    if with(|c| c.spec.uniforms_as_storage) {
        (
            AddressSpace::Storage {
                access: naga::StorageAccess::LOAD,
            },
            BindingKind::StorageRead,
        )
    } else {
        (AddressSpace::Uniform, BindingKind::Uniform)
    }
}

fn global_ptr(g: Handle<GlobalVariable>) -> Handle<Expression> {
    with(|c| c.expr(Expression::GlobalVariable(g)))
}

/// A storage buffer parameter (`&[T]` or `&mut [T]`).
pub struct Buffer<T> {
    g: Handle<GlobalVariable>,
    /// Index among the kernel's storage buffers: its entry in the lengths binding.
    slot: u32,
    _t: PhantomData<fn() -> T>,
}

/// Name of the binding through which a launch passes the element count of every storage
/// buffer (only kernels that call `len()` have it); generated launch code fills it.
#[doc(hidden)]
pub const LENGTHS_BINDING: &str = "__lengths";

/// The lengths binding, declared on first use.
fn lengths_global() -> Handle<GlobalVariable> {
    if let Some(g) = with(|c| c.lengths) {
        return g;
    }
    let ty = with(|c| {
        let base = <u32 as GpuType>::naga_type(&mut c.module);
        c.ty(TypeInner::Array {
            base,
            size: ArraySize::Dynamic,
            stride: 4,
        })
    });
    let g = add_global(
        LENGTHS_BINDING,
        AddressSpace::Storage {
            access: StorageAccess::LOAD,
        },
        ty,
        Some(BindingKind::StorageRead),
    );
    with(|c| c.lengths = Some(g));
    g
}
impl<T> Clone for Buffer<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Buffer<T> {}

impl<T: GpuType> Buffer<T> {
    pub fn declare(name: &str, writable: bool) -> Buffer<T> {
        let stride = round_up(T::GPU_SIZE, T::GPU_ALIGN);
        let info = with(|c| c.info);
        assert!(
            super::types::storage_element_ok::<T>(),
            "kernel `{}`, buffer `{name}`: elements of type `{}` have a different layout on the host \
             and the GPU (GPU stride {stride} bytes, host size {}); use a type with the same layout \
             (e.g. Vec4 or [f32; 3] instead of Vec3)",
            info.name,
            std::any::type_name::<T>(),
            std::mem::size_of::<T>()
        );
        let ty = with(|c| {
            let base = T::naga_type(&mut c.module);
            c.ty(TypeInner::Array {
                base,
                size: ArraySize::Dynamic,
                stride: stride as u32,
            })
        });
        let access = if writable {
            StorageAccess::LOAD | StorageAccess::STORE
        } else {
            StorageAccess::LOAD
        };
        let kind = if writable {
            BindingKind::StorageReadWrite
        } else {
            BindingKind::StorageRead
        };
        let slot = with(|c| {
            c.storage_buffers += 1;
            c.storage_buffers - 1
        });
        Buffer {
            g: add_global(name, AddressSpace::Storage { access }, ty, Some(kind)),
            slot,
            _t: PhantomData,
        }
    }

    /// `buf.len()`: the element count the launch passed (not the bound size, which for an
    /// empty buffer is a stand-in's).
    pub fn len(&self) -> Val<usize> {
        let p = global_ptr(lengths_global());
        let slot = self.slot;
        Val::from_handle(with(|c| {
            let at = c.expr(Expression::AccessIndex {
                base: p,
                index: slot,
            });
            c.expr(Expression::Load { pointer: at })
        }))
    }
    pub fn is_empty(&self) -> Val<bool> {
        super::ops::eq(self.len(), crate::ir::val::lit(0usize))
    }
}
impl<T> AsPlace for Buffer<T> {
    type Target = RtArray<T>;
    fn as_place(&self) -> Place<RtArray<T>> {
        Place::from_handle(global_ptr(self.g))
    }
}

/// A uniform parameter (`&T` where `T` is not a slice).
pub struct Uniform<T> {
    g: Handle<GlobalVariable>,
    _t: PhantomData<fn() -> T>,
}
impl<T> Clone for Uniform<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Uniform<T> {}
impl<T: GpuType> Uniform<T> {
    pub fn declare(name: &str) -> Uniform<T> {
        // Where the macro could not check at compile time (a generic parameter's type):
        // the user's error, reported when the kernel is built, not a validation failure.
        if let Some(why) = T::UNIFORM_PROBLEM {
            with(|c| c.unsupported.push(format!("uniform `{name}`: {why}")));
        }
        let ty = with(|c| T::naga_type(&mut c.module));
        let (space, kind) = uniform_space();
        Uniform {
            g: add_global(name, space, ty, Some(kind)),
            _t: PhantomData,
        }
    }
    pub fn get(&self) -> Val<T> {
        self.as_place().get()
    }
}
impl<T> AsPlace for Uniform<T> {
    type Target = T;
    fn as_place(&self) -> Place<T> {
        Place::from_handle(global_ptr(self.g))
    }
}

/// Workgroup memory (`#[workgroup] tile: &mut [f32; 256]`).
pub struct Workgroup<T> {
    g: Handle<GlobalVariable>,
    _t: PhantomData<fn() -> T>,
}
impl<T> Clone for Workgroup<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Workgroup<T> {}
impl<T: GpuType> Workgroup<T> {
    pub fn declare(name: &str) -> Workgroup<T> {
        let ty = with(|c| T::naga_type(&mut c.module));
        Workgroup {
            g: add_global(name, AddressSpace::WorkGroup, ty, None),
            _t: PhantomData,
        }
    }
}
impl<T> AsPlace for Workgroup<T> {
    type Target = T;
    fn as_place(&self) -> Place<T> {
        Place::from_handle(global_ptr(self.g))
    }
}

/// Takes the place of a reference-like root (`Var`, buffer, uniform, `&mut` argument).
pub fn place<P: AsPlace>(p: &P) -> Place<P::Target> {
    p.as_place()
}

impl<T> crate::ir::val::AutoDeref for Buffer<T> {
    type Target = Buffer<T>;
    fn auto_deref(self) -> Buffer<T> {
        self
    }
}
impl<T: GpuType> crate::ir::val::AutoDeref for Uniform<T> {
    type Target = Val<T>;
    fn auto_deref(self) -> Val<T> {
        self.get()
    }
}
impl<T: GpuType> crate::ir::val::AutoDeref for Workgroup<T> {
    type Target = Val<T>;
    fn auto_deref(self) -> Val<T> {
        self.as_place().get()
    }
}

impl<T: GpuType> crate::ir::val::ToVal<T> for Uniform<T> {
    fn to_val(self) -> Val<T> {
        self.get()
    }
}
