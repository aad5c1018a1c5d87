//! `acos` of float lanes in vector instructions, with the C library's bits.
//!
//! The host form calls the C library's `acosf` (Rust's `f32::acos`); the vector form called
//! it once per lane, and each call spills the vector registers around it: the coherent
//! samplers take an `acos` per path vertex. glibc's `acosf` (the fdlibm algorithm, in `f32`
//! arithmetic without fused operations) is, for |x| <= 1, a rational approximation in one of
//! three ranges: |x| < 0.5, x > 0.5 and x < -0.5, each a fixed sequence of `f32` operations.
//! `reference` is that sequence in Rust, operation for operation (read from the library's
//! code and its constants); the vector form evaluates the same operations for every lane
//! and selects each lane's range, and calls the C function only for lanes beyond |x| = 1
//! and NaN.
//!
//! As with `sin` and `cos` (`super::sincos`), `libm_agrees` compares `reference` with this
//! process's `acosf` on a sample of every binade once per process; where they differ, the
//! vector form keeps its call per lane.

use std::sync::OnceLock;

use super::lower::Fx;
use super::types::{lanes, splat_const};

/// The numerator's coefficients, of z^0 to z^5 (times z).
const PS: [u32; 6] = [
    0x3e2a_aaab,
    0xbea6_b090,
    0x3e4e_0aa8,
    0xbd24_1146,
    0x3a4f_7f04,
    0x3811_ef08,
];
/// The denominator's coefficients of z^1 to z^4 (its z^0 is 1).
const QS: [u32; 4] = [0xc019_d139, 0x4001_572d, 0xbf30_3361, 0x3d9d_c62e];
/// pi/2 in two parts, high and low.
const PIO2_HI: u32 = 0x3fc9_0fda;
const PIO2_LO: u32 = 0x33a2_2168;
/// pi, rounded down to a float (the x < -0.5 range subtracts from it).
const PI: u32 = 0x4049_0fda;

/// |x|'s bits below which the C function returns pi/2 at once: |x| <= 2^-26.
const TINY: u32 = 0x3280_0000;
/// |x|'s bits below which it takes the range around zero: |x| < 0.5.
const HALF: u32 = 0x3f00_0000;
/// |x|'s bits of 1.
const ONE: u32 = 0x3f80_0000;
/// The bits of the square root that the x > 0.5 range keeps in its head.
const HEAD: u32 = 0xffff_f000;

fn c(bits: u32) -> f32 {
    f32::from_bits(bits)
}

/// The C function's result for |x| <= 2^-26: pi/2, as its two parts' float sum.
fn at_tiny() -> f32 {
    c(PIO2_HI) + c(PIO2_LO)
}

/// Its result for x = -1: pi as a float plus twice pi/2's low part.
fn at_minus_one() -> f32 {
    c(PI) + 2.0 * c(PIO2_LO)
}

/// The rational function's numerator and denominator at `z`.
fn p_and_q(z: f32) -> (f32, f32) {
    let p = z
        * (c(PS[0])
            + z * (c(PS[1]) + z * (c(PS[2]) + z * (c(PS[3]) + z * (c(PS[4]) + z * c(PS[5]))))));
    let q = 1.0 + z * (c(QS[0]) + z * (c(QS[1]) + z * (c(QS[2]) + z * c(QS[3]))));
    (p, q)
}

/// `acos x` with the C library's bits, where |x| <= 1; `None` beyond and for NaN, where
/// the C function takes other paths.
pub(crate) fn reference(x: f32) -> Option<f32> {
    let ix = x.to_bits() & 0x7fff_ffff;
    if ix > ONE {
        return None;
    }
    if ix == ONE {
        return Some(if x > 0.0 { 0.0 } else { at_minus_one() });
    }
    if ix <= TINY {
        return Some(at_tiny());
    }
    if ix < HALF {
        let (p, q) = p_and_q(x * x);
        let r = p / q;
        return Some(c(PIO2_HI) - (x - (c(PIO2_LO) - x * r)));
    }
    if x < 0.0 {
        let z = (1.0 + x) * 0.5;
        let (p, q) = p_and_q(z);
        let s = z.sqrt();
        let r = p / q;
        let w = r * s - c(PIO2_LO);
        let t = s + w;
        return Some(c(PI) - (t + t));
    }
    let z = (1.0 - x) * 0.5;
    let s = z.sqrt();
    let df = f32::from_bits(s.to_bits() & HEAD);
    let cc = (z - df * df) / (s + df);
    let (p, q) = p_and_q(z);
    let r = p / q;
    let w = r * s + cc;
    let t = df + w;
    Some(t + t)
}

/// Whether this process's `acosf` gives `reference`'s bits: on 64 values of every binade
/// below 1, each sign, and the edges of the C function's ranges.
pub(crate) fn libm_agrees() -> bool {
    static AGREES: OnceLock<bool> = OnceLock::new();
    *AGREES.get_or_init(|| {
        let mut xs = Vec::new();
        for e in 0u32..127 {
            for k in 0u32..64 {
                xs.push(f32::from_bits(
                    (e << 23) | (k.wrapping_mul(0x9e37_79b9) >> 9),
                ));
            }
        }
        for b in [TINY, HALF, ONE] {
            xs.extend([b - 1, b, b + 1].map(f32::from_bits));
        }
        xs.iter()
            .flat_map(|&x| [x, -x])
            .all(|x| reference(x).is_none_or(|a| a.to_bits() == x.acos().to_bits()))
    })
}

impl Fx<'_> {
    /// `acos x` of float lanes `x`: `reference`'s three ranges for every lane, each lane's
    /// picked, and the C function for lanes beyond |x| = 1 (and NaN), called only where a
    /// running lane is one.
    pub(super) fn acos(&mut self, x: &str) -> String {
        let v = lanes("float");
        let vi = lanes("i32");
        let m = Self::mask_ty();
        let fc = |bits: u32| fconst(c(bits));
        let ic = |n: u32| splat_const("i32", &(n as i32).to_string());
        let bits = self.op(&format!("bitcast {v} {x} to {vi}"));
        let ix = self.op(&format!("and {vi} {bits}, {}", ic(0x7fff_ffff)));
        let beyond = self.op(&format!("icmp ugt {vi} {ix}, {}", ic(ONE)));
        let one = self.op(&format!("icmp eq {vi} {ix}, {}", ic(ONE)));
        let tiny = self.op(&format!("icmp ule {vi} {ix}, {}", ic(TINY)));
        let small = self.op(&format!("icmp ult {vi} {ix}, {}", ic(HALF)));
        let neg = self.op(&format!("icmp slt {vi} {bits}, zeroinitializer"));
        let fone = splat_const("float", "1.0");
        let half = splat_const("float", "0.5");
        // z per range: x^2 around zero, (1 + x) / 2 below -0.5, (1 - x) / 2 above 0.5.
        let xx = self.op(&format!("fmul {v} {x}, {x}"));
        let up = self.op(&format!("fadd {v} {fone}, {x}"));
        let down = self.op(&format!("fsub {v} {fone}, {x}"));
        let ends = self.op(&format!("select {m} {neg}, {v} {up}, {v} {down}"));
        let ends = self.op(&format!("fmul {v} {ends}, {half}"));
        let z = self.op(&format!("select {m} {small}, {v} {xx}, {v} {ends}"));
        // p = z (ps0 + z (ps1 + ... + z ps5)), q = 1 + z (qs1 + ... + z qs4), r = p / q.
        let p = self.z_times_poly(&z, &PS);
        let q = self.z_times_poly(&z, &QS);
        let q = self.op(&format!("fadd {v} {fone}, {q}"));
        let r = self.op(&format!("fdiv {v} {p}, {q}"));
        // |x| < 0.5: pi/2 - (x - (lo - x r)).
        let xr = self.op(&format!("fmul {v} {x}, {r}"));
        let lo_xr = self.op(&format!("fsub {v} {}, {xr}", fc(PIO2_LO)));
        let inner = self.op(&format!("fsub {v} {x}, {lo_xr}"));
        let at_small = self.op(&format!("fsub {v} {}, {inner}", fc(PIO2_HI)));
        let s = self.fintr("sqrt", std::slice::from_ref(&z));
        let rs = self.op(&format!("fmul {v} {r}, {s}"));
        // x < -0.5: pi - 2 (s + (r s - lo)).
        let w = self.op(&format!("fsub {v} {rs}, {}", fc(PIO2_LO)));
        let t = self.op(&format!("fadd {v} {s}, {w}"));
        let tt = self.op(&format!("fadd {v} {t}, {t}"));
        let at_neg = self.op(&format!("fsub {v} {}, {tt}", fc(PI)));
        // x > 0.5: 2 (df + (r s + (z - df^2) / (s + df))), df = s with its tail cleared.
        let sb = self.op(&format!("bitcast {v} {s} to {vi}"));
        let head = self.op(&format!("and {vi} {sb}, {}", ic(HEAD)));
        let df = self.op(&format!("bitcast {vi} {head} to {v}"));
        let df2 = self.op(&format!("fmul {v} {df}, {df}"));
        let num = self.op(&format!("fsub {v} {z}, {df2}"));
        let den = self.op(&format!("fadd {v} {s}, {df}"));
        let cc = self.op(&format!("fdiv {v} {num}, {den}"));
        let w = self.op(&format!("fadd {v} {rs}, {cc}"));
        let t = self.op(&format!("fadd {v} {df}, {w}"));
        let at_pos = self.op(&format!("fadd {v} {t}, {t}"));
        let ends = self.op(&format!("select {m} {neg}, {v} {at_neg}, {v} {at_pos}"));
        let mid = self.op(&format!("select {m} {small}, {v} {at_small}, {v} {ends}"));
        let mid = self.op(&format!(
            "select {m} {tiny}, {v} {}, {v} {mid}",
            fconst(at_tiny())
        ));
        let at_one = self.op(&format!(
            "select {m} {neg}, {v} {}, {v} zeroinitializer",
            fconst(at_minus_one())
        ));
        let fast = self.op(&format!("select {m} {one}, {v} {at_one}, {v} {mid}"));
        self.with_c_lanes(x, &fast, &beyond, "acosf")
    }

    /// `z (c0 + z (c1 + ... + z cn))` of float lanes `z`, the coefficients' bits in `cs`,
    /// in the C function's order of operations.
    fn z_times_poly(&mut self, z: &str, cs: &[u32]) -> String {
        let v = lanes("float");
        let (last, rest) = cs.split_last().expect("a coefficient");
        let mut acc = self.op(&format!("fmul {v} {z}, {}", fconst(c(*last))));
        for &k in rest.iter().rev() {
            let sum = self.op(&format!("fadd {v} {}, {acc}", fconst(c(k))));
            acc = self.op(&format!("fmul {v} {z}, {sum}"));
        }
        acc
    }
}

/// A float as a constant of every lane (LLVM writes a float constant as its double's bits).
fn fconst(x: f32) -> String {
    splat_const("float", &format!("0x{:016X}", f64::from(x).to_bits()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `reference` against this process's `acosf` on every 97th float of magnitude up to 1
    /// (of either sign): 22 million values.
    #[test]
    fn reference_has_the_c_librarys_bits() {
        let mut checked = 0u64;
        let mut bits = 0u32;
        while bits <= ONE {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                let a = reference(x).expect("|x| <= 1");
                assert_eq!(a.to_bits(), x.acos().to_bits(), "acos {x:e}");
                checked += 1;
            }
            bits += 97;
        }
        assert!(checked > 20_000_000);
        for x in [1.0f32, -1.0, 0.5, -0.5, 0.0, -0.0] {
            assert_eq!(
                reference(x).unwrap().to_bits(),
                x.acos().to_bits(),
                "acos {x}"
            );
        }
        assert!(libm_agrees());
        for x in [1.0000001f32, 2.0, f32::INFINITY, f32::NAN, f32::MAX] {
            assert!(reference(x).is_none() && reference(-x).is_none());
        }
    }
}
