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
                // Non-finite float results become bit casts (WGSL rejects `3.4e38f * 2f`).
                return match v {
                    naga::Literal::F32(x) if !x.is_finite() => {
                        let bits = c.expr(Expression::Literal(naga::Literal::U32(x.to_bits())));
                        c.expr(Expression::As {
                            expr: bits,
                            kind: ScalarKind::Float,
                            convert: None,
                        })
                    }
                    v => c.expr(Expression::Literal(v)),
                };
            }
        }
        if matches!(op, B::Divide | B::Modulo) {
            if let Some((zero, one, size)) = zero_int_divisor(c, r) {
                return guarded_divide(c, op, l, r, zero, one, size);
            }
        }
        c.expr(Expression::Binary {
            op,
            left: l,
            right: r,
        })
    }))
}

/// naga rejects an integer division whose divisor is a constant expression containing
/// zero (`x / 0`, `v / vec2(y, 0)`), although the language defines it (`x / 0 == x`,
/// `x % 0 == 0`). Such a divisor is found here: its zero and one literals and vector size.
fn zero_int_divisor(
    c: &mut super::builder::Ctx,
    r: naga::Handle<Expression>,
) -> Option<(naga::Literal, naga::Literal, Option<VectorSize>)> {
    use naga::Literal as L;
    fn find(e: &naga::Arena<Expression>, h: naga::Handle<Expression>) -> Option<(L, L)> {
        match e[h] {
            Expression::Literal(L::I32(0)) => Some((L::I32(0), L::I32(1))),
            Expression::Literal(L::U32(0)) => Some((L::U32(0), L::U32(1))),
            Expression::Splat { value, .. } => find(e, value),
            Expression::Compose { ref components, .. } => {
                components.iter().find_map(|&x| find(e, x))
            }
            _ => None,
        }
    }
    let exprs = &c.f().func.expressions;
    let (zero, one) = find(exprs, r)?;
    let size = match exprs[r] {
        Expression::Splat { size, .. } => Some(size),
        Expression::Compose { ty, .. } => match c.module.types[ty].inner {
            naga::TypeInner::Vector { size, .. } => Some(size),
            _ => None,
        },
        _ => None,
    };
    Some((zero, one, size))
}

/// `l / r` (`l % r`) with the defined results where `r` is zero, without a constant zero
/// divisor in the IR: `select(l / select(r, 1, r == 0), l (or 0), r == 0)`.
fn guarded_divide(
    c: &mut super::builder::Ctx,
    op: B,
    l: naga::Handle<Expression>,
    r: naga::Handle<Expression>,
    zero: naga::Literal,
    one: naga::Literal,
    size: Option<VectorSize>,
) -> naga::Handle<Expression> {
    if let Expression::Literal(_) = c.f().func.expressions[r] {
        // A scalar `x / 0` (`x % 0`) is `x` (`0`).
        return if op == B::Divide {
            l
        } else {
            c.expr(Expression::Literal(zero))
        };
    }
    let lit = |c: &mut super::builder::Ctx, v| {
        let h = c.expr(Expression::Literal(v));
        match size {
            Some(size) => c.expr(Expression::Splat { size, value: h }),
            None => h,
        }
    };
    let (z, o) = (lit(c, zero), lit(c, one));
    let is_zero = c.expr(Expression::Binary {
        op: B::Equal,
        left: r,
        right: z,
    });
    let safe = c.expr(Expression::Select {
        condition: is_zero,
        accept: o,
        reject: r,
    });
    let q = c.expr(Expression::Binary {
        op,
        left: l,
        right: safe,
    });
    let at_zero = if op == B::Divide { l } else { lit(c, zero) };
    c.expr(Expression::Select {
        condition: is_zero,
        accept: at_zero,
        reject: q,
    })
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
    )*};
}
arith_same!(f32, u32, i32, usize, Vec2, Vec3, Vec4, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);
// Integer `/` and `%` are naga's `Divide`/`Modulo`: WGSL defines `x / 0 == x`,
// `x % 0 == 0`, `MIN / -1 == MIN` and `MIN % -1 == 0`, and naga's SPIR-V writer implements
// the same (its `naga_div`/`naga_mod` wrappers, on by default); the host form of a kernel
// computes the same values (`cohort::host::ops`).
macro_rules! int_rem {
    ($($t:ty),*) => {$( binop!(Rem, rem, B::Modulo, $t, $t => $t); )*};
}
int_rem!(u32, i32, usize, UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);

/// `x % y` on `f32` is Rust's: the exact truncated remainder (C's `fmodf`), with the sign
/// of `x`; `x % 0`, `inf % y` and NaN operands give NaN, `x % inf == x`. naga's float `%`
/// (`x - y * trunc(x / y)`) is inexact, so this is an exact integer algorithm in a helper.
impl Rem<Val<f32>> for Val<f32> {
    type Output = Val<f32>;
    fn rem(self, rhs: Val<f32>) -> Val<f32> {
        super::math::fmod(self, rhs)
    }
}

/// `%` on float vectors is refused: glam gives it two meanings on the host (`Vec2`/`Vec3`
/// use Rust's `%` per component, `Vec4` on x86 `x - y * floor(x / y)`).
#[diagnostic::on_unimplemented(
    message = "`%` on float vectors is not supported in kernels (glam's `Vec4 % Vec4` is `x - y * floor(x / y)` on x86 but `Vec3 % Vec3` is Rust's `%`)",
    label = "write the components: `Vec3::new(a.x % b.x, a.y % b.y, a.z % b.z)`"
)]
pub trait FloatVectorRem<Rhs> {}
macro_rules! float_vec_rem {
    ($($v:ty),*) => {$(
        impl<R> Rem<Val<R>> for Val<$v> where $v: FloatVectorRem<R> {
            type Output = Val<$v>;
            fn rem(self, _: Val<R>) -> Val<$v> { unreachable!("refused at compile time") }
        }
    )*};
}
float_vec_rem!(Vec2, Vec3, Vec4);

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

/// Shifts mask the amount to the bit width (`x << (s & 31)`), as release Rust and WGSL do;
/// the mask is explicit in the IR because SPIR-V leaves larger amounts undefined.
macro_rules! shifts {
    ($($t:ty),*) => {$(
        impl Shl<Val<u32>> for Val<$t> {
            type Output = Val<$t>;
            fn shl(self, rhs: Val<u32>) -> Val<$t> {
                let s: Val<u32> = binary(B::And, rhs.h, super::val::lit(31u32).h);
                binary(B::ShiftLeft, self.h, s.h)
            }
        }
        impl Shr<Val<u32>> for Val<$t> {
            type Output = Val<$t>;
            fn shr(self, rhs: Val<u32>) -> Val<$t> {
                let s: Val<u32> = binary(B::And, rhs.h, super::val::lit(31u32).h);
                binary(B::ShiftRight, self.h, s.h)
            }
        }
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
macro_rules! int_vec_scalar_rem {
    ($($v:ty, $s:ty, $n:expr);*) => {$( vec_scalar!(@one Rem, rem, B::Modulo, $v, $s, $n); )*};
}
int_vec_scalar_rem!(UVec2, u32, VectorSize::Bi; UVec3, u32, VectorSize::Tri; UVec4, u32, VectorSize::Quad;
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
    const IS_FLOAT: bool;
}
macro_rules! eq_impl { ($v:expr, $f:expr; $($t:ty),*) => { $(impl Equatable for $t { const IS_VECTOR: bool = $v; const IS_FLOAT: bool = $f; })* }; }
eq_impl!(false, false; u32, i32, usize, bool);
eq_impl!(false, true; f32);
eq_impl!(true, false; UVec2, UVec3, UVec4, IVec2, IVec3, IVec4);
eq_impl!(true, true; Vec2, Vec3, Vec4);

fn relational(fun: naga::RelationalFunction, v: naga::Handle<Expression>) -> Val<bool> {
    Val::from_handle(with(|c| {
        c.expr(Expression::Relational { fun, argument: v })
    }))
}

pub fn eq<T: Equatable>(a: Val<T>, b: Val<T>) -> Val<bool> {
    let e: Val<bool> = binary(B::Equal, a.h, b.h);
    if T::IS_VECTOR {
        relational(naga::RelationalFunction::All, e.h)
    } else {
        e
    }
}
/// `a != b` is `!(a == b)`, as in Rust: true when either float operand is NaN. naga's
/// float `NotEqual` is SPIR-V's *ordered* `OpFOrdNotEqual` (false with a NaN operand), so
/// floats are lowered as the negated ordered equality.
pub fn ne<T: Equatable>(a: Val<T>, b: Val<T>) -> Val<bool> {
    if T::IS_FLOAT {
        return unary(U::LogicalNot, eq(a, b).h);
    }
    let e: Val<bool> = binary(B::NotEqual, a.h, b.h);
    if T::IS_VECTOR {
        relational(naga::RelationalFunction::Any, e.h)
    } else {
        e
    }
}

/// `x as T` between scalar types, with Rust's meaning: float → integer truncates toward
/// zero and saturates (NaN → 0, values beyond the range → `MIN`/`MAX`); integer → float
/// rounds to nearest-even; `i32` ↔ `u32` reinterprets the bits; `bool` → integer is 0 or 1.
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
                let converted = with(|c| c.expr(Expression::As {
                    expr: v.h,
                    kind: tk.kind,
                    convert: Some(tk.width),
                }));
                if fk.kind == ScalarKind::Float && tk.kind != ScalarKind::Float {
                    return Val::from_handle(saturate_float_to_int(v.h, converted, tk.kind, None));
                }
                Val::from_handle(converted)
            }
        }
    )*)*};
}
casts!(f32 => [f32, u32, i32, usize]; u32 => [f32, u32, i32, usize]; i32 => [f32, u32, i32, usize];
    usize => [f32, u32, i32, usize]; bool => [u32, i32, usize]);

/// Completes a float → integer `As` into Rust's saturating cast. naga's backends clamp
/// the float to the closest values representable in both types first (WGSL's rule:
/// `i32(3e9) == 2147483520`, `u32(inf) == 4294967040`, NaN unspecified), so only the
/// values at or beyond 2^31 (2^32) and NaN need fixing: two selects. `size` is the vector
/// size for component-wise casts.
pub(crate) fn saturate_float_to_int(
    x: naga::Handle<Expression>,
    converted: naga::Handle<Expression>,
    kind: ScalarKind,
    size: Option<VectorSize>,
) -> naga::Handle<Expression> {
    use naga::Literal as L;
    let (limit, max) = match kind {
        ScalarKind::Sint => (L::F32(2147483648.0), L::I32(i32::MAX)),
        _ => (L::F32(4294967296.0), L::U32(u32::MAX)),
    };
    let zero = match kind {
        ScalarKind::Sint => L::I32(0),
        _ => L::U32(0),
    };
    with(|c| {
        let mut lit = |l| {
            let h = c.expr(Expression::Literal(l));
            match size {
                Some(size) => c.expr(Expression::Splat { size, value: h }),
                None => h,
            }
        };
        let (limit, max, zero) = (lit(limit), lit(max), lit(zero));
        let nan = is_nan_bits(c, x, size);
        let big = c.expr(Expression::Binary {
            op: B::GreaterEqual,
            left: x,
            right: limit,
        });
        let r = c.expr(Expression::Select {
            condition: big,
            accept: max,
            reject: converted,
        });
        c.expr(Expression::Select {
            condition: nan,
            accept: zero,
            reject: r,
        })
    })
}

/// `x` is NaN, tested on its bits (`(bits << 1) > 0xff00_0000`), which no fast-math
/// assumption about NaN can remove (drivers may fold `x != x` to false).
pub(crate) fn is_nan_bits(
    c: &mut super::builder::Ctx,
    x: naga::Handle<Expression>,
    size: Option<VectorSize>,
) -> naga::Handle<Expression> {
    use naga::Literal as L;
    let bits = c.expr(Expression::As {
        expr: x,
        kind: ScalarKind::Uint,
        convert: None,
    });
    let mut lit = |l| {
        let h = c.expr(Expression::Literal(l));
        match size {
            Some(size) => c.expr(Expression::Splat { size, value: h }),
            None => h,
        }
    };
    let (one, limit) = (lit(L::U32(1)), lit(L::U32(0xff00_0000)));
    let shifted = c.expr(Expression::Binary {
        op: B::ShiftLeft,
        left: bits,
        right: one,
    });
    c.expr(Expression::Binary {
        op: B::Greater,
        left: shifted,
        right: limit,
    })
}

pub fn cast<T, S: CastTo<T>>(v: Val<S>) -> Val<T> {
    S::cast(v)
}

pub(crate) fn bitcast<T>(v: naga::Handle<Expression>, kind: ScalarKind) -> Val<T> {
    Val::from_handle(with(|c| {
        c.expr(Expression::As {
            expr: v,
            kind,
            convert: None,
        })
    }))
}
