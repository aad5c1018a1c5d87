//! Uniformity check: barriers and `group_share` must be reached by every invocation of
//! the workgroup, so they may not sit under control flow that depends on a value that
//! differs between invocations. naga does not check this; a violation hangs or silently
//! misbehaves on the GPU, so it is a compile error here, at the call.
//!
//! The analysis is conservative and syntactic. Uniform values: literals, constants,
//! uniform-buffer reads, `workgroup_id`/`num_workgroups`/`workgroup_index`/
//! `subgroup_size`/`num_subgroups` builtins, and expressions built only from those.
//! Everything else (thread ids, storage and workgroup memory, atomics, subgroup
//! operations, `group_share` results) is non-uniform. A `let mut` is uniform when every
//! assignment to it is. Code after a `return`, `break` or `continue` taken under
//! non-uniform control is non-uniform too.

use proc_macro2::Span;
use std::collections::{HashMap, HashSet};
use syn::spanned::Spanned;
use syn::{Block, Expr, Pat, Stmt};

const UNIFORM_BUILTINS: &[&str] = &["workgroup_id", "num_workgroups", "workgroup_index", "workgroup_size", "subgroup_size", "num_subgroups"];
const SYNC_CALLS: &[&str] = &["workgroup_barrier", "storage_barrier", "group_share"];

#[derive(Default)]
pub struct Params {
    /// Names of parameters whose values are uniform (uniform buffers, uniform builtins).
    pub uniform: HashSet<String>,
    /// Names of parameters that are uniform buffers (readable by host-computed closures).
    pub uniform_buffers: HashSet<String>,
    /// Names of parameters whose values differ between invocations (thread ids).
    pub nonuniform: HashSet<String>,
}

pub fn uniform_builtin(name: &str) -> bool {
    UNIFORM_BUILTINS.contains(&name)
}

struct Walker<'a> {
    params: &'a Params,
    scopes: Vec<HashMap<String, bool>>,
    /// `let mut` names found non-uniform in an earlier pass.
    nonuniform_vars: HashSet<String>,
    changed: bool,
    /// Why control is non-uniform here, if it is.
    divergent: Option<Span>,
    /// A non-uniform exit (`return`) happened earlier in the function.
    exited: Option<Span>,
    error: Option<syn::Error>,
    check: bool,
    found_exit: bool,
}

fn call_name(e: &Expr) -> Option<String> {
    if let Expr::Call(c) = e {
        if let Expr::Path(p) = &*c.func {
            return p.path.segments.last().map(|s| s.ident.to_string());
        }
    }
    None
}

impl Walker<'_> {
    fn lookup(&self, n: &str) -> Option<bool> {
        self.scopes.iter().rev().find_map(|s| s.get(n).copied())
    }

    fn fail(&mut self, span: Span, what: &str, why: Span) {
        if self.check && self.error.is_none() {
            let mut e = syn::Error::new(
                span,
                format!(
                    "`{what}` must be reached by every invocation of the workgroup, but it is under control flow that depends on a non-uniform value"
                ),
            );
            e.combine(syn::Error::new(why, "the non-uniform control flow starts here"));
            self.error = Some(e);
        }
    }

    fn control(&self) -> Option<Span> {
        self.divergent.or(self.exited)
    }

    fn block(&mut self, b: &Block) {
        self.scopes.push(HashMap::new());
        for s in &b.stmts {
            self.stmt(s);
        }
        self.scopes.pop();
    }

    fn stmt(&mut self, s: &Stmt) {
        match s {
            Stmt::Local(l) => {
                let u = l.init.as_ref().map(|i| self.expr(&i.expr)).unwrap_or(true);
                if let Some((name, mutable)) = pat_name(&l.pat) {
                    let u = if mutable || l.init.is_none() { u && !self.nonuniform_vars.contains(&name) } else { u };
                    self.scopes.last_mut().unwrap().insert(name, u);
                }
            }
            Stmt::Expr(e, _) => {
                self.expr(e);
            }
            _ => {}
        }
    }

    fn with_divergence<R>(&mut self, cond_uniform: bool, span: Span, f: impl FnOnce(&mut Self) -> R) -> R {
        let saved = self.divergent;
        if !cond_uniform && self.divergent.is_none() {
            self.divergent = Some(span);
        }
        let r = f(self);
        self.divergent = saved;
        r
    }

    fn loop_body(&mut self, cond_uniform: bool, span: Span, body: &Block) {
        // A non-uniform `break`/`continue` inside makes later iterations non-uniform, so
        // probe the body first and re-walk it as divergent if one exists.
        let exits = cond_uniform && self.divergent.is_none() && self.has_divergent_exit(body);
        let uniform = cond_uniform && !exits;
        self.with_divergence(uniform, span, |w| w.block(body));
    }

    fn has_divergent_exit(&mut self, body: &Block) -> bool {
        let mut probe = Walker {
            params: self.params,
            scopes: self.scopes.clone(),
            nonuniform_vars: self.nonuniform_vars.clone(),
            changed: false,
            divergent: None,
            exited: None,
            error: None,
            check: false,
            found_exit: false,
        };
        probe.block(body);
        probe.found_exit
    }

    fn expr(&mut self, e: &Expr) -> bool {
        match e {
            Expr::Lit(_) => true,
            Expr::Path(p) => {
                if p.path.segments.len() == 1 {
                    let n = p.path.segments[0].ident.to_string();
                    if let Some(u) = self.lookup(&n) {
                        return u;
                    }
                    if self.params.uniform.contains(&n) {
                        return true;
                    }
                    if self.params.uniform_buffers.contains(&n) {
                        return true;
                    }
                }
                // Constants, or parameters that are not uniform (buffers are handles;
                // reading them is caught at the index/field below).
                !self.is_nonuniform_root(p)
            }
            Expr::Field(f) => {
                let root = root_name(&f.base);
                let base = self.expr(&f.base);
                base || root.is_some_and(|r| self.params.uniform_buffers.contains(&r))
            }
            Expr::Index(i) => {
                let b = self.expr(&i.expr);
                let ix = self.expr(&i.index);
                let root = root_name(&i.expr);
                let from_uniform = root.as_ref().is_some_and(|r| self.params.uniform_buffers.contains(r));
                let from_local = root.as_ref().is_some_and(|r| self.lookup(r).is_some());
                (from_uniform || from_local) && b && ix
            }
            Expr::Paren(p) => self.expr(&p.expr),
            Expr::Group(g) => self.expr(&g.expr),
            Expr::Unary(u) => self.expr(&u.expr),
            Expr::Cast(c) => self.expr(&c.expr),
            Expr::Reference(r) => self.expr(&r.expr),
            Expr::Binary(b) => {
                let l = self.expr(&b.left);
                let r = self.expr(&b.right);
                if let Some(target) = assigned_var(&b.left) {
                    if is_compound(&b.op) {
                        self.assign(&target, l && r);
                    }
                }
                l && r
            }
            Expr::Assign(a) => {
                let r = self.expr(&a.right);
                self.expr(&a.left);
                if let Some(target) = assigned_var(&a.left) {
                    self.assign(&target, r);
                }
                true
            }
            Expr::Array(a) => a.elems.iter().fold(true, |acc, x| self.expr(x) && acc),
            Expr::Repeat(r) => self.expr(&r.expr),
            Expr::Struct(s) => s.fields.iter().fold(true, |acc, f| self.expr(&f.expr) && acc),
            Expr::MethodCall(m) => {
                let r = self.expr(&m.receiver);
                let args = m.args.iter().fold(true, |acc, a| self.expr(a) && acc);
                let atomic = matches!(m.method.to_string().as_str(), "fetch_add" | "fetch_sub" | "fetch_min" | "fetch_max" | "fetch_and" | "fetch_or" | "fetch_xor" | "swap" | "load" | "store");
                r && args && !atomic
            }
            Expr::Call(c) => {
                let name = call_name(e).unwrap_or_default();
                if SYNC_CALLS.contains(&name.as_str()) {
                    if let Some(why) = self.control() {
                        self.fail(c.func.span(), &format!("{name}()"), why);
                    }
                }
                let mut all = true;
                for a in &c.args {
                    if let Expr::Closure(cl) = a {
                        self.scopes.push(HashMap::new());
                        for i in &cl.inputs {
                            if let Some((n, _)) = pat_name(i) {
                                self.scopes.last_mut().unwrap().insert(n, false);
                            }
                        }
                        self.expr(&cl.body);
                        self.scopes.pop();
                        all = false;
                    } else {
                        all &= self.expr(a);
                    }
                }
                let nonuniform_fn = name.starts_with("subgroup_") || name.starts_with("atomic_") || name == "group_share";
                all && !nonuniform_fn
            }
            Expr::If(i) => {
                let c = self.expr(&i.cond);
                let span = i.cond.span();
                let t = self.with_divergence(c, span, |w| {
                    w.block(&i.then_branch);
                    block_tail_uniform(w, &i.then_branch)
                });
                let e = match &i.else_branch {
                    Some((_, eb)) => self.with_divergence(c, span, |w| w.expr(eb)),
                    None => true,
                };
                c && t && e
            }
            Expr::Block(b) => {
                self.block(&b.block);
                block_tail_uniform(self, &b.block)
            }
            Expr::While(w) => {
                let c = self.expr(&w.cond);
                self.loop_body(c, w.cond.span(), &w.body);
                true
            }
            Expr::Loop(l) => {
                self.loop_body(true, l.span(), &l.body);
                true
            }
            Expr::ForLoop(f) => {
                let r = self.expr(&f.expr);
                self.scopes.push(HashMap::new());
                if let Some((n, _)) = pat_name(&f.pat) {
                    self.scopes.last_mut().unwrap().insert(n, r);
                }
                self.loop_body(r, f.expr.span(), &f.body);
                self.scopes.pop();
                true
            }
            Expr::Break(_) | Expr::Continue(_) => {
                if self.divergent.is_some() {
                    self.found_exit = true;
                }
                true
            }
            Expr::Return(r) => {
                if let Some(v) = &r.expr {
                    self.expr(v);
                }
                if let Some(d) = self.divergent {
                    self.found_exit = true;
                    if self.exited.is_none() {
                        self.exited = Some(d);
                    }
                }
                true
            }
            Expr::Closure(c) => {
                self.expr(&c.body);
                false
            }
            _ => false,
        }
    }

    fn is_nonuniform_root(&self, p: &syn::ExprPath) -> bool {
        p.path.segments.len() == 1 && self.params.nonuniform.contains(&p.path.segments[0].ident.to_string())
    }

    fn assign(&mut self, name: &str, uniform: bool) {
        let uniform = uniform && self.divergent.is_none();
        if !uniform && !self.nonuniform_vars.contains(name) && self.lookup(name).is_some() {
            self.nonuniform_vars.insert(name.to_string());
            self.changed = true;
        }
    }
}

fn block_tail_uniform(w: &mut Walker, b: &Block) -> bool {
    match b.stmts.last() {
        Some(Stmt::Expr(e, None)) => {
            let _ = e;
            // The tail was already walked with the block; walking again would repeat
            // assignments, so approximate the tail's uniformity by a fresh walk that
            // does not record anything.
            let saved_check = w.check;
            w.check = false;
            w.scopes.push(HashMap::new());
            for s in &b.stmts[..b.stmts.len() - 1] {
                w.stmt(s);
            }
            let u = w.expr(e);
            w.scopes.pop();
            w.check = saved_check;
            u
        }
        _ => true,
    }
}

fn is_compound(op: &syn::BinOp) -> bool {
    use syn::BinOp::*;
    matches!(
        op,
        AddAssign(_) | SubAssign(_) | MulAssign(_) | DivAssign(_) | RemAssign(_) | BitAndAssign(_) | BitOrAssign(_)
            | BitXorAssign(_) | ShlAssign(_) | ShrAssign(_)
    )
}

fn pat_name(p: &Pat) -> Option<(String, bool)> {
    match p {
        Pat::Ident(i) => Some((i.ident.to_string(), i.mutability.is_some())),
        Pat::Type(t) => pat_name(&t.pat),
        _ => None,
    }
}

fn root_name(e: &Expr) -> Option<String> {
    match e {
        Expr::Path(p) if p.path.segments.len() == 1 => Some(p.path.segments[0].ident.to_string()),
        Expr::Field(f) => root_name(&f.base),
        Expr::Index(i) => root_name(&i.expr),
        Expr::Paren(p) => root_name(&p.expr),
        Expr::Unary(u) => root_name(&u.expr),
        _ => None,
    }
}

fn assigned_var(e: &Expr) -> Option<String> {
    root_name(e)
}

/// Checks a kernel body. `params` says which parameter names are uniform.
pub fn check(body: &Block, params: &Params) -> syn::Result<()> {
    let mut nonuniform_vars = HashSet::new();
    // Iterate to a fixed point: a `let mut` found non-uniform can make others so.
    for _ in 0..16 {
        let mut w = Walker {
            params,
            scopes: vec![HashMap::new()],
            nonuniform_vars: nonuniform_vars.clone(),
            changed: false,
            divergent: None,
            exited: None,
            error: None,
            check: false,
            found_exit: false,
        };
        w.block(body);
        let changed = w.changed;
        nonuniform_vars = w.nonuniform_vars;
        if !changed {
            break;
        }
    }
    let mut w = Walker {
        params,
        scopes: vec![HashMap::new()],
        nonuniform_vars,
        changed: false,
        divergent: None,
        exited: None,
        error: None,
        check: true,
        found_exit: false,
    };
    w.block(body);
    match w.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Checks that a `group_share` closure reads only its group index, uniform parameters
/// and constants: for `group = Grid` the host runs it before the dispatch, where no
/// other kernel value exists.
pub fn check_grid_closures(body: &Block, params: &Params, all_params: &HashSet<String>) -> syn::Result<()> {
    use syn::visit::Visit;
    struct V<'a> {
        params: &'a Params,
        all: &'a HashSet<String>,
        locals: Vec<HashSet<String>>,
        in_closure: Option<HashSet<String>>,
        err: Option<syn::Error>,
    }
    impl<'ast> Visit<'ast> for V<'_> {
        fn visit_local(&mut self, l: &'ast syn::Local) {
            if let Some(i) = &l.init {
                self.visit_expr(&i.expr);
            }
            if let Some((n, _)) = pat_name(&l.pat) {
                if let Some(c) = &mut self.in_closure {
                    c.insert(n);
                } else {
                    self.locals.last_mut().unwrap().insert(n);
                }
            }
        }
        fn visit_expr_call(&mut self, c: &'ast syn::ExprCall) {
            let is_share = matches!(&*c.func, Expr::Path(p) if p.path.segments.last().is_some_and(|s| s.ident == "group_share"));
            if is_share && self.in_closure.is_none() {
                for a in &c.args {
                    if let Expr::Closure(cl) = a {
                        let mut inner = HashSet::new();
                        for i in &cl.inputs {
                            if let Some((n, _)) = pat_name(i) {
                                inner.insert(n);
                            }
                        }
                        self.in_closure = Some(inner);
                        self.visit_expr(&cl.body);
                        self.in_closure = None;
                    }
                }
                return;
            }
            syn::visit::visit_expr_call(self, c);
        }
        fn visit_expr_path(&mut self, p: &'ast syn::ExprPath) {
            if let Some(inner) = &self.in_closure {
                if p.qself.is_none() && p.path.segments.len() == 1 {
                    let n = p.path.segments[0].ident.to_string();
                    let ok = inner.contains(&n)
                        || self.params.uniform_buffers.contains(&n)
                        || (!self.all.contains(&n) && !self.locals.iter().any(|s| s.contains(&n)));
                    if !ok && self.err.is_none() {
                        self.err = Some(syn::Error::new(
                            p.span(),
                            format!(
                                "`group_share` closures may read only their group index, uniform parameters and constants, not `{n}`: with `group = Grid` the host runs the closure before the dispatch"
                            ),
                        ));
                    }
                }
            }
        }
        fn visit_block(&mut self, b: &'ast Block) {
            self.locals.push(HashSet::new());
            syn::visit::visit_block(self, b);
            self.locals.pop();
        }
    }
    let mut v = V { params, all: all_params, locals: vec![HashSet::new()], in_closure: None, err: None };
    v.visit_block(body);
    match v.err {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
