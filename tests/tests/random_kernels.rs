//! Randomized differential test: generates arithmetic kernels (integer and float
//! expression trees) through the same typed IR builder the macro's output calls, runs
//! them on both backends and evaluates the same trees on the host. Integer results must
//! agree exactly. Float trees use only correctly rounded operations (add, sub, min, max,
//! abs, neg, floor, scaling by powers of two), but drivers may reassociate float adds
//! (Mesa's NIR does unless an operation is marked exact, and SPIR-V lets it), so float
//! results must agree within 8 ulps or 1/8 absolute: a few ulps of the largest
//! intermediate value, which stays under 2^17.

mod common;
use cohort::ir::{self, builtin, AsPlace, Buffer, Val};
use cohort::runtime::{BufferArg, Dispatch};
use cohort::{Group, KernelInfo, Spec};
use common::{devices, is_cpu, Rng};

#[derive(Clone, Debug)]
enum U {
    A,
    B,
    Const(u32),
    Add(Box<U>, Box<U>),
    Sub(Box<U>, Box<U>),
    Mul(Box<U>, Box<U>),
    Xor(Box<U>, Box<U>),
    And(Box<U>, Box<U>),
    Or(Box<U>, Box<U>),
    Shl(Box<U>, u32),
    Shr(Box<U>, u32),
    Min(Box<U>, Box<U>),
    Max(Box<U>, Box<U>),
    Rotl(Box<U>, u32),
    Ones(Box<U>),
    Not(Box<U>),
    /// if l < r { a } else { b }
    SelLt(Box<U>, Box<U>, Box<U>, Box<U>),
    /// (f as u32) for a float tree clamped to [0, 1e6]
    FromF(Box<F>),
}

#[derive(Clone, Debug)]
enum F {
    X,
    Y,
    Const(f32),
    Add(Box<F>, Box<F>),
    Sub(Box<F>, Box<F>),
    Min(Box<F>, Box<F>),
    Max(Box<F>, Box<F>),
    Abs(Box<F>),
    Neg(Box<F>),
    Floor(Box<F>),
    Scale(Box<F>, i32),
    /// (u & 0xffff) as f32
    FromU(Box<U>),
}

fn gen_u(r: &mut Rng, depth: u32) -> U {
    let b = |r: &mut Rng| Box::new(gen_u(r, depth - 1));
    if depth == 0 {
        return match r.next_u32() % 3 {
            0 => U::A,
            1 => U::B,
            _ => U::Const(r.next_u32()),
        };
    }
    match r.next_u32() % 17 {
        0 => U::Add(b(r), b(r)),
        1 => U::Sub(b(r), b(r)),
        2 => U::Mul(b(r), b(r)),
        3 => U::Xor(b(r), b(r)),
        4 => U::And(b(r), b(r)),
        5 => U::Or(b(r), b(r)),
        6 => U::Shl(b(r), r.next_u32() % 32),
        7 => U::Shr(b(r), r.next_u32() % 32),
        8 => U::Min(b(r), b(r)),
        9 => U::Max(b(r), b(r)),
        10 => U::Rotl(b(r), r.next_u32() % 32),
        11 => U::Ones(b(r)),
        12 => U::Not(b(r)),
        13 => U::SelLt(b(r), b(r), b(r), b(r)),
        14 => U::FromF(Box::new(gen_f(r, depth - 1))),
        15 => U::A,
        _ => U::B,
    }
}

fn gen_f(r: &mut Rng, depth: u32) -> F {
    let b = |r: &mut Rng| Box::new(gen_f(r, depth - 1));
    if depth == 0 {
        return match r.next_u32() % 3 {
            0 => F::X,
            1 => F::Y,
            _ => F::Const(((r.next_u32() % 4001) as f32 - 2000.0) * 0.25),
        };
    }
    match r.next_u32() % 10 {
        0 => F::Add(b(r), b(r)),
        1 => F::Sub(b(r), b(r)),
        2 => F::Min(b(r), b(r)),
        3 => F::Max(b(r), b(r)),
        4 => F::Abs(b(r)),
        5 => F::Neg(b(r)),
        6 => F::Floor(b(r)),
        7 => F::Scale(b(r), (r.next_u32() % 5) as i32 - 2),
        8 => F::FromU(Box::new(gen_u(r, depth - 1))),
        _ => F::X,
    }
}

fn host_u(e: &U, a: u32, b: u32, x: f32, y: f32) -> u32 {
    let h = |e: &U| host_u(e, a, b, x, y);
    match e {
        U::A => a,
        U::B => b,
        U::Const(c) => *c,
        U::Add(l, r) => h(l).wrapping_add(h(r)),
        U::Sub(l, r) => h(l).wrapping_sub(h(r)),
        U::Mul(l, r) => h(l).wrapping_mul(h(r)),
        U::Xor(l, r) => h(l) ^ h(r),
        U::And(l, r) => h(l) & h(r),
        U::Or(l, r) => h(l) | h(r),
        U::Shl(l, s) => h(l) << s,
        U::Shr(l, s) => h(l) >> s,
        U::Min(l, r) => h(l).min(h(r)),
        U::Max(l, r) => h(l).max(h(r)),
        U::Rotl(l, s) => h(l).rotate_left(*s),
        U::Ones(l) => h(l).count_ones(),
        U::Not(l) => !h(l),
        U::SelLt(l, r, p, q) => {
            if h(l) < h(r) {
                h(p)
            } else {
                h(q)
            }
        }
        U::FromF(f) => host_f(f, a, b, x, y).clamp(0.0, 1e6) as u32,
    }
}

fn host_f(e: &F, a: u32, b: u32, x: f32, y: f32) -> f32 {
    let h = |e: &F| host_f(e, a, b, x, y);
    match e {
        F::X => x,
        F::Y => y,
        F::Const(c) => *c,
        F::Add(l, r) => h(l) + h(r),
        F::Sub(l, r) => h(l) - h(r),
        F::Min(l, r) => h(l).min(h(r)),
        F::Max(l, r) => h(l).max(h(r)),
        F::Abs(l) => h(l).abs(),
        F::Neg(l) => -h(l),
        F::Floor(l) => h(l).floor(),
        F::Scale(l, k) => h(l) * 2f32.powi(*k),
        F::FromU(u) => (host_u(u, a, b, x, y) & 0xffff) as f32,
    }
}

type In = (Val<u32>, Val<u32>, Val<f32>, Val<f32>);

fn ir_u(e: &U, i: In) -> Val<u32> {
    let h = |e: &U| ir_u(e, i);
    match e {
        U::A => i.0,
        U::B => i.1,
        U::Const(c) => ir::lit(*c),
        U::Add(l, r) => h(l) + h(r),
        U::Sub(l, r) => h(l) - h(r),
        U::Mul(l, r) => h(l) * h(r),
        U::Xor(l, r) => h(l) ^ h(r),
        U::And(l, r) => h(l) & h(r),
        U::Or(l, r) => h(l) | h(r),
        U::Shl(l, s) => h(l) << ir::lit(*s),
        U::Shr(l, s) => h(l) >> ir::lit(*s),
        U::Min(l, r) => h(l).min(h(r)),
        U::Max(l, r) => h(l).max(h(r)),
        U::Rotl(l, s) => h(l).rotate_left(ir::lit(*s)),
        U::Ones(l) => h(l).count_ones(),
        U::Not(l) => !h(l),
        U::SelLt(l, r, p, q) => ir::if_value(ir::lt(h(l), h(r)), || h(p), || h(q)),
        U::FromF(f) => ir::cast::<u32, f32>(ir_f(f, i).clamp(ir::lit(0.0), ir::lit(1e6))),
    }
}

fn ir_f(e: &F, i: In) -> Val<f32> {
    let h = |e: &F| ir_f(e, i);
    match e {
        F::X => i.2,
        F::Y => i.3,
        F::Const(c) => ir::lit(*c),
        F::Add(l, r) => h(l) + h(r),
        F::Sub(l, r) => h(l) - h(r),
        F::Min(l, r) => h(l).min(h(r)),
        F::Max(l, r) => h(l).max(h(r)),
        F::Abs(l) => h(l).abs(),
        F::Neg(l) => -h(l),
        F::Floor(l) => h(l).floor(),
        F::Scale(l, k) => h(l) * ir::lit(2f32.powi(*k)),
        F::FromU(u) => ir::cast::<f32, u32>(ir_u(u, i) & ir::lit(0xffffu32)),
    }
}

static INFO: KernelInfo = common::ir_kernel_info("random_expr", file!(), line!());

#[test]
fn random_arithmetic_kernels_agree_everywhere() {
    let n = 256usize;
    let mut rng = Rng(0x5eed_1234);
    let a: Vec<u32> = (0..n).map(|_| rng.next_u32()).collect();
    let b: Vec<u32> = (0..n)
        .map(|k| if k % 7 == 0 { 0 } else { rng.next_u32() })
        .collect();
    let x: Vec<f32> = (0..n).map(|_| rng.f32(-1000.0, 1000.0)).collect();
    let y: Vec<f32> = (0..n).map(|_| rng.f32(-4.0, 4.0)).collect();
    // These kernels are IR built without Rust source, so they have no host form for the
    // CPU backend to run; `host_u` / `host_f` evaluate the same expression trees instead.
    let devs: Vec<_> = devices().into_iter().filter(|d| !is_cpu(d)).collect();
    for k in 0..48 {
        let ut = gen_u(&mut rng, 1 + k % 5);
        let ft = gen_f(&mut rng, 1 + k % 5);
        let spec = Spec::portable(&INFO, Group::Thread);
        let built = ir::build_kernel(&INFO, spec, || {
            let gi = builtin::global_index();
            let ab = Buffer::<u32>::declare("a", false);
            let bb = Buffer::<u32>::declare("b", false);
            let xb = Buffer::<f32>::declare("x", false);
            let yb = Buffer::<f32>::declare("y", false);
            let ou = Buffer::<u32>::declare("out_u", true);
            let of = Buffer::<f32>::declare("out_f", true);
            let load_u = |buf: Buffer<u32>| ir::place_index(buf.as_place(), gi).get();
            let load_f = |buf: Buffer<f32>| ir::place_index(buf.as_place(), gi).get();
            let i = (load_u(ab), load_u(bb), load_f(xb), load_f(yb));
            ir::place_index(ou.as_place(), gi).set(ir_u(&ut, i));
            ir::place_index(of.as_place(), gi).set(ir_f(&ft, i));
        });
        let art = cohort::emit::compile(&built, format!("random_expr_{k}"))
            .unwrap_or_else(|e| panic!("{e}\n{ut:?}\n{ft:?}"));
        let host_u_out: Vec<u32> = (0..n)
            .map(|j| host_u(&ut, a[j], b[j], x[j], y[j]))
            .collect();
        let host_f_out: Vec<u32> = (0..n)
            .map(|j| host_f(&ft, a[j], b[j], x[j], y[j]).to_bits())
            .collect();
        for d in &devs {
            let bufs_u = [d.upload(&a).unwrap(), d.upload(&b).unwrap()];
            let bufs_f = [d.upload(&x).unwrap(), d.upload(&y).unwrap()];
            let ou = d.alloc::<u32>(n).unwrap();
            let of = d.alloc::<f32>(n).unwrap();
            let args: Vec<BufferArg> = vec![
                bufs_u[0].arg(),
                bufs_u[1].arg(),
                bufs_f[0].arg(),
                bufs_f[1].arg(),
                ou.arg(),
                of.arg(),
            ];
            d.dispatch(&art, &args, Dispatch::Groups([(n / 64) as u32, 1, 1]))
                .unwrap();
            let gu = d.read(&ou).unwrap();
            let gf: Vec<u32> = d.read(&of).unwrap().iter().map(|v| v.to_bits()).collect();
            assert_eq!(
                gu,
                host_u_out,
                "integer kernel {k} on {:?}: {ut:?}",
                d.info().backend
            );
            for j in 0..n {
                let (g, h) = (f32::from_bits(gf[j]), f32::from_bits(host_f_out[j]));
                // -0.0 and +0.0 compare equal: min/max of zeros may pick either sign.
                let close = g == h || common::ulps(g, h) <= 8 || (g - h).abs() <= 0.125;
                assert!(
                    close,
                    "float kernel {k} on {:?}, element {j}: {g} vs {h}: {ft:?}",
                    d.info().backend
                );
            }
        }
    }
}
