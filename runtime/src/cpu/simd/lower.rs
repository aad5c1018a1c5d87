//! naga IR to LLVM IR in vector form: one call runs a block of `W` invocations, each value a
//! vector of `W` lanes, and divergent control flow runs under a lane mask (the lowering ISPC
//! and the work-item loops of CPU OpenCL compilers use). Structured naga control flow maps
//! onto masks directly:
//!
//! - `exec` holds the lanes that run the current statement. An `If` runs each arm with
//!   `exec` narrowed to the lanes that take it, and skips an arm no lane takes, unless the
//!   arm is a few register operations (`straight`), cheaper to run than to test.
//! - A loop runs while any lane is in it. `break` moves the lanes to the loop's `broken`
//!   set, `continue` to its `continued` set until `continuing`; when the loop ends, the
//!   lanes that broke out go on. `return` drops the lanes for the rest of the function.
//! - Every store and buffer access is masked, so lanes that are off change nothing.
//!
//! This file lowers modules, functions and statements; `expr` lowers expressions and
//! `memory` pointers, loads and stores. A kernel that uses what the vector form does not
//! cover yet (barriers, subgroups, workgroup memory, printing) gets `Err` with the reason,
//! and the CPU backend runs its host form instead.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use cohort_compiler::CompiledKernel;
use naga::valid::FunctionInfo;
use naga::{Block, Function, Handle, Module, Statement, TypeInner};

use super::memory::{Place, Root};
use super::types::{iota, lanes, splat_const, value_type, w, Lowering, Width};
use super::{deferred, straight};

/// Default name of the generated function the backend calls:
/// `run(env, err, first, end, nx, ny, nz)` runs workgroups `first..end` of an
/// `nx * ny * nz` grid (the JIT names each kernel's its own).
pub const RUN: &str = "cohort_run";

/// A value of the vector form: a register (or constant) of an LLVM type, or a place in
/// memory (naga pointers, which are never stored).
#[derive(Clone, Debug)]
pub enum Val {
    R { ty: String, v: String },
    P(Place),
}

impl Val {
    pub fn r(ty: impl Into<String>, v: impl Into<String>) -> Val {
        Val::R {
            ty: ty.into(),
            v: v.into(),
        }
    }
    /// `type value`, as an operand.
    pub fn typed(&self) -> Lowering<String> {
        match self {
            Val::R { ty, v } => Ok(format!("{ty} {v}")),
            Val::P(_) => Err("a pointer used as a value".into()),
        }
    }
    pub fn ty(&self) -> Lowering<&str> {
        match self {
            Val::R { ty, .. } => Ok(ty),
            Val::P(_) => Err("a pointer used as a value".into()),
        }
    }
    pub fn v(&self) -> Lowering<&str> {
        match self {
            Val::R { v, .. } => Ok(v),
            Val::P(_) => Err("a pointer used as a value".into()),
        }
    }
}

/// What `break` and `continue` leave.
enum Ctl {
    Loop { broken: String, continued: String },
    Switch { broken: String },
}

/// One function being lowered.
pub struct Fx<'a> {
    pub m: &'a Module,
    pub fun: &'a Function,
    pub info: &'a FunctionInfo,
    /// Position in the `env` table of each global's buffer (`None`: not a buffer).
    pub globals: &'a [Option<usize>],
    pub decls: &'a mut BTreeSet<String>,
    /// Deferred atomic add sites of the whole module so far (`deferred`).
    pub sites: &'a mut u32,
    pub allocas: String,
    pub body: String,
    next: u32,
    pub vals: Vec<Option<Val>>,
    pub locals: Vec<(String, String)>,
    args: Vec<Val>,
    ctl: Vec<Ctl>,
    /// The return value's slot and type, for functions that return one.
    ret: Option<(String, String)>,
    /// Function indices of `Call`s, for the callee's LLVM name.
    pub functions: &'a naga::Arena<Function>,
}

impl<'a> Fx<'a> {
    /// A fresh register name.
    pub fn tmp(&mut self) -> String {
        self.next += 1;
        format!("%t{}", self.next)
    }
    pub fn label(&mut self) -> String {
        self.next += 1;
        format!("L{}", self.next)
    }
    pub fn line(&mut self, s: &str) {
        self.body.push_str("  ");
        self.body.push_str(s);
        self.body.push('\n');
    }
    /// `%t = <instruction>`; returns `%t`.
    pub fn op(&mut self, s: &str) -> String {
        let t = self.tmp();
        let _ = writeln!(self.body, "  {t} = {s}");
        t
    }
    pub fn declare(&mut self, d: &str) {
        self.decls.insert(d.to_string());
    }
    /// A stack slot of type `ty` in the entry block (where LLVM promotes it to registers).
    pub fn alloca(&mut self, ty: &str) -> String {
        let t = self.tmp();
        let _ = writeln!(self.allocas, "  {t} = alloca {ty}, align 64");
        t
    }
    fn start_block(&mut self, l: &str) {
        let _ = writeln!(self.body, "{l}:");
    }
    fn br(&mut self, l: &str) {
        self.line(&format!("br label %{l}"));
    }

    pub fn mask_ty() -> String {
        lanes("i1")
    }
    /// The lanes that run the current statement.
    pub fn exec(&mut self) -> String {
        self.op(&format!("load {}, ptr %exec", Self::mask_ty()))
    }
    pub fn set_exec(&mut self, m: &str) {
        self.line(&format!("store {} {m}, ptr %exec", Self::mask_ty()));
    }
    pub fn any(&mut self, m: &str) -> String {
        self.declare(&format!(
            "declare i1 @llvm.vector.reduce.or.v{}i1({})",
            w(),
            Self::mask_ty()
        ));
        self.op(&format!(
            "call i1 @llvm.vector.reduce.or.v{}i1({} {m})",
            w(),
            Self::mask_ty()
        ))
    }
    pub fn and(&mut self, a: &str, b: &str) -> String {
        self.op(&format!("and {} {a}, {b}", Self::mask_ty()))
    }
    pub fn or(&mut self, a: &str, b: &str) -> String {
        self.op(&format!("or {} {a}, {b}", Self::mask_ty()))
    }
    pub fn not(&mut self, a: &str) -> String {
        self.op(&format!(
            "xor {} {a}, {}",
            Self::mask_ty(),
            splat_const("i1", "true")
        ))
    }
    /// Adds `m` to the mask in slot `slot`.
    fn or_into(&mut self, slot: &str, m: &str) {
        let old = self.op(&format!("load {}, ptr {slot}", Self::mask_ty()));
        let new = self.or(&old, m);
        self.line(&format!("store {} {new}, ptr {slot}", Self::mask_ty()));
    }
    fn zero_mask(&mut self, slot: &str) {
        self.line(&format!(
            "store {} zeroinitializer, ptr {slot}",
            Self::mask_ty()
        ));
    }

    /// The naga type of expression `h`.
    pub fn ty_of(&self, h: Handle<naga::Expression>) -> &'a TypeInner {
        self.info[h].ty.inner_with(&self.m.types)
    }

    pub fn val(&self, h: Handle<naga::Expression>) -> Lowering<Val> {
        self.vals[h.index()]
            .clone()
            .ok_or_else(|| format!("expression {h:?} used before it was emitted"))
    }

    fn block(&mut self, b: &Block) -> Lowering<()> {
        for s in b.iter() {
            self.statement(s)?;
        }
        Ok(())
    }

    fn statement(&mut self, s: &Statement) -> Lowering<()> {
        match *s {
            Statement::Emit(ref range) => {
                for h in range.clone() {
                    let v = self.expression(h)?;
                    self.vals[h.index()] = Some(v);
                }
            }
            Statement::Block(ref b) => self.block(b)?,
            Statement::If {
                condition,
                ref accept,
                ref reject,
            } => {
                let c = self.val(condition)?.v()?.to_string();
                let saved = self.exec();
                let taken = self.and(&saved, &c);
                let nc = self.not(&c);
                let other = self.and(&saved, &nc);
                let after_accept = self.arm(&taken, accept)?;
                let after_reject = self.arm(&other, reject)?;
                let joined = self.or(&after_accept, &after_reject);
                self.set_exec(&joined);
            }
            Statement::Loop {
                ref body,
                ref continuing,
                break_if,
            } => {
                let broken = self.alloca(&Self::mask_ty());
                let continued = self.alloca(&Self::mask_ty());
                self.zero_mask(&broken);
                self.zero_mask(&continued);
                let (head, run, exit) = (self.label(), self.label(), self.label());
                self.br(&head);
                self.start_block(&head);
                let e = self.exec();
                let go = self.any(&e);
                self.line(&format!("br i1 {go}, label %{run}, label %{exit}"));
                self.start_block(&run);
                self.ctl.push(Ctl::Loop {
                    broken: broken.clone(),
                    continued: continued.clone(),
                });
                self.block(body)?;
                let e = self.exec();
                let c = self.op(&format!("load {}, ptr {continued}", Self::mask_ty()));
                let e = self.or(&e, &c);
                self.set_exec(&e);
                self.zero_mask(&continued);
                self.block(continuing)?;
                if let Some(cond) = break_if {
                    let c = self.val(cond)?.v()?.to_string();
                    let e = self.exec();
                    let leaving = self.and(&e, &c);
                    self.or_into(&broken, &leaving);
                    let nc = self.not(&c);
                    let stay = self.and(&e, &nc);
                    self.set_exec(&stay);
                }
                self.ctl.pop();
                self.br(&head);
                self.start_block(&exit);
                let b = self.op(&format!("load {}, ptr {broken}", Self::mask_ty()));
                self.set_exec(&b);
            }
            Statement::Break => {
                let slot = match self.ctl.last() {
                    Some(Ctl::Loop { broken, .. } | Ctl::Switch { broken }) => broken.clone(),
                    None => return Err("`break` outside a loop".into()),
                };
                let e = self.exec();
                self.or_into(&slot, &e);
                self.set_exec("zeroinitializer");
            }
            Statement::Continue => {
                let slot = self
                    .ctl
                    .iter()
                    .rev()
                    .find_map(|c| match c {
                        Ctl::Loop { continued, .. } => Some(continued.clone()),
                        Ctl::Switch { .. } => None,
                    })
                    .ok_or("`continue` outside a loop")?;
                let e = self.exec();
                self.or_into(&slot, &e);
                self.set_exec("zeroinitializer");
            }
            Statement::Return { value } => {
                if let (Some(v), Some((slot, ty))) = (value, self.ret.clone()) {
                    let v = self.val(v)?;
                    let e = self.exec();
                    let old = self.op(&format!("load {ty}, ptr {slot}"));
                    let new = self.blend(&e, &v, &Val::r(ty.clone(), old))?;
                    self.line(&format!("store {}, ptr {slot}", new.typed()?));
                }
                self.set_exec("zeroinitializer");
            }
            Statement::Switch {
                selector,
                ref cases,
            } => self.switch(selector, cases)?,
            Statement::Store { pointer, value } => {
                let p = self.place(pointer)?;
                let v = self.val(value)?;
                let e = self.exec();
                self.store(&p, &v, &e)?;
            }
            Statement::Call {
                function,
                ref arguments,
                result,
            } => {
                let mut ops = vec!["ptr %env".to_string(), "ptr %err".to_string()];
                let e = self.exec();
                ops.push(format!("{} {e}", Self::mask_ty()));
                for &a in arguments {
                    match self.val(a)? {
                        Val::P(p) => {
                            let at = self.uniform_local(&p).ok_or(
                                "a pointer argument other than a local at one place in every lane",
                            )?;
                            ops.push(format!("ptr {at}"));
                        }
                        v => ops.push(v.typed()?),
                    }
                }
                let callee = &self.functions[function];
                let name = format!("@f{}", function.index());
                match (callee.result.as_ref(), result) {
                    (Some(r), Some(h)) => {
                        let ty = value_type(self.m, &self.m.types[r.ty].inner)?;
                        let v = self.op(&format!("call {ty} {name}({})", ops.join(", ")));
                        self.vals[h.index()] = Some(Val::r(ty, v));
                    }
                    (Some(r), None) => {
                        let ty = value_type(self.m, &self.m.types[r.ty].inner)?;
                        self.op(&format!("call {ty} {name}({})", ops.join(", ")));
                    }
                    _ => self.line(&format!("call void {name}({})", ops.join(", "))),
                }
            }
            Statement::Atomic {
                pointer,
                ref fun,
                value,
                result,
            } => self.atomic(pointer, fun, value, result)?,
            ref other => return Err(format!("the statement {other:?}")),
        }
        Ok(())
    }

    /// Runs `b` for the lanes of `mask` (skipped when there are none); returns the lanes
    /// still running at its end.
    fn arm(&mut self, mask: &str, b: &Block) -> Lowering<String> {
        self.set_exec(mask);
        if b.is_empty() {
            return Ok(mask.to_string());
        }
        if straight::straight(self, b) {
            self.block(b)?;
            return Ok(self.exec());
        }
        let (run, done) = (self.label(), self.label());
        let go = self.any(mask);
        self.line(&format!("br i1 {go}, label %{run}, label %{done}"));
        self.start_block(&run);
        self.block(b)?;
        self.br(&done);
        self.start_block(&done);
        Ok(self.exec())
    }

    fn switch(
        &mut self,
        selector: Handle<naga::Expression>,
        cases: &[naga::SwitchCase],
    ) -> Lowering<()> {
        let sel = self.val(selector)?;
        let (sty, sv) = (sel.ty()?.to_string(), sel.v()?.to_string());
        let saved = self.exec();
        let broken = self.alloca(&Self::mask_ty());
        self.zero_mask(&broken);
        let literal = |v: &naga::SwitchValue| match *v {
            naga::SwitchValue::I32(i) => Some(i.to_string()),
            naga::SwitchValue::U32(u) => Some((u as i32).to_string()),
            naga::SwitchValue::Default => None,
        };
        // Lanes whose selector matches no case value take the default case.
        let mut matched = "zeroinitializer".to_string();
        let mut hits = Vec::new();
        for c in cases {
            let hit = match literal(&c.value) {
                Some(k) => {
                    let eq = self.op(&format!("icmp eq {sty} {sv}, {}", splat_const("i32", &k)));
                    matched = self.or(&matched, &eq);
                    Some(eq)
                }
                None => None,
            };
            hits.push(hit);
        }
        let unmatched = self.not(&matched);
        let mut finished = "zeroinitializer".to_string();
        let mut falling = "zeroinitializer".to_string();
        self.ctl.push(Ctl::Switch {
            broken: broken.clone(),
        });
        for (c, hit) in cases.iter().zip(hits) {
            let own = self.and(&saved, hit.as_deref().unwrap_or(&unmatched));
            let entering = self.or(&own, &falling);
            let after = self.arm(&entering, &c.body)?;
            if c.fall_through {
                falling = after;
            } else {
                finished = self.or(&finished, &after);
                falling = "zeroinitializer".to_string();
            }
        }
        self.ctl.pop();
        let b = self.op(&format!("load {}, ptr {broken}", Self::mask_ty()));
        let out = self.or(&finished, &b);
        let out = self.or(&out, &falling);
        self.set_exec(&out);
        Ok(())
    }
}

/// Lowers every function of the kernel, and the workgroup loop that calls its entry point,
/// for blocks of `width` invocations (one of `types::WIDTHS`).
pub fn lower(k: &CompiledKernel, symbol: &str, width: u32) -> Lowering<String> {
    let _width = Width::set(width);
    if !k.prints.is_empty() {
        return Err("printing".into());
    }
    if k.synchronises || k.features.subgroups {
        return Err("barriers or subgroup operations".into());
    }
    if k.features.workgroup_memory_bytes > 0 {
        return Err("workgroup memory".into());
    }
    let m = &k.module;
    let mut globals = vec![None; m.global_variables.len()];
    for (h, g) in m.global_variables.iter() {
        let b = g
            .binding
            .as_ref()
            .ok_or_else(|| format!("the global `{:?}` without a binding", g.name))?;
        let pos = k
            .bindings
            .iter()
            .position(|x| x.binding == b.binding)
            .ok_or("a global that is not one of the kernel's bindings")?;
        globals[h.index()] = Some(pos);
    }
    let mut decls = BTreeSet::new();
    let mut sites = 0u32;
    let mut out = String::new();
    for (h, f) in m.functions.iter() {
        let ret = match &f.result {
            Some(r) => Some(value_type(m, &m.types[r.ty].inner)?),
            None => None,
        };
        let mut params = Vec::new();
        let mut args = Vec::new();
        for (i, a) in f.arguments.iter().enumerate() {
            // A `&mut` argument of a `#[kernel_fn]` (a pointer to a caller's local) is the
            // address of the caller's per-lane slot: callees are inlined, so the slot is
            // promoted to registers as if it were the caller's own.
            if let TypeInner::Pointer {
                base,
                space: naga::AddressSpace::Function,
            } = m.types[a.ty].inner
            {
                let pointee = m.types[base].inner.clone();
                params.push(format!("ptr %a{i}"));
                args.push(Val::P(Place {
                    root: Root::Local {
                        slot: format!("%a{i}"),
                        slot_ty: value_type(m, &pointee)?,
                        path: Vec::new(),
                    },
                    ty: pointee,
                }));
                continue;
            }
            let ty = value_type(m, &m.types[a.ty].inner)?;
            params.push(format!("{ty} %a{i}"));
            args.push(Val::r(ty, format!("%a{i}")));
        }
        let body = function(
            k,
            f,
            &k.info[h],
            &globals,
            &mut decls,
            &mut sites,
            args,
            ret.clone(),
            "",
        )?;
        let _ = writeln!(
            out,
            "define internal {} @f{}(ptr %env, ptr %err, {} %mask{}{}) alwaysinline {{\n{body}}}\n",
            ret.as_deref().unwrap_or("void"),
            h.index(),
            Fx::mask_ty(),
            if params.is_empty() { "" } else { ", " },
            params.join(", ")
        );
    }
    let ep = &m.entry_points[0];
    let wg = k.workgroup_size[0];
    let args = ep
        .function
        .arguments
        .iter()
        .map(|a| builtin(m, a, wg))
        .collect::<Lowering<Vec<_>>>()?;
    let (pre, args): (Vec<String>, Vec<Val>) = args.into_iter().unzip();
    let body = function(
        k,
        &ep.function,
        k.info.get_entry_point(0),
        &globals,
        &mut decls,
        &mut sites,
        args,
        None,
        &pre.concat(),
    )?;
    let v = lanes("i32");
    let _ = writeln!(
        out,
        "define internal void @entry(ptr %env, ptr %err, {} %mask, {v} %li, i32 %wx, i32 %wy, i32 %wz, i32 %nx, i32 %ny, i32 %nz) alwaysinline {{\n{body}}}\n",
        Fx::mask_ty()
    );
    let _ = writeln!(out, "{}", driver(wg, symbol, sites));
    let _ = writeln!(out, "{}", deferred::flush_function(sites));
    if sites > 0 {
        decls.insert("declare void @llvm.memset.p0.i64(ptr, i8, i64, i1)".into());
    }
    for d in decls {
        let _ = writeln!(out, "{d}");
    }
    // Loads of the `env` table: no kernel store changes it.
    let _ = writeln!(out, "!0 = !{{}}");
    Ok(out)
}

/// The body of one function (without its `define` line); `prelude` computes its arguments.
#[allow(clippy::too_many_arguments)]
fn function(
    k: &CompiledKernel,
    f: &Function,
    info: &FunctionInfo,
    globals: &[Option<usize>],
    decls: &mut BTreeSet<String>,
    sites: &mut u32,
    args: Vec<Val>,
    ret: Option<String>,
    prelude: &str,
) -> Lowering<String> {
    let m = &k.module;
    let mut fx = Fx {
        m,
        fun: f,
        info,
        globals,
        decls,
        sites,
        allocas: String::new(),
        body: String::new(),
        next: 0,
        vals: vec![None; f.expressions.len()],
        locals: Vec::new(),
        args,
        ctl: Vec::new(),
        ret: None,
        functions: &m.functions,
    };
    let _ = writeln!(fx.allocas, "  %exec = alloca {}, align 64", Fx::mask_ty());
    fx.body.push_str(prelude);
    fx.line(&format!("store {} %mask, ptr %exec", Fx::mask_ty()));
    if let Some(ty) = ret {
        let slot = fx.alloca(&ty);
        fx.line(&format!("store {ty} zeroinitializer, ptr {slot}"));
        fx.ret = Some((slot, ty));
    }
    for (_, l) in f.local_variables.iter() {
        let ty = value_type(m, &m.types[l.ty].inner)?;
        let slot = fx.alloca(&ty);
        let init = match l.init {
            Some(h) => {
                let v = fx.pre_emit(h)?;
                v.typed()?
            }
            None => format!("{ty} zeroinitializer"),
        };
        fx.line(&format!("store {init}, ptr {slot}"));
        fx.locals.push((slot, ty));
    }
    for (h, e) in f.expressions.iter() {
        if e.needs_pre_emit() && fx.vals[h.index()].is_none() {
            let v = fx.pre_emit(h)?;
            fx.vals[h.index()] = Some(v);
        }
    }
    fx.block(&f.body)?;
    match fx.ret.clone() {
        Some((slot, ty)) => {
            let r = fx.op(&format!("load {ty}, ptr {slot}"));
            fx.line(&format!("ret {ty} {r}"));
        }
        None => fx.line("ret void"),
    }
    Ok(format!("entry:\n{}{}", fx.allocas, fx.body))
}

impl Fx<'_> {
    /// An expression that needs no evaluation order: literals, constants, arguments,
    /// variables.
    fn pre_emit(&mut self, h: Handle<naga::Expression>) -> Lowering<Val> {
        if let Some(v) = &self.vals[h.index()] {
            return Ok(v.clone());
        }
        let v = match self.fun.expressions[h] {
            naga::Expression::FunctionArgument(i) => self.args[i as usize].clone(),
            _ => self.expression(h)?,
        };
        self.vals[h.index()] = Some(v.clone());
        Ok(v)
    }
}

/// The value of an entry-point argument: a builtin, computed from the block's lane indices
/// and the workgroup's id. Returns the instructions that compute it and the value.
fn builtin(m: &Module, a: &naga::FunctionArgument, wg: u32) -> Lowering<(String, Val)> {
    use naga::BuiltIn as B;
    let v = lanes("i32");
    let Some(naga::Binding::BuiltIn(b)) = a.binding else {
        return Err("an entry-point argument that is not a builtin".into());
    };
    let splat = |name: &str, x: &str| {
        format!(
            "  %{name}.0 = insertelement {v} poison, i32 {x}, i32 0\n  %{name} = shufflevector {v} %{name}.0, {v} poison, {v} zeroinitializer\n"
        )
    };
    let vec3 = |name: &str, parts: [&str; 3]| {
        format!(
            "  %{name}.a = insertvalue [3 x {v}] poison, {v} {}, 0\n  %{name}.b = insertvalue [3 x {v}] %{name}.a, {v} {}, 1\n  %{name} = insertvalue [3 x {v}] %{name}.b, {v} {}, 2\n",
            parts[0], parts[1], parts[2]
        )
    };
    let is_vec3 = matches!(
        m.types[a.ty].inner,
        TypeInner::Vector {
            size: naga::VectorSize::Tri,
            ..
        }
    );
    let ty3 = format!("[3 x {v}]");
    Ok(match b {
        B::LocalInvocationIndex => (String::new(), Val::r(v.clone(), "%li")),
        B::LocalInvocationId if is_vec3 => (
            vec3("lid", ["%li", "zeroinitializer", "zeroinitializer"]),
            Val::r(ty3, "%lid"),
        ),
        B::WorkGroupId if is_vec3 => (
            format!(
                "{}{}{}{}",
                splat("swx", "%wx"),
                splat("swy", "%wy"),
                splat("swz", "%wz"),
                vec3("wid", ["%swx", "%swy", "%swz"])
            ),
            Val::r(ty3, "%wid"),
        ),
        B::NumWorkGroups if is_vec3 => (
            format!(
                "{}{}{}{}",
                splat("snx", "%nx"),
                splat("sny", "%ny"),
                splat("snz", "%nz"),
                vec3("nwg", ["%snx", "%sny", "%snz"])
            ),
            Val::r(ty3, "%nwg"),
        ),
        B::GlobalInvocationId if is_vec3 => (
            format!(
                "  %gx.s = mul i32 %wx, {wg}\n{}  %gx = add {v} %gx.v, %li\n{}{}{}",
                splat("gx.v", "%gx.s"),
                splat("gy", "%wy"),
                splat("gz", "%wz"),
                vec3("gid", ["%gx", "%gy", "%gz"])
            ),
            Val::r(ty3, "%gid"),
        ),
        other => return Err(format!("the builtin {other:?}")),
    })
}

/// `cohort_run`: every workgroup of `first..end`, each as blocks of `W` lanes, in the
/// context of the module's `sites` deferred atomic adds.
fn driver(wg: u32, symbol: &str, sites: u32) -> String {
    let v = lanes("i32");
    let m = Fx::mask_ty();
    let (setup, finish, ctx) = deferred::driver_context(sites);
    format!(
        r#"define void @{symbol}(ptr %env, ptr %err, i32 %first, i32 %end, i32 %nx, i32 %ny, i32 %nz) {{
entry:
{setup}  br label %wg_head
wg_head:
  %w = phi i32 [ %first, %entry ], [ %w.next, %blocks_done ]
  %more = icmp ult i32 %w, %end
  br i1 %more, label %wg_body, label %exit
wg_body:
  %wx = urem i32 %w, %nx
  %wyz = udiv i32 %w, %nx
  %wy = urem i32 %wyz, %ny
  %wz = udiv i32 %wyz, %ny
  br label %block_head
block_head:
  %b = phi i32 [ 0, %wg_body ], [ %b.next, %block_body ]
  %blocks_more = icmp ult i32 %b, {wg}
  br i1 %blocks_more, label %block_body, label %blocks_done
block_body:
  %b.0 = insertelement {v} poison, i32 %b, i32 0
  %b.v = shufflevector {v} %b.0, {v} poison, {v} zeroinitializer
  %li = add {v} %b.v, {iota}
  %mask = icmp ult {v} %li, {wgv}
  call void @entry(ptr %env, ptr {ctx}, {m} %mask, {v} %li, i32 %wx, i32 %wy, i32 %wz, i32 %nx, i32 %ny, i32 %nz)
  %b.next = add i32 %b, {w}
  br label %block_head
blocks_done:
  %w.next = add i32 %w, 1
  br label %wg_head
exit:
{finish}}}
"#,
        iota = iota(),
        w = w(),
        wgv = splat_const("i32", &wg.to_string()),
    )
}
