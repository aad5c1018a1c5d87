//! Numeric conformance (the numeric-semantics work; docs/LANGUAGE.md sections 3-9): every
//! operator, method, cast, constant and builtin that the language lists means what Rust
//! (release) means, on wgpu (WGSL), on Vulkan (SPIR-V) and on the host. Each kernel of
//! `cohort_tests::kernels::numeric` runs on edge values (NaN of both signs, ±inf, ±0,
//! subnormals, MIN/MAX, halfway cases, large values, saturation limits) over buffers whose
//! sizes are not multiples of the workgroup size. Results are compared bit for bit (NaNs as
//! "both NaN") with the host run of the same Rust function and with hand-written Rust
//! `f32`/integer expressions, except where LANGUAGE.md states a precision bound
//! (transcendental functions, `powf`).

// The references spell out Rust's meaning on purpose (`!(x < y)`, `NAN as i32`, `x % 3 == 0`,
// division with its defined result at zero).
#![allow(
    clippy::neg_cmp_op_on_partial_ord,
    clippy::cast_nan_to_int,
    clippy::manual_is_multiple_of,
    clippy::manual_checked_ops
)]

mod common;
use cohort::host::{for_each_invocation, for_each_invocation_in_groups};
use cohort::runtime::Device;
use cohort::{Grid, Group};
use cohort_tests::kernels::numeric::*;
use common::*;
use glam::{IVec2, UVec4, Vec2, Vec3, Vec4};
use std::sync::atomic::{AtomicU32, Ordering};

const NEG_NAN: u32 = 0xffc0_0000;

/// Edge values of `f32`.
fn edges() -> Vec<f32> {
    let mut v = vec![
        0.0,
        -0.0,
        1.0,
        -1.0,
        0.5,
        -0.5,
        1.5,
        -1.5,
        2.5,
        -2.5,
        3.5,
        -3.5,
        0.49999997,
        -0.49999997,
        8388609.0,
        -8388609.0,
        8388607.5,
        16777217.0,
        1e10,
        -1e10,
        3.0,
        0.1,
        0.3,
        2.0,
        7.0,
        -7.0,
        100.0,
        0.75,
        1e-3,
        88.0,
        89.0,
        -104.0,
        1e30,
        0.999_999,
        1e-45,
        -1e-45,
        1.1754942e-38,
        f32::MIN_POSITIVE,
        f32::MAX,
        f32::MIN,
        f32::EPSILON,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        f32::from_bits(NEG_NAN),
        2147483520.0,
        2147483648.0,
        4294967040.0,
        4294967296.0,
        -2147483648.0,
        -2147483904.0,
        -0.3,
        1.0e-40,
        6.0,
        -8.0,
    ];
    v.dedup_by(|a, b| a.to_bits() == b.to_bits());
    v
}

/// All ordered pairs of edge values (a size that is not a multiple of 64).
fn pairs() -> (Vec<f32>, Vec<f32>) {
    let e = edges();
    let mut a = Vec::new();
    let mut b = Vec::new();
    for x in &e {
        for y in &e {
            a.push(*x);
            b.push(*y);
        }
    }
    (a, b)
}

fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Collects mismatches and fails with all of them at once.
#[derive(Default)]
struct Report(Vec<String>);
impl Report {
    fn check(&mut self, ok: bool, msg: impl FnOnce() -> String) {
        if !ok && self.0.len() < 200 {
            self.0.push(msg());
        }
    }
    fn finish(self, what: &str) {
        assert!(
            self.0.is_empty(),
            "{what}: {} mismatches:\n{}",
            self.0.len(),
            self.0.join("\n")
        );
    }
}

fn backend(d: &Device) -> String {
    format!("{:?}", d.info().backend)
}

/// What docs/LANGUAGE.md (section 4) lets a device's f32 results differ in from Rust's.
/// The software driver keeps everything exact; GPUs may flush subnormals unless the backend
/// can ask them not to (`DeviceInfo::f32_subnormals`), may fold NaN in min/max/clamp
/// (`f32_nan_inf`), and round `/`, `recip` and `sqrt` to within 3 ulp (Vulkan: 2.5).
struct Model {
    subnormals: bool,
    nan_inf: bool,
    exact_div_sqrt: bool,
}

/// Divisions and square roots (by the name the reference tables give them).
const DIV_SQRT_ULPS: u32 = 3;

fn model(d: &Device) -> Model {
    let info = d.info();
    let software = info.adapter_name.contains("llvmpipe");
    Model {
        subnormals: software || info.f32_subnormals,
        nan_inf: software || info.f32_nan_inf,
        exact_div_sqrt: software,
    }
}

/// Results a driver without float controls may compute instead of Rust's, for the
/// operations where one was seen to (H100, wgpu): `x / y` as `x * (1 / y)` with the
/// reciprocal flushed when subnormal, and `element_sum` of `(x, y, -x, 1)` (the
/// reference's vector) in any order of additions.
fn fast_math_candidates(name: &str, operands: &[f32]) -> Option<Vec<f32>> {
    match (name, operands) {
        ("/", [x, y]) => {
            let r = 1.0 / y;
            let r = if subnormal(r) { 0.0f32.copysign(r) } else { r };
            Some(vec![x * r])
        }
        ("Vec4::element_sum", [x, y]) => {
            let q = [*x, *y, -x, 1.0];
            let mut out = Vec::new();
            for a in 0..4 {
                for b in 0..4 {
                    for c in 0..4 {
                        let d = 6 - a - b - c;
                        if a == b
                            || a == c
                            || b == c
                            || !(0..4).contains(&d)
                            || d == a
                            || d == b
                            || d == c
                        {
                            continue;
                        }
                        out.push(((q[a] + q[b]) + q[c]) + q[d]);
                        out.push((q[a] + q[b]) + (q[c] + q[d]));
                    }
                }
            }
            Some(out)
        }
        _ => None,
    }
}

fn subnormal(x: f32) -> bool {
    x != 0.0 && x.abs() < f32::MIN_POSITIVE
}

impl Model {
    /// Whether a case with these operands (and Rust's result) is outside what the device
    /// guarantees: subnormal operands or results where subnormals may be flushed.
    fn unspecified(&self, operands: &[f32], want: f32) -> bool {
        (!self.subnormals && (operands.iter().any(|x| subnormal(*x)) || subnormal(want)))
            // Without NaN/inf preservation the driver may assume finite values (the H100
            // with wgpu folds `inf + y - inf + 1` to `y + 1`).
            || (!self.nan_inf && (operands.iter().any(|x| !x.is_finite()) || !want.is_finite()))
    }

    /// Whether `got` is allowed for operation `name` where Rust gives `want`.
    fn allows(&self, name: &str, operands: &[f32], got: f32, want: f32) -> bool {
        if same(got, want) || self.unspecified(operands, want) {
            return true;
        }
        let min_max = name.contains("max") || name.contains("min") || name.contains("clamp");
        // Rust: "if the inputs compare equal (such as +0.0 and -0.0), either may be returned".
        if min_max && got == 0.0 && want == 0.0 {
            return true;
        }
        // Without NaN preservation a NaN operand may lose to the other operand (or a bound).
        if !self.nan_inf && min_max && operands.iter().any(|x| x.is_nan()) && !got.is_nan() {
            return true;
        }
        // Where subnormals are flushed the H100 computes `x / y` as `x * (1 / y)` (the
        // reciprocal flushes for |y| >= 2^126); without float controls it also sums a
        // vector's components in another order.
        if !self.nan_inf || (!self.subnormals && name == "/") {
            if let Some(candidates) = fast_math_candidates(name, operands) {
                if candidates.iter().any(|c| {
                    same(got, *c)
                        || (c.is_finite() && got.is_finite() && ulps(got, *c) <= DIV_SQRT_ULPS)
                }) {
                    return true;
                }
            }
        }
        let div_sqrt = name == "/"
            || name == "recip"
            || name.starts_with("sqrt")
            || name.starts_with("powi(-");
        !self.exact_div_sqrt
            && div_sqrt
            && want.is_finite()
            && got.is_finite()
            && ulps(got, want) <= DIV_SQRT_ULPS
    }
}

#[test]
fn comparisons_and_classification() {
    let (a, b) = pairs();
    let n = a.len();
    let mut host = vec![0u32; n];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_compare(inv.global_index, &a, &b, &mut host)
    });
    let mut r = Report::default();
    for k in 0..n {
        let (x, y) = (a[k], b[k]);
        let (v, w) = (Vec3::new(x, y, 1.0), Vec3::new(y, x, 1.0));
        #[allow(clippy::eq_op)]
        let want = [
            x < y,
            x <= y,
            x > y,
            x >= y,
            x == y,
            x != y,
            x.is_nan(),
            x.is_finite(),
            x.is_infinite(),
            x.is_sign_negative(),
            x.is_sign_positive(),
            x.is_normal(),
            x.is_subnormal(),
            v == w,
            v != w,
            v == v,
            v != v,
            !(x < y),
            x != x,
        ];
        assert_eq!(want.len() as u32, COMPARE_FLAGS);
        let want = want
            .iter()
            .enumerate()
            .fold(0u32, |acc, (i, f)| acc | (*f as u32) << i);
        r.check(host[k] == want, || {
            format!("host {x:?} vs {y:?}: {:019b} want {want:019b}", host[k])
        });
    }
    for d in devices() {
        let (ab, bb, o) = (
            d.upload(&a).unwrap(),
            d.upload(&b).unwrap(),
            d.alloc::<u32>(n).unwrap(),
        );
        float_compare::launch(&d, n as u32, &ab, &bb, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        let m = model(&d);
        for k in 0..n {
            r.check(
                gpu[k] == host[k] || m.unspecified(&[a[k], b[k]], 0.0),
                || {
                    format!(
                        "{} {:?} vs {:?}: flags {:019b}, host {:019b} (bit i: see float_compare)",
                        backend(&d),
                        a[k],
                        b[k],
                        gpu[k],
                        host[k]
                    )
                },
            );
        }
    }
    r.finish("comparisons");
}

/// `(name, Rust reference)` of the outputs of `float_unary`.
fn unary_reference(x: f32) -> [(&'static str, f32); UNARY_N] {
    [
        ("round", x.round()),
        ("floor", x.floor()),
        ("ceil", x.ceil()),
        ("trunc", x.trunc()),
        ("fract", x.fract()),
        ("abs", x.abs()),
        ("signum", x.signum()),
        ("neg", -x),
        ("clamp(-1.5, 2.5)", x.clamp(-1.5, 2.5)),
        ("round_ties_even", x.round_ties_even()),
        ("to_degrees", x.to_degrees()),
        ("to_radians", x.to_radians()),
        ("copysign(-1)", x.copysign(-1.0)),
        ("powi(3)", x.powi(3)),
        ("powi(-2)", x.powi(-2)),
        ("powi(0)", x.powi(0)),
        ("max(0)", x.max(0.0)),
        ("min(1)", x.min(1.0)),
        ("sqrt", x.sqrt()),
        ("recip", x.recip()),
    ]
}

#[test]
fn float_methods_exact() {
    let a = edges();
    let n = a.len();
    let mut host = vec![0f32; n * UNARY_N];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_unary(inv.global_index, &a, &mut host)
    });
    let mut r = Report::default();
    for (k, x) in a.iter().enumerate() {
        for (j, (name, want)) in unary_reference(*x).into_iter().enumerate() {
            let got = host[k * UNARY_N + j];
            r.check(same(got, want), || {
                format!("host {name}({x:?}) = {got:?}, Rust {want:?}")
            });
        }
    }
    for d in devices() {
        let (ab, o) = (d.upload(&a).unwrap(), d.alloc::<f32>(n * UNARY_N).unwrap());
        float_unary::launch(&d, n as u32, &ab, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        let m = model(&d);
        for (k, x) in a.iter().enumerate() {
            for (j, (name, want)) in unary_reference(*x).into_iter().enumerate() {
                let got = gpu[k * UNARY_N + j];
                r.check(m.allows(name, &[*x], got, want), || {
                    format!(
                        "{} {name}({x:?}) = {got:?} ({:#010x}), Rust {want:?} ({:#010x})",
                        backend(&d),
                        got.to_bits(),
                        want.to_bits()
                    )
                });
            }
        }
    }
    r.finish("float methods");
}

fn binary_reference(x: f32, y: f32) -> [(&'static str, f32); BINARY_N] {
    let (v, w) = (Vec2::new(x, y), Vec2::new(y, x));
    let q = Vec4::new(x, y, -x, 1.0);
    [
        ("+", x + y),
        ("-", x - y),
        ("*", x * y),
        ("/", x / y),
        ("%", x % y),
        ("min", x.min(y)),
        ("max", x.max(y)),
        ("copysign", x.copysign(y)),
        ("powf", x.powf(y)),
        ("mul_add(y, 0.25)", x.mul_add(y, 0.25)),
        ("atan2", x.atan2(y)),
        ("Vec2::min", v.min(w).x),
        ("Vec2::max", v.max(w).x),
        ("Vec4::min_element", q.min_element()),
        ("Vec4::max_element", q.max_element()),
        ("Vec4::element_sum", q.element_sum()),
        (
            "Vec3::clamp",
            Vec3::new(x, y, 0.5)
                .clamp(Vec3::splat(-2.0), Vec3::splat(3.0))
                .x,
        ),
        ("%=", x % y),
    ]
}

/// Outputs of `float_binary` that LANGUAGE.md gives a precision bound (in ulps) instead
/// of exactness; special values (NaN, ±inf, ±0 results) are still exact.
fn binary_bound(name: &str) -> Option<u32> {
    match name {
        "powf" => Some(POWF_ULPS),
        "atan2" => Some(TRANSC_ULPS),
        _ => None,
    }
}

/// The precision bounds stated in docs/LANGUAGE.md, section 7.
const TRANSC_ULPS: u32 = 4096;
const POWF_ULPS: u32 = 4096;
/// The absolute error of `log2` that `powf` inherits, per unit of |y| (2^-21).
const POWF_LOG2_ABS: f64 = 1.0 / 2097152.0;
const TRANSC_ABS: f32 = 1e-6;

fn within(got: f32, want: f32, ulps_bound: u32) -> bool {
    if same(got, want) {
        return true;
    }
    if !want.is_finite() || want == 0.0 || !got.is_finite() {
        return false;
    }
    ulps(got, want) <= ulps_bound || (got - want).abs() <= TRANSC_ABS
}

#[test]
fn float_operators_and_binary_methods() {
    let (a, b) = pairs();
    let n = a.len();
    let mut host = vec![0f32; n * BINARY_N];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_binary(inv.global_index, &a, &b, &mut host)
    });
    let mut r = Report::default();
    for k in 0..n {
        for (j, (name, want)) in binary_reference(a[k], b[k]).into_iter().enumerate() {
            let got = host[k * BINARY_N + j];
            r.check(same(got, want), || {
                format!("host {:?} {name} {:?} = {got:?}, Rust {want:?}", a[k], b[k])
            });
        }
    }
    for d in devices() {
        let (ab, bb, o) = (
            d.upload(&a).unwrap(),
            d.upload(&b).unwrap(),
            d.alloc::<f32>(n * BINARY_N).unwrap(),
        );
        float_binary::launch(&d, n as u32, &ab, &bb, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        let m = model(&d);
        for k in 0..n {
            for (j, (name, want)) in binary_reference(a[k], b[k]).into_iter().enumerate() {
                let got = gpu[k * BINARY_N + j];
                let (x, y) = (a[k], b[k]);
                let ok = m.unspecified(&[x, y], want)
                    || match name {
                        // Either Rust's fused result or `x * y + 0.25` rounded twice (section 7).
                        "mul_add(y, 0.25)" => same(got, want) || same(got, x * y + 0.25),
                        // Bounded where LANGUAGE.md states a bound: normal operands; for powf the
                        // bound scales with |y log2 x| (drivers compute exp2(y * log2(x))).
                        "powf" if x.is_subnormal() || y.is_subnormal() => {
                            !want.is_nan() || got.is_nan()
                        }
                        "powf" => {
                            within(got, want, (POWF_ULPS as f32 * (y * x.abs().log2()).abs().max(1.0)).min(u32::MAX as f32) as u32)
                            // log2's absolute error (2^-21 on [0.5, 2]) times |y|, in the exponent.
                            || (got.is_finite() && want.is_finite() && got.signum() == want.signum() && (got as f64 / want as f64).log2().abs() <= y.abs() as f64 * POWF_LOG2_ABS + 1e-4)
                        }
                        "atan2" if x.is_subnormal() || y.is_subnormal() => {
                            !want.is_nan() || got.is_nan()
                        }
                        _ => match binary_bound(name) {
                            Some(u) => within(got, want, u),
                            None => m.allows(name, &[x, y], got, want),
                        },
                    };
                r.check(ok, || {
                    format!(
                        "{} {:?} {name} {:?} = {got:?} ({:#010x}), Rust {want:?} ({:#010x})",
                        backend(&d),
                        a[k],
                        b[k],
                        got.to_bits(),
                        want.to_bits()
                    )
                });
            }
        }
    }
    r.finish("float operators");
}

/// Exact values of float `%` that a naive `x - y * trunc(x / y)` gets wrong.
#[test]
fn float_remainder_is_exact() {
    let cases: [(f32, f32, f32); 9] = [
        (1e10, 3.0, 1.0),
        (5.0, f32::INFINITY, 5.0),
        (0.3, 0.1, 7.450581e-9),
        (-7.5, 2.0, -1.5),
        (7.5, -2.0, 1.5),
        (f32::MAX, 1.0e-45, 0.0),
        (1.0e-40, 3.0e-41, 9.998e-42),
        (-0.0, 1.0, -0.0),
        (16777217.0, 0.1, 0.050000004),
    ];
    let a: Vec<f32> = cases.iter().map(|c| c.0).collect();
    let b: Vec<f32> = cases.iter().map(|c| c.1).collect();
    let mut r = Report::default();
    for (x, y, want) in cases {
        r.check(same(x % y, want), || {
            format!("Rust {x:?} % {y:?} = {:?}, table says {want:?}", x % y)
        });
    }
    for d in devices() {
        let (ab, bb, o) = (
            d.upload(&a).unwrap(),
            d.upload(&b).unwrap(),
            d.alloc::<f32>(a.len() * BINARY_N).unwrap(),
        );
        float_binary::launch(&d, a.len() as u32, &ab, &bb, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        for (k, (x, y, _)) in cases.iter().enumerate() {
            let got = gpu[k * BINARY_N + 4];
            r.check(same(got, x % y), || {
                format!("{} {x:?} % {y:?} = {got:?}, Rust {:?}", backend(&d), x % y)
            });
        }
    }
    r.finish("float %");
}

/// Where docs/LANGUAGE.md states a precision bound for a transcendental function:
/// trigonometric functions on [-π, π] (Vulkan and WGSL state none beyond), and normal
/// inputs (drivers may flush subnormal inputs to zero). Outside, only special values
/// (NaN, ±inf, ±0 results) are checked.
fn transc_bounded(name: &str, x: f32) -> bool {
    let trig = matches!(name, "sin" | "cos" | "tan");
    !(x.is_subnormal() || trig && x.abs() > std::f32::consts::PI)
}

fn transc_reference(x: f32) -> [(&'static str, f32); TRANSC_N] {
    [
        ("exp", x.exp()),
        ("exp2", x.exp2()),
        ("ln", x.ln()),
        ("log2", x.log2()),
        ("sin", x.sin()),
        ("cos", x.cos()),
        ("tan", x.tan()),
        ("asin", x.asin()),
        ("acos", x.acos()),
        ("atan", x.atan()),
        ("sinh", x.sinh()),
        ("cosh", x.cosh()),
        ("tanh", x.tanh()),
    ]
}

#[test]
fn transcendental_special_values_and_bounds() {
    let mut a = edges();
    a.extend((0..300).map(|i| (i as f32 - 150.0) * 0.0731));
    let n = a.len();
    let mut host = vec![0f32; n * TRANSC_N];
    let mut worst = 0u32;
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_transcendental(inv.global_index, &a, &mut host)
    });
    let mut r = Report::default();
    for (k, x) in a.iter().enumerate() {
        for (j, (name, want)) in transc_reference(*x).into_iter().enumerate() {
            let got = host[k * TRANSC_N + j];
            r.check(same(got, want), || {
                format!("host {name}({x:?}) = {got:?}, Rust {want:?}")
            });
        }
    }
    for d in devices() {
        let (ab, o) = (d.upload(&a).unwrap(), d.alloc::<f32>(n * TRANSC_N).unwrap());
        float_transcendental::launch(&d, n as u32, &ab, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        let m = model(&d);
        for (k, x) in a.iter().enumerate() {
            for (j, (name, want)) in transc_reference(*x).into_iter().enumerate() {
                let got = gpu[k * TRANSC_N + j];
                let special = want.is_nan() || want.is_infinite() || want == 0.0;
                let ok = if m.unspecified(&[*x], want) {
                    true
                } else if transc_bounded(name, *x) {
                    within(got, want, TRANSC_ULPS)
                } else {
                    !special || same(got, want)
                };
                worst = worst.max(if transc_bounded(name, *x) && !special {
                    ulps(got, want)
                } else {
                    0
                });
                r.check(ok, || {
                    format!(
                        "{} {name}({x:?}) = {got:?}, Rust {want:?} ({} ulps)",
                        backend(&d),
                        ulps(got, want)
                    )
                });
            }
        }
    }
    eprintln!("transcendentals: worst error in the bounded domain {worst} ulps");
    r.finish("transcendentals");
}

#[test]
fn float_to_int_casts_saturate() {
    let a = edges();
    let n = a.len();
    let reference = |x: f32| {
        let (v, w) = (
            Vec3::new(x, -x, 0.5).as_uvec3(),
            Vec3::new(x, -x, 0.5).as_ivec3(),
        );
        UVec4::new(
            x as i32 as u32,
            x as u32,
            v.x ^ (v.y << 1),
            (w.x as u32) ^ ((w.y as u32) >> 1),
        )
    };
    let mut host = vec![UVec4::ZERO; n];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_casts(inv.global_index, &a, &mut host)
    });
    let mut r = Report::default();
    for (k, x) in a.iter().enumerate() {
        r.check(host[k] == reference(*x), || {
            format!("host casts of {x:?}: {} want {}", host[k], reference(*x))
        });
    }
    assert_eq!(
        (
            f32::NAN as i32,
            f32::INFINITY as u32,
            3e9f32 as i32,
            -1.0f32 as u32
        ),
        (0, u32::MAX, i32::MAX, 0)
    );
    for d in devices() {
        let (ab, o) = (d.upload(&a).unwrap(), d.alloc::<UVec4>(n).unwrap());
        float_casts::launch(&d, n as u32, &ab, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        for (k, x) in a.iter().enumerate() {
            r.check(gpu[k] == reference(*x), || {
                format!(
                    "{} casts of {x:?} (as i32, as u32, as_uvec3, as_ivec3): {} want {}",
                    backend(&d),
                    gpu[k],
                    reference(*x)
                )
            });
        }
    }
    r.finish("float casts");
}

#[test]
fn int_to_float_and_bit_casts() {
    let mut a: Vec<u32> = vec![
        0,
        1,
        2,
        7,
        8,
        9,
        16777216,
        16777217,
        16777218,
        16777219,
        0x7fff_ffff,
        0x8000_0000,
        0x8000_0001,
        u32::MAX,
        u32::MAX - 1,
        0xffff_ff7f,
        0xffff_ff80,
        33554435,
        3,
        6,
    ];
    let mut rng = Rng(17);
    a.extend((0..77).map(|_| rng.next_u32()));
    let n = a.len();
    let reference = |x: u32| {
        let s = x as i32;
        let flags = (s < 0) as u32 | ((x > 7) as u32) << 1 | ((x % 3 == 0) as u32) << 2;
        UVec4::new((x as f32).to_bits(), (s as f32).to_bits(), 0, flags)
    };
    let mut host = vec![UVec4::ZERO; n];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        int_casts(inv.global_index, &a, &mut host)
    });
    let mut r = Report::default();
    for (k, x) in a.iter().enumerate() {
        r.check(host[k] == reference(*x), || {
            format!("host casts of {x}: {} want {}", host[k], reference(*x))
        });
    }
    for d in devices() {
        let (ab, o) = (d.upload(&a).unwrap(), d.alloc::<UVec4>(n).unwrap());
        int_casts::launch(&d, n as u32, &ab, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        for (k, x) in a.iter().enumerate() {
            r.check(gpu[k] == reference(*x), || {
                format!(
                    "{} casts of {x}: {} want {}",
                    backend(&d),
                    gpu[k],
                    reference(*x)
                )
            });
        }
    }
    r.finish("int casts");
}

/// Release Rust's integer semantics, with the results LANGUAGE.md defines where Rust
/// panics (division by zero, `MIN / -1`).
fn int_reference(x: i32, y: i32) -> [i32; INT_N] {
    let (ux, uy) = (x as u32, y as u32);
    let div = |a: i32, b: i32| if b == 0 { a } else { a.wrapping_div(b) };
    let rem = |a: i32, b: i32| if b == 0 { 0 } else { a.wrapping_rem(b) };
    let udiv = |a: u32, b: u32| if b == 0 { a } else { a / b };
    let urem = |a: u32, b: u32| if b == 0 { 0 } else { a % b };
    let acc = div(x.wrapping_mul(y).wrapping_add(x).wrapping_shl(uy), y);
    let (n, m) = (ux, uy);
    let us = udiv(
        n.wrapping_sub(m).wrapping_mul(n.wrapping_add(1)),
        m.wrapping_add(1),
    );
    let iv = IVec2::new(div(x, y), div(y, 0)) + IVec2::new(rem(x, y), rem(y, y));
    [
        x.wrapping_add(y),
        x.wrapping_sub(y),
        x.wrapping_mul(y),
        div(x, y),
        rem(x, y),
        x.wrapping_shl(uy),
        x.wrapping_shr(uy),
        x.wrapping_neg(),
        x.wrapping_abs(),
        x.wrapping_pow(uy & 7),
        ux.wrapping_add(uy) as i32,
        ux.wrapping_sub(uy) as i32,
        ux.wrapping_mul(uy) as i32,
        udiv(ux, uy) as i32,
        urem(ux, uy) as i32,
        ux.wrapping_shl(uy) as i32,
        ux.wrapping_shr(uy) as i32,
        acc,
        us as i32,
        iv.x.wrapping_add(0) ^ iv.y,
    ]
}

#[test]
fn integer_arithmetic_wraps_and_divides_as_documented() {
    let e: Vec<i32> = vec![
        0,
        1,
        -1,
        2,
        -2,
        3,
        7,
        -7,
        31,
        32,
        33,
        63,
        64,
        -31,
        -32,
        1000,
        0x4000_0000,
        i32::MAX,
        i32::MIN,
        i32::MIN + 1,
        65536,
        -65536,
        0x1234_5678,
    ];
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for x in &e {
        for y in &e {
            a.push(*x);
            b.push(*y);
        }
    }
    // Pairs over the whole range, divisors of every magnitude, and dividends one below
    // a multiple of the divisor, whose quotient lies closest under an integer: the CPU
    // vector form divides by a non-constant through f64 (`cpu::simd`), exact only if
    // such a quotient never rounds up.
    let mut h = 0x9e37_79b9u32;
    let mut next = || {
        h ^= h << 13;
        h ^= h >> 17;
        h ^= h << 5;
        h
    };
    for k in 0..4096u32 {
        let x = next();
        let d = next() >> (k % 32);
        let q = next() >> (31 - k % 31);
        a.push(x as i32);
        b.push(d as i32);
        a.push(q.wrapping_mul(d).wrapping_sub(1) as i32);
        b.push(d as i32);
    }
    let n = a.len();
    let mut host = vec![0i32; n * INT_N];
    // The host form wraps in this (debug) build instead of panicking.
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        int_ops(inv.global_index, &a, &b, &mut host)
    });
    let names = [
        "+",
        "-",
        "*",
        "/",
        "%",
        "<<",
        ">>",
        "neg",
        "abs",
        "pow",
        "u+",
        "u-",
        "u*",
        "u/",
        "u%",
        "u<<",
        "u>>",
        "compound",
        "usize",
        "IVec2 / %",
    ];
    let mut r = Report::default();
    for k in 0..n {
        let want = int_reference(a[k], b[k]);
        for j in 0..INT_N {
            r.check(host[k * INT_N + j] == want[j], || {
                format!(
                    "host {} {} {}: {} want {}",
                    a[k],
                    names[j],
                    b[k],
                    host[k * INT_N + j],
                    want[j]
                )
            });
        }
    }
    for d in devices() {
        let (ab, bb, o) = (
            d.upload(&a).unwrap(),
            d.upload(&b).unwrap(),
            d.alloc::<i32>(n * INT_N).unwrap(),
        );
        int_ops::launch(&d, n as u32, &ab, &bb, &o).unwrap();
        let gpu = d.read(&o).unwrap();
        for k in 0..n {
            let want = int_reference(a[k], b[k]);
            for j in 0..INT_N {
                r.check(gpu[k * INT_N + j] == want[j], || {
                    format!(
                        "{} {} {} {}: {} want {}",
                        backend(&d),
                        a[k],
                        names[j],
                        b[k],
                        gpu[k * INT_N + j],
                        want[j]
                    )
                });
            }
        }
    }
    r.finish("integer arithmetic");
}

#[test]
fn float_constants_build_and_mean_their_value() {
    let a = edges();
    let n = a.len();
    #[allow(invalid_nan_comparisons)]
    let reference = |x: f32| -> [u32; CONST_N] {
        [
            f32::INFINITY.to_bits(),
            f32::NEG_INFINITY.to_bits(),
            1,
            f32::MAX.to_bits(),
            f32::MIN.to_bits(),
            f32::MIN_POSITIVE.to_bits(),
            f32::EPSILON.to_bits(),
            (x < f32::INFINITY) as u32
                | ((x > f32::NEG_INFINITY) as u32) << 1
                | ((x == f32::NAN) as u32) << 2,
            (x * f32::INFINITY).to_bits(),
            (f32::MAX * 2.0).to_bits(),
            (-f32::INFINITY).to_bits(),
            (x + f32::MIN_POSITIVE).to_bits(),
            Vec3::INFINITY.min_element().to_bits(),
            x.max(f32::NEG_INFINITY).to_bits(),
            (core::f32::consts::PI * x).to_bits(),
            (i32::MIN as u32) ^ u32::MAX ^ 1,
        ]
    };
    let nan_bits = |b: u32| f32::from_bits(b).is_nan();
    let mut host = vec![0u32; n * CONST_N];
    for_each_invocation(n as u32, 64, Group::Thread, |inv| {
        float_constants(inv.global_index, &a, &mut host)
    });
    let mut r = Report::default();
    for d in devices() {
        let (ab, o) = (d.upload(&a).unwrap(), d.alloc::<u32>(n * CONST_N).unwrap());
        float_constants::launch(&d, n as u32, &ab, &o).unwrap_or_else(|e| panic!("{e}"));
        let gpu = d.read(&o).unwrap();
        let m = model(&d);
        for (k, x) in a.iter().enumerate() {
            let want = reference(*x);
            let unspecified = m.unspecified(&[*x], 0.0);
            for j in 0..CONST_N {
                let (g, h) = (gpu[k * CONST_N + j], host[k * CONST_N + j]);
                let eq = |p: u32, q: u32| {
                    p == q || (j != 7 && j != 15 && j != 2 && nan_bits(p) && nan_bits(q))
                };
                r.check(eq(h, want[j]), || {
                    format!(
                        "host constant #{j} with x = {x:?}: {h:#010x} want {:#010x}",
                        want[j]
                    )
                });
                r.check(eq(g, want[j]) || unspecified, || {
                    format!(
                        "{} constant #{j} with x = {x:?}: {g:#010x} want {:#010x}",
                        backend(&d),
                        want[j]
                    )
                });
            }
        }
    }
    r.finish("constants");
}

/// `global_index` is `workgroup_index * workgroup_size + local_index`, with workgroups
/// numbered x fastest, then y, then z: unique and dense on 1-D, 2-D and 3-D dispatches, on
/// the GPU and on the host.
#[test]
fn global_index_is_unique_over_1d_2d_3d_dispatches() {
    let shapes: [[u32; 3]; 6] = [
        [3, 1, 1],
        [5, 3, 1],
        [4, 3, 2],
        [7, 2, 3],
        [1, 1, 6],
        [2, 5, 3],
    ];
    let mut r = Report::default();
    for d in devices() {
        for g in shapes {
            let total = (g[0] * g[1] * g[2] * 64) as usize;
            // A buffer shorter than the dispatch, of a size that is not a multiple of 64.
            let len = total - 5;
            let out = d.upload(&vec![u32::MAX; len]).unwrap();
            let visits = d.alloc::<u32>(len).unwrap();
            global_index_map::launch(&d, Grid::Groups(g), &out, &visits).unwrap();
            let (o, v) = (d.read(&out).unwrap(), d.read(&visits).unwrap());
            let wrong = (0..len).filter(|&i| o[i] != i as u32 || v[i] != 1).count();
            let distinct: std::collections::HashSet<_> = o.iter().collect();
            r.check(wrong == 0, || {
                format!(
                    "{} groups {g:?}: {wrong} of {len} slots wrong, {} distinct indices",
                    backend(&d),
                    distinct.len()
                )
            });
        }
        // Grid::Threads with a count that is not a multiple of the workgroup size.
        let len = 1000;
        let out = d.upload(&vec![u32::MAX; len]).unwrap();
        let visits = d.alloc::<u32>(len).unwrap();
        global_index_map::launch(&d, len as u32, &out, &visits).unwrap();
        let (o, v) = (d.read(&out).unwrap(), d.read(&visits).unwrap());
        r.check((0..len).all(|i| o[i] == i as u32 && v[i] == 1), || {
            format!("{} Threads(1000) not dense", backend(&d))
        });
        // Rows of at most `max_x` workgroups (the layout of launches beyond 65535 groups).
        let g = cohort::launch::groups_for_threads(1000, 64, 4);
        assert_eq!(g, [4, 4, 1]);
        let out = d.upload(&vec![u32::MAX; len]).unwrap();
        let visits = d.alloc::<u32>(len).unwrap();
        global_index_map::launch(&d, Grid::Groups(g), &out, &visits).unwrap();
        let (o, v) = (d.read(&out).unwrap(), d.read(&visits).unwrap());
        r.check((0..len).all(|i| o[i] == i as u32 && v[i] == 1), || {
            format!("{} rows of 4 groups not dense", backend(&d))
        });
    }
    for g in shapes {
        let total = (g[0] * g[1] * g[2] * 64) as usize;
        let len = total - 5;
        let mut out = vec![u32::MAX; len];
        let visits: Vec<AtomicU32> = (0..len).map(|_| AtomicU32::new(0)).collect();
        let mut seen = 0usize;
        for_each_invocation_in_groups(g, 64, Group::Thread, |inv| {
            seen += 1;
            global_index_map(
                inv.global_index,
                inv.workgroup_index,
                inv.local_index,
                &mut out,
                &visits,
            )
        });
        assert_eq!(seen, total);
        let ok = (0..len).all(|i| out[i] == i as u32 && visits[i].load(Ordering::Relaxed) == 1);
        r.check(ok, || format!("host groups {g:?} not dense"));
    }
    r.finish("global_index");
}
