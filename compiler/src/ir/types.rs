//! Host Rust types ↔ naga types.
//!
//! Every type a kernel can hold implements [`GpuType`]: it registers its naga type and
//! states its GPU layout (WGSL storage rules), so that a buffer of `T` means the same
//! bytes on the host and in the shader. User structs get the impl from
//! `#[derive(GpuType)]`, which also checks their layout at compile time
//! (`const` assertions) and against naga's layouter when first registered.

use naga::{ArraySize, Handle, Module, Scalar, Span, StructMember, Type, TypeInner, VectorSize};
use std::sync::atomic::{AtomicI32, AtomicU32};

/// A type that kernels can hold in values, variables and buffers.
///
/// # Safety
/// The all-zero bit pattern must be a valid value of the type (it is used to find
/// field offsets by projecting a zeroed value), and `member_index` must agree with the
/// host layout. Implement it through `#[derive(GpuType)]`, not by hand.
pub unsafe trait GpuType: 'static + Sized {
    /// Registers the type in the module (types are de-duplicated by naga).
    fn naga_type(m: &mut Module) -> Handle<Type>;
    /// Alignment under WGSL's storage-buffer layout rules.
    const GPU_ALIGN: usize;
    /// Size under WGSL's storage-buffer layout rules.
    const GPU_SIZE: usize;
    /// True when a host value has exactly the GPU layout (so it can be uploaded as bytes).
    const HOST_SHAREABLE: bool;
    /// Why a value of this type cannot be a uniform (`&T` parameter), if it cannot: WGSL's
    /// uniform layout needs array strides and struct members of struct type at multiples
    /// of 16 bytes, where the storage layout (which the host layout follows) does not.
    const UNIFORM_PROBLEM: Option<&'static str> = None;
    /// A `#[derive(GpuType)]` struct (its members in a uniform start at multiples of 16).
    const IS_STRUCT: bool = false;
    /// Index of the struct member / vector component / matrix column that starts at byte
    /// `offset` of the host value.
    fn member_index(offset: usize) -> Option<u32> {
        let _ = offset;
        None
    }
}

/// Scalar types, with their naga scalar.
pub trait ScalarType: GpuType + Copy {
    const SCALAR: Scalar;
    fn literal(self) -> naga::Literal;
}

/// Types whose values can be written in a kernel as literals or `const` items.
pub trait ConstValue: GpuType {
    /// Builds the value as an expression of the current function.
    fn build(&self) -> Handle<naga::Expression>;
}

/// The expression for a scalar constant. WGSL has no literal for infinities and NaN
/// (naga rejects `Literal(F32(inf))`), so a non-finite `f32` is the bit cast of its `u32`
/// bits (`bitcast<f32>(0x7f800000u)`), which keeps its exact bits (NaN payload and sign
/// included) on both backends.
pub(crate) fn literal_expr(l: naga::Literal) -> Handle<naga::Expression> {
    crate::ir::builder::with(|c| match l {
        naga::Literal::F32(v) if !v.is_finite() => {
            let bits = c.expr(naga::Expression::Literal(naga::Literal::U32(v.to_bits())));
            c.expr(naga::Expression::As {
                expr: bits,
                kind: naga::ScalarKind::Float,
                convert: None,
            })
        }
        l => c.expr(naga::Expression::Literal(l)),
    })
}

fn scalar_ty(m: &mut Module, s: Scalar) -> Handle<Type> {
    m.types.insert(
        Type {
            name: None,
            inner: TypeInner::Scalar(s),
        },
        Span::UNDEFINED,
    )
}

macro_rules! scalar {
    ($t:ty, $s:expr, $lit:expr, $shareable:expr) => {
        unsafe impl GpuType for $t {
            fn naga_type(m: &mut Module) -> Handle<Type> {
                scalar_ty(m, $s)
            }
            const GPU_ALIGN: usize = 4;
            const GPU_SIZE: usize = 4;
            const HOST_SHAREABLE: bool = $shareable;
        }
        impl ScalarType for $t {
            const SCALAR: Scalar = $s;
            fn literal(self) -> naga::Literal {
                #[allow(clippy::redundant_closure_call)]
                ($lit)(self)
            }
        }
        impl ConstValue for $t {
            fn build(&self) -> Handle<naga::Expression> {
                literal_expr(self.literal())
            }
        }
    };
}

scalar!(f32, Scalar::F32, |v: f32| naga::Literal::F32(v), true);
scalar!(u32, Scalar::U32, |v: u32| naga::Literal::U32(v), true);
scalar!(i32, Scalar::I32, |v: i32| naga::Literal::I32(v), true);
scalar!(bool, Scalar::BOOL, |v: bool| naga::Literal::Bool(v), false);
// `usize` is how Rust indexes slices; in kernels it is a 32-bit unsigned integer. It
// is never shareable: the host's usize is 8 bytes.
scalar!(
    usize,
    Scalar::U32,
    |v: usize| naga::Literal::U32(
        u32::try_from(v).expect("usize constant does not fit in 32 bits")
    ),
    false
);

macro_rules! vector {
    ($t:ty, $elem:ty, $size:expr, $n:expr, $align:expr, [$($f:ident),+]) => {
        unsafe impl GpuType for $t {
            fn naga_type(m: &mut Module) -> Handle<Type> {
                m.types.insert(
                    Type {
                        name: None,
                        inner: TypeInner::Vector { size: $size, scalar: <$elem as ScalarType>::SCALAR },
                    },
                    Span::UNDEFINED,
                )
            }
            const GPU_ALIGN: usize = $align;
            const GPU_SIZE: usize = 4 * $n;
            const HOST_SHAREABLE: bool = std::mem::size_of::<$t>() == 4 * $n;
            fn member_index(offset: usize) -> Option<u32> {
                (offset % 4 == 0 && offset / 4 < $n).then_some((offset / 4) as u32)
            }
        }
        impl ConstValue for $t {
            fn build(&self) -> Handle<naga::Expression> {
                let comps: Vec<_> = [$(self.$f),+].iter().map(|c| c.build()).collect();
                crate::ir::builder::with(|c| {
                    let ty = <$t as GpuType>::naga_type(&mut c.module);
                    c.expr(naga::Expression::Compose { ty, components: comps })
                })
            }
        }
    };
}

use glam::{IVec2, IVec3, IVec4, Mat3, Mat4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};
vector!(Vec2, f32, VectorSize::Bi, 2, 8, [x, y]);
vector!(Vec3, f32, VectorSize::Tri, 3, 16, [x, y, z]);
vector!(Vec4, f32, VectorSize::Quad, 4, 16, [x, y, z, w]);
vector!(UVec2, u32, VectorSize::Bi, 2, 8, [x, y]);
vector!(UVec3, u32, VectorSize::Tri, 3, 16, [x, y, z]);
vector!(UVec4, u32, VectorSize::Quad, 4, 16, [x, y, z, w]);
vector!(IVec2, i32, VectorSize::Bi, 2, 8, [x, y]);
vector!(IVec3, i32, VectorSize::Tri, 3, 16, [x, y, z]);
vector!(IVec4, i32, VectorSize::Quad, 4, 16, [x, y, z, w]);

macro_rules! matrix {
    ($t:ty, $size:expr, $n:expr, $col:ty, [$($f:ident),+]) => {
        unsafe impl GpuType for $t {
            fn naga_type(m: &mut Module) -> Handle<Type> {
                m.types.insert(
                    Type {
                        name: None,
                        inner: TypeInner::Matrix { columns: $size, rows: $size, scalar: Scalar::F32 },
                    },
                    Span::UNDEFINED,
                )
            }
            const GPU_ALIGN: usize = 16;
            const GPU_SIZE: usize = 16 * $n;
            // glam's Mat3 packs columns at 12 bytes; WGSL pads them to 16.
            const HOST_SHAREABLE: bool = std::mem::size_of::<$t>() == 16 * $n;
            fn member_index(offset: usize) -> Option<u32> {
                let col = std::mem::size_of::<$col>();
                (offset % col == 0 && offset / col < $n).then_some((offset / col) as u32)
            }
        }
        impl ConstValue for $t {
            fn build(&self) -> Handle<naga::Expression> {
                let comps: Vec<_> = [$(self.$f),+].iter().map(|c| c.build()).collect();
                crate::ir::builder::with(|c| {
                    let ty = <$t as GpuType>::naga_type(&mut c.module);
                    c.expr(naga::Expression::Compose { ty, components: comps })
                })
            }
        }
    };
}
matrix!(Mat3, VectorSize::Tri, 3, Vec3, [x_axis, y_axis, z_axis]);
matrix!(
    Mat4,
    VectorSize::Quad,
    4,
    Vec4,
    [x_axis, y_axis, z_axis, w_axis]
);

const fn round_up(x: usize, a: usize) -> usize {
    x.div_ceil(a) * a
}

unsafe impl<T: GpuType, const N: usize> GpuType for [T; N] {
    fn naga_type(m: &mut Module) -> Handle<Type> {
        let base = T::naga_type(m);
        let size = ArraySize::Constant(
            std::num::NonZeroU32::new(N as u32)
                .expect("zero-length arrays are not supported in kernels"),
        );
        m.types.insert(
            Type {
                name: None,
                inner: TypeInner::Array {
                    base,
                    size,
                    stride: round_up(T::GPU_SIZE, T::GPU_ALIGN) as u32,
                },
            },
            Span::UNDEFINED,
        )
    }
    const GPU_ALIGN: usize = T::GPU_ALIGN;
    const GPU_SIZE: usize = round_up(T::GPU_SIZE, T::GPU_ALIGN) * N;
    const HOST_SHAREABLE: bool =
        T::HOST_SHAREABLE && std::mem::size_of::<T>() == round_up(T::GPU_SIZE, T::GPU_ALIGN);
    const UNIFORM_PROBLEM: Option<&'static str> = if !round_up(T::GPU_SIZE, T::GPU_ALIGN)
        .is_multiple_of(16)
    {
        Some("an array whose elements are not 16 bytes apart cannot be in a uniform (WGSL's uniform layout needs a 16-byte array stride): use an array of Vec4 / UVec4 / IVec4, or pass the data in a storage buffer (&[T])")
    } else {
        T::UNIFORM_PROBLEM
    };
}

/// Panics (at compile time, where the kernel macro evaluates it for a uniform parameter)
/// with the reason `T` cannot be a uniform.
#[doc(hidden)]
pub const fn assert_uniform<T: GpuType>() {
    if let Some(why) = T::UNIFORM_PROBLEM {
        panic!("{}", why);
    }
}

impl<T: ConstValue, const N: usize> ConstValue for [T; N] {
    fn build(&self) -> Handle<naga::Expression> {
        let comps: Vec<_> = self.iter().map(|c| c.build()).collect();
        crate::ir::builder::with(|c| {
            let ty = <[T; N] as GpuType>::naga_type(&mut c.module);
            c.expr(naga::Expression::Compose {
                ty,
                components: comps,
            })
        })
    }
}

macro_rules! atomic {
    ($t:ty, $s:expr) => {
        unsafe impl GpuType for $t {
            fn naga_type(m: &mut Module) -> Handle<Type> {
                m.types.insert(
                    Type {
                        name: None,
                        inner: TypeInner::Atomic($s),
                    },
                    Span::UNDEFINED,
                )
            }
            const GPU_ALIGN: usize = 4;
            const GPU_SIZE: usize = 4;
            const HOST_SHAREABLE: bool = true;
        }
    };
}
atomic!(AtomicU32, Scalar::U32);
atomic!(AtomicI32, Scalar::I32);

/// The plain-data type a buffer element is uploaded as: itself, except atomics, which
/// are uploaded as their integer. The typed launch API uses it for buffer arguments.
pub trait HostRepr {
    type Pod: bytemuck::Pod;
}
macro_rules! host_repr_self { ($($t:ty),*) => { $(impl HostRepr for $t { type Pod = $t; })* }; }
host_repr_self!(f32, u32, i32, Vec2, Vec3, Vec4, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4, Mat4);
impl HostRepr for AtomicU32 {
    type Pod = u32;
}
impl HostRepr for AtomicI32 {
    type Pod = i32;
}
impl<T: HostRepr<Pod = T> + bytemuck::Pod, const N: usize> HostRepr for [T; N]
where
    [T; N]: bytemuck::Pod,
{
    type Pod = [T; N];
}

/// One member of a derived struct, as the derive describes it.
pub struct MemberDesc {
    pub name: &'static str,
    pub ty: Handle<Type>,
    pub host_offset: usize,
    pub gpu_align: usize,
}

/// Registers a struct type from a derive. Member offsets are the host offsets; they are
/// checked against naga's layouter so that host and shader agree byte for byte.
pub fn struct_type(
    m: &mut Module,
    name: &str,
    members: Vec<MemberDesc>,
    host_size: usize,
    gpu_align: usize,
    host_shareable: bool,
) -> Handle<Type> {
    let naga_members: Vec<StructMember> = members
        .iter()
        .map(|d| StructMember {
            name: Some(d.name.to_string()),
            ty: d.ty,
            binding: None,
            offset: d.host_offset as u32,
        })
        .collect();
    let span = round_up(host_size, gpu_align) as u32;
    let h = m.types.insert(
        Type {
            name: Some(name.to_string()),
            inner: TypeInner::Struct {
                members: naga_members,
                span,
            },
        },
        Span::UNDEFINED,
    );
    if host_shareable {
        check_layout(m, name, h, &members, host_size);
    }
    h
}

fn check_layout(m: &Module, name: &str, h: Handle<Type>, members: &[MemberDesc], host_size: usize) {
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(m.to_ctx())
        .unwrap_or_else(|e| panic!("struct `{name}`: naga could not lay it out: {e:?}"));
    for d in members {
        let align = layouter[d.ty].alignment.round_up(1) as usize;
        assert!(
            d.host_offset % align == 0,
            "struct `{name}`: field `{}` is at host offset {} but the GPU needs {}-byte alignment; \
             reorder the fields or add padding",
            d.name,
            d.host_offset,
            align
        );
    }
    let gpu_size = layouter[h].size as usize;
    assert!(
        gpu_size == host_size,
        "struct `{name}`: host size {host_size} bytes but GPU size {gpu_size} bytes; add padding \
         fields so the size is a multiple of the largest field alignment"
    );
}

/// Whether a storage buffer of `T` can be shared with the host as bytes: `T` has the GPU
/// layout and its host size is its stride in a GPU array (Vec3 is 12 bytes on the host and
/// 16 apart in a WGSL array). The kernel macro asserts it at compile time per buffer
/// parameter; `Buffer::declare` again when the kernel is built (for generic element types).
#[doc(hidden)]
pub const fn storage_element_ok<T: GpuType>() -> bool {
    T::HOST_SHAREABLE && std::mem::size_of::<T>() == round_up(T::GPU_SIZE, T::GPU_ALIGN)
}
