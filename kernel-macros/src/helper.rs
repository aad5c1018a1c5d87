//! `#[kernel_fn]`, `#[kernel_trait]` and `#[kernel_impl]`: helpers callable from kernels.
//!
//! A free helper `f` keeps its host body and gets a module `f` with `ir`, the IR version;
//! a trait method `m` gets a sibling `__ir_m`. Helpers become naga functions (one per
//! generic instance), except those taking buffers, which are inlined into the caller
//! because WGSL cannot pass storage pointers to functions.

use proc_macro2::TokenStream;
use quote::{format_ident, quote, quote_spanned};
use syn::spanned::Spanned;
use syn::{FnArg, Pat, Signature, Type};

use crate::rewrite::{err_at, Bind, Rewriter};

struct IrSig {
    params: Vec<TokenStream>,
    names: Vec<syn::Ident>,
    /// Statements run at the top of the body (conversions, `mut` rebinding).
    prelude: Vec<TokenStream>,
    /// Names passed through the naga function boundary (non-inline only).
    arg_names: Vec<syn::Ident>,
    ret: TokenStream,
    inline: bool,
    binds: Vec<(String, Bind)>,
}

fn ir_signature(sig: &Signature) -> syn::Result<IrSig> {
    let mut out = IrSig {
        params: vec![],
        names: vec![],
        prelude: vec![],
        arg_names: vec![],
        ret: quote!(()),
        inline: false,
        binds: vec![],
    };
    for arg in &sig.inputs {
        let FnArg::Typed(pt) = arg else {
            return err_at(
                arg,
                "kernel helpers take no `self`; use an associated function (`fn f(x: T)`)",
            );
        };
        let (name, mutable) = match &*pt.pat {
            Pat::Ident(i) => (i.ident.clone(), i.mutability.is_some()),
            other => return err_at(other, "helper parameters bind one name each"),
        };
        let span = pt.ty.span();
        match &*pt.ty {
            Type::Reference(r) => {
                match &*r.elem {
                    Type::Slice(s) => {
                        let elem = &s.elem;
                        out.inline = true;
                        out.params
                            .push(quote_spanned! {span=> #name: ::cohort::ir::Buffer<#elem> });
                        out.binds.push((name.to_string(), Bind::Root));
                    }
                    elem if r.mutability.is_some() => {
                        out.params.push(quote_spanned! {span=> #name: impl ::cohort::ir::AsPlace<Target = #elem> });
                        out.prelude.push(quote_spanned! {span=> let #name = ::cohort::ir::AsPlace::as_place(&#name); });
                        out.arg_names.push(name.clone());
                        out.binds.push((name.to_string(), Bind::Root));
                    }
                    elem => {
                        out.params
                            .push(quote_spanned! {span=> #name: impl ::cohort::ir::ToVal<#elem> });
                        out.prelude.push(quote_spanned! {span=> let #name = ::cohort::ir::ToVal::to_val(#name); });
                        out.arg_names.push(name.clone());
                        out.binds.push((name.to_string(), Bind::Val));
                    }
                }
            }
            ty => {
                out.params
                    .push(quote_spanned! {span=> #name: ::cohort::ir::Val<#ty> });
                out.arg_names.push(name.clone());
                if mutable {
                    let lit = name.to_string();
                    out.prelude.push(
                        quote_spanned! {span=> let #name = ::cohort::ir::Var::new(#lit, #name); },
                    );
                    out.binds.push((name.to_string(), Bind::Var));
                } else {
                    out.binds.push((name.to_string(), Bind::Val));
                }
            }
        }
        out.names.push(name);
    }
    if let syn::ReturnType::Type(_, t) = &sig.output {
        out.ret = quote_spanned! {t.span()=> ::cohort::ir::Val<#t> };
    }
    if let Some(a) = &sig.asyncness {
        return err_at(a, "kernel helpers are plain `fn`s (not async or unsafe)");
    }
    if let Some(u) = &sig.unsafety {
        return err_at(u, "kernel helpers are plain `fn`s (not async or unsafe)");
    }
    Ok(out)
}

/// Builds the body of an IR function: `function::<Key>(..)` or, inlined, the body.
fn ir_body(
    sig: &Signature,
    block: &syn::Block,
    key: TokenStream,
    extra_generics: &[String],
    display: &str,
) -> syn::Result<(IrSig, TokenStream)> {
    let s = ir_signature(sig)?;
    let mut rw = Rewriter::new();
    for g in sig.generics.type_params() {
        rw.generics.insert(g.ident.to_string());
    }
    for g in extra_generics {
        rw.generics.insert(g.clone());
    }
    rw.forbid_return = s.inline;
    for (n, b) in &s.binds {
        rw.bind(n, *b);
    }
    let body = rw.block(block)?;
    let prelude = &s.prelude;
    let tokens = if s.inline {
        // Inlined (it takes a buffer or a reference): still tracked on the call stack, so
        // that recursion through helpers is an error of the kernel's build, not an endless
        // inlining.
        quote! { #(#prelude)* ::cohort::ir::inlined::<#key, _>(#display, || #body) }
    } else {
        let is_conv = |t: &&TokenStream| {
            let s = t.to_string();
            s.contains("ToVal") || s.contains("AsPlace")
        };
        let conv: Vec<_> = prelude.iter().filter(is_conv).collect();
        let rebind: Vec<_> = prelude.iter().filter(|t| !is_conv(t)).collect();
        let args = &s.arg_names;
        let lits: Vec<String> = args.iter().map(|a| a.to_string()).collect();
        quote! {
            #(#conv)*
            ::cohort::ir::function::<#key, _, _>(#display, &[#(#lits),*], (#(#args,)*), |(#(#args,)*)| {
                #(#rebind)*
                #body
            })
        }
    };
    Ok((s, tokens))
}

/// The key of a trait method's IR instances: the implementing type, and the method's own
/// type parameters where it has some (`fn sample<S: Sampler>(..)`), so that each of its
/// instances is its own naga function.
fn method_key(generics: &syn::Generics) -> TokenStream {
    let tps: Vec<_> = generics.type_params().map(|t| t.ident.clone()).collect();
    if tps.is_empty() {
        quote!(Self)
    } else {
        // `*const Self`: `Self` may be unsized in a trait's default body.
        quote!((*const Self, #(#tps,)*))
    }
}

fn static_where(generics: &syn::Generics) -> TokenStream {
    let tps: Vec<_> = generics.type_params().map(|t| t.ident.clone()).collect();
    let bounds = tps.iter().map(|t| quote!(#t: 'static));
    match &generics.where_clause {
        Some(w) => {
            let preds = &w.predicates;
            quote!(where #preds, #(#bounds),*)
        }
        None if tps.is_empty() => quote!(),
        None => quote!(where #(#bounds),*),
    }
}

pub fn expand_fn(mut f: syn::ItemFn) -> syn::Result<TokenStream> {
    crate::types_check::check(&f)?;
    // Expanded anyway, so that callers see the helper and the refusal is the only error.
    let refusal = refuse_self_call(&f).err().map(|e| e.to_compile_error());
    let tps: Vec<_> = f
        .sig
        .generics
        .type_params()
        .map(|t| t.ident.clone())
        .collect();
    let key = quote!(__Key<#(#tps),*>);
    // Uniformity inside the helper (value parameters taken as uniform: the caller's check
    // covers them; references as memory), and what its callers must know: whether it, or
    // a helper it calls, waits at a barrier or group operation.
    let mut up = crate::uniformity::Params::default();
    for arg in &f.sig.inputs {
        if let FnArg::Typed(pt) = arg {
            if let Pat::Ident(i) = &*pt.pat {
                let set = if matches!(&*pt.ty, Type::Reference(_)) {
                    &mut up.memory
                } else {
                    &mut up.uniform
                };
                set.insert(i.ident.to_string());
            }
        }
    }
    up.generics = tps.iter().map(|t| t.to_string()).collect();
    let calls = crate::uniformity::check(&f.block, &up)?;
    let (uniform_call_checks, needs_uniform) =
        crate::uniformity::call_checks(&calls, Some(&f.sig.ident));
    let (s, body) = ir_body(&f.sig, &f.block, key, &[], &f.sig.ident.to_string())?;
    crate::host::host_block(&mut f.block);
    let name = &f.sig.ident;
    let vis = &f.vis;
    let generics = &f.sig.generics;
    let params = &s.params;
    let ret = &s.ret;
    let wh = static_where(generics);
    Ok(quote! {
        #refusal
        #f

        #[allow(non_snake_case, unused_imports, unused_variables, unused_mut, unused_braces, unused_parens, clippy::all)]
        #vis mod #name {
            use super::*;
            #[doc(hidden)]
            pub struct __Key #generics (::core::marker::PhantomData<fn() -> (#(#tps,)*)>);
            /// Whether the helper, or a helper it calls, waits at a workgroup barrier or
            /// group operation: then every invocation of the group must call it.
            pub const NEEDS_UNIFORM: bool = #needs_uniform;
            #(#uniform_call_checks)*
            /// The IR version of the helper, called from rewritten kernel code.
            pub fn ir #generics (#(#params),*) -> #ret #wh {
                #body
            }
        }
    })
}

fn is_assoc_fn(sig: &Signature) -> bool {
    !matches!(sig.inputs.first(), Some(FnArg::Receiver(_)))
}

pub fn expand_trait(mut t: syn::ItemTrait) -> syn::Result<TokenStream> {
    let trait_name = t.ident.to_string();
    let mut extra = Vec::new();
    for item in &t.items {
        if let syn::TraitItem::Fn(m) = item {
            if !is_assoc_fn(&m.sig) {
                return err_at(m.sig.inputs.first(), "kernel trait methods take no `self`: strategies are types with associated functions and constants");
            }
            let ir_name = format_ident!("__ir_{}", m.sig.ident);
            let s = ir_signature(&m.sig)?;
            let params = &s.params;
            let ret = &s.ret;
            let generics = &m.sig.generics;
            let wh = static_where(generics);
            let decl = match &m.default {
                Some(block) => {
                    let display = format!("{}_{}", trait_name, m.sig.ident);
                    let (_, body) = ir_body(
                        &m.sig,
                        block,
                        method_key(generics),
                        &["Self".to_string()],
                        &display,
                    )?;
                    quote! { #[doc(hidden)] #[allow(unused_variables, unused_mut, unused_braces, unused_parens, clippy::multiple_bound_locations)] fn #ir_name #generics (#(#params),*) -> #ret #wh { #body } }
                }
                None => {
                    quote! { #[doc(hidden)] #[allow(clippy::multiple_bound_locations)] fn #ir_name #generics (#(#params),*) -> #ret #wh; }
                }
            };
            extra.push(syn::parse2::<syn::TraitItem>(decl)?);
        }
    }
    for item in t.items.iter_mut() {
        if let syn::TraitItem::Fn(m) = item {
            if let Some(block) = &mut m.default {
                crate::host::host_block(block);
            }
        }
    }
    t.items.extend(extra);
    // Helper instances are keyed by the implementing type, which must be 'static.
    t.supertraits.push(syn::parse_quote!('static));
    if t.colon_token.is_none() {
        t.colon_token = Some(Default::default());
    }
    Ok(quote!(#t))
}

pub fn expand_impl(mut i: syn::ItemImpl) -> syn::Result<TokenStream> {
    let Some((_, trait_path, _)) = &i.trait_ else {
        let (it, ty) = (&i.impl_token, &i.self_ty);
        return err_at(
            quote!(#it #ty),
            "`#[kernel_impl]` goes on `impl Trait for Type` of a `#[kernel_trait]`",
        );
    };
    let trait_name = trait_path
        .segments
        .last()
        .map(|s| s.ident.to_string())
        .unwrap_or_default();
    let mut extra = Vec::new();
    for item in &i.items {
        if let syn::ImplItem::Fn(m) = item {
            if !is_assoc_fn(&m.sig) {
                return err_at(m.sig.inputs.first(), "kernel trait methods take no `self`");
            }
            let ir_name = format_ident!("__ir_{}", m.sig.ident);
            let display = format!("{}_{}", trait_name, m.sig.ident);
            let generics = &m.sig.generics;
            let (s, body) = ir_body(
                &m.sig,
                &m.block,
                method_key(generics),
                &["Self".to_string()],
                &display,
            )?;
            let params = &s.params;
            let ret = &s.ret;
            let wh = static_where(generics);
            extra.push(syn::parse2::<syn::ImplItem>(quote! {
                #[allow(unused_variables, unused_mut, unused_braces, unused_parens, clippy::multiple_bound_locations)]
                fn #ir_name #generics (#(#params),*) -> #ret #wh { #body }
            })?);
        }
    }
    for item in i.items.iter_mut() {
        if let syn::ImplItem::Fn(m) = item {
            crate::host::host_block(&mut m.block);
        }
    }
    i.items.extend(extra);
    Ok(quote!(#i))
}

/// A helper that calls itself is refused at the call: GPUs have no call stack (naga and
/// WGSL forbid recursion). Recursion through other helpers is found when the kernel is
/// built (`cohort::ir::function`), where the whole call graph is known.
fn refuse_self_call(f: &syn::ItemFn) -> syn::Result<()> {
    use syn::visit::Visit;
    struct V<'a> {
        name: &'a syn::Ident,
        found: Option<proc_macro2::Span>,
    }
    impl<'ast> Visit<'ast> for V<'_> {
        fn visit_expr_call(&mut self, c: &'ast syn::ExprCall) {
            if let syn::Expr::Path(p) = &*c.func {
                let segs = &p.path.segments;
                let direct = segs.len() == 1
                    || (segs.len() == 2
                        && matches!(
                            segs[0].ident.to_string().as_str(),
                            "self" | "super" | "crate" | "Self"
                        ));
                if direct
                    && segs.last().is_some_and(|s| &s.ident == self.name)
                    && self.found.is_none()
                {
                    self.found = Some(syn::spanned::Spanned::span(&c.func));
                }
            }
            syn::visit::visit_expr_call(self, c);
        }
        // A nested item's body is not this function's.
        fn visit_item(&mut self, _: &'ast syn::Item) {}
    }
    let mut v = V {
        name: &f.sig.ident,
        found: None,
    };
    v.visit_block(&f.block);
    match v.found {
        Some(span) => Err(syn::Error::new(
            span,
            format!(
                "`{}` calls itself: kernel code cannot recurse (GPUs have no call stack); \
                 write it as a loop, with a local array as the stack if it needs one",
                f.sig.ident
            ),
        )),
        None => Ok(()),
    }
}
