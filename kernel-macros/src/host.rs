//! The host form of a kernel or helper: the function as written, with the arithmetic
//! whose Rust meaning depends on the build profile (integer overflow, division by zero,
//! shift amounts) routed through `::cohort::host::ops`, so that a test built in debug
//! computes what the GPU computes (docs/LANGUAGE.md, section 3). Floats are unaffected.

use proc_macro2::TokenStream;
use quote::quote_spanned;
use syn::spanned::Spanned;
use syn::visit_mut::{self, VisitMut};
use syn::{BinOp, Expr, UnOp};

struct HostOps;

fn op_fn(op: &BinOp) -> Option<(&'static str, bool)> {
    Some(match op {
        BinOp::Add(_) => ("add", false),
        BinOp::Sub(_) => ("sub", false),
        BinOp::Mul(_) => ("mul", false),
        BinOp::Div(_) => ("div", false),
        BinOp::Rem(_) => ("rem", false),
        BinOp::Shl(_) => ("shl", false),
        BinOp::Shr(_) => ("shr", false),
        BinOp::AddAssign(_) => ("add", true),
        BinOp::SubAssign(_) => ("sub", true),
        BinOp::MulAssign(_) => ("mul", true),
        BinOp::DivAssign(_) => ("div", true),
        BinOp::RemAssign(_) => ("rem", true),
        BinOp::ShlAssign(_) => ("shl", true),
        BinOp::ShrAssign(_) => ("shr", true),
        _ => return None,
    })
}

/// An operand passed to a function needs no parentheses (and would draw `unused_parens`).
fn bare(e: &Expr) -> &Expr {
    match e {
        Expr::Paren(p) => bare(&p.expr),
        other => other,
    }
}

fn parse(t: TokenStream) -> Expr {
    syn::parse2(t).expect("cohort-macros: host rewrite produced an invalid expression")
}

impl VisitMut for HostOps {
    fn visit_expr_mut(&mut self, e: &mut Expr) {
        visit_mut::visit_expr_mut(self, e);
        let new = match e {
            Expr::Binary(b) => {
                let Some((f, assign)) = op_fn(&b.op) else {
                    return;
                };
                let f = syn::Ident::new(f, b.op.span());
                let (l, r) = (bare(&b.left), bare(&b.right));
                let span = b.op.span();
                if assign {
                    // As for primitive compound assignment: the right operand first.
                    parse(quote_spanned! {span=> {
                        let __cohort_rhs = #r;
                        let __cohort_lhs = &mut #l;
                        *__cohort_lhs = ::cohort::host::ops::#f(*__cohort_lhs, __cohort_rhs);
                    } })
                } else {
                    parse(quote_spanned! {span=> ::cohort::host::ops::#f(#l, #r) })
                }
            }
            Expr::Unary(u) if matches!(u.op, UnOp::Neg(_)) && !matches!(&*u.expr, Expr::Lit(_)) => {
                let (span, x) = (u.op.span(), bare(&u.expr));
                parse(quote_spanned! {span=> ::cohort::host::ops::neg(#x) })
            }
            Expr::MethodCall(m)
                if m.turbofish.is_none()
                    && ((m.method == "abs" && m.args.is_empty())
                        || (m.method == "pow" && m.args.len() == 1)) =>
            {
                let (span, recv, f) = (m.method.span(), bare(&m.receiver), &m.method);
                let args = m.args.iter();
                parse(quote_spanned! {span=> ::cohort::host::ops::#f(#recv #(, #args)*) })
            }
            _ => return,
        };
        *e = new;
    }
    // A print's arguments are kernel expressions like any other (the format string stays).
    fn visit_macro_mut(&mut self, m: &mut syn::Macro) {
        if crate::print::is_print(m) {
            crate::print::host_form(m, |e| HostOps.visit_expr_mut(e));
        }
    }
    // Constant contexts (`const` items, array lengths, types) keep Rust's own arithmetic.
    fn visit_item_mut(&mut self, _: &mut syn::Item) {}
    fn visit_type_mut(&mut self, _: &mut syn::Type) {}
    fn visit_expr_repeat_mut(&mut self, r: &mut syn::ExprRepeat) {
        self.visit_expr_mut(&mut r.expr);
    }
    fn visit_expr_const_mut(&mut self, _: &mut syn::ExprConst) {}
    fn visit_generic_argument_mut(&mut self, _: &mut syn::GenericArgument) {}
}

/// Rewrites a host body in place.
pub fn host_block(b: &mut syn::Block) {
    HostOps.visit_block_mut(b);
}
