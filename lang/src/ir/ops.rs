//! Operators on IR values: arithmetic, bit operations, comparisons, negation and casts.
//!
//! Each `impl` exists only for the type pairs that Rust (and glam) accept on the host, so
//! a kernel that type-checks on the host type-checks here, and one that does not is a
//! rustc error on the rewritten code at the user's span.

use naga::{BinaryOperator as B, Expression, ScalarKind, UnaryOperator as U, VectorSize};
use std::ops::*;

use super::builder::with;
use super::types::{GpuType, ScalarType};
use super::val::Val;
use glam::{IVec2, IVec3, IVec4, Mat3, Mat4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};

pub(crate) fn binary<R>(op: B, l: naga::Handle<Expression>, r: naga::Handle<Expression>) -> Val<R> {
    Val::from_handle(with(|c| {
        // Operations on literals are folded here, with Rust's (wrapping) semantics:
        // WGSL rejects constant expressions that overflow, such as `1384639240u << 27u`.
        let exprs = &c.f().func.expressions;
        let lit = |h| match exprs[h] {
            Expression::Literal(v) => Some(v),
            _ => None,
        };
        if let (Some(a), Some(b)) = (lit(l), lit(r)) {
            if let Some(v) = super::fold::binary(op, a, b) {
                return c.expr(Expression::Literal(v));
            }
        }
        c.expr(Expression::Binary { op, left: l, right: r })
    }))
}

pub(crate) fn unary<R>(op: U, e: naga::Handle<Expression>) -> Val<R> {
    Val::from_handle(with(|c| {
        if let Expression::Literal(v) = c.f().func.expressions[e] {
            if let Some(v) = super::fold::unary(op, v) {
                return c.expr(Expression::Literal(v));
            }
        }
        c.expr(Expression::Unary { op, expr: e })
    }))
}

pub(crate) fn splat<S>(size: VectorSize, v: Val<S>) -> naga::Handle<Expression> {
    with(|c| c.expr(Expression::Splat { size, value: v.h }))
}

macro_rules! binop {
    ($tr:ident, $m:ident, $op:expr, $l:ty, $r:ty => $out:ty) => {
        impl $tr<Val<$r>> for Val<$l> {
            type Output = Val<$out>;
            fn $m(self, rhs: Val<$r>) -> Val<$out> {
                binary($op, self.h, rhs.h)
            }
        }
    };
}

macro_rules! arith_same {
    ($($t:ty),*) => {$(
        binop!(Add, add, B::Add, $t, $t => $t);
        binop!(Sub, sub, B::Subtract, $t, $t => $t);
        binop!(Mul, mul, B::Multiply, $t, $t => $t);
        binop!(Div, div, B::Divide, $t, $t => $t);
        binop!(Rem, rem, B::Modulo, $t, $t => $t);
    )*};
}
arith_same!(f32, u32, i32, usize, Vec2, Vec3, Vec4, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);

macro_rules! bits_same {
    ($($t:ty),*) => {$(
        binop!(BitAnd, bitand, B::And, $t, $t => $t);
        binop!(BitOr, bitor, B::InclusiveOr, $t, $t => $t);
        binop!(BitXor, bitxor, B::ExclusiveOr, $t, $t => $t);
    )*};
}
bits_same!(u32, i32, usize, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);
binop!(BitAnd, bitand, B::LogicalAnd, bool, bool => bool);
binop!(BitOr, bitor, B::LogicalOr, bool, bool => bool);
binop!(BitXor, bitxor, B::NotEqual, bool, bool => bool);

macro_rules! shifts {
    ($($t:ty),*) => {$(
        binop!(Shl, shl, B::ShiftLeft, $t, u32 => $t);
        binop!(Shr, shr, B::ShiftRight, $t, u32 => $t);
    )*};
}
shifts!(u32, i32);

// Vector-scalar mixes, as glam allows them: the scalar is splatted.
macro_rules! vec_scalar {
    ($($v:ty, $s:ty, $n:expr);*) => {$(
        vec_scalar!(@one Add, add, B::Add, $v, $s, $n);
        vec_scalar!(@one Sub, sub, B::Subtract, $v, $s, $n);
        vec_scalar!(@one Mul, mul, B::Multiply, $v, $s, $n);
        vec_scalar!(@one Div, div, B::Divide, $v, $s, $n);
        vec_scalar!(@one Rem, rem, B::Modulo, $v, $s, $n);
    )*};
    (@one $tr:ident, $m:ident, $op:expr, $v:ty, $s:ty, $n:expr) => {
        impl $tr<Val<$s>> for Val<$v> {
            type Output = Val<$v>;
            fn $m(self, rhs: Val<$s>) -> Val<$v> {
                let r = splat($n, rhs);
                binary($op, self.h, r)
            }
        }
        impl $tr<Val<$v>> for Val<$s> {
            type Output = Val<$v>;
            fn $m(self, rhs: Val<$v>) -> Val<$v> {
                let l = splat($n, self);
                binary($op, l, rhs.h)
            }
        }
    };
}
vec_scalar!(Vec2, f32, VectorSize::Bi; Vec3, f32, VectorSize::Tri; Vec4, f32, VectorSize::Quad;
    UVec2, u32, VectorSize::Bi; UVec3, u32, VectorSize::Tri; UVec4, u32, VectorSize::Quad;
    IVec2, i32, VectorSize::Bi; IVec3, i32, VectorSize::Tri; IVec4, i32, VectorSize::Quad);

binop!(Mul, mul, B::Multiply, Mat3, Vec3 => Vec3);
binop!(Mul, mul, B::Multiply, Mat4, Vec4 => Vec4);
binop!(Mul, mul, B::Multiply, Mat3, Mat3 => Mat3);
binop!(Mul, mul, B::Multiply, Mat4, Mat4 => Mat4);
binop!(Mul, mul, B::Multiply, Mat3, f32 => Mat3);
binop!(Mul, mul, B::Multiply, Mat4, f32 => Mat4);
binop!(Add, add, B::Add, Mat3, Mat3 => Mat3);
binop!(Add, add, B::Add, Mat4, Mat4 => Mat4);
binop!(Sub, sub, B::Subtract, Mat3, Mat3 => Mat3);
binop!(Sub, sub, B::Subtract, Mat4, Mat4 => Mat4);

macro_rules! neg {
    ($($t:ty),*) => {$(
        impl Neg for Val<$t> {
            type Output = Val<$t>;
            fn neg(self) -> Val<$t> { unary(U::Negate, self.h) }
        }
    )*};
}
neg!(f32, i32, Vec2, Vec3, Vec4, IVec2, IVec3, IVec4);

macro_rules! not {
    ($op:expr; $($t:ty),*) => {$(
        impl Not for Val<$t> {
            type Output = Val<$t>;
            fn not(self) -> Val<$t> { unary($op, self.h) }
        }
    )*};
}
not!(U::LogicalNot; bool);
not!(U::BitwiseNot; u32, i32, usize, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);

/// Types with `<`, `<=`, `>`, `>=` (Rust's `PartialOrd` on the host).
pub trait Ordered: ScalarType {}
impl Ordered for f32 {}
impl Ordered for u32 {}
impl Ordered for i32 {}
impl Ordered for usize {}

pub fn lt<T: Ordered>(a: Val<T>, b: Val<T>) -> Val<bool> {
    binary(B::Less, a.h, b.h)
}
pub fn le<T: Ordered>(a: Val<T>, b: Val<T>) -> Val<bool> {
    binary(B::LessEqual, a.h, b.h)
}
pub fn gt<T: Ordered>(a: Val<T>, b: Val<T>) -> Val<bool> {
    binary(B::Greater, a.h, b.h)
}
pub fn ge<T: Ordered>(a: Val<T>, b: Val<T>) -> Val<bool> {
    binary(B::GreaterEqual, a.h, b.h)
}

/// Types with `==` and `!=`. On vectors, as on the host, equality means every
/// component is equal.
pub trait Equatable: GpuType {
    const IS_VECTOR: bool;
}
macro_rules! eq_scalar { ($($t:ty),*) => { $(impl Equatable for $t { const IS_VECTOR: bool = false; })* }; }
macro_rules! eq_vector { ($($t:ty),*) => { $(impl Equatable for $t { const IS_VECTOR: bool = true; })* }; }
eq_scalar!(f32, u32, i32, usize, bool);
eq_vector!(Vec2, Vec3, Vec4, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);

fn relational(fun: naga::RelationalFunction, v: naga::Handle<Expression>) -> Val<bool> {
    Val::from_handle(with(|c| c.expr(Expression::Relational { fun, argument: v })))
}

pub fn eq<T: Equatable>(a: Val<T>, b: Val<T>) -> Val<bool> {
    let e: Val<bool> = binary(B::Equal, a.h, b.h);
    if T::IS_VECTOR {
        relational(naga::RelationalFunction::All, e.h)
    } else {
        e
    }
}
pub fn ne<T: Equatable>(a: Val<T>, b: Val<T>) -> Val<bool> {
    let e: Val<bool> = binary(B::NotEqual, a.h, b.h);
    if T::IS_VECTOR {
        relational(naga::RelationalFunction::Any, e.h)
    } else {
        e
    }
}

/// `x as T` between scalar types. Float → integer conversions of out-of-range values
/// differ between host (saturating) and GPU (backend-defined); kernels should not rely
/// on them.
pub trait CastTo<T> {
    fn cast(v: Val<Self>) -> Val<T>
    where
        Self: Sized;
}
macro_rules! casts {
    ($($from:ty => [$($to:ty),*]);*) => {$($(
        impl CastTo<$to> for $from {
            fn cast(v: Val<$from>) -> Val<$to> {
                let (fk, tk) = (<$from as ScalarType>::SCALAR, <$to as ScalarType>::SCALAR);
                if fk == tk {
                    return Val::from_handle(v.h);
                }
                Val::from_handle(with(|c| c.expr(Expression::As {
                    expr: v.h,
                    kind: tk.kind,
                    convert: Some(tk.width),
                })))
            }
        }
    )*)*};
}
casts!(f32 => [f32, u32, i32, usize]; u32 => [f32, u32, i32, usize]; i32 => [f32, u32, i32, usize];
    usize => [f32, u32, i32, usize]; bool => [u32, i32, usize]);

pub fn cast<T, S: CastTo<T>>(v: Val<S>) -> Val<T> {
    S::cast(v)
}

pub(crate) fn bitcast<T>(v: naga::Handle<Expression>, kind: ScalarKind) -> Val<T> {
    Val::from_handle(with(|c| c.expr(Expression::As { expr: v, kind, convert: None })))
}
