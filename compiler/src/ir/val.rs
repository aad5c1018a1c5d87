//! Typed handles to IR: values (`Val<T>`), mutable locals (`Var<T>`) and memory places
//! (`Place<T>`: a pointer into a local, a buffer or workgroup memory).
//!
//! The kernel body that `#[kernel]` rewrites manipulates only these handles; their Rust
//! types carry the kernel's types, so a type error in a kernel is a rustc error on the
//! generated code, spanned at the user's line.

use naga::{Expression, Handle};
use std::marker::PhantomData;

use super::builder::with;
use super::types::{ConstValue, GpuType, ScalarType};

/// A value of type `T` computed by the kernel.
pub struct Val<T> {
    pub(crate) h: Handle<Expression>,
    _t: PhantomData<fn() -> T>,
}
impl<T> Clone for Val<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Val<T> {}

impl<T> Val<T> {
    /// Wraps an expression handle of the function being built. The caller vouches that
    /// the expression has type `T`.
    pub fn from_handle(h: Handle<Expression>) -> Self {
        Val { h, _t: PhantomData }
    }
    pub fn handle(self) -> Handle<Expression> {
        self.h
    }
}

/// A literal in kernel source: `lit(2.0)` becomes an `f32` literal when the context
/// wants an `f32`.
pub fn lit<T: ScalarType>(v: T) -> Val<T> {
    Val::from_handle(super::types::literal_expr(v.literal()))
}

/// Lifts a host value that the kernel reads as a constant (a `const` item, an
/// associated constant such as `f32::MAX` or `Vec3::ZERO`).
pub trait Konst {
    type Ir;
    fn konst(self) -> Self::Ir;
}
impl<T: ConstValue> Konst for T {
    type Ir = Val<T>;
    fn konst(self) -> Val<T> {
        Val::from_handle(self.build())
    }
}
/// Memory orderings appear as arguments of atomic methods; they pass through.
impl Konst for std::sync::atomic::Ordering {
    type Ir = std::sync::atomic::Ordering;
    fn konst(self) -> Self {
        self
    }
}
pub fn konst<K: Konst>(k: K) -> K::Ir {
    k.konst()
}

/// Gives a value the name of the Rust binding it was assigned to, so the emitted WGSL
/// reads `let dir = ...;`.
pub fn name<T>(v: Val<T>, name: &str) -> Val<T> {
    with(|c| c.name_expr(v.h, name));
    v
}

/// A zero value; stands in for the value of a branch that diverges (`break`, `return`).
pub fn zero<T: GpuType>() -> Val<T> {
    Val::from_handle(with(|c| {
        let ty = T::naga_type(&mut c.module);
        c.expr(Expression::ZeroValue(ty))
    }))
}

/// A pointer to memory holding a `T`.
pub struct Place<T> {
    pub(crate) ptr: Handle<Expression>,
    _t: PhantomData<fn() -> T>,
}
impl<T> Clone for Place<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Place<T> {}

impl<T> Place<T> {
    pub fn from_handle(ptr: Handle<Expression>) -> Self {
        Place {
            ptr,
            _t: PhantomData,
        }
    }
    pub fn handle(self) -> Handle<Expression> {
        self.ptr
    }
}

impl<T: GpuType> Place<T> {
    /// Reads the value (`get`/`set` rather than `load`/`store`, which atomics use with
    /// an `Ordering` argument, as on the host).
    pub fn get(self) -> Val<T> {
        Val::from_handle(with(|c| c.expr(Expression::Load { pointer: self.ptr })))
    }
    pub fn set(self, v: Val<T>) {
        with(|c| {
            c.stmt(naga::Statement::Store {
                pointer: self.ptr,
                value: v.h,
            })
        })
    }
}

/// A `let mut` binding: a naga local variable.
pub struct Var<T> {
    ptr: Handle<Expression>,
    _t: PhantomData<fn() -> T>,
}
impl<T> Clone for Var<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Var<T> {}

impl<T: GpuType> Var<T> {
    pub fn uninit(name: &str) -> Var<T> {
        let ptr = with(|c| {
            let ty = T::naga_type(&mut c.module);
            c.local(Some(name), ty)
        });
        Var {
            ptr,
            _t: PhantomData,
        }
    }
    pub fn new(name: &str, init: Val<T>) -> Var<T> {
        let v = Var::uninit(name);
        v.set(init);
        v
    }
    pub fn get(self) -> Val<T> {
        self.place().get()
    }
    pub fn set(self, v: Val<T>) {
        self.place().set(v)
    }
    pub fn place(self) -> Place<T> {
        Place::from_handle(self.ptr)
    }
}

/// Anything the rewritten code can take a place of: `&mut x`, `x.f = ..`, `x[i] = ..`.
pub trait AsPlace {
    type Target;
    fn as_place(&self) -> Place<Self::Target>;
}
impl<T: GpuType> AsPlace for Var<T> {
    type Target = T;
    fn as_place(&self) -> Place<T> {
        self.place()
    }
}
impl<T> AsPlace for Place<T> {
    type Target = T;
    fn as_place(&self) -> Place<T> {
        *self
    }
}

fn zeroed_member_offset<S: GpuType, F>(proj: impl FnOnce(&S) -> &F) -> usize {
    // SAFETY: GpuType guarantees that all-zero bytes are a valid `S`.
    let dummy: std::mem::MaybeUninit<S> = std::mem::MaybeUninit::zeroed();
    let s: &S = unsafe { dummy.assume_init_ref() };
    let base = s as *const S as usize;
    let f = proj(s) as *const F as usize;
    f.wrapping_sub(base)
}

fn member_index<S: GpuType, F>(proj: impl FnOnce(&S) -> &F) -> u32 {
    let off = zeroed_member_offset::<S, F>(proj);
    S::member_index(off).unwrap_or_else(|| {
        panic!(
            "cohort: field at offset {off} of `{}` is not a member kernels can access",
            std::any::type_name::<S>()
        )
    })
}

/// `v.f` on a value: the rewritten code passes `|s| &s.f`, so rustc checks the field
/// exists and gives its type; the member index is found from the field's offset.
pub fn field<S: GpuType, F: GpuType>(v: Val<S>, proj: impl FnOnce(&S) -> &F) -> Val<F> {
    let index = member_index::<S, F>(proj);
    Val::from_handle(with(|c| {
        c.expr(Expression::AccessIndex { base: v.h, index })
    }))
}

/// `p.f` on a place.
pub fn place_field<S: GpuType, F: GpuType>(p: Place<S>, proj: impl FnOnce(&S) -> &F) -> Place<F> {
    let index = member_index::<S, F>(proj);
    Place::from_handle(with(|c| {
        c.expr(Expression::AccessIndex { base: p.ptr, index })
    }))
}

/// Integer types that can index arrays.
pub trait IndexInt: ScalarType {}
impl IndexInt for u32 {}
impl IndexInt for i32 {}
impl IndexInt for usize {}

/// Containers that `x[i]` indexes: fixed arrays, vectors, matrices and runtime arrays
/// (storage buffers).
pub trait Indexable {
    type Elem;
}
impl<T: GpuType, const N: usize> Indexable for [T; N] {
    type Elem = T;
}
/// The element type of a storage buffer (a runtime-sized array).
pub struct RtArray<T>(PhantomData<T>);
impl<T> Indexable for RtArray<T> {
    type Elem = T;
}
macro_rules! indexable_vec { ($($t:ty => $e:ty),*) => { $(impl Indexable for $t { type Elem = $e; })* }; }
indexable_vec!(glam::Vec2 => f32, glam::Vec3 => f32, glam::Vec4 => f32, glam::UVec2 => u32,
    glam::UVec3 => u32, glam::UVec4 => u32, glam::IVec2 => i32, glam::IVec3 => i32, glam::IVec4 => i32,
    glam::Mat3 => glam::Vec3, glam::Mat4 => glam::Vec4);

pub fn index<A: Indexable + GpuType, I: IndexInt>(v: Val<A>, i: Val<I>) -> Val<A::Elem> {
    Val::from_handle(with(|c| {
        c.expr(Expression::Access {
            base: v.h,
            index: i.h,
        })
    }))
}

pub fn place_index<A: Indexable, I: IndexInt>(p: Place<A>, i: Val<I>) -> Place<A::Elem> {
    Place::from_handle(with(|c| {
        c.expr(Expression::Access {
            base: p.ptr,
            index: i.h,
        })
    }))
}

/// `[a, b, c]`
pub fn array<T: GpuType, const N: usize>(items: [Val<T>; N]) -> Val<[T; N]> {
    Val::from_handle(with(|c| {
        let ty = <[T; N] as GpuType>::naga_type(&mut c.module);
        c.expr(Expression::Compose {
            ty,
            components: items.iter().map(|v| v.h).collect(),
        })
    }))
}

/// `[x; N]`
pub fn array_repeat<T: GpuType, const N: usize>(item: Val<T>) -> Val<[T; N]> {
    array([item; N])
}

/// One field of a struct literal: its member index and value.
pub struct FieldInit {
    index: u32,
    h: Handle<Expression>,
}
pub fn field_init<S: GpuType, F: GpuType>(proj: impl FnOnce(&S) -> &F, v: Val<F>) -> FieldInit {
    FieldInit {
        index: member_index::<S, F>(proj),
        h: v.h,
    }
}

/// `S { a: .., b: .. }`: rustc has already checked that every field is given once.
pub fn compose<S: GpuType>(mut fields: Vec<FieldInit>) -> Val<S> {
    fields.sort_by_key(|f| f.index);
    Val::from_handle(with(|c| {
        let ty = S::naga_type(&mut c.module);
        c.expr(Expression::Compose {
            ty,
            components: fields.iter().map(|f| f.h).collect(),
        })
    }))
}

/// A `&T` argument of a helper: a value, or a place that is read.
pub trait ToVal<T> {
    fn to_val(self) -> Val<T>;
}
impl<T> ToVal<T> for Val<T> {
    fn to_val(self) -> Val<T> {
        self
    }
}
impl<T: GpuType> ToVal<T> for Place<T> {
    fn to_val(self) -> Val<T> {
        self.get()
    }
}

/// Method-call auto-deref on a reference-like root (`a.min(b)` with `a: &mut f32`):
/// places and uniforms are read, buffers stay handles (`buf.len()`).
pub trait AutoDeref {
    type Target;
    fn auto_deref(self) -> Self::Target;
}
impl<T: GpuType> AutoDeref for Place<T> {
    type Target = Val<T>;
    fn auto_deref(self) -> Val<T> {
        self.get()
    }
}

/// Never implemented: the bound of the stand-in that `#[kernel]` puts in scope for a
/// method call the kernel's types may not have, so that calling a method of one's own
/// type in a kernel says what to write instead of only "no method found for `Val<T>`".
#[doc(hidden)]
#[diagnostic::on_unimplemented(
    message = "kernels cannot call methods of `{Self}` defined in plain Rust",
    note = "write the method as a #[kernel_fn] helper that takes the value as a parameter (e.g. `#[kernel_fn] fn area(s: Sphere) -> f32`) and call it as a function (`area(s)`)"
)]
pub trait MethodNeedsKernelFn {}

/// The types a `#[specialize]` kernel parameter may have, and how each is kept in
/// [`Spec::constants`](crate::spec::Spec::constants).
pub trait SpecConstant: ScalarType + Copy {
    fn raw(self) -> u32;
    fn from_raw(raw: u32) -> Self;
}
impl SpecConstant for u32 {
    fn raw(self) -> u32 {
        self
    }
    fn from_raw(raw: u32) -> Self {
        raw
    }
}
impl SpecConstant for bool {
    fn raw(self) -> u32 {
        self as u32
    }
    fn from_raw(raw: u32) -> Self {
        raw != 0
    }
}

/// A `#[specialize]` parameter in the kernel being built: a literal, so that the branches
/// it decides (and `&&`, `||` and operations on it) fold when the kernel is built.
#[doc(hidden)]
pub fn spec_constant<T: SpecConstant>(raw: u32) -> Val<T> {
    lit(T::from_raw(raw))
}
