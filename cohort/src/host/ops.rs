//! The host form of kernel arithmetic. `#[kernel]` and `#[kernel_fn]` keep the function
//! for the host, with every `+ - * / % << >>` (and their compound assignments), unary `-`,
//! `.abs()` and `.pow(n)` routed through these functions, so that the host computes what
//! the GPU computes in any build profile (docs/LANGUAGE.md, sections 3 and 4):
//!
//! - integer `+ - *`, negation, `abs` and `pow` wrap (as release Rust; debug Rust panics);
//! - `usize` is 32 bits wide in kernels: its arithmetic wraps modulo 2^32 here too;
//! - `x / 0 == x`, `x % 0 == 0`, `MIN / -1 == MIN`, `MIN % -1 == 0` (WGSL's definition,
//!   which naga's SPIR-V writer also implements); Rust would panic;
//! - shift amounts are masked to the bit width (`x << (s & 31)`, release Rust);
//! - floats are untouched: the host's IEEE operations are the reference.
//!
//! Each trait is implemented exactly for the operand types that `cohort::ir` implements,
//! so a kernel that type-checks for the GPU type-checks here and vice versa.

use glam::{IVec2, IVec3, IVec4, Mat3, Mat4, UVec2, UVec3, UVec4, Vec2, Vec3, Vec4};

macro_rules! op_trait {
    ($tr:ident, $m:ident, $f:ident, $sym:literal, $msg:literal, $label:literal) => {
        #[doc = concat!("`a ", $sym, " b` in the host form of a kernel.")]
        #[diagnostic::on_unimplemented(message = $msg, label = $label)]
        pub trait $tr<Rhs> {
            type Output;
            fn $m(self, rhs: Rhs) -> Self::Output;
        }
        #[doc = concat!("`a ", $sym, " b` in the host form of a kernel.")]
        #[inline]
        pub fn $f<A: $tr<B>, B>(a: A, b: B) -> A::Output {
            a.$m(b)
        }
    };
}
op_trait!(
    KAdd,
    k_add,
    add,
    "+",
    "cannot compute `{Self} + {Rhs}` in a kernel",
    "no implementation for `{Self} + {Rhs}`"
);
op_trait!(
    KSub,
    k_sub,
    sub,
    "-",
    "cannot compute `{Self} - {Rhs}` in a kernel",
    "no implementation for `{Self} - {Rhs}`"
);
op_trait!(
    KMul,
    k_mul,
    mul,
    "*",
    "cannot compute `{Self} * {Rhs}` in a kernel",
    "no implementation for `{Self} * {Rhs}`"
);
op_trait!(
    KDiv,
    k_div,
    div,
    "/",
    "cannot compute `{Self} / {Rhs}` in a kernel",
    "no implementation for `{Self} / {Rhs}`"
);
op_trait!(
    KRem,
    k_rem,
    rem,
    "%",
    "cannot compute `{Self} % {Rhs}` in a kernel",
    "no implementation for `{Self} % {Rhs}`"
);
op_trait!(
    KShl,
    k_shl,
    shl,
    "<<",
    "cannot compute `{Self} << {Rhs}` in a kernel",
    "no implementation for `{Self} << {Rhs}`"
);
op_trait!(
    KShr,
    k_shr,
    shr,
    ">>",
    "cannot compute `{Self} >> {Rhs}` in a kernel",
    "no implementation for `{Self} >> {Rhs}`"
);

/// `-a` in the host form of a kernel.
pub trait KNeg {
    type Output;
    fn k_neg(self) -> Self::Output;
}
#[inline]
pub fn neg<A: KNeg>(a: A) -> A::Output {
    a.k_neg()
}
/// `a.abs()` in the host form of a kernel (`i32::MIN.abs() == i32::MIN`).
pub trait KAbs {
    type Output;
    fn k_abs(self) -> Self::Output;
}
#[inline]
pub fn abs<A: KAbs>(a: A) -> A::Output {
    a.k_abs()
}
/// `a.pow(n)` in the host form of a kernel (wrapping).
pub trait KPow {
    type Output;
    fn k_pow(self, n: u32) -> Self::Output;
}
#[inline]
pub fn pow<A: KPow>(a: A, n: u32) -> A::Output {
    a.k_pow(n)
}

macro_rules! impl_op {
    ($tr:ident, $m:ident, $l:ty, $r:ty => $out:ty, |$a:ident, $b:ident| $e:expr) => {
        impl $tr<$r> for $l {
            type Output = $out;
            #[inline]
            fn $m(self, rhs: $r) -> $out {
                let ($a, $b) = (self, rhs);
                $e
            }
        }
    };
}

// Floats, float vectors and matrices: the host's own operations.
macro_rules! float_like {
    ($($t:ty),*) => {$(
        impl_op!(KAdd, k_add, $t, $t => $t, |a, b| a + b);
        impl_op!(KSub, k_sub, $t, $t => $t, |a, b| a - b);
        impl_op!(KMul, k_mul, $t, $t => $t, |a, b| a * b);
        impl_op!(KDiv, k_div, $t, $t => $t, |a, b| a / b);
        impl KNeg for $t { type Output = $t; #[inline] fn k_neg(self) -> $t { -self } }
    )*};
}
float_like!(f32, Vec2, Vec3, Vec4);
impl_op!(KRem, k_rem, f32, f32 => f32, |a, b| a % b);
macro_rules! float_vec_scalar {
    ($($v:ty),*) => {$(
        impl_op!(KAdd, k_add, $v, f32 => $v, |a, b| a + b);
        impl_op!(KSub, k_sub, $v, f32 => $v, |a, b| a - b);
        impl_op!(KMul, k_mul, $v, f32 => $v, |a, b| a * b);
        impl_op!(KDiv, k_div, $v, f32 => $v, |a, b| a / b);
        impl_op!(KAdd, k_add, f32, $v => $v, |a, b| a + b);
        impl_op!(KSub, k_sub, f32, $v => $v, |a, b| a - b);
        impl_op!(KMul, k_mul, f32, $v => $v, |a, b| a * b);
        impl_op!(KDiv, k_div, f32, $v => $v, |a, b| a / b);
        impl KAbs for $v { type Output = $v; #[inline] fn k_abs(self) -> $v { self.abs() } }
    )*};
}
float_vec_scalar!(Vec2, Vec3, Vec4);
impl KAbs for f32 {
    type Output = f32;
    #[inline]
    fn k_abs(self) -> f32 {
        self.abs()
    }
}
impl_op!(KMul, k_mul, Mat3, Vec3 => Vec3, |a, b| a * b);
impl_op!(KMul, k_mul, Mat4, Vec4 => Vec4, |a, b| a * b);
impl_op!(KMul, k_mul, Mat3, Mat3 => Mat3, |a, b| a * b);
impl_op!(KMul, k_mul, Mat4, Mat4 => Mat4, |a, b| a * b);
impl_op!(KMul, k_mul, Mat3, f32 => Mat3, |a, b| a * b);
impl_op!(KMul, k_mul, Mat4, f32 => Mat4, |a, b| a * b);
impl_op!(KAdd, k_add, Mat3, Mat3 => Mat3, |a, b| a + b);
impl_op!(KAdd, k_add, Mat4, Mat4 => Mat4, |a, b| a + b);
impl_op!(KSub, k_sub, Mat3, Mat3 => Mat3, |a, b| a - b);
impl_op!(KSub, k_sub, Mat4, Mat4 => Mat4, |a, b| a - b);

/// Scalar integer semantics, shared by scalars and vector components.
trait IntSem: Copy {
    fn w_add(self, o: Self) -> Self;
    fn w_sub(self, o: Self) -> Self;
    fn w_mul(self, o: Self) -> Self;
    fn d_div(self, o: Self) -> Self;
    fn d_rem(self, o: Self) -> Self;
}
macro_rules! int_sem {
    ($($t:ty),*) => {$(
        impl IntSem for $t {
            #[inline] fn w_add(self, o: Self) -> Self { self.wrapping_add(o) }
            #[inline] fn w_sub(self, o: Self) -> Self { self.wrapping_sub(o) }
            #[inline] fn w_mul(self, o: Self) -> Self { self.wrapping_mul(o) }
            #[inline] fn d_div(self, o: Self) -> Self { if o == 0 { self } else { self.wrapping_div(o) } }
            #[inline] fn d_rem(self, o: Self) -> Self { if o == 0 { 0 } else { self.wrapping_rem(o) } }
        }
    )*};
}
int_sem!(u32, i32);

macro_rules! int_scalar {
    ($($t:ty),*) => {$(
        impl_op!(KAdd, k_add, $t, $t => $t, |a, b| a.w_add(b));
        impl_op!(KSub, k_sub, $t, $t => $t, |a, b| a.w_sub(b));
        impl_op!(KMul, k_mul, $t, $t => $t, |a, b| a.w_mul(b));
        impl_op!(KDiv, k_div, $t, $t => $t, |a, b| a.d_div(b));
        impl_op!(KRem, k_rem, $t, $t => $t, |a, b| a.d_rem(b));
        impl_op!(KShl, k_shl, $t, u32 => $t, |a, b| a.wrapping_shl(b));
        impl_op!(KShr, k_shr, $t, u32 => $t, |a, b| a.wrapping_shr(b));
        impl KPow for $t { type Output = $t; #[inline] fn k_pow(self, n: u32) -> $t { self.wrapping_pow(n) } }
    )*};
}
int_scalar!(u32, i32);
impl KNeg for i32 {
    type Output = i32;
    #[inline]
    fn k_neg(self) -> i32 {
        self.wrapping_neg()
    }
}
impl KAbs for i32 {
    type Output = i32;
    #[inline]
    fn k_abs(self) -> i32 {
        self.wrapping_abs()
    }
}

// usize: 32 bits in kernels.
fn u(x: usize) -> u32 {
    x as u32
}
impl_op!(KAdd, k_add, usize, usize => usize, |a, b| u(a).w_add(u(b)) as usize);
impl_op!(KSub, k_sub, usize, usize => usize, |a, b| u(a).w_sub(u(b)) as usize);
impl_op!(KMul, k_mul, usize, usize => usize, |a, b| u(a).w_mul(u(b)) as usize);
impl_op!(KDiv, k_div, usize, usize => usize, |a, b| u(a).d_div(u(b)) as usize);
impl_op!(KRem, k_rem, usize, usize => usize, |a, b| u(a).d_rem(u(b)) as usize);

macro_rules! int_vec {
    ($($v:ty, $s:ty);*) => {$(
        impl_op!(KAdd, k_add, $v, $v => $v, |a, b| zip(a, b, <$s>::w_add));
        impl_op!(KSub, k_sub, $v, $v => $v, |a, b| zip(a, b, <$s>::w_sub));
        impl_op!(KMul, k_mul, $v, $v => $v, |a, b| zip(a, b, <$s>::w_mul));
        impl_op!(KDiv, k_div, $v, $v => $v, |a, b| zip(a, b, <$s>::d_div));
        impl_op!(KRem, k_rem, $v, $v => $v, |a, b| zip(a, b, <$s>::d_rem));
        impl_op!(KAdd, k_add, $v, $s => $v, |a, b| zip(a, <$v>::splat(b), <$s>::w_add));
        impl_op!(KSub, k_sub, $v, $s => $v, |a, b| zip(a, <$v>::splat(b), <$s>::w_sub));
        impl_op!(KMul, k_mul, $v, $s => $v, |a, b| zip(a, <$v>::splat(b), <$s>::w_mul));
        impl_op!(KDiv, k_div, $v, $s => $v, |a, b| zip(a, <$v>::splat(b), <$s>::d_div));
        impl_op!(KRem, k_rem, $v, $s => $v, |a, b| zip(a, <$v>::splat(b), <$s>::d_rem));
        impl_op!(KAdd, k_add, $s, $v => $v, |a, b| zip(<$v>::splat(a), b, <$s>::w_add));
        impl_op!(KSub, k_sub, $s, $v => $v, |a, b| zip(<$v>::splat(a), b, <$s>::w_sub));
        impl_op!(KMul, k_mul, $s, $v => $v, |a, b| zip(<$v>::splat(a), b, <$s>::w_mul));
        impl_op!(KDiv, k_div, $s, $v => $v, |a, b| zip(<$v>::splat(a), b, <$s>::d_div));
        impl_op!(KRem, k_rem, $s, $v => $v, |a, b| zip(<$v>::splat(a), b, <$s>::d_rem));
    )*};
}
int_vec!(UVec2, u32; UVec3, u32; UVec4, u32; IVec2, i32; IVec3, i32; IVec4, i32);
macro_rules! ivec_neg {
    ($($v:ty),*) => {$(
        impl KNeg for $v { type Output = $v; #[inline] fn k_neg(self) -> $v { <$v>::ZERO.wrapping_sub(self) } }
    )*};
}
ivec_neg!(IVec2, IVec3, IVec4);

/// Component-wise `f` over two integer vectors.
trait IntVec: Copy {
    type S: Copy;
    fn map2(self, o: Self, f: impl Fn(Self::S, Self::S) -> Self::S) -> Self;
}
macro_rules! int_vec_map {
    ($($v:ty, $s:ty);*) => {$(
        impl IntVec for $v {
            type S = $s;
            #[inline]
            fn map2(self, o: Self, f: impl Fn($s, $s) -> $s) -> Self {
                let (mut a, b) = (self.to_array(), o.to_array());
                for (x, y) in a.iter_mut().zip(b) {
                    *x = f(*x, y);
                }
                <$v>::from_array(a)
            }
        }
    )*};
}
int_vec_map!(UVec2, u32; UVec3, u32; UVec4, u32; IVec2, i32; IVec3, i32; IVec4, i32);
#[inline]
fn zip<V: IntVec>(a: V, b: V, f: impl Fn(V::S, V::S) -> V::S) -> V {
    a.map2(b, f)
}

// References to values (helper parameters `x: &f32`) compute on the value.
macro_rules! by_ref {
    ($($tr:ident, $m:ident);*) => {$(
        impl<T: Copy + $tr<R>, R> $tr<R> for &T {
            type Output = T::Output;
            #[inline]
            fn $m(self, rhs: R) -> T::Output {
                (*self).$m(rhs)
            }
        }
    )*};
}
by_ref!(KAdd, k_add; KSub, k_sub; KMul, k_mul; KDiv, k_div; KRem, k_rem; KShl, k_shl; KShr, k_shr);
impl<T: Copy + KNeg> KNeg for &T {
    type Output = T::Output;
    #[inline]
    fn k_neg(self) -> T::Output {
        (*self).k_neg()
    }
}
impl<T: Copy + KAbs> KAbs for &T {
    type Output = T::Output;
    #[inline]
    fn k_abs(self) -> T::Output {
        (*self).k_abs()
    }
}
impl<T: Copy + KPow> KPow for &T {
    type Output = T::Output;
    #[inline]
    fn k_pow(self, n: u32) -> T::Output {
        (*self).k_pow(n)
    }
}

// `%` on float vectors is refused (see `cohort::ir::ops::FloatVectorRem`); these impls
// exist only to carry the refusal's message to the host form's error.
macro_rules! float_vec_rem_refused {
    ($($v:ty),*) => {$(
        impl<R> KRem<R> for $v where $v: crate::ir::ops::FloatVectorRem<R> {
            type Output = $v;
            fn k_rem(self, _: R) -> $v {
                unreachable!("refused at compile time")
            }
        }
    )*};
}
float_vec_rem_refused!(Vec2, Vec3, Vec4);
