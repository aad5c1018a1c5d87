//! Uniformity check: barriers and `group_share` must be reached by every invocation of
//! the workgroup, so they may not sit under control flow that depends on a value that
//! differs between invocations. naga does not check this; a violation hangs or silently
//! misbehaves on the GPU, so it is a compile error here, at the call.
//!
//! The analysis is conservative and syntactic. Uniform values: literals, constants,
//! uniform-buffer reads, `workgroup_id`/`num_workgroups`/`workgroup_index`/
//! `subgroup_size`/`num_subgroups` builtins, and expressions built only from those
//! (ranges included). Everything else (thread ids, storage and workgroup memory, atomics,
//! subgroup operations, `group_share` results, calls that are given a buffer) is
//! non-uniform. A `let mut` is uniform when every assignment to it is. Code after a
//! `return`, `break` or `continue` taken under non-uniform control is non-uniform too, and
//! so is the right side of `&&`/`||` when the left side is. Inside a `group_share`
//! closure only the group's leader runs, so no synchronising call may appear there.

use proc_macro2::TokenStream;
use quote::ToTokens;
use std::collections::{HashMap, HashSet};
use syn::{Block, Expr, Pat, Stmt};

const UNIFORM_BUILTINS: &[&str] = &[
    "workgroup_id",
    "num_workgroups",
    "workgroup_index",
    "workgroup_size",
    "subgroup_size",
    "num_subgroups",
];
const SYNC_CALLS: &[&str] = &[
    "workgroup_barrier",
    "storage_barrier",
    "subgroup_barrier",
    "group_share",
    "group_any",
    "workgroup_uniform_load",
];

const STARTS_HERE: &str = "the non-uniform control flow starts here";
const AND_NOTE: &str = "the non-uniform control flow starts here: the right side of `&&` runs only for the invocations where this is true";
const OR_NOTE: &str = "the non-uniform control flow starts here: the right side of `||` runs only for the invocations where this is false";

#[derive(Default)]
pub struct Params {
    /// Names of parameters whose values are uniform (uniform buffers, uniform builtins).
    pub uniform: HashSet<String>,
    /// Names of parameters that are uniform buffers (readable by grid-level closures).
    pub uniform_buffers: HashSet<String>,
    /// Names of parameters whose values differ between invocations (thread ids).
    pub nonuniform: HashSet<String>,
    /// Names of storage-buffer and workgroup-memory parameters: a call given one may read
    /// memory or use atomics, so its result is non-uniform.
    pub memory: HashSet<String>,
    /// The function's generic type parameters (`T::f` calls are not helper calls here).
    pub generics: HashSet<String>,
}

/// What the check found besides errors: the helper calls of the body, for the compile-time
/// checks that follow uniformity into helpers (each `#[kernel_fn]` module has a
/// `NEEDS_UNIFORM` constant: it, or a helper it calls, waits at a barrier or group operation).
#[derive(Default)]
pub struct Calls {
    /// Every call of a helper or intrinsic (`path::f(..)`), as its path.
    pub all: Vec<syn::Path>,
    /// Those made under non-uniform control flow or inside a `group_share` closure: the
    /// callee must not need uniform control.
    pub guarded: Vec<syn::Path>,
}

/// The helper (or intrinsic) a call goes to, when it is a free function with a module of
/// its own (`f(..)`, `path::f(..)`): not `Type::f`, `Self::f`, `T::f` or `<T as Tr>::f`.
fn helper_path(c: &syn::ExprCall, generics: &HashSet<String>) -> Option<syn::Path> {
    let Expr::Path(fp) = &*c.func else {
        return None;
    };
    if fp.qself.is_some() {
        return None;
    }
    let segs = &fp.path.segments;
    if segs.len() >= 2 {
        let ty = segs[segs.len() - 2].ident.to_string();
        let first = segs[0].ident.to_string();
        let lower = ty.chars().next().is_some_and(|ch| ch.is_lowercase())
            && !crate::rewrite::is_builtin_type(&ty);
        if !lower || first == "Self" || generics.contains(&first) {
            return None;
        }
    }
    let mut p = fp.path.clone();
    if let Some(last) = p.segments.last_mut() {
        last.arguments = syn::PathArguments::None;
    }
    Some(p)
}

pub fn uniform_builtin(name: &str) -> bool {
    UNIFORM_BUILTINS.contains(&name)
}

/// The innermost condition that governs the current code, when it is non-uniform.
#[derive(Clone)]
struct Cond {
    tokens: TokenStream,
    /// Whether the code runs where the condition holds (`then`) or where it does not.
    holds: bool,
}

struct Walker<'a> {
    params: &'a Params,
    scopes: Vec<HashMap<String, bool>>,
    /// `let mut` names found non-uniform in an earlier pass.
    nonuniform_vars: HashSet<String>,
    changed: bool,
    /// Why control is non-uniform here, if it is: the notes to attach to an error.
    divergent: Option<syn::Error>,
    /// The innermost enclosing condition, if it is non-uniform.
    cond: Option<Cond>,
    /// A non-uniform exit (`return`) happened earlier in the function: its notes.
    exited: Option<syn::Error>,
    error: Option<syn::Error>,
    check: bool,
    /// The first `break`/`continue`/`return` taken under non-uniform control: its notes.
    first_exit: Option<syn::Error>,
    /// Inside the closure of a `group_share` (run by the group's leader only).
    in_share: bool,
    calls: Calls,
}

fn call_name(e: &Expr) -> Option<String> {
    if let Expr::Call(c) = e {
        if let Expr::Path(p) = &*c.func {
            return p.path.segments.last().map(|s| s.ident.to_string());
        }
    }
    None
}

/// What an error about a call underlines: the whole call when it has no arguments
/// (`workgroup_barrier()`), else the called path (a closure argument can be long).
fn call_site(c: &syn::ExprCall) -> TokenStream {
    if c.args.is_empty() {
        c.to_token_stream()
    } else {
        c.func.to_token_stream()
    }
}

impl Walker<'_> {
    fn lookup(&self, n: &str) -> Option<bool> {
        self.scopes.iter().rev().find_map(|s| s.get(n).copied())
    }

    fn fail(&mut self, at: TokenStream, what: &str, why: syn::Error) {
        if self.check && self.error.is_none() {
            let scope = if what.starts_with("subgroup_") {
                "subgroup"
            } else {
                "workgroup"
            };
            let mut e = syn::Error::new_spanned(
                at,
                format!(
                    "`{what}` must be reached by every invocation of the {scope}, but it is under control flow that depends on a non-uniform value"
                ),
            );
            e.combine(why);
            self.error = Some(e);
        }
    }

    fn fail_in_share(&mut self, at: TokenStream, what: &str) {
        if self.check && self.error.is_none() {
            self.error = Some(syn::Error::new_spanned(
                at,
                format!("`{what}` cannot be called inside a `group_share` closure (only the group's leader runs it)"),
            ));
        }
    }

    fn control(&self) -> Option<syn::Error> {
        self.divergent.clone().or_else(|| self.exited.clone())
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
                    let u = if mutable || l.init.is_none() {
                        u && !self.nonuniform_vars.contains(&name)
                    } else {
                        u
                    };
                    self.scopes.last_mut().unwrap().insert(name, u);
                }
            }
            Stmt::Expr(e, _) => {
                self.expr(e);
            }
            _ => {}
        }
    }

    /// Runs `f` for code governed by `cond` (where it holds, or where it does not), which
    /// is non-uniform unless `cond_uniform`; `note` says so at the condition.
    fn guarded<R>(
        &mut self,
        cond: &impl ToTokens,
        holds: bool,
        cond_uniform: bool,
        note: &str,
        f: impl FnOnce(&mut Self) -> R,
    ) -> R {
        let c = (!cond_uniform).then(|| Cond {
            tokens: cond.to_token_stream(),
            holds,
        });
        let why = c.as_ref().map(|c| syn::Error::new_spanned(&c.tokens, note));
        self.diverging(why, c, f)
    }

    /// Runs `f` with control non-uniform for the reason `why` (if any and not already),
    /// and `cond` as the innermost condition.
    fn diverging<R>(
        &mut self,
        why: Option<syn::Error>,
        cond: Option<Cond>,
        f: impl FnOnce(&mut Self) -> R,
    ) -> R {
        let saved = self.divergent.clone();
        let saved_cond = std::mem::replace(&mut self.cond, cond);
        if self.divergent.is_none() {
            self.divergent = why;
        }
        let r = f(self);
        self.divergent = saved;
        self.cond = saved_cond;
        r
    }

    fn loop_body(
        &mut self,
        cond_uniform: bool,
        why: impl FnOnce() -> (syn::Error, Option<Cond>),
        body: &Block,
    ) {
        // A non-uniform `break`/`continue` inside makes later iterations non-uniform, so
        // probe the body first and re-walk it as divergent if one exists. Such an exit is
        // also the reason to report when the condition is non-uniform too: typically the
        // condition reads a variable that the exit made non-uniform.
        let exit = if self.divergent.is_none() {
            self.divergent_exit(body)
        } else {
            None
        };
        let (why, cond) = match exit {
            Some(notes) => (Some(notes), None),
            None if cond_uniform => (None, None),
            None => {
                let (w, c) = why();
                (Some(w), c)
            }
        };
        self.diverging(why, cond, |w| w.block(body));
    }

    /// The notes of the first `break`/`continue`/`return` in `body` that only some
    /// invocations take, if any.
    fn divergent_exit(&mut self, body: &Block) -> Option<syn::Error> {
        let mut probe = Walker {
            params: self.params,
            scopes: self.scopes.clone(),
            nonuniform_vars: self.nonuniform_vars.clone(),
            changed: false,
            divergent: None,
            cond: None,
            exited: None,
            error: None,
            check: false,
            first_exit: None,
            in_share: self.in_share,
            calls: Calls::default(),
        };
        probe.block(body);
        probe.first_exit
    }

    /// Records a `break`/`continue`/`return` (`e`); when only some invocations take it,
    /// returns the notes that explain the non-uniform control flow after it.
    fn exit(&mut self, e: &Expr, kw: &str) -> Option<syn::Error> {
        let d = self.divergent.as_ref()?;
        let (scope, what) = match kw {
            "break" => ("loop", "leave the loop"),
            "continue" => ("loop", "skip the rest of the iteration"),
            _ => ("kernel", "return early"),
        };
        let mut notes = syn::Error::new_spanned(
            e,
            format!("this `{kw}` is taken by only some invocations, so the rest of the {scope} is non-uniform"),
        );
        match &self.cond {
            Some(c) => notes.combine(syn::Error::new_spanned(
                &c.tokens,
                format!(
                    "invocations for which this {} {what}",
                    if c.holds { "holds" } else { "does not hold" }
                ),
            )),
            None => notes.combine(d.clone()),
        }
        if self.first_exit.is_none() {
            self.first_exit = Some(notes.clone());
        }
        Some(notes)
    }

    /// Whether every expression is uniform. Each one is visited, also after a divergent
    /// one: visiting records assignments and reports misplaced barriers (no short circuit).
    fn all_uniform<'e>(&mut self, exprs: impl Iterator<Item = &'e Expr>) -> bool {
        let mut uniform = true;
        for e in exprs {
            uniform &= self.expr(e);
        }
        uniform
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
                let from_uniform = root
                    .as_ref()
                    .is_some_and(|r| self.params.uniform_buffers.contains(r));
                let from_local = root.as_ref().is_some_and(|r| self.lookup(r).is_some());
                (from_uniform || from_local) && b && ix
            }
            Expr::Paren(p) => self.expr(&p.expr),
            Expr::Group(g) => self.expr(&g.expr),
            Expr::Unary(u) => self.expr(&u.expr),
            Expr::Cast(c) => self.expr(&c.expr),
            Expr::Reference(r) => self.expr(&r.expr),
            Expr::Range(r) => {
                // Uniform when both ends are (a missing end is no value).
                let s = r.start.as_ref().is_none_or(|s| self.expr(s));
                let t = r.end.as_ref().is_none_or(|t| self.expr(t));
                s && t
            }
            Expr::Binary(b) => {
                let l = self.expr(&b.left);
                let r = match b.op {
                    // The right side runs only where the left side is true (`&&`) or
                    // false (`||`): under non-uniform control when the left side is.
                    syn::BinOp::And(_) => {
                        self.guarded(&b.left, true, l, AND_NOTE, |w| w.expr(&b.right))
                    }
                    syn::BinOp::Or(_) => {
                        self.guarded(&b.left, false, l, OR_NOTE, |w| w.expr(&b.right))
                    }
                    _ => self.expr(&b.right),
                };
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
            Expr::Array(a) => self.all_uniform(a.elems.iter()),
            Expr::Repeat(r) => self.expr(&r.expr),
            Expr::Struct(s) => self.all_uniform(s.fields.iter().map(|f| &f.expr)),
            Expr::MethodCall(m) => {
                let r = self.expr(&m.receiver);
                let args = self.all_uniform(m.args.iter());
                let atomic = matches!(
                    m.method.to_string().as_str(),
                    "fetch_add"
                        | "fetch_sub"
                        | "fetch_min"
                        | "fetch_max"
                        | "fetch_and"
                        | "fetch_or"
                        | "fetch_xor"
                        | "swap"
                        | "load"
                        | "store"
                );
                r && args && !atomic
            }
            Expr::Call(c) => {
                let name = call_name(e).unwrap_or_default();
                let sync = SYNC_CALLS.contains(&name.as_str());
                if sync {
                    if self.in_share {
                        self.fail_in_share(call_site(c), &format!("{name}()"));
                    } else if let Some(why) = self.control() {
                        self.fail(call_site(c), &format!("{name}()"), why);
                    }
                }
                if self.check {
                    if let Some(p) = helper_path(c, &self.params.generics) {
                        // The synchronising intrinsics are checked above, with notes.
                        if !sync && (self.in_share || self.control().is_some()) {
                            self.calls.guarded.push(p.clone());
                        }
                        self.calls.all.push(p);
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
                        let saved = self.in_share;
                        self.in_share |= name == "group_share";
                        self.expr(&cl.body);
                        self.in_share = saved;
                        self.scopes.pop();
                        all = false;
                    } else {
                        all &= self.expr(a);
                    }
                }
                let nonuniform_fn = name.starts_with("subgroup_")
                    || name.starts_with("atomic_")
                    || name == "group_share";
                // A helper given a buffer may read memory or use atomics.
                let memory = c.args.iter().any(|a| self.is_memory(a));
                // workgroup_uniform_load gives every invocation the same value by definition.
                name == "workgroup_uniform_load" || (all && !nonuniform_fn && !memory)
            }
            Expr::If(i) => {
                let c = self.expr(&i.cond);
                let t = self.guarded(&i.cond, true, c, STARTS_HERE, |w| {
                    w.block(&i.then_branch);
                    block_tail_uniform(w, &i.then_branch)
                });
                let e = match &i.else_branch {
                    Some((_, eb)) => self.guarded(&i.cond, false, c, STARTS_HERE, |w| w.expr(eb)),
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
                let why = || {
                    let cond = Cond {
                        tokens: w.cond.to_token_stream(),
                        holds: true,
                    };
                    (syn::Error::new_spanned(&w.cond, STARTS_HERE), Some(cond))
                };
                self.loop_body(c, why, &w.body);
                true
            }
            Expr::Loop(l) => {
                self.loop_body(true, || unreachable!("a `loop` has no condition"), &l.body);
                true
            }
            Expr::ForLoop(f) => {
                let r = self.expr(&f.expr);
                self.scopes.push(HashMap::new());
                if let Some((n, _)) = pat_name(&f.pat) {
                    self.scopes.last_mut().unwrap().insert(n, r);
                }
                let why = || (syn::Error::new_spanned(&f.expr, STARTS_HERE), None);
                self.loop_body(r, why, &f.body);
                self.scopes.pop();
                true
            }
            Expr::Break(_) => {
                self.exit(e, "break");
                true
            }
            Expr::Continue(_) => {
                self.exit(e, "continue");
                true
            }
            Expr::Return(r) => {
                if let Some(v) = &r.expr {
                    self.expr(v);
                }
                if let Some(notes) = self.exit(e, "return") {
                    if self.exited.is_none() {
                        self.exited = Some(notes);
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
        p.path.segments.len() == 1
            && self
                .params
                .nonuniform
                .contains(&p.path.segments[0].ident.to_string())
    }

    /// Whether a call argument is (a reference into) a storage buffer or workgroup memory.
    fn is_memory(&self, a: &Expr) -> bool {
        root_name(a).is_some_and(|r| self.lookup(&r).is_none() && self.params.memory.contains(&r))
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
        AddAssign(_)
            | SubAssign(_)
            | MulAssign(_)
            | DivAssign(_)
            | RemAssign(_)
            | BitAndAssign(_)
            | BitOrAssign(_)
            | BitXorAssign(_)
            | ShlAssign(_)
            | ShrAssign(_)
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
        Expr::Reference(r) => root_name(&r.expr),
        Expr::Group(g) => root_name(&g.expr),
        _ => None,
    }
}

fn assigned_var(e: &Expr) -> Option<String> {
    root_name(e)
}

/// Checks a kernel body. `params` says which parameter names are uniform. Returns the
/// helper calls found (see [`Calls`]).
pub fn check(body: &Block, params: &Params) -> syn::Result<Calls> {
    let mut nonuniform_vars = HashSet::new();
    // Iterate to a fixed point: a `let mut` found non-uniform can make others so.
    for _ in 0..16 {
        let mut w = Walker {
            params,
            scopes: vec![HashMap::new()],
            nonuniform_vars: nonuniform_vars.clone(),
            changed: false,
            divergent: None,
            cond: None,
            exited: None,
            error: None,
            check: false,
            first_exit: None,
            in_share: false,
            calls: Calls::default(),
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
        cond: None,
        exited: None,
        error: None,
        check: true,
        first_exit: None,
        in_share: false,
        calls: Calls::default(),
    };
    w.block(body);
    match w.error {
        Some(e) => Err(e),
        None => Ok(w.calls),
    }
}

/// The compile-time checks of a body's helper calls: a helper called under non-uniform
/// control must not need uniform control (error at the call), and the body's own
/// `NEEDS_UNIFORM` (for a helper: whether any helper or intrinsic it calls does).
pub fn call_checks(
    calls: &Calls,
    own_name: Option<&syn::Ident>,
) -> (Vec<TokenStream>, TokenStream) {
    use quote::quote_spanned;
    use syn::spanned::Spanned;
    let asserts = calls
        .guarded
        .iter()
        .map(|p| {
            let name = p.segments.last().map(|s| s.ident.to_string()).unwrap_or_default();
            let msg = format!(
                "`{name}` waits at a workgroup barrier or group operation (itself or a helper it calls), so every invocation of the group must call it, but this call is under control flow that depends on a non-uniform value (or inside a `group_share` closure): call it where all invocations do"
            );
            quote_spanned! {p.span()=> const _: () = ::core::assert!(!#p::NEEDS_UNIFORM, #msg); }
        })
        .collect();
    // A helper's call of itself is refused elsewhere; here it would be a constant cycle.
    let is_self = |p: &&syn::Path| {
        p.segments.len() == 1 && own_name.is_some_and(|n| p.segments[0].ident == *n)
    };
    let callees = calls
        .all
        .iter()
        .filter(|p| !is_self(p))
        .map(|p| quote::quote!(#p::NEEDS_UNIFORM));
    let needs = quote::quote!(false #(|| #callees)*);
    (asserts, needs)
}

/// Checks that a `group_share` closure reads only its group index, uniform parameters
/// and constants: for `group = Grid` every invocation computes the value of group 0,
/// which is the same for all only if it reads nothing that differs between them.
pub fn check_grid_closures(
    body: &Block,
    params: &Params,
    all_params: &HashSet<String>,
) -> syn::Result<()> {
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
                        self.err = Some(syn::Error::new_spanned(
                            p,
                            format!(
                                "`group_share` closures may read only their group index, uniform parameters and constants, not `{n}`: with `group = Grid` every invocation computes the value of group 0, which must then be the same for all (any kernel can be launched at `Grid` level)"
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
        // A `for` variable is a kernel value like a `let` (the loop binds it, not a `let`).
        fn visit_expr_for_loop(&mut self, f: &'ast syn::ExprForLoop) {
            self.visit_expr(&f.expr);
            self.locals.push(HashSet::new());
            if let Some((n, _)) = pat_name(&f.pat) {
                match &mut self.in_closure {
                    Some(c) => {
                        c.insert(n);
                    }
                    None => {
                        self.locals.last_mut().unwrap().insert(n);
                    }
                }
            }
            self.visit_block(&f.body);
            self.locals.pop();
        }
    }
    let mut v = V {
        params,
        all: all_params,
        locals: vec![HashSet::new()],
        in_closure: None,
        err: None,
    };
    v.visit_block(body);
    match v.err {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
