//! The body rewriter: kernel Rust → Rust that builds IR when it runs.
//!
//! Every construct of the subset has one rule here; every other construct is a
//! `syn::Error` at its span that says what to write instead. The output calls only
//! `::cohort::ir` (typed handles), so rustc checks the rewritten body's types at the
//! user's spans (`quote_spanned!`).

use proc_macro2::{Span, TokenStream};
use quote::{format_ident, quote, quote_spanned, ToTokens};
use std::collections::{HashMap, HashSet};
use syn::spanned::Spanned;
use syn::{BinOp, Block, Expr, Lit, Pat, Stmt, UnOp};

type Result<T> = syn::Result<T>;

/// What a name in the kernel body is bound to in the rewritten code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bind {
    /// An immutable value: `Val<T>`.
    Val,
    /// A `let mut` (or late-initialised) binding: `Var<T>`.
    Var,
    /// A reference-like root: buffer, uniform, workgroup memory, `&mut` argument.
    Root,
}

/// Types whose associated functions (`Vec3::new`, `f32::from_bits`) map to `Val<T>`'s.
/// Whether `name` is one of the types whose methods calls become `Val` methods.
pub fn is_builtin_type(name: &str) -> bool {
    BUILTIN_TYPES.contains(&name)
}

const BUILTIN_TYPES: &[&str] = &[
    "f32", "u32", "i32", "usize", "bool", "Vec2", "Vec3", "Vec4", "UVec2", "UVec3", "UVec4",
    "IVec2", "IVec3", "IVec4", "Mat3", "Mat4",
];

/// Methods that act on an atomic in memory rather than on a loaded value.
const ATOMIC_METHODS: &[&str] = &[
    "fetch_add",
    "fetch_sub",
    "fetch_min",
    "fetch_max",
    "fetch_and",
    "fetch_or",
    "fetch_xor",
    "swap",
    "load",
    "store",
];

/// Methods the kernel types have, called without the stand-in of `method_call` (which
/// only improves the message when a method is missing, so this list needs not be
/// complete: it keeps the generated code small for the common calls).
const KNOWN_METHODS: &[&str] = &[
    "abs",
    "min",
    "max",
    "clamp",
    "sqrt",
    "dot",
    "cross",
    "normalize",
    "length",
    "length_squared",
    "floor",
    "ceil",
    "round",
    "fract",
    "exp",
    "ln",
    "powf",
    "powi",
    "sin",
    "cos",
    "tan",
    "atan2",
    "mul_add",
    "to_bits",
    "recip",
    "signum",
    "is_nan",
    "is_finite",
    "len",
    "is_empty",
    "x",
    "extend",
    "truncate",
    "min_element",
    "max_element",
    "element_sum",
    "wrapping_add",
    "wrapping_sub",
    "wrapping_mul",
    "count_ones",
    "leading_zeros",
    "trailing_zeros",
    "exp2",
    "log2",
    "asin",
    "acos",
    "atan",
    "sinh",
    "cosh",
    "tanh",
    "rotate_left",
    "rotate_right",
    "reverse_bits",
    "copysign",
    "rem_euclid",
    "div_euclid",
    "abs_diff",
    "lerp",
    "reflect",
    "distance",
    "xyz",
    "xy",
];

pub struct Rewriter {
    scopes: Vec<HashMap<String, Bind>>,
    /// Generic type parameters of the function (calls `T::f(..)` go to `T::__ir_f`).
    pub generics: HashSet<String>,
    loop_depth: usize,
    /// In an inlined helper `return` cannot be expressed; only the tail value returns.
    pub forbid_return: bool,
    /// Whether `group_share` may be called (only directly in kernel bodies).
    pub allow_group_share: bool,
}

/// An error at one span (a single token, or a span that is all there is).
pub fn err<T>(span: Span, msg: impl std::fmt::Display) -> Result<T> {
    Err(syn::Error::new(span, msg.to_string()))
}

/// An error about a whole syntax node: underlines it from its first to its last token.
pub fn err_at<T>(node: impl ToTokens, msg: impl std::fmt::Display) -> Result<T> {
    Err(syn::Error::new_spanned(node, msg.to_string()))
}

/// What to write instead of a loop label.
const LABEL_HINT: &str = "use a `let mut` flag that the outer loop tests";
const NO_LABELS: &str =
    "loop labels are not supported in kernels; use a `let mut` flag that the outer loop tests";

/// Why a macro other than the print macros is refused, and what to write instead.
fn unsupported_macro(mac: &syn::Macro) -> String {
    format!(
        "macro `{}!` is not supported in kernels (kernels cannot panic or allocate); the only \
         macros kernels take are `print!`, `println!`, `eprint!` and `eprintln!`",
        mac.path.to_token_stream()
    )
}

fn is_diverging(e: &Expr) -> bool {
    matches!(e, Expr::Break(_) | Expr::Continue(_) | Expr::Return(_))
}

impl Rewriter {
    pub fn new() -> Self {
        Rewriter {
            scopes: vec![HashMap::new()],
            generics: HashSet::new(),
            loop_depth: 0,
            forbid_return: false,
            allow_group_share: false,
        }
    }

    pub fn bind(&mut self, name: &str, b: Bind) {
        self.scopes.last_mut().unwrap().insert(name.to_string(), b);
    }

    fn lookup(&self, name: &str) -> Option<Bind> {
        self.scopes.iter().rev().find_map(|s| s.get(name).copied())
    }

    fn push(&mut self) {
        self.scopes.push(HashMap::new());
    }
    fn pop(&mut self) {
        self.scopes.pop();
    }

    fn local_ident(&self, e: &Expr) -> Option<(syn::Ident, Bind)> {
        if let Expr::Path(p) = e {
            if p.qself.is_none() && p.path.segments.len() == 1 && p.path.leading_colon.is_none() {
                let id = &p.path.segments[0].ident;
                return self.lookup(&id.to_string()).map(|b| (id.clone(), b));
            }
        }
        None
    }

    /// Whether `e` denotes memory (a place) rather than a value: a `let mut`, a buffer,
    /// uniform or `&mut` root, possibly with field and index projections.
    fn is_place(&self, e: &Expr) -> bool {
        match e {
            Expr::Paren(p) => self.is_place(&p.expr),
            Expr::Field(f) => self.is_place(&f.base),
            Expr::Index(i) => self.is_place(&i.expr),
            Expr::Unary(u) if matches!(u.op, UnOp::Deref(_)) => self.is_place(&u.expr),
            _ => matches!(self.local_ident(e), Some((_, Bind::Var | Bind::Root))),
        }
    }

    // ---------------------------------------------------------------- blocks

    /// A block as a Rust block expression: statements rewritten, tail value kept.
    pub fn block(&mut self, b: &Block) -> Result<TokenStream> {
        self.push();
        let r = self.block_inner(b);
        self.pop();
        let inner = r?;
        Ok(quote! { { #inner } })
    }

    fn block_inner(&mut self, b: &Block) -> Result<TokenStream> {
        let mut out = TokenStream::new();
        let n = b.stmts.len();
        for (i, s) in b.stmts.iter().enumerate() {
            let last = i + 1 == n;
            match s {
                Stmt::Expr(e, None) if last && !is_statement_like(e) => {
                    let v = self.rv(e)?;
                    out.extend(v);
                }
                Stmt::Expr(e, None) if last && is_diverging(e) => {
                    out.extend(self.stmt_expr(e)?);
                    out.extend(quote! { ::cohort::ir::diverged() });
                }
                Stmt::Expr(e, semi) => {
                    out.extend(self.stmt_expr(e)?);
                    if last && semi.is_some() && is_diverging(e) {
                        out.extend(quote! { ::cohort::ir::diverged() });
                    }
                }
                _ => out.extend(self.stmt(s)?),
            }
        }
        Ok(out)
    }

    fn stmt(&mut self, s: &Stmt) -> Result<TokenStream> {
        match s {
            Stmt::Local(l) => self.local(l),
            Stmt::Item(syn::Item::Const(c)) => Ok(c.to_token_stream()),
            Stmt::Item(i) => err_at(i, "only `const` items may be declared inside kernels; move other items out of the function"),
            Stmt::Expr(e, _) => self.stmt_expr(e),
            Stmt::Macro(m) if crate::print::is_print(&m.mac) => self.print_macro(&m.mac),
            Stmt::Macro(m) => err_at(m, unsupported_macro(&m.mac)),
        }
    }

    fn local(&mut self, l: &syn::Local) -> Result<TokenStream> {
        if let Some(init) = &l.init {
            if let Some((else_token, _)) = &init.diverge {
                return err_at(
                    else_token,
                    "`let … else` is not supported in kernels; use a boolean check with if/else, e.g. `if i < buf.len() { let v = buf[i]; … }`",
                );
            }
        }
        let (ident, mutable, ty) = match &l.pat {
            Pat::Ident(p) => (p.ident.clone(), p.mutability.is_some(), None),
            Pat::Type(t) => match &*t.pat {
                Pat::Ident(p) => (
                    p.ident.clone(),
                    p.mutability.is_some(),
                    Some((*t.ty).clone()),
                ),
                other => {
                    return err_at(
                        other,
                        "destructuring is not supported in kernels; bind one name per `let`",
                    )
                }
            },
            other => {
                return err_at(
                    other,
                    "destructuring is not supported in kernels; bind one name per `let`",
                )
            }
        };
        if let Pat::Ident(p) = &l.pat {
            if p.by_ref.is_some() {
                return err_at(p, "`ref` bindings are not supported in kernels");
            }
        }
        let name = ident.to_string();
        let span = l.span();
        if let Some(call) = l.init.as_ref().and_then(|i| uninit_call(&i.expr)) {
            return self.uninit_local(l, call, ident, mutable, ty);
        }
        let init = match &l.init {
            Some(i) => Some(self.rv(&i.expr)?),
            None => None,
        };
        let ty_tokens = ty.as_ref().map(|t| quote! { #t });
        let out = match (mutable || init.is_none(), init) {
            (false, Some(v)) => {
                let annot = ty_tokens.map(|t| quote_spanned! {span=> : ::cohort::ir::Val<#t> });
                quote_spanned! {span=> let #ident #annot = ::cohort::ir::name(#v, #name); }
            }
            (true, Some(v)) => {
                let annot = ty_tokens.map(|t| quote_spanned! {span=> : ::cohort::ir::Var<#t> });
                quote_spanned! {span=> let #ident #annot = ::cohort::ir::Var::new(#name, #v); }
            }
            (_, None) => match ty_tokens {
                Some(t) => {
                    quote_spanned! {span=> let #ident = ::cohort::ir::Var::<#t>::uninit(#name); }
                }
                None => {
                    return err_at(
                        l,
                        "a `let` without initial value needs a type annotation in kernels",
                    )
                }
            },
        };
        let bind = if mutable || l.init.is_none() {
            Bind::Var
        } else {
            Bind::Val
        };
        self.bind(&name, bind);
        Ok(out)
    }

    /// `let mut x: T = uninit();` (or `uninit::<T>()`): a variable without an initial
    /// store (docs/LANGUAGE.md, "Uninitialised locals").
    fn uninit_local(
        &mut self,
        l: &syn::Local,
        call: &syn::ExprCall,
        ident: syn::Ident,
        mutable: bool,
        ty: Option<syn::Type>,
    ) -> Result<TokenStream> {
        let span = l.span();
        if !mutable {
            return err_at(l, "`uninit()` starts a variable that is written before it is read: bind it with `let mut`, e.g. `let mut stack: [u32; 64] = uninit();`");
        }
        let turbofish = match &*call.func {
            Expr::Path(p) => match &p.path.segments.last().map(|s| &s.arguments) {
                Some(syn::PathArguments::AngleBracketed(a)) => {
                    a.args.first().and_then(|g| match g {
                        syn::GenericArgument::Type(t) => Some(t.clone()),
                        _ => None,
                    })
                }
                _ => None,
            },
            _ => None,
        };
        let Some(t) = ty.or(turbofish) else {
            return err_at(
                l,
                "`uninit()` needs the variable's type: `let mut stack: [u32; 64] = uninit();`",
            );
        };
        let name = ident.to_string();
        self.bind(&name, Bind::Var);
        Ok(quote_spanned! {span=> let #ident = ::cohort::ir::Var::<#t>::uninit(#name); })
    }

    // ---------------------------------------------------------------- statements

    fn stmt_expr(&mut self, e: &Expr) -> Result<TokenStream> {
        let span = e.span();
        match e {
            Expr::If(_) | Expr::Block(_) => {
                let v = self.rv(e)?;
                Ok(quote_spanned! {span=> ::cohort::ir::discard(#v); })
            }
            Expr::While(w) => {
                if let Some(l) = &w.label {
                    return err_at(l, NO_LABELS);
                }
                if let Expr::Let(l) = &*w.cond {
                    return err_at(
                        l,
                        "`while let` is not supported in kernels; use `while` with a condition",
                    );
                }
                let c = self.rv(&w.cond)?;
                self.loop_depth += 1;
                let body = self.block(&w.body);
                self.loop_depth -= 1;
                let body = body?;
                Ok(
                    quote_spanned! {span=> ::cohort::ir::while_(|| #c, || { ::cohort::ir::discard(#body); }); },
                )
            }
            Expr::Loop(l) => {
                if let Some(lb) = &l.label {
                    return err_at(lb, NO_LABELS);
                }
                self.loop_depth += 1;
                let body = self.block(&l.body);
                self.loop_depth -= 1;
                let body = body?;
                Ok(
                    quote_spanned! {span=> ::cohort::ir::loop_(|| { ::cohort::ir::discard(#body); }); },
                )
            }
            Expr::ForLoop(f) => self.for_loop(f),
            Expr::Break(b) => {
                if b.label.is_some() {
                    return err_at(
                        b,
                        format!(
                            "labelled `break` is not supported in kernels; {}",
                            LABEL_HINT
                        ),
                    );
                }
                if let Some(v) = &b.expr {
                    return err_at(v, "`break` with a value is not supported in kernels; assign to a `let mut` before `break`");
                }
                if self.loop_depth == 0 {
                    return err_at(b, "`break` outside of a loop");
                }
                Ok(quote_spanned! {span=> ::cohort::ir::break_(); })
            }
            Expr::Continue(c) => {
                if c.label.is_some() {
                    return err_at(
                        c,
                        format!(
                            "labelled `continue` is not supported in kernels; {}",
                            LABEL_HINT
                        ),
                    );
                }
                Ok(quote_spanned! {span=> ::cohort::ir::continue_(); })
            }
            Expr::Return(r) => {
                if self.forbid_return {
                    return err_at(
                        r,
                        "early `return` is not supported in helpers that take buffers (they are inlined); end the function with its value instead",
                    );
                }
                match &r.expr {
                    Some(v) => {
                        let v = self.rv(v)?;
                        Ok(quote_spanned! {span=> ::cohort::ir::return_value(#v); })
                    }
                    None => Ok(quote_spanned! {span=> ::cohort::ir::return_(); }),
                }
            }
            Expr::Assign(a) => {
                let p = self.place(&a.left)?;
                let v = self.rv(&a.right)?;
                Ok(quote_spanned! {span=> ::cohort::ir::Place::set(#p, #v); })
            }
            Expr::Binary(b) if compound_op(&b.op).is_some() => {
                let op = compound_op(&b.op).unwrap();
                let p = self.place(&b.left)?;
                let v = self.rv(&b.right)?;
                let opspan = b.op.span();
                let combined = quote_spanned! {opspan=> ::cohort::ir::Place::get(__place) #op #v };
                Ok(
                    quote_spanned! {span=> { let __place = #p; ::cohort::ir::Place::set(__place, #combined); } },
                )
            }
            _ => {
                let v = self.rv(e)?;
                Ok(quote_spanned! {span=> ::cohort::ir::discard(#v); })
            }
        }
    }

    fn for_loop(&mut self, f: &syn::ExprForLoop) -> Result<TokenStream> {
        let span = f.span();
        if let Some(l) = &f.label {
            return err_at(l, NO_LABELS);
        }
        let var = match &*f.pat {
            Pat::Ident(p) if p.mutability.is_none() => p.ident.clone(),
            Pat::Wild(_) => format_ident!("_"),
            other => {
                return err_at(
                    other,
                    "`for` binds one immutable name in kernels, e.g. `for i in 0..n`",
                )
            }
        };
        let (range, rev) = match &*f.expr {
            Expr::Range(r) => (r.clone(), false),
            Expr::MethodCall(m) if m.method == "rev" && m.args.is_empty() => {
                match strip_paren(&m.receiver) {
                    Expr::Range(r) => (r.clone(), true),
                    other => return err_at(
                        other,
                        "`for` in kernels iterates over a range: `a..b`, `a..=b` or `(a..b).rev()`",
                    ),
                }
            }
            other => {
                return err_at(
                    other,
                    "`for` in kernels iterates over a range: `a..b`, `a..=b` or `(a..b).rev()`",
                )
            }
        };
        let (Some(start), Some(end)) = (&range.start, &range.end) else {
            return err_at(
                &range,
                "ranges in kernel `for` loops need both ends: `a..b`",
            );
        };
        let inclusive = matches!(range.limits, syn::RangeLimits::Closed(_));
        if rev && inclusive {
            return err_at(
                &range,
                "`(a..=b).rev()` is not supported in kernels; write `(a..b + 1).rev()`",
            );
        }
        let s = self.rv(start)?;
        let e = self.rv(end)?;
        self.push();
        self.bind(&var.to_string(), Bind::Val);
        self.loop_depth += 1;
        let body = self.block(&f.body);
        self.loop_depth -= 1;
        self.pop();
        let body = body?;
        if rev {
            Ok(
                quote_spanned! {span=> ::cohort::ir::for_range_rev(#s, #e, |#var| { ::cohort::ir::discard(#body); }); },
            )
        } else {
            Ok(
                quote_spanned! {span=> ::cohort::ir::for_range(#s, #e, #inclusive, |#var| { ::cohort::ir::discard(#body); }); },
            )
        }
    }

    // ---------------------------------------------------------------- places

    pub fn place(&mut self, e: &Expr) -> Result<TokenStream> {
        let span = e.span();
        match e {
            Expr::Paren(p) => self.place(&p.expr),
            Expr::Field(f) => {
                let base = self.place(&f.base)?;
                let member = &f.member;
                Ok(quote_spanned! {span=> ::cohort::ir::place_field(#base, |__s| &__s.#member) })
            }
            Expr::Index(i) => {
                let base = self.place(&i.expr)?;
                let idx = self.rv(&i.index)?;
                Ok(quote_spanned! {span=> ::cohort::ir::place_index(#base, #idx) })
            }
            Expr::Unary(u) if matches!(u.op, UnOp::Deref(_)) => self.place(&u.expr),
            _ => match self.local_ident(e) {
                Some((id, Bind::Var | Bind::Root)) => Ok(quote_spanned! {span=> ::cohort::ir::place(&#id) }),
                Some((id, Bind::Val)) => err_at(e, format!("cannot assign to `{id}`: it is not declared `let mut`")),
                None => err_at(e, "this expression is not a place that kernels can assign to (a `let mut` variable, a buffer element, a field of one, or `*r` of a `&mut` parameter)"),
            },
        }
    }

    // ---------------------------------------------------------------- values

    pub(crate) fn rv(&mut self, e: &Expr) -> Result<TokenStream> {
        let span = e.span();
        match e {
            Expr::Lit(l) => match &l.lit {
                Lit::Int(_) | Lit::Float(_) | Lit::Bool(_) => {
                    let lit = &l.lit;
                    Ok(quote_spanned! {span=> ::cohort::ir::lit(#lit) })
                }
                other => err_at(other, "only integer, float and bool literals are supported in kernels"),
            },
            Expr::Paren(p) => {
                let inner = self.rv(&p.expr)?;
                Ok(quote_spanned! {span=> (#inner) })
            }
            Expr::Group(g) => self.rv(&g.expr),
            Expr::Path(p) => self.path_value(p),
            Expr::Field(f) => {
                if self.is_place(&f.base) {
                    let p = self.place(e)?;
                    Ok(quote_spanned! {span=> ::cohort::ir::Place::get(#p) })
                } else {
                    let base = self.rv(&f.base)?;
                    let member = &f.member;
                    Ok(quote_spanned! {span=> ::cohort::ir::field(#base, |__s| &__s.#member) })
                }
            }
            Expr::Index(i) => {
                if self.is_place(&i.expr) {
                    let p = self.place(e)?;
                    Ok(quote_spanned! {span=> ::cohort::ir::Place::get(#p) })
                } else {
                    let base = self.rv(&i.expr)?;
                    let idx = self.rv(&i.index)?;
                    Ok(quote_spanned! {span=> ::cohort::ir::index(#base, #idx) })
                }
            }
            Expr::Unary(u) => match u.op {
                UnOp::Deref(_) => {
                    let p = self.place(&u.expr)?;
                    Ok(quote_spanned! {span=> ::cohort::ir::Place::get(#p) })
                }
                UnOp::Neg(_) => {
                    let v = self.rv(&u.expr)?;
                    Ok(quote_spanned! {span=> (-#v) })
                }
                UnOp::Not(_) => {
                    let v = self.rv(&u.expr)?;
                    Ok(quote_spanned! {span=> (!#v) })
                }
                _ => err_at(u, "unsupported unary operator in kernels"),
            },
            Expr::Binary(b) => self.binary(b),
            Expr::Cast(c) => {
                let v = self.rv(&c.expr)?;
                let ty = &c.ty;
                Ok(quote_spanned! {span=> ::cohort::ir::cast::<#ty, _>(#v) })
            }
            Expr::Reference(r) => {
                if r.mutability.is_some() || self.is_place(&r.expr) {
                    self.place(&r.expr)
                } else {
                    self.rv(&r.expr)
                }
            }
            Expr::If(i) => self.if_expr(i),
            Expr::Block(b) => {
                if let Some(l) = &b.label {
                    return err_at(l, "labelled blocks are not supported in kernels; use if/else or a `let mut` flag");
                }
                self.block(&b.block)
            }
            Expr::Unsafe(u) => err_at(u.unsafe_token, "`unsafe` blocks are not supported in kernels"),
            Expr::MethodCall(m) => self.method_call(m),
            Expr::Call(c) => self.call(c),
            Expr::Struct(s) => self.struct_lit(s),
            Expr::Array(a) => {
                let items = a.elems.iter().map(|x| self.rv(x)).collect::<Result<Vec<_>>>()?;
                Ok(quote_spanned! {span=> ::cohort::ir::array([#(#items),*]) })
            }
            Expr::Repeat(r) => {
                let v = self.rv(&r.expr)?;
                let n = &r.len;
                Ok(quote_spanned! {span=> ::cohort::ir::array_repeat::<_, { #n }>(#v) })
            }
            Expr::Match(m) => err(m.match_token.span, "`match` is not supported in kernels; use an if/else chain"),
            Expr::Tuple(t) => err_at(t, "tuples are not supported in kernels; use a struct with #[derive(GpuType)]"),
            Expr::Closure(c) => err_at(c, "closures are only supported as the argument of `group_share`; use a #[kernel_fn] helper"),
            Expr::Range(r) => err_at(r, "ranges are only supported as the iterator of a `for` loop"),
            Expr::Try(t) => err_at(t.question_token, "the `?` operator is not supported in kernels; check with if/else instead"),
            Expr::Macro(m) if crate::print::is_print(&m.mac) => self.print_macro(&m.mac),
            Expr::Macro(m) => err_at(m, unsupported_macro(&m.mac)),
            Expr::Let(l) => err_at(l, "`if let` / `let` patterns are not supported in kernels; use a boolean condition"),
            Expr::Async(a) => err_at(a.async_token, "`async` is not supported in kernels"),
            Expr::Await(a) => err_at(a, "`.await` is not supported in kernels"),
            Expr::While(_) | Expr::Loop(_) | Expr::ForLoop(_) | Expr::Break(_) | Expr::Continue(_)
            | Expr::Return(_) | Expr::Assign(_) => {
                let s = self.stmt_expr(e)?;
                Ok(quote_spanned! {span=> { #s } })
            }
            other => err_at(other, "this expression is not supported in kernels"),
        }
    }

    fn path_value(&mut self, p: &syn::ExprPath) -> Result<TokenStream> {
        let span = p.span();
        if let Some((id, b)) = self.local_ident(&Expr::Path(p.clone())) {
            return Ok(match b {
                Bind::Val | Bind::Root => quote_spanned! {span=> #id },
                Bind::Var => quote_spanned! {span=> ::cohort::ir::Var::get(#id) },
            });
        }
        // A constant: a `const` item, an associated constant (`f32::MAX`, `S::N`).
        Ok(quote_spanned! {span=> ::cohort::ir::konst(#p) })
    }

    fn binary(&mut self, b: &syn::ExprBinary) -> Result<TokenStream> {
        let span = b.span();
        if compound_op(&b.op).is_some() {
            let s = self.stmt_expr(&Expr::Binary(b.clone()))?;
            return Ok(quote_spanned! {span=> { #s } });
        }
        let l = self.rv(&b.left)?;
        let r = self.rv(&b.right)?;
        let opspan = b.op.span();
        Ok(match b.op {
            BinOp::And(_) => quote_spanned! {opspan=> ::cohort::ir::and(#l, || #r) },
            BinOp::Or(_) => quote_spanned! {opspan=> ::cohort::ir::or(#l, || #r) },
            BinOp::Lt(_) => quote_spanned! {opspan=> ::cohort::ir::lt(#l, #r) },
            BinOp::Le(_) => quote_spanned! {opspan=> ::cohort::ir::le(#l, #r) },
            BinOp::Gt(_) => quote_spanned! {opspan=> ::cohort::ir::gt(#l, #r) },
            BinOp::Ge(_) => quote_spanned! {opspan=> ::cohort::ir::ge(#l, #r) },
            BinOp::Eq(_) => quote_spanned! {opspan=> ::cohort::ir::eq(#l, #r) },
            BinOp::Ne(_) => quote_spanned! {opspan=> ::cohort::ir::ne(#l, #r) },
            _ => {
                let op = &b.op;
                quote_spanned! {span=> (#l #op #r) }
            }
        })
    }

    fn if_expr(&mut self, i: &syn::ExprIf) -> Result<TokenStream> {
        let span = i.span();
        if let Expr::Let(l) = &*i.cond {
            return err_at(
                l,
                "`if let` is not supported in kernels; use a boolean condition",
            );
        }
        let c = self.rv(&i.cond)?;
        let then = self.block(&i.then_branch)?;
        let otherwise = match &i.else_branch {
            Some((_, e)) => self.rv(e)?,
            None => quote! { {} },
        };
        Ok(quote_spanned! {span=> ::cohort::ir::if_else(#c, || #then, || #otherwise) })
    }

    fn method_call(&mut self, m: &syn::ExprMethodCall) -> Result<TokenStream> {
        let span = m.span();
        if let Some(t) = &m.turbofish {
            return err_at(t, "turbofish on methods is not supported in kernels");
        }
        let method = &m.method;
        let args = m
            .args
            .iter()
            .map(|a| self.rv(a))
            .collect::<Result<Vec<_>>>()?;
        let name = method.to_string();
        if name == "clone" && args.is_empty() {
            return self.rv(&m.receiver);
        }
        let recv = if ATOMIC_METHODS.contains(&name.as_str())
            && self.is_place(&m.receiver)
            && !self.is_bare_var(&m.receiver)
        {
            self.place(&m.receiver)?
        } else if let Some((id, Bind::Root)) = self.local_ident(&m.receiver) {
            quote_spanned! {span=> ::cohort::ir::AutoDeref::auto_deref(#id) }
        } else {
            self.rv(&m.receiver)?
        };
        let call = quote_spanned! {span=> (#recv).#method(#(#args),*) };
        if KNOWN_METHODS.contains(&name.as_str()) || ATOMIC_METHODS.contains(&name.as_str()) {
            return Ok(call);
        }
        // A method kernels may not have (e.g. one of the user's own struct): a stand-in
        // trait method of that name, by reference so that any real method of `Val<T>`
        // (by value) is found first, whose unsatisfiable bound makes rustc say what to
        // write instead.
        let hint = format_ident!("__CohortMethod_{}", name);
        let params: Vec<_> = (0..args.len()).map(|i| format_ident!("A{i}")).collect();
        Ok(quote_spanned! {span=> {
            #[allow(non_camel_case_types, dead_code)]
            trait #hint { fn #method<#(#params),*>(&self #(, _: #params)*) -> ::cohort::ir::Val<()>; }
            impl<T: ::cohort::ir::MethodNeedsKernelFn> #hint for ::cohort::ir::Val<T> {
                fn #method<#(#params),*>(&self #(, _: #params)*) -> ::cohort::ir::Val<()> {
                    ::core::unreachable!()
                }
            }
            #call
        } })
    }

    fn is_bare_var(&self, e: &Expr) -> bool {
        matches!(self.local_ident(e), Some((_, Bind::Var)))
    }

    fn call(&mut self, c: &syn::ExprCall) -> Result<TokenStream> {
        let span = c.span();
        let Expr::Path(fp) = &*c.func else {
            return err_at(
                &c.func,
                "only calls of named functions are supported in kernels",
            );
        };
        if self.local_ident(&c.func).is_some() {
            return err_at(&c.func, "calling a local value is not supported in kernels");
        }
        let is_group_share = fp.qself.is_none()
            && fp
                .path
                .segments
                .last()
                .is_some_and(|s| s.ident == "group_share");
        if is_group_share && !self.allow_group_share {
            return err_at(
                &c.func,
                "`group_share` can only be called directly in a `#[kernel]` body (its group level is the kernel's)",
            );
        }
        if is_uninit(c) {
            return err_at(c, "`uninit()` is only supported as the initial value of a `let mut` with a type, e.g. `let mut stack: [u32; 64] = uninit();`");
        }
        let mut args = Vec::new();
        for a in &c.args {
            args.push(match a {
                Expr::Closure(cl) if is_group_share => self.closure(cl)?,
                _ => self.rv(a)?,
            });
        }
        let target = self.call_target(fp)?;
        Ok(quote_spanned! {span=> #target(#(#args),*) })
    }

    fn closure(&mut self, cl: &syn::ExprClosure) -> Result<TokenStream> {
        let span = cl.span();
        if cl.inputs.len() != 1 {
            let (open, inputs, close) = (&cl.or1_token, &cl.inputs, &cl.or2_token);
            return err_at(quote!(#open #inputs #close), "the closure of `group_share` takes one argument: the group index, e.g. `|group| ...`");
        }
        let name = match &cl.inputs[0] {
            Pat::Ident(p) => p.ident.clone(),
            Pat::Type(t) => match &*t.pat {
                Pat::Ident(p) => p.ident.clone(),
                other => return err_at(other, "bind the group index to a name"),
            },
            Pat::Wild(_) => format_ident!("_"),
            other => return err_at(other, "bind the group index to a name"),
        };
        self.push();
        self.bind(&name.to_string(), Bind::Val);
        let saved = self.allow_group_share;
        self.allow_group_share = false;
        let body = self.rv(&cl.body);
        self.allow_group_share = saved;
        self.pop();
        let body = body?;
        Ok(quote_spanned! {span=> |#name: ::cohort::ir::Val<u32>| #body })
    }

    /// Where a call goes in the rewritten code:
    /// `Vec3::new` → `<Val<Vec3>>::new`; `T::f` (T generic) and `<T as Tr>::f` →
    /// `T::__ir_f`; any other `path::f::<G>` → `path::f::ir::<G>`.
    fn call_target(&mut self, fp: &syn::ExprPath) -> Result<TokenStream> {
        let span = fp.span();
        let segs = &fp.path.segments;
        let last = segs.last().unwrap();
        if fp.qself.is_some() {
            let mut p = fp.clone();
            let l = p.path.segments.last_mut().unwrap();
            l.ident = format_ident!("__ir_{}", l.ident, span = l.ident.span());
            return Ok(p.to_token_stream());
        }
        if segs.len() >= 2 {
            let ty_seg = &segs[segs.len() - 2];
            let ty_name = ty_seg.ident.to_string();
            if BUILTIN_TYPES.contains(&ty_name.as_str()) && ty_seg.arguments.is_empty() {
                let ty = &ty_seg.ident;
                let f = &last.ident;
                if last.arguments != syn::PathArguments::None {
                    return err_at(last, "generic arguments are not supported here");
                }
                return Ok(quote_spanned! {span=> <::cohort::ir::Val<#ty>>::#f });
            }
            let first = segs[0].ident.to_string();
            if segs.len() == 2 && (first == "Self" || self.generics.contains(&first)) {
                let mut p = fp.clone();
                let l = p.path.segments.last_mut().unwrap();
                l.ident = format_ident!("__ir_{}", l.ident, span = l.ident.span());
                return Ok(p.to_token_stream());
            }
        }
        let mut p = fp.path.clone();
        let l = p.segments.last_mut().unwrap();
        let generics = std::mem::replace(&mut l.arguments, syn::PathArguments::None);
        p.segments.push(syn::PathSegment {
            ident: format_ident!("ir", span = span),
            arguments: generics,
        });
        Ok(p.to_token_stream())
    }

    fn struct_lit(&mut self, s: &syn::ExprStruct) -> Result<TokenStream> {
        let span = s.span();
        if let Some(r) = &s.rest {
            let dots = &s.dot2_token;
            return err_at(
                quote!(#dots #r),
                "struct update syntax (`..base`) is not supported in kernels; list every field",
            );
        }
        if s.qself.is_some() {
            return err_at(s, "qualified struct paths are not supported in kernels");
        }
        let path = &s.path;
        let mut inits = Vec::new();
        let mut check = Vec::new();
        for f in &s.fields {
            let member = &f.member;
            let v = self.rv(&f.expr)?;
            let fspan = f.span();
            inits.push(
                quote_spanned! {fspan=> ::cohort::ir::field_init(|__s: &#path| &__s.#member, #v) },
            );
            check.push(quote_spanned! {fspan=> #member: ::core::unreachable!() });
        }
        Ok(quote_spanned! {span=> {
            // Lets rustc report missing fields at the literal.
            #[allow(unreachable_code, dead_code, clippy::diverging_sub_expression)]
            fn __all_fields_given() -> #path { #path { #(#check),* } }
            ::cohort::ir::compose::<#path>(::std::vec![#(#inits),*])
        } })
    }
}

fn strip_paren(e: &Expr) -> &Expr {
    match e {
        Expr::Paren(p) => strip_paren(&p.expr),
        other => other,
    }
}

fn compound_op(op: &BinOp) -> Option<TokenStream> {
    Some(match op {
        BinOp::AddAssign(_) => quote!(+),
        BinOp::SubAssign(_) => quote!(-),
        BinOp::MulAssign(_) => quote!(*),
        BinOp::DivAssign(_) => quote!(/),
        BinOp::RemAssign(_) => quote!(%),
        BinOp::BitAndAssign(_) => quote!(&),
        BinOp::BitOrAssign(_) => quote!(|),
        BinOp::BitXorAssign(_) => quote!(^),
        BinOp::ShlAssign(_) => quote!(<<),
        BinOp::ShrAssign(_) => quote!(>>),
        _ => return None,
    })
}

/// Expressions that are statements even without a `;` (their value is `()`).
fn is_statement_like(e: &Expr) -> bool {
    match e {
        Expr::While(_)
        | Expr::Loop(_)
        | Expr::ForLoop(_)
        | Expr::Assign(_)
        | Expr::Break(_)
        | Expr::Continue(_)
        | Expr::Return(_) => true,
        Expr::Binary(b) => compound_op(&b.op).is_some(),
        _ => false,
    }
}

/// `uninit()`, `uninit::<T>()` or `cohort::uninit()` (any path ending in `uninit`, no
/// arguments): the intrinsic for a variable without an initial store.
fn is_uninit(c: &syn::ExprCall) -> bool {
    let Expr::Path(p) = &*c.func else {
        return false;
    };
    p.qself.is_none()
        && c.args.is_empty()
        && p.path.segments.last().is_some_and(|s| s.ident == "uninit")
}

/// `e` as an `uninit()` call ([`is_uninit`]).
fn uninit_call(e: &Expr) -> Option<&syn::ExprCall> {
    match e {
        Expr::Call(c) if is_uninit(c) => Some(c),
        _ => None,
    }
}
