//! Expressions of the vector form. Every operation is the host form's, lane by lane and in
//! the same order, so that results agree bit for bit: integer division by zero and
//! shift amounts follow WGSL (`cohort::host::ops`), casts from float saturate (Rust's
//! `as`), libm functions are the same C functions, and the vector helpers group their
//! sums as glam does (`dot` on four components as `(x + z) + (y + w)`, SSE's order).

use naga::{BinaryOperator as Bo, Expression as E, Handle, MathFunction as Mf, Scalar};
use naga::{ScalarKind, TypeInner, UnaryOperator as Uo};

use super::lower::{Fx, Val};
use super::types::{float_text, lanes, scalar, splat_const, value_type, w, Lowering};

/// A value's shape: its vector size (`None` for a scalar) and scalar.
fn shape(t: &TypeInner) -> Lowering<(Option<u32>, Scalar)> {
    match *t {
        TypeInner::Scalar(s) => Ok((None, s)),
        TypeInner::Vector { size, scalar } => Ok((Some(size as u32), scalar)),
        ref other => Err(format!("arithmetic on {other:?}")),
    }
}

fn literal(l: &naga::Literal) -> Lowering<Val> {
    Ok(match *l {
        naga::Literal::F32(v) => Val::r(lanes("float"), splat_const("float", &float_text(v))),
        naga::Literal::U32(v) => Val::r(lanes("i32"), splat_const("i32", &(v as i32).to_string())),
        naga::Literal::I32(v) => Val::r(lanes("i32"), splat_const("i32", &v.to_string())),
        naga::Literal::Bool(b) => Val::r(lanes("i1"), splat_const("i1", &b.to_string())),
        ref other => return Err(format!("the literal {other:?}")),
    })
}

impl Fx<'_> {
    /// Component `i` of a value of shape `n` (a scalar is its own every component).
    fn comp(&mut self, v: &Val, n: Option<u32>, i: u32) -> Lowering<String> {
        match n {
            None => Ok(v.v()?.to_string()),
            Some(_) => Ok(self.op(&format!("extractvalue {}, {i}", v.typed()?))),
        }
    }

    /// A value of shape `n` from its components, each `<W x s>`.
    fn build(&mut self, parts: Vec<String>, n: Option<u32>, s: &str) -> Val {
        let v = lanes(s);
        match n {
            None => Val::r(v, parts.into_iter().next().unwrap_or_default()),
            Some(n) => {
                let ty = format!("[{n} x {v}]");
                let mut acc = "poison".to_string();
                for (i, p) in parts.iter().enumerate() {
                    acc = self.op(&format!("insertvalue {ty} {acc}, {v} {p}, {i}"));
                }
                Val::r(ty, acc)
            }
        }
    }

    /// `f` applied to each component of `args` (all of shape `n`, scalars splatted).
    fn map(
        &mut self,
        args: &[(Val, Option<u32>)],
        n: Option<u32>,
        out: &str,
        mut f: impl FnMut(&mut Self, &[String]) -> Lowering<String>,
    ) -> Lowering<Val> {
        let mut parts = Vec::new();
        for i in 0..n.unwrap_or(1) {
            let mut cs = Vec::new();
            for (a, an) in args {
                cs.push(self.comp(a, *an, i)?);
            }
            parts.push(f(self, &cs)?);
        }
        Ok(self.build(parts, n, out))
    }

    /// `call ret @name(args)`, each argument a (type, value) pair; declares the callee.
    fn call(&mut self, ret: &str, name: &str, args: &[(String, String)]) -> String {
        let params: Vec<&str> = args.iter().map(|(t, _)| t.as_str()).collect();
        let ops: Vec<String> = args.iter().map(|(t, v)| format!("{t} {v}")).collect();
        self.declare(&format!("declare {ret} @{name}({})", params.join(", ")));
        self.op(&format!("call {ret} @{name}({})", ops.join(", ")))
    }

    /// An LLVM intrinsic on `<W x float>`, e.g. `sqrt`.
    pub(super) fn fintr(&mut self, name: &str, xs: &[String]) -> String {
        let v = lanes("float");
        let args: Vec<(String, String)> = xs.iter().map(|x| (v.clone(), x.clone())).collect();
        self.call(&v, &format!("llvm.{name}.v{}f32", w()), &args)
    }

    /// A function of floats that LLVM has no vector instruction for (`sin`, `acosf`, ...),
    /// so it costs one libm call per lane. Where every running lane passes the same
    /// arguments bit for bit (a group's shared draw, a value of constants), one call
    /// serves them all: the same C function on the same bits gives the same result, so the
    /// block's values are the host form's either way. `libm` names a C function;
    /// otherwise `name` is an LLVM intrinsic (`llvm.NAME.f32`, which is that C function).
    fn once_if_uniform(&mut self, name: &str, libm: bool, xs: &[String]) -> String {
        let v = lanes("float");
        let vi = lanes("i32");
        let mask = self.exec();
        let first = self.first_active(&mask);
        let mut firsts = Vec::new();
        let mut differ: Option<String> = None;
        for x in xs {
            let x0 = self.op(&format!("extractelement {v} {x}, i32 {first}"));
            let bits = self.op(&format!("bitcast {v} {x} to {vi}"));
            let b0 = self.op(&format!("bitcast float {x0} to i32"));
            let all = self.splat("i32", &b0);
            let same = self.op(&format!("icmp eq {vi} {bits}, {all}"));
            let d = self.not(&same);
            differ = Some(match differ {
                None => d,
                Some(acc) => self.or(&acc, &d),
            });
            firsts.push(("float".to_string(), x0));
        }
        let differ = differ.unwrap_or_else(|| splat_const("i1", "false"));
        let differ = self.and(&mask, &differ);
        let diverge = self.any(&differ);
        let slot = self.alloca(&v);
        let (one, many, join) = (self.label(), self.label(), self.label());
        self.line(&format!("br i1 {diverge}, label %{many}, label %{one}"));
        self.body.push_str(&format!("{one}:\n"));
        let callee = if libm {
            name.to_string()
        } else {
            format!("llvm.{name}.f32")
        };
        let r = self.call("float", &callee, &firsts);
        let r = self.splat("float", &r);
        self.line(&format!("store {v} {r}, ptr {slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{many}:\n"));
        let r = if libm {
            self.libm(name, xs)
        } else {
            self.fintr(name, xs)
        };
        self.line(&format!("store {v} {r}, ptr {slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        self.op(&format!("load {v}, ptr {slot}"))
    }

    /// Whether `Sin` or `Cos` of `arg` has its partner (`Cos` or `Sin` of the same
    /// expression) in this function: LLVM turns such a pair into one `sincosf` call per
    /// lane when both sit in one basic block, which a uniformity test between them would
    /// prevent. The pairs the kernels have are a direction's azimuth, which varies by lane.
    fn sincos_pair(&self, fun: Mf, arg: Handle<naga::Expression>) -> bool {
        let partner = match fun {
            Mf::Sin => Mf::Cos,
            Mf::Cos => Mf::Sin,
            _ => return false,
        };
        self.fun
            .expressions
            .iter()
            .any(|(_, e)| matches!(*e, E::Math { fun: f, arg: a, .. } if f == partner && a == arg))
    }

    /// A libm function, called once per lane (the C function the host form calls).
    fn libm(&mut self, name: &str, xs: &[String]) -> String {
        let v = lanes("float");
        let mut acc = "poison".to_string();
        for lane in 0..w() {
            let args: Vec<(String, String)> = xs
                .iter()
                .map(|x| {
                    let e = self.op(&format!("extractelement {v} {x}, i32 {lane}"));
                    ("float".to_string(), e)
                })
                .collect();
            let r = self.call("float", name, &args);
            acc = self.op(&format!("insertelement {v} {acc}, float {r}, i32 {lane}"));
        }
        acc
    }

    fn fsel(&mut self, pred: &str, a: &str, b: &str, x: &str, y: &str) -> String {
        let v = lanes("float");
        let c = self.op(&format!("fcmp {pred} {v} {a}, {b}"));
        self.op(&format!("select {} {c}, {v} {x}, {v} {y}", Fx::mask_ty()))
    }

    pub fn expression(&mut self, h: Handle<naga::Expression>) -> Lowering<Val> {
        let e = &self.fun.expressions[h];
        match *e {
            E::Literal(ref l) => literal(l),
            E::Constant(c) => self.global_expression(self.m.constants[c].init),
            E::ZeroValue(t) => Ok(Val::r(
                value_type(self.m, &self.m.types[t].inner)?,
                "zeroinitializer",
            )),
            E::GlobalVariable(g) => self.global_place(g),
            E::LocalVariable(l) => Ok(self.local_place(l)),
            E::Compose { ty, ref components } => {
                let comps: Vec<Handle<naga::Expression>> = components.clone();
                let t = self.m.types[ty].inner.clone();
                self.compose(&t, &comps)
            }
            E::Splat { size, value } => {
                let v = self.val(value)?;
                let s = v.ty()?.to_string();
                let n = size as u32;
                let ty = format!("[{n} x {s}]");
                let mut acc = "poison".to_string();
                for i in 0..n {
                    acc = self.op(&format!("insertvalue {ty} {acc}, {}, {i}", v.typed()?));
                }
                Ok(Val::r(ty, acc))
            }
            E::Swizzle {
                size,
                vector,
                pattern,
            } => {
                let v = self.val(vector)?;
                let (_, s) = shape(self.ty_of(vector))?;
                let mut parts = Vec::new();
                for p in pattern.iter().take(size as usize) {
                    parts.push(self.op(&format!("extractvalue {}, {}", v.typed()?, *p as u32)));
                }
                Ok(self.build(parts, Some(size as u32), scalar(s)?))
            }
            E::Access { base, index } => {
                let i = self.val(index)?;
                let kind = shape(self.ty_of(index))?.1.kind;
                match self.val(base)? {
                    Val::P(p) => self.index_place(p, &i, kind),
                    v => self.index_value(&v, self.ty_of(base), &i),
                }
            }
            E::AccessIndex { base, index } => match self.val(base)? {
                Val::P(p) => self.member_place(p, index),
                v => {
                    let t = match self.ty_of(h) {
                        TypeInner::Pointer { .. } | TypeInner::ValuePointer { .. } => {
                            return Err("a member pointer of a value".into())
                        }
                        t => value_type(self.m, t)?,
                    };
                    let r = self.op(&format!("extractvalue {}, {index}", v.typed()?));
                    Ok(Val::r(t, r))
                }
            },
            E::Load { pointer } => {
                let p = self.place(pointer)?;
                self.load(&p)
            }
            E::Unary { op, expr } => self.unary(op, expr),
            E::Binary { op, left, right } => self.binary(op, left, right),
            E::Select {
                condition,
                accept,
                reject,
            } => {
                let (cn, _) = shape(self.ty_of(condition))?;
                let (n, s) = shape(self.ty_of(accept))?;
                let args = [
                    (self.val(condition)?, cn),
                    (self.val(accept)?, n),
                    (self.val(reject)?, n),
                ];
                let v = lanes(scalar(s)?);
                self.map(&args, n, scalar(s)?, |fx, c| {
                    Ok(fx.op(&format!(
                        "select {} {}, {v} {}, {v} {}",
                        Fx::mask_ty(),
                        c[0],
                        c[1],
                        c[2]
                    )))
                })
            }
            E::Relational { fun, argument } => self.relational(fun, argument),
            E::Math {
                fun,
                arg,
                arg1,
                arg2,
                ..
            } => self.math(fun, arg, arg1, arg2),
            E::As {
                expr,
                kind,
                convert,
            } => self.cast(expr, kind, convert),
            E::ArrayLength(p) => {
                let p = self.place(p)?;
                let (super::memory::Root::Buf { g, konst: 0, .. }, TypeInner::Array { stride, .. }) =
                    (&p.root, &p.ty)
                else {
                    return Err("the length of an array inside a struct".into());
                };
                let at = self.op(&format!(
                    "getelementptr i8, ptr %env, i64 {}",
                    *g as u64 * 16 + 8
                ));
                let size = self.op(&format!("load i64, ptr {at}, !invariant.load !0"));
                let n = self.op(&format!("udiv i64 {size}, {stride}"));
                let n = self.op(&format!("trunc i64 {n} to i32"));
                let v = self.splat("i32", &n);
                Ok(Val::r(lanes("i32"), v))
            }
            ref other => Err(format!("the expression {other:?}")),
        }
    }

    fn compose(&mut self, t: &TypeInner, comps: &[Handle<naga::Expression>]) -> Lowering<Val> {
        let ty = value_type(self.m, t)?;
        let mut parts = Vec::new();
        if let TypeInner::Vector { .. } = t {
            // Vector components may themselves be vectors: flatten them.
            for &c in comps {
                let v = self.val(c)?;
                match shape(self.ty_of(c))? {
                    (Some(n), s) => {
                        for i in 0..n {
                            let x = self.op(&format!("extractvalue {}, {i}", v.typed()?));
                            parts.push(format!("{} {x}", lanes(scalar(s)?)));
                        }
                    }
                    (None, _) => parts.push(v.typed()?),
                }
            }
        } else {
            for &c in comps {
                parts.push(self.val(c)?.typed()?);
            }
        }
        let mut acc = "poison".to_string();
        for (i, p) in parts.iter().enumerate() {
            acc = self.op(&format!("insertvalue {ty} {acc}, {p}, {i}"));
        }
        Ok(Val::r(ty, acc))
    }

    /// A constant's initializer, computed in place.
    fn global_expression(&mut self, h: Handle<naga::Expression>) -> Lowering<Val> {
        match self.m.global_expressions[h] {
            E::Literal(ref l) => literal(l),
            E::Constant(c) => self.global_expression(self.m.constants[c].init),
            E::ZeroValue(t) => Ok(Val::r(
                value_type(self.m, &self.m.types[t].inner)?,
                "zeroinitializer",
            )),
            E::Compose { ty, ref components } => {
                let ty_s = value_type(self.m, &self.m.types[ty].inner)?;
                let comps = components.clone();
                let mut acc = "poison".to_string();
                for (i, c) in comps.into_iter().enumerate() {
                    let v = self.global_expression(c)?;
                    acc = self.op(&format!("insertvalue {ty_s} {acc}, {}, {i}", v.typed()?));
                }
                Ok(Val::r(ty_s, acc))
            }
            ref other => Err(format!("the constant expression {other:?}")),
        }
    }

    /// `v[i]` with a per-lane index, on a vector or array value.
    fn index_value(&mut self, v: &Val, t: &TypeInner, i: &Val) -> Lowering<Val> {
        let (n, elem) = match *t {
            TypeInner::Vector { size, scalar: s } => (size as u32, lanes(scalar(s)?)),
            TypeInner::Array {
                base,
                size: naga::ArraySize::Constant(n),
                ..
            } => (n.get(), value_type(self.m, &self.m.types[base].inner)?),
            ref other => return Err(format!("indexing a {other:?} value")),
        };
        if elem.starts_with('[') || elem.starts_with('{') {
            return Err("a per-lane index into an array of aggregates".into());
        }
        // A lane out of range is an error, as the host form's panic (and reads element 0).
        let e = self.exec();
        let ok = self.op(&format!(
            "icmp ult {}, {}",
            i.typed()?,
            splat_const("i32", &n.to_string())
        ));
        let nok = self.not(&ok);
        let bad = self.and(&e, &nok);
        self.report(&bad);
        let mut acc = self.op(&format!("extractvalue {}, 0", v.typed()?));
        for k in 1..n {
            let x = self.op(&format!("extractvalue {}, {k}", v.typed()?));
            let c = self.op(&format!(
                "icmp eq {}, {}",
                i.typed()?,
                splat_const("i32", &k.to_string())
            ));
            acc = self.op(&format!(
                "select {} {c}, {elem} {x}, {elem} {acc}",
                Fx::mask_ty()
            ));
        }
        Ok(Val::r(elem, acc))
    }

    fn unary(&mut self, op: Uo, x: Handle<naga::Expression>) -> Lowering<Val> {
        let (n, s) = shape(self.ty_of(x))?;
        let st = scalar(s)?;
        let v = lanes(st);
        let args = [(self.val(x)?, n)];
        self.map(&args, n, st, |fx, c| {
            Ok(match (op, s.kind) {
                (Uo::Negate, ScalarKind::Float) => fx.op(&format!("fneg {v} {}", c[0])),
                (Uo::Negate, _) => fx.op(&format!("sub {v} zeroinitializer, {}", c[0])),
                (Uo::LogicalNot | Uo::BitwiseNot, ScalarKind::Bool) => fx.not(&c[0]),
                (Uo::BitwiseNot, _) => {
                    fx.op(&format!("xor {v} {}, {}", c[0], splat_const("i32", "-1")))
                }
                _ => return Err(format!("{op:?} on {s:?}")),
            })
        })
    }

    fn binary(
        &mut self,
        op: Bo,
        l: Handle<naga::Expression>,
        r: Handle<naga::Expression>,
    ) -> Lowering<Val> {
        if let (Bo::Multiply, &TypeInner::Matrix { columns, rows, .. }) = (op, self.ty_of(l)) {
            return self.matrix_times_vector(columns as u32, rows as u32, l, r);
        }
        let (ln, ls) = shape(self.ty_of(l))?;
        let (rn, _) = shape(self.ty_of(r))?;
        let n = ln.or(rn);
        let compare = matches!(
            op,
            Bo::Equal | Bo::NotEqual | Bo::Less | Bo::LessEqual | Bo::Greater | Bo::GreaterEqual
        );
        let out = if compare { "i1" } else { scalar(ls)? };
        let args = [(self.val(l)?, ln), (self.val(r)?, rn)];
        self.map(&args, n, out, |fx, c| {
            fx.scalar_binary(op, ls, &c[0], &c[1])
        })
    }

    fn scalar_binary(&mut self, op: Bo, s: Scalar, a: &str, b: &str) -> Lowering<String> {
        let v = lanes(scalar(s)?);
        let ins = match (s.kind, op) {
            (ScalarKind::Float, _) => match op {
                Bo::Add => "fadd",
                Bo::Subtract => "fsub",
                Bo::Multiply => "fmul",
                Bo::Divide => "fdiv",
                Bo::Modulo => "frem",
                Bo::Equal => "fcmp oeq",
                Bo::NotEqual => "fcmp une",
                Bo::Less => "fcmp olt",
                Bo::LessEqual => "fcmp ole",
                Bo::Greater => "fcmp ogt",
                Bo::GreaterEqual => "fcmp oge",
                _ => return Err(format!("{op:?} on floats")),
            },
            (ScalarKind::Bool, _) => match op {
                Bo::And | Bo::LogicalAnd => "and",
                Bo::InclusiveOr | Bo::LogicalOr => "or",
                Bo::ExclusiveOr | Bo::NotEqual => "xor",
                Bo::Equal => "icmp eq",
                _ => return Err(format!("{op:?} on booleans")),
            },
            (kind, Bo::Divide | Bo::Modulo) => return Ok(self.int_div(op, kind, a, b)),
            (kind, Bo::ShiftLeft | Bo::ShiftRight) => {
                let amount = self.op(&format!("and {v} {b}, {}", splat_const("i32", "31")));
                let ins = match (op, kind) {
                    (Bo::ShiftLeft, _) => "shl",
                    (_, ScalarKind::Sint) => "ashr",
                    _ => "lshr",
                };
                return Ok(self.op(&format!("{ins} {v} {a}, {amount}")));
            }
            (kind, _) => {
                let signed = kind == ScalarKind::Sint;
                match op {
                    Bo::Add => "add",
                    Bo::Subtract => "sub",
                    Bo::Multiply => "mul",
                    Bo::And => "and",
                    Bo::InclusiveOr => "or",
                    Bo::ExclusiveOr => "xor",
                    Bo::Equal => "icmp eq",
                    Bo::NotEqual => "icmp ne",
                    Bo::Less if signed => "icmp slt",
                    Bo::Less => "icmp ult",
                    Bo::LessEqual if signed => "icmp sle",
                    Bo::LessEqual => "icmp ule",
                    Bo::Greater if signed => "icmp sgt",
                    Bo::Greater => "icmp ugt",
                    Bo::GreaterEqual if signed => "icmp sge",
                    Bo::GreaterEqual => "icmp uge",
                    _ => return Err(format!("{op:?} on integers")),
                }
            }
        };
        Ok(self.op(&format!("{ins} {v} {a}, {b}")))
    }

    /// WGSL's integer `/` and `%`: `x / 0 == x`, `x % 0 == 0`, `MIN / -1 == MIN`,
    /// `MIN % -1 == 0`; dividing by 1 instead gives exactly those.
    fn int_div(&mut self, op: Bo, kind: ScalarKind, a: &str, b: &str) -> String {
        let v = lanes("i32");
        let m = Fx::mask_ty();
        let zero = self.op(&format!("icmp eq {v} {b}, zeroinitializer"));
        let one = splat_const("i32", "1");
        let signed = kind == ScalarKind::Sint;
        let bad = if signed {
            let m1 = self.op(&format!("icmp eq {v} {b}, {}", splat_const("i32", "-1")));
            let min = self.op(&format!(
                "icmp eq {v} {a}, {}",
                splat_const("i32", &i32::MIN.to_string())
            ));
            let ovf = self.and(&m1, &min);
            self.or(&zero, &ovf)
        } else {
            zero.clone()
        };
        let d = self.op(&format!("select {m} {bad}, {v} {one}, {v} {b}"));
        // A constant divisor stays an integer division, which LLVM turns into a multiply
        // and shifts. Any other goes through f64: x86 has no vector integer division, so
        // LLVM splits `udiv` into one scalar `div` per lane (a coherent `extend` has three
        // per bounce). For 32-bit operands the quotient truncated from the correctly
        // rounded f64 one is exact: a quotient k - r/d (r >= 1) lies at least 1/|a| >=
        // 2^-32 below k relative to it, far above f64's 2^-53, so it never rounds up to k.
        if !b.starts_with('<') {
            let (to_f, to_i) = if signed {
                ("sitofp", "fptosi")
            } else {
                ("uitofp", "fptoui")
            };
            let f64s = lanes("double");
            let fa = self.op(&format!("{to_f} {v} {a} to {f64s}"));
            let fd = self.op(&format!("{to_f} {v} {d} to {f64s}"));
            let fq = self.op(&format!("fdiv {f64s} {fa}, {fd}"));
            let q = self.op(&format!("{to_i} {f64s} {fq} to {v}"));
            return match op {
                Bo::Divide => self.op(&format!("select {m} {zero}, {v} {a}, {v} {q}")),
                // a - q d wraps in i32 to the remainder, whose sign is a's (WGSL's `%`).
                _ => {
                    let qd = self.op(&format!("mul {v} {q}, {d}"));
                    self.op(&format!("sub {v} {a}, {qd}"))
                }
            };
        }
        match (op, signed) {
            (Bo::Divide, s) => {
                let q = self.op(&format!("{} {v} {a}, {d}", if s { "sdiv" } else { "udiv" }));
                self.op(&format!("select {m} {zero}, {v} {a}, {v} {q}"))
            }
            (_, s) => self.op(&format!("{} {v} {a}, {d}", if s { "srem" } else { "urem" })),
        }
    }

    fn relational(
        &mut self,
        fun: naga::RelationalFunction,
        x: Handle<naga::Expression>,
    ) -> Lowering<Val> {
        use naga::RelationalFunction as R;
        let (n, _) = shape(self.ty_of(x))?;
        let xv = self.val(x)?;
        match fun {
            R::All | R::Any => {
                let mut acc = self.comp(&xv, n, 0)?;
                for i in 1..n.unwrap_or(1) {
                    let c = self.comp(&xv, n, i)?;
                    acc = if fun == R::All {
                        self.and(&acc, &c)
                    } else {
                        self.or(&acc, &c)
                    };
                }
                Ok(Val::r(Fx::mask_ty(), acc))
            }
            R::IsNan | R::IsInf => {
                let v = lanes("float");
                self.map(&[(xv, n)], n, "i1", |fx, c| {
                    Ok(if fun == R::IsNan {
                        fx.op(&format!("fcmp uno {v} {}, {}", c[0], c[0]))
                    } else {
                        let a = fx.fintr("fabs", &[c[0].clone()]);
                        fx.op(&format!(
                            "fcmp oeq {v} {a}, {}",
                            splat_const("float", "0x7FF0000000000000")
                        ))
                    })
                })
            }
        }
    }

    fn cast(
        &mut self,
        x: Handle<naga::Expression>,
        kind: ScalarKind,
        convert: Option<u8>,
    ) -> Lowering<Val> {
        let (n, from) = shape(self.ty_of(x))?;
        let to = Scalar {
            kind,
            width: convert.unwrap_or(from.width),
        };
        let (fs, ts) = (scalar(from)?, scalar(to)?);
        let (fv, tv) = (lanes(fs), lanes(ts));
        let xv = self.val(x)?;
        self.map(&[(xv, n)], n, ts, |fx, c| {
            let a = &c[0];
            use ScalarKind::*;
            Ok(match (from.kind, kind, convert.is_some()) {
                (f, t, _) if f == t => a.clone(),
                (Sint | Uint, Sint | Uint, _) => a.clone(),
                (Float, Sint | Uint, false) | (Sint | Uint, Float, false) => {
                    fx.op(&format!("bitcast {fv} {a} to {tv}"))
                }
                (Float, t @ (Sint | Uint), true) => fx.float_to_int(a, t == Sint),
                (Sint, Float, true) => fx.op(&format!("sitofp {fv} {a} to {tv}")),
                (Uint, Float, true) => fx.op(&format!("uitofp {fv} {a} to {tv}")),
                (Bool, Sint | Uint, true) => fx.op(&format!("zext {fv} {a} to {tv}")),
                (Bool, Float, true) => fx.op(&format!("uitofp {fv} {a} to {tv}")),
                (Sint | Uint, Bool, true) => fx.op(&format!("icmp ne {fv} {a}, zeroinitializer")),
                (Float, Bool, true) => fx.op(&format!("fcmp une {fv} {a}, zeroinitializer")),
                _ => return Err(format!("casting {from:?} to {to:?}")),
            })
        })
    }

    /// Rust's `as i32` / `as u32` of f32 lanes (WGSL's conversion): truncated, NaN to 0,
    /// saturated at the type's bounds. The value is clamped into range first, so that
    /// the plain `fptosi` / `fptoui` is one vector instruction: LLVM turns its saturating
    /// intrinsics into a compare, a scalar conversion and two moves per lane (a coherent
    /// `extend` converts two floats per bounce).
    fn float_to_int(&mut self, a: &str, signed: bool) -> String {
        let (v, vi, m) = (lanes("float"), lanes("i32"), Self::mask_ty());
        let f = |x: f32| splat_const("float", &float_text(x));
        // The largest f32 below the type's upper bound, which converts exactly.
        let (low, high, beyond, at_beyond, to) = if signed {
            (
                -2_147_483_648.0f32,
                2_147_483_520.0f32,
                2_147_483_648.0f32,
                i32::MAX,
                "fptosi",
            )
        } else {
            (0.0, 4_294_967_040.0, 4_294_967_296.0, -1, "fptoui")
        };
        // NaN becomes 0, then what lies outside [low, high] is clamped to it; values at or
        // past the upper bound take the type's maximum below.
        let nan = self.op(&format!("fcmp uno {v} {a}, {a}"));
        let x = self.op(&format!("select {m} {nan}, {v} zeroinitializer, {v} {a}"));
        let under = self.op(&format!("fcmp olt {v} {x}, {}", f(low)));
        let x = self.op(&format!("select {m} {under}, {v} {}, {v} {x}", f(low)));
        let over = self.op(&format!("fcmp ogt {v} {x}, {}", f(high)));
        let x = self.op(&format!("select {m} {over}, {v} {}, {v} {x}", f(high)));
        let t = self.op(&format!("{to} {v} {x} to {vi}"));
        let past = self.op(&format!("fcmp oge {v} {a}, {}", f(beyond)));
        self.op(&format!(
            "select {m} {past}, {vi} {}, {vi} {t}",
            splat_const("i32", &at_beyond.to_string())
        ))
    }

    fn math(
        &mut self,
        fun: Mf,
        arg: Handle<naga::Expression>,
        arg1: Option<Handle<naga::Expression>>,
        arg2: Option<Handle<naga::Expression>>,
    ) -> Lowering<Val> {
        if let (
            Mf::Transpose,
            &TypeInner::Matrix {
                columns,
                rows,
                scalar: s,
            },
        ) = (fun, self.ty_of(arg))
        {
            return self.transpose(arg, columns as u32, rows as u32, s);
        }
        let (n, s) = shape(self.ty_of(arg))?;
        let st = scalar(s)?;
        let v = lanes(st);
        let mut args = vec![(self.val(arg)?, n)];
        for a in [arg1, arg2].into_iter().flatten() {
            args.push((self.val(a)?, shape(self.ty_of(a))?.0));
        }
        let float = s.kind == ScalarKind::Float;
        let signed = s.kind == ScalarKind::Sint;
        let m = Fx::mask_ty();
        let intrinsic = |name: &'static str| {
            move |fx: &mut Self, c: &[String]| -> Lowering<String> { Ok(fx.fintr(name, c)) }
        };
        let libm = |name: &'static str| {
            move |fx: &mut Self, c: &[String]| -> Lowering<String> {
                Ok(fx.once_if_uniform(name, true, c))
            }
        };
        // LLVM expands these intrinsics on vectors into one libm call per lane.
        let paired = self.sincos_pair(fun, arg);
        let per_lane = move |name: &'static str| {
            move |fx: &mut Self, c: &[String]| -> Lowering<String> {
                Ok(if paired {
                    fx.fintr(name, c)
                } else {
                    fx.once_if_uniform(name, false, c)
                })
            }
        };
        match fun {
            Mf::Abs if float => self.map(&args, n, st, intrinsic("fabs")),
            Mf::Abs if signed => self.map(&args, n, st, |fx, c| {
                let neg = fx.op(&format!("icmp slt {v} {}, zeroinitializer", c[0]));
                let flip = fx.op(&format!("sub {v} zeroinitializer, {}", c[0]));
                Ok(fx.op(&format!("select {m} {neg}, {v} {flip}, {v} {}", c[0])))
            }),
            Mf::Abs => Ok(args.remove(0).0),
            // Scalars are Rust's `f32::min` (IEEE minNum); glam's vectors pick with `<`.
            Mf::Min | Mf::Max if float && n.is_none() => self.map(
                &args,
                n,
                st,
                intrinsic(if fun == Mf::Min { "minnum" } else { "maxnum" }),
            ),
            Mf::Min | Mf::Max if float => self.map(&args, n, st, |fx, c| {
                let p = if fun == Mf::Min { "olt" } else { "ogt" };
                Ok(fx.fsel(p, &c[0], &c[1], &c[0], &c[1]))
            }),
            Mf::Min | Mf::Max => self.map(&args, n, st, |fx, c| {
                let p = match (fun == Mf::Min, signed) {
                    (true, true) => "slt",
                    (true, false) => "ult",
                    (false, true) => "sgt",
                    (false, false) => "ugt",
                };
                let k = fx.op(&format!("icmp {p} {v} {}, {}", c[0], c[1]));
                Ok(fx.op(&format!("select {m} {k}, {v} {}, {v} {}", c[0], c[1])))
            }),
            // Rust's `f32::clamp` on scalars; glam's `max(lo).min(hi)` on vectors.
            Mf::Clamp if float && n.is_none() => self.map(&args, n, st, |fx, c| {
                let x = fx.fsel("olt", &c[0], &c[1], &c[1], &c[0]);
                Ok(fx.fsel("ogt", &x, &c[2], &c[2], &x))
            }),
            Mf::Clamp if float => self.map(&args, n, st, |fx, c| {
                let x = fx.fsel("ogt", &c[0], &c[1], &c[0], &c[1]);
                Ok(fx.fsel("olt", &x, &c[2], &x, &c[2]))
            }),
            Mf::Clamp => self.map(&args, n, st, |fx, c| {
                let (gt, lt) = if signed {
                    ("sgt", "slt")
                } else {
                    ("ugt", "ult")
                };
                let k = fx.op(&format!("icmp {gt} {v} {}, {}", c[0], c[1]));
                let x = fx.op(&format!("select {m} {k}, {v} {}, {v} {}", c[0], c[1]));
                let k = fx.op(&format!("icmp {lt} {v} {x}, {}", c[2]));
                Ok(fx.op(&format!("select {m} {k}, {v} {x}, {v} {}", c[2])))
            }),
            Mf::Floor if float => self.map(&args, n, st, intrinsic("floor")),
            Mf::Ceil if float => self.map(&args, n, st, intrinsic("ceil")),
            Mf::Trunc if float => self.map(&args, n, st, intrinsic("trunc")),
            Mf::Sqrt if float => self.map(&args, n, st, intrinsic("sqrt")),
            Mf::Sin | Mf::Cos if float && super::sincos::libm_agrees() => {
                self.map(&args, n, st, |fx, c| {
                    Ok(fx.sin_or_cos(&c[0], fun == Mf::Cos))
                })
            }
            Mf::Sin if float => self.map(&args, n, st, per_lane("sin")),
            Mf::Cos if float => self.map(&args, n, st, per_lane("cos")),
            Mf::Exp if float => self.map(&args, n, st, per_lane("exp")),
            Mf::Exp2 if float => self.map(&args, n, st, per_lane("exp2")),
            Mf::Log if float => self.map(&args, n, st, per_lane("log")),
            Mf::Log2 if float => self.map(&args, n, st, per_lane("log2")),
            Mf::Pow if float => self.map(&args, n, st, per_lane("pow")),
            Mf::Fma if float => self.map(&args, n, st, intrinsic("fma")),
            Mf::Tan if float => self.map(&args, n, st, libm("tanf")),
            Mf::Acos if float && super::acos::libm_agrees() => {
                self.map(&args, n, st, |fx, c| Ok(fx.acos(&c[0])))
            }
            Mf::Acos if float => self.map(&args, n, st, libm("acosf")),
            Mf::Asin if float => self.map(&args, n, st, libm("asinf")),
            Mf::Atan if float => self.map(&args, n, st, libm("atanf")),
            Mf::Atan2 if float => self.map(&args, n, st, libm("atan2f")),
            Mf::CountTrailingZeros | Mf::CountLeadingZeros if !float => {
                let name = if fun == Mf::CountTrailingZeros {
                    "cttz"
                } else {
                    "ctlz"
                };
                self.map(&args, n, st, |fx, c| {
                    Ok(fx.call(
                        &v,
                        &format!("llvm.{name}.v{}i32", w()),
                        &[(v.clone(), c[0].clone()), ("i1".into(), "false".into())],
                    ))
                })
            }
            Mf::CountOneBits | Mf::ReverseBits if !float => {
                let name = if fun == Mf::CountOneBits {
                    "ctpop"
                } else {
                    "bitreverse"
                };
                self.map(&args, n, st, |fx, c| {
                    Ok(fx.call(
                        &v,
                        &format!("llvm.{name}.v{}i32", w()),
                        &[(v.clone(), c[0].clone())],
                    ))
                })
            }
            Mf::Dot => {
                let n = n.ok_or("dot of scalars")?;
                let p = self.products(&args, n, s)?;
                let add = if float { "fadd" } else { "add" };
                let sum = if n == 4 {
                    let xz = self.op(&format!("{add} {v} {}, {}", p[0], p[2]));
                    let yw = self.op(&format!("{add} {v} {}, {}", p[1], p[3]));
                    self.op(&format!("{add} {v} {xz}, {yw}"))
                } else {
                    let mut acc = p[0].clone();
                    for x in &p[1..] {
                        acc = self.op(&format!("{add} {v} {acc}, {x}"));
                    }
                    acc
                };
                Ok(Val::r(v, sum))
            }
            Mf::Length | Mf::Normalize | Mf::Distance if float => {
                let x = if fun == Mf::Distance {
                    let d = self.map(&args, n, st, |fx, c| {
                        Ok(fx.op(&format!("fsub {v} {}, {}", c[0], c[1])))
                    })?;
                    vec![(d, n)]
                } else {
                    vec![args[0].clone()]
                };
                let Some(k) = n else {
                    let a = self.comp(&x[0].0, None, 0)?;
                    return match fun {
                        Mf::Normalize => Err("normalize of a scalar".into()),
                        _ => Ok(Val::r(v, self.fintr("fabs", &[a]))),
                    };
                };
                let sq = [x[0].clone(), x[0].clone()];
                let p = self.products(&sq, k, s)?;
                let dot = if k == 4 {
                    let xz = self.op(&format!("fadd {v} {}, {}", p[0], p[2]));
                    let yw = self.op(&format!("fadd {v} {}, {}", p[1], p[3]));
                    self.op(&format!("fadd {v} {xz}, {yw}"))
                } else {
                    let mut acc = p[0].clone();
                    for q in &p[1..] {
                        acc = self.op(&format!("fadd {v} {acc}, {q}"));
                    }
                    acc
                };
                let len = self.fintr("sqrt", &[dot]);
                if fun != Mf::Normalize {
                    return Ok(Val::r(v, len));
                }
                // glam: four components divide by the length, fewer multiply by its inverse.
                let (ins, by) = if k == 4 {
                    ("fdiv", len)
                } else {
                    let r = self.op(&format!(
                        "fdiv {v} {}, {len}",
                        splat_const("float", &float_text(1.0))
                    ));
                    ("fmul", r)
                };
                self.map(&x, n, st, |fx, c| {
                    Ok(fx.op(&format!("{ins} {v} {}, {by}", c[0])))
                })
            }
            Mf::Cross if float => {
                let a: Vec<String> = (0..3)
                    .map(|i| self.comp(&args[0].0, n, i))
                    .collect::<Lowering<_>>()?;
                let b: Vec<String> = (0..3)
                    .map(|i| self.comp(&args[1].0, n, i))
                    .collect::<Lowering<_>>()?;
                let mut parts = Vec::new();
                for (i, j) in [(1, 2), (2, 0), (0, 1)] {
                    let l = self.op(&format!("fmul {v} {}, {}", a[i], b[j]));
                    let r = self.op(&format!("fmul {v} {}, {}", b[i], a[j]));
                    parts.push(self.op(&format!("fsub {v} {l}, {r}")));
                }
                Ok(self.build(parts, Some(3), st))
            }
            other => Err(format!("the math function {other:?} on {s:?}")),
        }
    }

    /// The transpose of a `columns x rows` matrix value: element `[c][r]` moves to `[r][c]`.
    fn transpose(
        &mut self,
        arg: Handle<naga::Expression>,
        columns: u32,
        rows: u32,
        s: Scalar,
    ) -> Lowering<Val> {
        let m = self.val(arg)?;
        let v = lanes(scalar(s)?);
        let ty = format!("[{rows} x [{columns} x {v}]]");
        let mut acc = "poison".to_string();
        for c in 0..columns {
            for r in 0..rows {
                let e = self.op(&format!("extractvalue {}, {c}, {r}", m.typed()?));
                acc = self.op(&format!("insertvalue {ty} {acc}, {v} {e}, {r}, {c}"));
            }
        }
        Ok(Val::r(ty, acc))
    }

    /// `m * v` as glam computes it: `((m.x * v.x) + (m.y * v.y)) + ...`, column by column.
    fn matrix_times_vector(
        &mut self,
        columns: u32,
        rows: u32,
        l: Handle<naga::Expression>,
        r: Handle<naga::Expression>,
    ) -> Lowering<Val> {
        if !matches!(self.ty_of(r), TypeInner::Vector { .. }) {
            return Err("a matrix times anything but a vector".into());
        }
        let (m, x) = (self.val(l)?, self.val(r)?);
        let v = lanes("float");
        let mut parts = Vec::new();
        for row in 0..rows {
            let mut acc: Option<String> = None;
            for c in 0..columns {
                let e = self.op(&format!("extractvalue {}, {c}, {row}", m.typed()?));
                let k = self.op(&format!("extractvalue {}, {c}", x.typed()?));
                let p = self.op(&format!("fmul {v} {e}, {k}"));
                acc = Some(match acc {
                    Some(a) => self.op(&format!("fadd {v} {a}, {p}")),
                    None => p,
                });
            }
            parts.push(acc.unwrap_or_default());
        }
        Ok(self.build(parts, Some(rows), "float"))
    }

    /// The component products of a dot product.
    fn products(
        &mut self,
        args: &[(Val, Option<u32>)],
        n: u32,
        s: Scalar,
    ) -> Lowering<Vec<String>> {
        let v = lanes(scalar(s)?);
        let mul = if s.kind == ScalarKind::Float {
            "fmul"
        } else {
            "mul"
        };
        (0..n)
            .map(|i| {
                let a = self.comp(&args[0].0, args[0].1, i)?;
                let b = self.comp(&args[1].0, args[1].1, i)?;
                Ok(self.op(&format!("{mul} {v} {a}, {b}")))
            })
            .collect()
    }
}
