//! Methods of `f32`, the integer types and glam's vectors and matrices, mapped to naga
//! math functions. Each keeps the host method's name and meaning, so the host copy of a
//! kernel and the shader compute the same thing (where the two differ, e.g. `fract` and
//! `signum`, the method is built from other operations to match the host).

use naga::{Expression, Handle, MathFunction as M, ScalarKind, VectorSize};

use super::builder::with;
use super::ops::{bitcast, cast, lt, splat};
use super::types::GpuType;
use super::val::{lit, Val};
use glam::{IVec2, IVec3, IVec4, Mat3, Mat4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};

fn math<R>(fun: M, args: &[Handle<Expression>]) -> Val<R> {
    Val::from_handle(with(|c| {
        c.expr(Expression::Math {
            fun,
            arg: args[0],
            arg1: args.get(1).copied(),
            arg2: args.get(2).copied(),
            arg3: args.get(3).copied(),
        })
    }))
}

fn select<T>(cond: Val<bool>, accept: Val<T>, reject: Val<T>) -> Val<T> {
    Val::from_handle(with(|c| c.expr(Expression::Select { condition: cond.h, accept: accept.h, reject: reject.h })))
}

macro_rules! unary_math {
    ($t:ty; $($name:ident => $f:expr),*) => {
        impl Val<$t> { $(pub fn $name(self) -> Val<$t> { math($f, &[self.h]) })* }
    };
}
macro_rules! binary_math {
    ($t:ty; $($name:ident => $f:expr),*) => {
        impl Val<$t> { $(pub fn $name(self, o: Val<$t>) -> Val<$t> { math($f, &[self.h, o.h]) })* }
    };
}

unary_math!(f32; abs => M::Abs, sqrt => M::Sqrt, sin => M::Sin, cos => M::Cos, tan => M::Tan,
    asin => M::Asin, acos => M::Acos, atan => M::Atan, sinh => M::Sinh, cosh => M::Cosh,
    tanh => M::Tanh, exp => M::Exp, exp2 => M::Exp2, ln => M::Log, log2 => M::Log2,
    floor => M::Floor, ceil => M::Ceil, trunc => M::Trunc, to_radians => M::Radians,
    to_degrees => M::Degrees);
binary_math!(f32; min => M::Min, max => M::Max, powf => M::Pow, atan2 => M::Atan2);

impl Val<f32> {
    pub fn clamp(self, lo: Val<f32>, hi: Val<f32>) -> Val<f32> {
        math(M::Clamp, &[self.h, lo.h, hi.h])
    }
    pub fn mul_add(self, a: Val<f32>, b: Val<f32>) -> Val<f32> {
        math(M::Fma, &[self.h, a.h, b.h])
    }
    /// Rust's `fract` is `x - trunc(x)` (WGSL's is `x - floor(x)`).
    pub fn fract(self) -> Val<f32> {
        self - self.trunc()
    }
    /// Rust rounds half away from zero (WGSL's `round` rounds half to even).
    pub fn round(self) -> Val<f32> {
        let r = (self.abs() + lit(0.5)).floor();
        select(lt(self, lit(0.0)), -r, r)
    }
    /// Rust's `signum` is ±1 for ±0 (WGSL's `sign(0)` is 0).
    pub fn signum(self) -> Val<f32> {
        let neg = bitcast::<u32>(self.h, ScalarKind::Uint) >> lit(31u32);
        select(super::ops::eq(neg, lit(1u32)), lit(-1.0), lit(1.0))
    }
    pub fn recip(self) -> Val<f32> {
        lit(1.0f32) / self
    }
    pub fn sqrt_recip(self) -> Val<f32> {
        math(M::InverseSqrt, &[self.h])
    }
    pub fn powi(self, n: Val<i32>) -> Val<f32> {
        math(M::Pow, &[self.h, cast::<f32, i32>(n).h])
    }
    pub fn is_nan(self) -> Val<bool> {
        super::ops::ne(self, self)
    }
    pub fn is_finite(self) -> Val<bool> {
        lt(self.abs(), lit(f32::INFINITY))
    }
    pub fn is_sign_negative(self) -> Val<bool> {
        super::ops::eq(bitcast::<u32>(self.h, ScalarKind::Uint) >> lit(31u32), lit(1u32))
    }
    pub fn copysign(self, sign: Val<f32>) -> Val<f32> {
        let mag = bitcast::<u32>(self.h, ScalarKind::Uint) & lit(0x7fff_ffffu32);
        let s = bitcast::<u32>(sign.h, ScalarKind::Uint) & lit(0x8000_0000u32);
        bitcast((mag | s).h, ScalarKind::Float)
    }
    pub fn to_bits(self) -> Val<u32> {
        bitcast(self.h, ScalarKind::Uint)
    }
    pub fn from_bits(bits: Val<u32>) -> Val<f32> {
        bitcast(bits.h, ScalarKind::Float)
    }
    pub fn lerp(self, to: Val<f32>, t: Val<f32>) -> Val<f32> {
        math(M::Mix, &[self.h, to.h, t.h])
    }
}

macro_rules! int_methods {
    ($($t:ty),*) => {$(
        binary_math!($t; min => M::Min, max => M::Max);
        impl Val<$t> {
            pub fn clamp(self, lo: Val<$t>, hi: Val<$t>) -> Val<$t> { math(M::Clamp, &[self.h, lo.h, hi.h]) }
            pub fn count_ones(self) -> Val<u32> { cast::<u32, $t>(math::<$t>(M::CountOneBits, &[self.h])) }
            pub fn leading_zeros(self) -> Val<u32> { cast::<u32, $t>(math::<$t>(M::CountLeadingZeros, &[self.h])) }
            pub fn trailing_zeros(self) -> Val<u32> { cast::<u32, $t>(math::<$t>(M::CountTrailingZeros, &[self.h])) }
            pub fn reverse_bits(self) -> Val<$t> { math(M::ReverseBits, &[self.h]) }
            pub fn wrapping_add(self, o: Val<$t>) -> Val<$t> { self + o }
            pub fn wrapping_sub(self, o: Val<$t>) -> Val<$t> { self - o }
            pub fn wrapping_mul(self, o: Val<$t>) -> Val<$t> { self * o }
            pub fn pow(self, e: Val<u32>) -> Val<$t> {
                // Small exponents only make sense in kernels; unrolled square-and-multiply
                // over the 32 bits would be wasteful, so this is a loop in the shader.
                let acc = super::val::Var::new("pow_acc", lit::<$t>(1 as $t));
                super::control::for_range(lit(0u32), e, false, |_| acc.set(acc.get() * self));
                acc.get()
            }
        }
    )*};
}
int_methods!(u32, i32);

impl Val<u32> {
    pub fn rotate_left(self, n: Val<u32>) -> Val<u32> {
        let n = n & lit(31u32);
        (self << n) | (self >> ((lit(32u32) - n) & lit(31u32)))
    }
    pub fn rotate_right(self, n: Val<u32>) -> Val<u32> {
        let n = n & lit(31u32);
        (self >> n) | (self << ((lit(32u32) - n) & lit(31u32)))
    }
    pub fn is_power_of_two(self) -> Val<bool> {
        super::ops::eq(self.count_ones(), lit(1u32))
    }
}

impl Val<i32> {
    pub fn abs(self) -> Val<i32> {
        math(M::Abs, &[self.h])
    }
    pub fn signum(self) -> Val<i32> {
        math(M::Sign, &[self.h])
    }
}

impl Val<usize> {
    pub fn min(self, o: Val<usize>) -> Val<usize> {
        math(M::Min, &[self.h, o.h])
    }
    pub fn max(self, o: Val<usize>) -> Val<usize> {
        math(M::Max, &[self.h, o.h])
    }
    pub fn wrapping_add(self, o: Val<usize>) -> Val<usize> {
        self + o
    }
    pub fn wrapping_sub(self, o: Val<usize>) -> Val<usize> {
        self - o
    }
}

impl Val<bool> {
    /// `bool::then_some`-free selection: `cond.select(a, b)` is `if cond { a } else { b }`
    /// without branching (both sides are evaluated).
    pub fn select<T>(self, a: Val<T>, b: Val<T>) -> Val<T> {
        select(self, a, b)
    }
}

fn compose<T: GpuType>(parts: &[Handle<Expression>]) -> Val<T> {
    Val::from_handle(with(|c| {
        let ty = T::naga_type(&mut c.module);
        c.expr(Expression::Compose { ty, components: parts.to_vec() })
    }))
}

fn swizzle<R>(v: Handle<Expression>, size: VectorSize, pattern: [naga::SwizzleComponent; 4]) -> Val<R> {
    Val::from_handle(with(|c| c.expr(Expression::Swizzle { size, vector: v, pattern })))
}

macro_rules! vec_common {
    ($v:ty, $s:ty, $n:expr, [$($c:ident),+]) => {
        impl Val<$v> {
            pub fn new($($c: Val<$s>),+) -> Val<$v> { compose(&[$($c.h),+]) }
            pub fn splat(x: Val<$s>) -> Val<$v> { Val::from_handle(splat($n, x)) }
            pub fn min(self, o: Val<$v>) -> Val<$v> { math(M::Min, &[self.h, o.h]) }
            pub fn max(self, o: Val<$v>) -> Val<$v> { math(M::Max, &[self.h, o.h]) }
            pub fn clamp(self, lo: Val<$v>, hi: Val<$v>) -> Val<$v> { math(M::Clamp, &[self.h, lo.h, hi.h]) }
            pub fn min_element(self) -> Val<$s> { let v = [$(super::val::field(self, |s: &$v| &s.$c)),+]; v.into_iter().reduce(|a, b| a.min(b)).unwrap() }
            pub fn max_element(self) -> Val<$s> { let v = [$(super::val::field(self, |s: &$v| &s.$c)),+]; v.into_iter().reduce(|a, b| a.max(b)).unwrap() }
            pub fn element_sum(self) -> Val<$s> { let v = [$(super::val::field(self, |s: &$v| &s.$c)),+]; v.into_iter().reduce(|a, b| a + b).unwrap() }
        }
    };
}
vec_common!(Vec2, f32, VectorSize::Bi, [x, y]);
vec_common!(Vec3, f32, VectorSize::Tri, [x, y, z]);
vec_common!(Vec4, f32, VectorSize::Quad, [x, y, z, w]);
vec_common!(UVec2, u32, VectorSize::Bi, [x, y]);
vec_common!(UVec3, u32, VectorSize::Tri, [x, y, z]);
vec_common!(UVec4, u32, VectorSize::Quad, [x, y, z, w]);
vec_common!(IVec2, i32, VectorSize::Bi, [x, y]);
vec_common!(IVec3, i32, VectorSize::Tri, [x, y, z]);
vec_common!(IVec4, i32, VectorSize::Quad, [x, y, z, w]);

macro_rules! vec_float {
    ($($v:ty),*) => {$(
        impl Val<$v> {
            pub fn dot(self, o: Val<$v>) -> Val<f32> { math(M::Dot, &[self.h, o.h]) }
            pub fn length(self) -> Val<f32> { math(M::Length, &[self.h]) }
            pub fn length_squared(self) -> Val<f32> { self.dot(self) }
            pub fn length_recip(self) -> Val<f32> { lit(1.0f32) / self.length() }
            pub fn distance(self, o: Val<$v>) -> Val<f32> { math(M::Distance, &[self.h, o.h]) }
            pub fn normalize(self) -> Val<$v> { math(M::Normalize, &[self.h]) }
            pub fn abs(self) -> Val<$v> { math(M::Abs, &[self.h]) }
            pub fn floor(self) -> Val<$v> { math(M::Floor, &[self.h]) }
            pub fn ceil(self) -> Val<$v> { math(M::Ceil, &[self.h]) }
            pub fn recip(self) -> Val<$v> { lit(1.0f32) / self }
            pub fn mul_add(self, a: Val<$v>, b: Val<$v>) -> Val<$v> { math(M::Fma, &[self.h, a.h, b.h]) }
            pub fn lerp(self, to: Val<$v>, t: Val<f32>) -> Val<$v> { self + (to - self) * t }
            pub fn reflect(self, normal: Val<$v>) -> Val<$v> { math(M::Reflect, &[self.h, normal.h]) }
        }
    )*};
}
vec_float!(Vec2, Vec3, Vec4);

use naga::SwizzleComponent::{W, X, Y, Z};
impl Val<Vec3> {
    pub fn cross(self, o: Val<Vec3>) -> Val<Vec3> {
        math(M::Cross, &[self.h, o.h])
    }
    pub fn extend(self, w: Val<f32>) -> Val<Vec4> {
        compose(&[self.h, w.h])
    }
    pub fn truncate(self) -> Val<Vec2> {
        swizzle(self.h, VectorSize::Bi, [X, Y, X, X])
    }
    pub fn xy(self) -> Val<Vec2> {
        self.truncate()
    }
    pub fn as_uvec3(self) -> Val<UVec3> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Uint, convert: Some(4) })))
    }
    pub fn as_ivec3(self) -> Val<IVec3> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Sint, convert: Some(4) })))
    }
    pub fn any_orthonormal_vector(self) -> Val<Vec3> {
        // Duff et al. 2017, as glam does it.
        let x = super::val::field(self, |s: &Vec3| &s.x);
        let y = super::val::field(self, |s: &Vec3| &s.y);
        let z = super::val::field(self, |s: &Vec3| &s.z);
        let sign = lit(1.0f32).copysign(z);
        let a = lit(-1.0f32) / (sign + z);
        let b = x * y * a;
        Val::<Vec3>::new(b, sign + y * y * a, -y)
    }
}
impl Val<Vec4> {
    pub fn truncate(self) -> Val<Vec3> {
        swizzle(self.h, VectorSize::Tri, [X, Y, Z, X])
    }
    pub fn xyz(self) -> Val<Vec3> {
        self.truncate()
    }
    pub fn xy(self) -> Val<Vec2> {
        swizzle(self.h, VectorSize::Bi, [X, Y, X, X])
    }
    pub fn zw(self) -> Val<Vec2> {
        swizzle(self.h, VectorSize::Bi, [Z, W, X, X])
    }
}
impl Val<Vec2> {
    pub fn extend(self, z: Val<f32>) -> Val<Vec3> {
        compose(&[self.h, z.h])
    }
    pub fn perp_dot(self, o: Val<Vec2>) -> Val<f32> {
        let (ax, ay) = (super::val::field(self, |s: &Vec2| &s.x), super::val::field(self, |s: &Vec2| &s.y));
        let (bx, by) = (super::val::field(o, |s: &Vec2| &s.x), super::val::field(o, |s: &Vec2| &s.y));
        ax * by - ay * bx
    }
    pub fn as_uvec2(self) -> Val<UVec2> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Uint, convert: Some(4) })))
    }
}
impl Val<UVec2> {
    pub fn as_vec2(self) -> Val<Vec2> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Float, convert: Some(4) })))
    }
}
impl Val<UVec3> {
    pub fn as_vec3(self) -> Val<Vec3> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Float, convert: Some(4) })))
    }
    pub fn extend(self, w: Val<u32>) -> Val<UVec4> {
        compose(&[self.h, w.h])
    }
    pub fn xy(self) -> Val<UVec2> {
        swizzle(self.h, VectorSize::Bi, [X, Y, X, X])
    }
}
impl Val<IVec3> {
    pub fn as_vec3(self) -> Val<Vec3> {
        Val::from_handle(with(|c| c.expr(Expression::As { expr: self.h, kind: ScalarKind::Float, convert: Some(4) })))
    }
}

impl Val<Mat3> {
    pub fn from_cols(a: Val<Vec3>, b: Val<Vec3>, c: Val<Vec3>) -> Val<Mat3> {
        compose(&[a.h, b.h, c.h])
    }
    pub fn transpose(self) -> Val<Mat3> {
        math(M::Transpose, &[self.h])
    }
    pub fn determinant(self) -> Val<f32> {
        math(M::Determinant, &[self.h])
    }
    pub fn mul_vec3(self, v: Val<Vec3>) -> Val<Vec3> {
        self * v
    }
}
impl Val<Mat4> {
    pub fn from_cols(a: Val<Vec4>, b: Val<Vec4>, c: Val<Vec4>, d: Val<Vec4>) -> Val<Mat4> {
        compose(&[a.h, b.h, c.h, d.h])
    }
    pub fn transpose(self) -> Val<Mat4> {
        math(M::Transpose, &[self.h])
    }
    pub fn determinant(self) -> Val<f32> {
        math(M::Determinant, &[self.h])
    }
    pub fn mul_vec4(self, v: Val<Vec4>) -> Val<Vec4> {
        self * v
    }
}
