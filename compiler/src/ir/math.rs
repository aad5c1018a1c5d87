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
    Val::from_handle(with(|c| {
        c.expr(Expression::Select {
            condition: cond.h,
            accept: accept.h,
            reject: reject.h,
        })
    }))
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

unary_math!(f32; abs => M::Abs, floor => M::Floor, ceil => M::Ceil, trunc => M::Trunc,
    round_ties_even => M::Round, exp => M::Exp, exp2 => M::Exp2);

fn fbits(x: Val<f32>) -> Val<u32> {
    bitcast(x.h, ScalarKind::Uint)
}
fn ffrom_bits(b: Val<u32>) -> Val<f32> {
    bitcast(b.h, ScalarKind::Float)
}
fn or(a: Val<bool>, b: Val<bool>) -> Val<bool> {
    super::ops::binary(naga::BinaryOperator::LogicalOr, a.h, b.h)
}
fn and(a: Val<bool>, b: Val<bool>) -> Val<bool> {
    super::ops::binary(naga::BinaryOperator::LogicalAnd, a.h, b.h)
}
fn not(a: Val<bool>) -> Val<bool> {
    super::ops::unary(naga::UnaryOperator::LogicalNot, a.h)
}

impl Val<f32> {
    /// `f32::min`: the non-NaN operand when one is NaN (not SPIR-V's `FMin`, which is
    /// undefined then): `if b < a || a is NaN { b } else { a }`.
    pub fn min(self, o: Val<f32>) -> Val<f32> {
        select(or(lt(o, self), self.is_nan()), o, self)
    }
    /// `f32::max`: the non-NaN operand when one is NaN.
    pub fn max(self, o: Val<f32>) -> Val<f32> {
        select(or(super::ops::gt(o, self), self.is_nan()), o, self)
    }
    /// `f32::clamp` as std writes it: `if x < lo { x = lo } if x > hi { x = hi }`, so a NaN
    /// `x` stays NaN. (Rust panics when `lo > hi` or a bound is NaN; kernels cannot panic and
    /// compute this expression.)
    pub fn clamp(self, lo: Val<f32>, hi: Val<f32>) -> Val<f32> {
        let r = select(lt(self, lo), lo, self);
        select(super::ops::gt(r, hi), hi, r)
    }
    /// Rust's `mul_add` is fused (one rounding); naga's `fma`. Vulkan and WGSL allow a driver
    /// to evaluate it as `a * b + c` (docs/LANGUAGE.md).
    pub fn mul_add(self, a: Val<f32>, b: Val<f32>) -> Val<f32> {
        math(M::Fma, &[self.h, a.h, b.h])
    }
    /// Rust's `fract` is `x - trunc(x)` (WGSL's is `x - floor(x)`).
    pub fn fract(self) -> Val<f32> {
        self - self.trunc()
    }
    /// Rust rounds half away from zero (WGSL's `round` rounds half to even):
    /// `t = trunc(x); t + (|x - t| >= 0.5 ? copysign(1, x) : 0)`. `x - t` is exact, so
    /// 0.49999997 and 8388609 round right (unlike `floor(x + 0.5)`), and the sign of zero is
    /// kept (`round(-0.4) == -0.0`).
    pub fn round(self) -> Val<f32> {
        let t = self.trunc();
        let d = (self - t).abs();
        let step = lit(1.0f32).copysign(self);
        select(super::ops::ge(d, lit(0.5)), t + step, t)
    }
    /// Rust's `signum`: ±1 by the sign bit (so ±1 for ±0), NaN for NaN.
    pub fn signum(self) -> Val<f32> {
        select(self.is_nan(), self, lit(1.0f32).copysign(self))
    }
    pub fn recip(self) -> Val<f32> {
        lit(1.0f32) / self
    }
    pub fn sqrt_recip(self) -> Val<f32> {
        math(M::InverseSqrt, &[self.h])
    }
    /// `sqrt`; GLSL's is undefined below zero: NaN there (as Rust), and `sqrt(-0.0) == -0.0`.
    pub fn sqrt(self) -> Val<f32> {
        let r: Val<f32> = math(M::Sqrt, &[self.h]);
        let r = select(super::ops::eq(self, lit(0.0)), self, r);
        select(lt(self, lit(0.0)), lit(f32::NAN), r)
    }
    /// `ln`/`log2`: GLSL's are undefined at and below zero: `-inf` at ±0, NaN below (as Rust).
    fn log_guarded(self, f: M) -> Val<f32> {
        let r: Val<f32> = math(f, &[self.h]);
        let r = select(super::ops::eq(self, lit(0.0)), lit(f32::NEG_INFINITY), r);
        select(or(lt(self, lit(0.0)), self.is_nan()), lit(f32::NAN), r)
    }
    pub fn ln(self) -> Val<f32> {
        self.log_guarded(M::Log)
    }
    pub fn log2(self) -> Val<f32> {
        self.log_guarded(M::Log2)
    }
    /// An odd function with `f(±0) == ±0` (`sin`, `tan`, `asin`, `atan`, `sinh`, `tanh`):
    /// ±0 and NaN pass through unchanged (drivers drop the sign of zero and may turn NaN
    /// into a number).
    fn odd_guarded(self, r: Val<f32>) -> Val<f32> {
        select(or(super::ops::eq(self, lit(0.0)), self.is_nan()), self, r)
    }
    /// `sin`/`cos`/`tan` of ±inf are NaN in Rust; GLSL leaves them undefined.
    fn trig_guarded(self, f: M) -> Val<f32> {
        let r: Val<f32> = math(f, &[self.h]);
        select(self.is_finite(), r, lit(f32::NAN))
    }
    pub fn sin(self) -> Val<f32> {
        self.odd_guarded(self.trig_guarded(M::Sin))
    }
    pub fn cos(self) -> Val<f32> {
        self.trig_guarded(M::Cos)
    }
    pub fn tan(self) -> Val<f32> {
        self.odd_guarded(self.trig_guarded(M::Tan))
    }
    /// `asin`/`acos` outside [-1, 1] are NaN in Rust; GLSL leaves them undefined.
    fn arc_guarded(self, f: M) -> Val<f32> {
        let r: Val<f32> = math(f, &[self.h]);
        select(super::ops::le(self.abs(), lit(1.0)), r, lit(f32::NAN))
    }
    pub fn asin(self) -> Val<f32> {
        self.odd_guarded(self.arc_guarded(M::Asin))
    }
    pub fn acos(self) -> Val<f32> {
        self.arc_guarded(M::Acos)
    }
    pub fn atan(self) -> Val<f32> {
        self.odd_guarded(math(M::Atan, &[self.h]))
    }
    pub fn tanh(self) -> Val<f32> {
        self.odd_guarded(math(M::Tanh, &[self.h]))
    }
    /// `sinh`/`cosh`: drivers compute `(e^x ∓ e^-x) / 2`, which overflows for |x| > 88.7
    /// while the result is finite up to |x| < 89.4: there, `e^(|x| - ln 2)`.
    fn hyperbolic_large(self) -> (Val<bool>, Val<f32>) {
        let ax = self.abs();
        (
            super::ops::gt(ax, lit(88.0)),
            (ax - lit(std::f32::consts::LN_2)).exp(),
        )
    }
    pub fn sinh(self) -> Val<f32> {
        let (large, big) = self.hyperbolic_large();
        let r = select(large, big.copysign(self), math(M::Sinh, &[self.h]));
        self.odd_guarded(r)
    }
    pub fn cosh(self) -> Val<f32> {
        let (large, big) = self.hyperbolic_large();
        select(
            or(large, self.is_nan()),
            select(self.is_nan(), self, big),
            math(M::Cosh, &[self.h]),
        )
    }
    /// Rust's `atan2` (C's `atan2f`): odd in `self` (so the sign of a zero `self` is kept),
    /// with C's values where GLSL's `atan` is undefined or loses them: `self == ±0`
    /// (±0 or ±π by the sign of `x`), infinities (±π/4, ±3π/4, ±π/2, ±0, ±π) and NaN.
    pub fn atan2(self, x: Val<f32>) -> Val<f32> {
        use super::ops::eq;
        use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
        let y = self;
        let ay = y.abs();
        let inf = lit(f32::INFINITY);
        let core: Val<f32> = math(M::Atan2, &[ay.h, x.h]);
        let x_neg = x.is_sign_negative();
        let r = select(eq(ay, lit(0.0)), select(x_neg, lit(PI), lit(0.0f32)), core);
        let y_inf = eq(ay, inf);
        let x_inf = eq(x.abs(), inf);
        let r = select(
            and(x_inf, not(y_inf)),
            select(x_neg, lit(PI), lit(0.0f32)),
            r,
        );
        let both = select(x_neg, lit(3.0 * FRAC_PI_4), lit(FRAC_PI_4));
        let r = select(y_inf, select(x_inf, both, lit(FRAC_PI_2)), r);
        let r = r.copysign(y);
        select(or(x.is_nan(), y.is_nan()), lit(f32::NAN), r)
    }
    /// Rust's `to_degrees`: `x * 57.29578` (one rounding, the same constant).
    pub fn to_degrees(self) -> Val<f32> {
        self * lit(57.295_78_f32)
    }
    /// Rust's `to_radians`: `x * (PI / 180.0)` with the quotient rounded to `f32`.
    pub fn to_radians(self) -> Val<f32> {
        self * lit(std::f32::consts::PI / 180.0f32)
    }
    /// Rust's `powi` (LLVM's `__powisf2`): square-and-multiply over the bits of `|n|`, then
    /// `1 / r` for negative `n`, so the GPU rounds exactly as the host does.
    pub fn powi(self, n: Val<i32>) -> Val<f32> {
        use super::control::{break_, if_, loop_};
        use super::val::Var;
        let neg = lt(n, lit(0i32));
        let b = Var::new("powi_n", n);
        let a = Var::new("powi_a", self);
        let r = Var::new("powi_r", lit(1.0f32));
        loop_(|| {
            let bv = b.get();
            if_(
                super::ops::ne(bv & lit(1i32), lit(0i32)),
                || r.set(r.get() * a.get()),
                || {},
            );
            // `b /= 2` truncates toward zero, as in C.
            let half = bv / lit(2i32);
            b.set(half);
            if_(super::ops::eq(half, lit(0i32)), break_, || {});
            a.set(a.get() * a.get());
        });
        select(neg, lit(1.0f32) / r.get(), r.get())
    }
    /// Rust's `powf` (C's `powf`): the special cases of C99 Annex F exactly (`x^0 == 1`,
    /// `1^y == 1`, NaN, zeros, infinities, negative bases with integer exponents); other
    /// values through `pow(|x|, y)` (GLSL's, defined for `|x| > 0`), within the driver's
    /// precision (docs/LANGUAGE.md).
    pub fn powf(self, y: Val<f32>) -> Val<f32> {
        use super::ops::{eq, gt};
        let x = self;
        let ax = x.abs();
        let ay = y.abs();
        let inf = lit(f32::INFINITY);
        let y_int = eq(y.trunc(), y);
        // |y| >= 2^24 is an even integer; below, test the low bit of the integer value.
        let y_odd = and(
            and(y_int, lt(ay, lit(16777216.0f32))),
            eq(cast::<u32, i32>(cast::<i32, f32>(y)) & lit(1u32), lit(1u32)),
        );
        let x_neg = x.is_sign_negative();
        let base_ok = and(gt(ax, lit(0.0)), lt(ax, inf));
        let safe = select(base_ok, ax, lit(1.0f32));
        let core: Val<f32> = math(M::Pow, &[safe.h, y.h]);
        let y_neg = lt(y, lit(0.0));
        // |x| = 0: +inf for y < 0, +0 for y > 0; |x| = inf: the reverse.
        let mag = select(eq(ax, lit(0.0)), select(y_neg, inf, lit(0.0f32)), core);
        let mag = select(eq(ax, inf), select(y_neg, lit(0.0f32), inf), mag);
        // y = ±inf: 1 for |x| == 1, else 0 or inf by whether |x| < 1 and y < 0 agree.
        let y_inf = eq(ay, inf);
        let grows = eq(lt(ax, lit(1.0)), y_neg);
        let mag = select(
            y_inf,
            select(
                eq(ax, lit(1.0)),
                lit(1.0f32),
                select(grows, inf, lit(0.0f32)),
            ),
            mag,
        );
        // The sign: negative base to an odd integer power.
        let r = select(and(x_neg, y_odd), -mag, mag);
        // NaN: a NaN operand, or a finite negative base to a non-integer power.
        let neg_base_frac = and(and(lt(x, lit(0.0)), x.is_finite()), not(y_int));
        let r = select(
            or(or(x.is_nan(), y.is_nan()), neg_base_frac),
            lit(f32::NAN),
            r,
        );
        // x^1 == x exactly (drivers' exp2(log2(x)) is not), x^±0 == 1 and 1^y == 1, even
        // for NaN.
        let r = select(eq(y, lit(1.0)), x, r);
        select(or(eq(y, lit(0.0)), eq(x, lit(1.0))), lit(1.0f32), r)
    }
    /// `is_nan`, `is_finite`, `is_infinite`, ...: tests on the bits, which drivers cannot
    /// fold away under "no NaN/inf" fast-math assumptions.
    pub fn is_nan(self) -> Val<bool> {
        Val::from_handle(with(|c| super::ops::is_nan_bits(c, self.h, None)))
    }
    pub fn is_finite(self) -> Val<bool> {
        lt(fbits(self) & lit(0x7fff_ffffu32), lit(0x7f80_0000u32))
    }
    pub fn is_infinite(self) -> Val<bool> {
        super::ops::eq(fbits(self) & lit(0x7fff_ffffu32), lit(0x7f80_0000u32))
    }
    pub fn is_normal(self) -> Val<bool> {
        let e = fbits(self) & lit(0x7f80_0000u32);
        and(
            super::ops::ne(e, lit(0u32)),
            super::ops::ne(e, lit(0x7f80_0000u32)),
        )
    }
    pub fn is_subnormal(self) -> Val<bool> {
        let b = fbits(self);
        and(
            super::ops::eq(b & lit(0x7f80_0000u32), lit(0u32)),
            super::ops::ne(b & lit(0x007f_ffffu32), lit(0u32)),
        )
    }
    pub fn is_sign_negative(self) -> Val<bool> {
        super::ops::ne(fbits(self) & lit(0x8000_0000u32), lit(0u32))
    }
    pub fn is_sign_positive(self) -> Val<bool> {
        super::ops::eq(fbits(self) & lit(0x8000_0000u32), lit(0u32))
    }
    pub fn copysign(self, sign: Val<f32>) -> Val<f32> {
        let mag = fbits(self) & lit(0x7fff_ffffu32);
        let s = fbits(sign) & lit(0x8000_0000u32);
        ffrom_bits(mag | s)
    }
    pub fn to_bits(self) -> Val<u32> {
        fbits(self)
    }
    pub fn from_bits(bits: Val<u32>) -> Val<f32> {
        ffrom_bits(bits)
    }
    /// glam's `FloatExt::lerp`: `self * (1 - t) + to * t`.
    pub fn lerp(self, to: Val<f32>, t: Val<f32>) -> Val<f32> {
        self * (lit(1.0f32) - t) + to * t
    }
}

/// Rust's `%` on `f32` (C's `fmodf`), exact: one naga function per module, `cohort_fmod`.
/// |x| and |y| as integer significands `mx`, `my` and exponents; the remainder of
/// `mx * 2^(ex - ey)` by `my` is computed 8 bits at a time with exact `u32` `%`
/// (`r < my < 2^24`, so `r << 8` fits), then packed with `y`'s exponent: the result is
/// exactly representable, so no rounding occurs. Special cases as C: NaN for `y == 0`,
/// NaN operands and infinite `x`; `x` itself when `|x| < |y|` (so `x % inf == x`).
pub(crate) fn fmod(x: Val<f32>, y: Val<f32>) -> Val<f32> {
    struct FmodKey;
    super::function::function::<FmodKey, _, _>(
        "cohort_fmod",
        &["x", "y"],
        (x, y),
        |(x, y): (Val<f32>, Val<f32>)| {
            use super::control::{break_, if_, loop_};
            use super::ops::{eq, ge, gt};
            use super::val::Var;
            let (ux, uy) = (fbits(x), fbits(y));
            let sx = ux & lit(0x8000_0000u32);
            let ax = ux & lit(0x7fff_ffffu32);
            let ay = uy & lit(0x7fff_ffffu32);
            let nan_case = or(
                or(eq(ay, lit(0u32)), gt(ay, lit(0x7f80_0000u32))),
                ge(ax, lit(0x7f80_0000u32)),
            );
            let small = lt(ax, ay);
            let equal = eq(ax, ay);
            let general = not(or(or(nan_case, small), equal));
            let ex = ax >> lit(23u32);
            let ey = ay >> lit(23u32);
            let mx = select(
                eq(ex, lit(0u32)),
                ax,
                (ax & lit(0x007f_ffffu32)) | lit(0x0080_0000u32),
            );
            let my = select(
                eq(ey, lit(0u32)),
                ay,
                (ay & lit(0x007f_ffffu32)) | lit(0x0080_0000u32),
            );
            let ex = ex.max(lit(1u32));
            let ey = ey.max(lit(1u32));
            // my is 0 only when y == 0 (then `nan_case`); integer `% 0` is defined (0) anyway.
            let d = Var::new("fmod_d", select(general, ex - ey, lit(0u32)));
            let r = Var::new("fmod_r", mx % my);
            loop_(|| {
                let dv = d.get();
                if_(eq(dv, lit(0u32)), break_, || {});
                let s = dv.min(lit(8u32));
                r.set((r.get() << s) % my);
                d.set(dv - s);
            });
            let rr = r.get();
            // Normalise: the leading bit of rr to bit 23; the biased exponent is then ey - sh.
            let sh = rr.leading_zeros() - lit(8u32);
            let normal = ((ey - sh) << lit(23u32)) | ((rr << sh) & lit(0x007f_ffffu32));
            let subnormal = rr << (ey - lit(1u32));
            let mag = select(super::ops::le(ey, sh), subnormal, normal);
            let mag = select(eq(rr, lit(0u32)), lit(0u32), mag);
            let res = ffrom_bits(mag | sx);
            let res = select(small, x, res);
            let res = select(equal, ffrom_bits(sx), res);
            select(nan_case, lit(f32::NAN), res)
        },
    )
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

fn float_vec_to_int<R>(v: Handle<Expression>, kind: ScalarKind, size: VectorSize) -> Val<R> {
    let converted = with(|c| {
        c.expr(Expression::As {
            expr: v,
            kind,
            convert: Some(4),
        })
    });
    Val::from_handle(super::ops::saturate_float_to_int(
        v,
        converted,
        kind,
        Some(size),
    ))
}

fn compose<T: GpuType>(parts: &[Handle<Expression>]) -> Val<T> {
    Val::from_handle(with(|c| {
        let ty = T::naga_type(&mut c.module);
        c.expr(Expression::Compose {
            ty,
            components: parts.to_vec(),
        })
    }))
}

fn swizzle<R>(
    v: Handle<Expression>,
    size: VectorSize,
    pattern: [naga::SwizzleComponent; 4],
) -> Val<R> {
    Val::from_handle(with(|c| {
        c.expr(Expression::Swizzle {
            size,
            vector: v,
            pattern,
        })
    }))
}

/// glam's `min`/`max` closures (`if a < b { a } else { b }`): with a NaN operand they give
/// the second operand. Used by float vector `min`, `max`, `clamp` and `*_element`.
fn glam_min<T>(a: Val<T>, b: Val<T>) -> Val<T> {
    select(
        Val::from_handle(super::ops::binary::<bool>(naga::BinaryOperator::Less, a.h, b.h).h),
        a,
        b,
    )
}
fn glam_max<T>(a: Val<T>, b: Val<T>) -> Val<T> {
    select(
        Val::from_handle(super::ops::binary::<bool>(naga::BinaryOperator::Greater, a.h, b.h).h),
        a,
        b,
    )
}

/// glam computes `Vec4`'s horizontal operations pairwise with SSE2 on x86
/// (`op(op(x, z), op(y, w))`, `(x + y) + (z + w)`) and left to right elsewhere; the IR
/// follows the host's order so that results agree bit for bit.
const VEC4_PAIRWISE: bool = cfg!(all(
    any(target_arch = "x86", target_arch = "x86_64"),
    target_feature = "sse2"
));

fn horizontal<S>(v: &[Val<S>], op: impl Fn(Val<S>, Val<S>) -> Val<S>, pairwise4: bool) -> Val<S> {
    match v.len() {
        4 if pairwise4 && VEC4_PAIRWISE => op(op(v[0], v[2]), op(v[1], v[3])),
        _ => {
            let mut it = v.iter().rev().copied();
            let last = it.next().unwrap();
            it.fold(last, |acc, x| op(x, acc))
        }
    }
}

macro_rules! vec_common {
    ($v:ty, $s:ty, $n:expr, [$($c:ident),+], $float:expr) => {
        impl Val<$v> {
            pub fn new($($c: Val<$s>),+) -> Val<$v> { compose(&[$($c.h),+]) }
            pub fn splat(x: Val<$s>) -> Val<$v> { Val::from_handle(splat($n, x)) }
            /// Per component `if a < b { a } else { b }` (glam).
            pub fn min(self, o: Val<$v>) -> Val<$v> { if $float { glam_min(self, o) } else { math(M::Min, &[self.h, o.h]) } }
            pub fn max(self, o: Val<$v>) -> Val<$v> { if $float { glam_max(self, o) } else { math(M::Max, &[self.h, o.h]) } }
            /// glam: `self.max(lo).min(hi)`.
            pub fn clamp(self, lo: Val<$v>, hi: Val<$v>) -> Val<$v> { self.max(lo).min(hi) }
            pub fn min_element(self) -> Val<$s> {
                let v = [$(super::val::field(self, |s: &$v| &s.$c)),+];
                if $float { horizontal(&v, glam_min, true) } else { horizontal(&v, |a, b| math(M::Min, &[a.h, b.h]), false) }
            }
            pub fn max_element(self) -> Val<$s> {
                let v = [$(super::val::field(self, |s: &$v| &s.$c)),+];
                if $float { horizontal(&v, glam_max, true) } else { horizontal(&v, |a, b| math(M::Max, &[a.h, b.h]), false) }
            }
            pub fn element_sum(self) -> Val<$s> {
                let v = [$(super::val::field(self, |s: &$v| &s.$c)),+];
                match v.as_slice() {
                    [x, y, z, w] if $float && VEC4_PAIRWISE => (*x + *y) + (*z + *w),
                    _ => v.into_iter().reduce(|a, b| a + b).unwrap(),
                }
            }
        }
    };
}
vec_common!(Vec2, f32, VectorSize::Bi, [x, y], true);
vec_common!(Vec3, f32, VectorSize::Tri, [x, y, z], true);
vec_common!(Vec4, f32, VectorSize::Quad, [x, y, z, w], true);
vec_common!(UVec2, u32, VectorSize::Bi, [x, y], false);
vec_common!(UVec3, u32, VectorSize::Tri, [x, y, z], false);
vec_common!(UVec4, u32, VectorSize::Quad, [x, y, z, w], false);
vec_common!(IVec2, i32, VectorSize::Bi, [x, y], false);
vec_common!(IVec3, i32, VectorSize::Tri, [x, y, z], false);
vec_common!(IVec4, i32, VectorSize::Quad, [x, y, z, w], false);

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
            /// glam: `self * (1 - t) + to * t`.
            pub fn lerp(self, to: Val<$v>, t: Val<f32>) -> Val<$v> { self * (lit(1.0f32) - t) + to * t }
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
    /// Per component `x as u32` (saturating, NaN → 0), as glam.
    pub fn as_uvec3(self) -> Val<UVec3> {
        float_vec_to_int(self.h, ScalarKind::Uint, VectorSize::Tri)
    }
    pub fn as_ivec3(self) -> Val<IVec3> {
        float_vec_to_int(self.h, ScalarKind::Sint, VectorSize::Tri)
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
        let (ax, ay) = (
            super::val::field(self, |s: &Vec2| &s.x),
            super::val::field(self, |s: &Vec2| &s.y),
        );
        let (bx, by) = (
            super::val::field(o, |s: &Vec2| &s.x),
            super::val::field(o, |s: &Vec2| &s.y),
        );
        ax * by - ay * bx
    }
    pub fn as_uvec2(self) -> Val<UVec2> {
        float_vec_to_int(self.h, ScalarKind::Uint, VectorSize::Bi)
    }
}
impl Val<UVec2> {
    pub fn as_vec2(self) -> Val<Vec2> {
        Val::from_handle(with(|c| {
            c.expr(Expression::As {
                expr: self.h,
                kind: ScalarKind::Float,
                convert: Some(4),
            })
        }))
    }
}
impl Val<UVec3> {
    pub fn as_vec3(self) -> Val<Vec3> {
        Val::from_handle(with(|c| {
            c.expr(Expression::As {
                expr: self.h,
                kind: ScalarKind::Float,
                convert: Some(4),
            })
        }))
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
        Val::from_handle(with(|c| {
            c.expr(Expression::As {
                expr: self.h,
                kind: ScalarKind::Float,
                convert: Some(4),
            })
        }))
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
