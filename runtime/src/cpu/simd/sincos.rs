//! `sin` and `cos` of float lanes in vector instructions, with the C library's bits.
//!
//! The host form calls the C library's `sinf` and `cosf` (Rust's `f32::sin` and `f32::cos`);
//! the vector form used to call them once per lane, 5 % of a render's time on the CPU backend,
//! and each call spills the vector registers around it. glibc's `sinf`, `cosf` and `sincosf`
//! (since 2.28, in the FMA build that glibc picks where the CPU has FMA and AVX2) evaluate, below
//! |x| = 120, a fixed sequence of `f64` operations: a reduction by the nearest multiple of
//! pi/2 and two short polynomials. `reference` is that sequence in Rust, operation for
//! operation; the vector form evaluates the same sequence in `f64` lanes, and calls the C
//! function only for lanes beyond it (|x| >= 120, infinities, NaN).
//!
//! Because the vector form must agree with the C library the process actually runs (another
//! libc, or glibc's build without FMA, rounds differently), `libm_agrees` compares
//! `reference` with `sinf` and `cosf` on a sample of every binade once per process; where
//! they differ, the vector form keeps its call per lane.

use std::sync::OnceLock;

use super::lower::Fx;
use super::types::{lanes, splat_const};

/// 2/pi scaled by 2^24: the quadrant is the product rounded at bit 24 (`quadrant`).
const HPI_INV: u64 = 0x4164_5f30_6dc9_c883;
/// pi/2.
const HPI: u64 = 0x3ff9_21fb_5444_2d18;
/// The cosine polynomial's coefficients of x^0, x^2, x^4, x^6 and x^8.
const C: [u64; 5] = [
    0x3ff0_0000_0000_0000,
    0xbfdf_ffff_fd0c_621c,
    0x3fa5_5553_e106_8f19,
    0xbf56_c087_e89a_359d,
    0x3ef9_9343_027b_f8c3,
];
/// The sine polynomial's coefficients of x^3, x^5 and x^7 (x^1's is 1).
const S: [u64; 3] = [
    0xbfc5_5554_5995_a603,
    0x3f81_1076_0523_0bc4,
    0xbf29_94eb_3774_cf24,
];

/// The top 12 bits of |x| below which the C functions return (x, 1): |x| < 2^-12.
const TINY_TOP: u32 = 0x397;
/// The top 12 bits of |x| below which they take no reduction: |x| < 0.75.
const SMALL_TOP: u32 = 0x3f3;
/// The top 12 bits of |x| up to which the fixed sequence holds: |x| < 120.
const REDUCED_TOP: u32 = 0x42e;

fn f(bits: u64) -> f64 {
    f64::from_bits(bits)
}

/// The top 12 bits of |x|'s representation (sign cleared), as the C functions classify.
fn top12(x: f32) -> u32 {
    (x.to_bits() >> 20) & 0x7ff
}

/// The quadrant of `d` (the nearest multiple of pi/2), as the C functions round it.
fn quadrant(d: f64) -> i32 {
    let r = d * f(HPI_INV);
    ((r as i32).wrapping_add(0x80_0000)) >> 24
}

/// `(sin x, cos x)` with the C library's bits, where |x| < 120; `None` beyond, and for
/// infinities and NaN, where the C functions take other paths.
pub(crate) fn reference(x: f32) -> Option<(f32, f32)> {
    let top = top12(x);
    if top <= TINY_TOP {
        return Some((x, 1.0));
    }
    if top > REDUCED_TOP {
        return None;
    }
    let d = f64::from(x);
    let n = if top <= SMALL_TOP { 0 } else { quadrant(d) };
    let xr = (-f64::from(n)).mul_add(f(HPI), d);
    // The sine's sign in quadrants 0..3 is +, -, -, +.
    let xs = if (n.wrapping_add(1) & 2) != 0 {
        -xr
    } else {
        xr
    };
    let x2 = xr * xr;
    let a0 = x2.mul_add(f(S[2]), f(S[1]));
    let a1 = x2.mul_add(f(C[4]), f(C[3]));
    let x3 = x2 * xs;
    let x4 = x2 * x2;
    let x5 = x2 * x3;
    let x6 = x2 * x4;
    let c01 = x2.mul_add(f(C[1]), f(C[0]));
    let s = a0.mul_add(x5, x3.mul_add(f(S[0]), xs));
    let mut c = a1.mul_add(x6, x4.mul_add(f(C[2]), c01));
    // Quadrants 2 and 3 take the cosine's coefficients negated, which negates it exactly.
    if n & 2 != 0 {
        c = -c;
    }
    let (s, c) = (s as f32, c as f32);
    Some(if n & 1 != 0 { (c, s) } else { (s, c) })
}

/// Whether this process's `sinf` and `cosf` give `reference`'s bits: on 64 values of every
/// binade below 120, each sign, and the edges of the C functions' ranges.
pub(crate) fn libm_agrees() -> bool {
    static AGREES: OnceLock<bool> = OnceLock::new();
    *AGREES.get_or_init(|| {
        let mut xs = Vec::new();
        for e in 0u32..=133 {
            for k in 0u32..64 {
                xs.push(f32::from_bits(
                    (e << 23) | (k.wrapping_mul(0x9e37_79b9) >> 9),
                ));
            }
        }
        use std::f32::consts::{FRAC_PI_2, PI, TAU};
        xs.extend([0.75, 0.7499999, FRAC_PI_2, PI, TAU, 119.99999, 2.4414062e-4]);
        xs.iter()
            .flat_map(|&x| [x, -x])
            .all(|x| match reference(x) {
                Some((s, c)) => {
                    s.to_bits() == x.sin().to_bits() && c.to_bits() == x.cos().to_bits()
                }
                None => true,
            })
    })
}

impl Fx<'_> {
    /// `sin x` (`cos`: `cos x`) of float lanes `x`: `reference`'s operations in `f64` lanes,
    /// and the C function for lanes beyond them, called only where a running lane is one.
    pub(super) fn sin_or_cos(&mut self, x: &str, cos: bool) -> String {
        let v = lanes("float");
        let vd = lanes("double");
        let vi = lanes("i32");
        let m = Self::mask_ty();
        let dc = |bits: u64| splat_const("double", &format!("0x{bits:016X}"));
        let ic = |n: i64| splat_const("i32", &n.to_string());
        let fma = |fx: &mut Self, a: &str, b: &str, c: &str| {
            fx.declare(&format!(
                "declare {vd} @llvm.fma.v{}f64({vd}, {vd}, {vd})",
                super::types::w()
            ));
            fx.op(&format!(
                "call {vd} @llvm.fma.v{}f64({vd} {a}, {vd} {b}, {vd} {c})",
                super::types::w()
            ))
        };
        let bits = self.op(&format!("bitcast {v} {x} to {vi}"));
        let shifted = self.op(&format!("lshr {vi} {bits}, {}", ic(20)));
        let top = self.op(&format!("and {vi} {shifted}, {}", ic(0x7ff)));
        let tiny = self.op(&format!("icmp ule {vi} {top}, {}", ic(TINY_TOP.into())));
        let small = self.op(&format!("icmp ule {vi} {top}, {}", ic(SMALL_TOP.into())));
        let beyond = self.op(&format!("icmp ugt {vi} {top}, {}", ic(REDUCED_TOP.into())));
        let d = self.op(&format!("fpext {v} {x} to {vd}"));
        // Lanes beyond the range reduce 0 instead: their product could overflow `i32`.
        let inside = self.op(&format!(
            "select {m} {beyond}, {vd} zeroinitializer, {vd} {d}"
        ));
        let r = self.op(&format!("fmul {vd} {inside}, {}", dc(HPI_INV)));
        let ri = self.op(&format!("fptosi {vd} {r} to {vi}"));
        let biased = self.op(&format!("add {vi} {ri}, {}", ic(0x80_0000)));
        let q = self.op(&format!("ashr {vi} {biased}, {}", ic(24)));
        let n = self.op(&format!(
            "select {m} {small}, {vi} zeroinitializer, {vi} {q}"
        ));
        let nd = self.op(&format!("sitofp {vi} {n} to {vd}"));
        let neg = self.op(&format!("fneg {vd} {nd}"));
        let xr = fma(self, &neg, &dc(HPI), &d);
        let n1 = self.op(&format!("add {vi} {n}, {}", ic(1)));
        let n12 = self.op(&format!("and {vi} {n1}, {}", ic(2)));
        let negative = self.op(&format!("icmp ne {vi} {n12}, zeroinitializer"));
        let sign = self.op(&format!(
            "select {m} {negative}, {vd} {}, {vd} {}",
            dc((-1.0f64).to_bits()),
            dc(1.0f64.to_bits())
        ));
        let xs = self.op(&format!("fmul {vd} {xr}, {sign}"));
        let x2 = self.op(&format!("fmul {vd} {xr}, {xr}"));
        let a0 = fma(self, &x2, &dc(S[2]), &dc(S[1]));
        let a1 = fma(self, &x2, &dc(C[4]), &dc(C[3]));
        let x3 = self.op(&format!("fmul {vd} {x2}, {xs}"));
        let x4 = self.op(&format!("fmul {vd} {x2}, {x2}"));
        let x5 = self.op(&format!("fmul {vd} {x2}, {x3}"));
        let x6 = self.op(&format!("fmul {vd} {x2}, {x4}"));
        let c01 = fma(self, &x2, &dc(C[1]), &dc(C[0]));
        let s_in = fma(self, &x3, &dc(S[0]), &xs);
        let s = fma(self, &a0, &x5, &s_in);
        let c_in = fma(self, &x4, &dc(C[2]), &c01);
        let c = fma(self, &a1, &x6, &c_in);
        let n2 = self.op(&format!("and {vi} {n}, {}", ic(2)));
        let flip = self.op(&format!("icmp ne {vi} {n2}, zeroinitializer"));
        let cneg = self.op(&format!("fneg {vd} {c}"));
        let c = self.op(&format!("select {m} {flip}, {vd} {cneg}, {vd} {c}"));
        let sf = self.op(&format!("fptrunc {vd} {s} to {v}"));
        let cf = self.op(&format!("fptrunc {vd} {c} to {v}"));
        let n_1 = self.op(&format!("and {vi} {n}, {}", ic(1)));
        let odd = self.op(&format!("icmp ne {vi} {n_1}, zeroinitializer"));
        let (own, other) = if cos { (&cf, &sf) } else { (&sf, &cf) };
        let poly = self.op(&format!("select {m} {odd}, {v} {other}, {v} {own}"));
        let at_tiny = if cos {
            splat_const("float", "1.0")
        } else {
            x.to_string()
        };
        let fast = self.op(&format!("select {m} {tiny}, {v} {at_tiny}, {v} {poly}"));
        self.with_c_lanes(x, &fast, &beyond, if cos { "cosf" } else { "sinf" })
    }

    /// `fast`, but the C function `name` of `x` in the lanes of `beyond` (outside the range
    /// that a vector sequence covers), called only where a running lane is one.
    pub(super) fn with_c_lanes(&mut self, x: &str, fast: &str, beyond: &str, name: &str) -> String {
        let v = lanes("float");
        let m = Self::mask_ty();
        let exec = self.exec();
        let slow = self.and(&exec, beyond);
        let any = self.any(&slow);
        let slot = self.alloca(&v);
        self.line(&format!("store {v} {fast}, ptr {slot}"));
        let (call, join) = (self.label(), self.label());
        self.line(&format!("br i1 {any}, label %{call}, label %{join}"));
        self.body.push_str(&format!("{call}:\n"));
        let helper = self.per_lane(name);
        let libm = self.op(&format!("call {v} @{helper}({v} {x})"));
        let mixed = self.op(&format!("select {m} {slow}, {v} {libm}, {v} {fast}"));
        self.line(&format!("store {v} {mixed}, ptr {slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        self.op(&format!("load {v}, ptr {slot}"))
    }

    /// A function of the module that calls the C function `name` (`sinf`, `cosf`, `acosf`)
    /// on every lane: one copy per kernel, not inlined, for the rare lanes beyond the vector
    /// sequence's range. (Sixteen calls inlined at each site took LLVM 15 % longer to
    /// compile stanford-like's `extend` than before the vector sequence.)
    fn per_lane(&mut self, name: &str) -> String {
        let v = lanes("float");
        let helper = format!("cohort_{name}_per_lane");
        let mut body = String::new();
        let mut acc = "poison".to_string();
        for lane in 0..super::types::w() {
            body.push_str(&format!(
                "  %x{lane} = extractelement {v} %x, i32 {lane}\n  \
                 %y{lane} = call float @{name}(float %x{lane})\n  \
                 %v{lane} = insertelement {v} {acc}, float %y{lane}, i32 {lane}\n"
            ));
            acc = format!("%v{lane}");
        }
        self.declare(&format!("declare float @{name}(float)"));
        self.declare(&format!(
            "define internal {v} @{helper}({v} %x) noinline {{\n{body}  ret {v} {acc}\n}}"
        ));
        helper
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `reference` against this process's `sinf` and `cosf` on every 211th float below 120
    /// (of either sign): 10 million values, each binade's mantissas sampled evenly.
    #[test]
    fn reference_has_the_c_librarys_bits() {
        let limit = 120.0f32.to_bits();
        let mut checked = 0u64;
        let mut bits = 0u32;
        while bits < limit {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                let (s, c) = reference(x).expect("below 120");
                assert_eq!(s.to_bits(), x.sin().to_bits(), "sin {x:e}");
                assert_eq!(c.to_bits(), x.cos().to_bits(), "cos {x:e}");
                checked += 1;
            }
            bits += 211;
        }
        assert!(checked > 10_000_000);
        assert!(libm_agrees());
        for x in [120.0f32, 1e10, f32::INFINITY, f32::NAN, f32::MAX] {
            assert!(reference(x).is_none() && reference(-x).is_none());
        }
    }
}
