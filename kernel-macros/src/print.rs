//! `print!`, `println!`, `eprint!` and `eprintln!` in kernel bodies.
//!
//! The host form keeps the macro (with its arguments' arithmetic rewritten as everywhere
//! else). The IR form evaluates the arguments, hands their words to
//! `::cohort::ir::print::record`, and with them a closure that reads the words back as
//! host values and applies the same format string with `format!`: what a kernel prints
//! on a GPU reads exactly as what its host form prints. Format specifications work as in
//! Rust, except widths and precisions taken from arguments (`{:1$}`, `{:.*}`), which are
//! refused at the format string.

use proc_macro2::TokenStream;
use quote::{format_ident, quote, quote_spanned, ToTokens};
use syn::punctuated::Punctuated;
use syn::spanned::Spanned;
use syn::{Expr, LitStr, Token};

use crate::rewrite::{err_at, Rewriter};

const PRINT_MACROS: &[&str] = &["print", "println", "eprint", "eprintln"];

/// Whether `mac` is one of the print macros a kernel may call.
pub fn is_print(mac: &syn::Macro) -> bool {
    mac.path
        .get_ident()
        .is_some_and(|i| PRINT_MACROS.contains(&i.to_string().as_str()))
}

/// A print macro's arguments: the format string, then expressions (`name = value` for
/// named ones).
pub struct PrintArgs {
    pub format: Option<LitStr>,
    pub args: Vec<Expr>,
}

pub fn parse(mac: &syn::Macro) -> syn::Result<PrintArgs> {
    let all = mac.parse_body_with(Punctuated::<Expr, Token![,]>::parse_terminated)?;
    let mut it = all.into_iter();
    let format = match it.next() {
        None => None,
        Some(Expr::Lit(syn::ExprLit {
            lit: syn::Lit::Str(s),
            ..
        })) => Some(s),
        Some(other) => {
            return err_at(
                other,
                format!(
                    "the first argument of `{}!` must be a string literal (the format string)",
                    mac.path.to_token_stream()
                ),
            )
        }
    };
    Ok(PrintArgs {
        format,
        args: it.collect(),
    })
}

/// The host form: the same macro, its argument expressions passed through `rewrite`.
pub fn host_form(mac: &mut syn::Macro, rewrite: impl Fn(&mut Expr)) {
    let Ok(PrintArgs { format, mut args }) = parse(mac) else {
        // Left as written: rustc reports the malformed macro call itself.
        return;
    };
    for a in &mut args {
        rewrite(a);
    }
    let format = format.into_iter();
    mac.tokens = quote!(#(#format),* #(, #args)*);
}

/// The names a format string captures from the enclosing scope (`{x}`, `{x:?}`).
fn captured_names(format: &LitStr) -> syn::Result<Vec<String>> {
    let text = format.value();
    let mut names = Vec::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '}' {
            chars.next_if_eq(&'}');
            continue;
        }
        if c != '{' {
            continue;
        }
        if chars.next_if_eq(&'{').is_some() {
            continue;
        }
        let mut inner = String::new();
        for c in chars.by_ref() {
            if c == '}' {
                break;
            }
            inner.push(c);
        }
        let (arg, spec) = inner.split_once(':').unwrap_or((&inner, ""));
        if spec.contains('$') || spec.contains(".*") {
            return err_at(
                format,
                format!(
                    "`{{{inner}}}` takes a width or precision from an argument, which kernels \
                     cannot print; write the number in the format string (e.g. `{{:8.3}}`)"
                ),
            );
        }
        let arg = arg.trim();
        let is_name = arg
            .chars()
            .next()
            .is_some_and(|c| c.is_alphabetic() || c == '_');
        if is_name && !names.iter().any(|n| n == arg) {
            names.push(arg.to_string());
        }
    }
    Ok(names)
}

impl Rewriter {
    /// The IR form of a print macro: a block of unit type.
    pub fn print_macro(&mut self, mac: &syn::Macro) -> syn::Result<TokenStream> {
        let span = mac.span();
        let which = mac.path.get_ident().expect("is_print").to_string();
        let PrintArgs { format, args } = parse(mac)?;
        let stream = if which.starts_with('e') {
            quote!(Stderr)
        } else {
            quote!(Stdout)
        };
        // (value variable, its expression, how `format!` names it)
        let mut values: Vec<(syn::Ident, Expr, TokenStream)> = Vec::new();
        let mut named = Vec::new();
        for (i, a) in args.into_iter().enumerate() {
            let v = format_ident!("__cohort_print_{i}");
            match a {
                Expr::Assign(asg) if matches!(&*asg.left, Expr::Path(p) if p.path.get_ident().is_some()) =>
                {
                    let name = asg.left.to_token_stream();
                    named.push(name.to_string());
                    values.push((v.clone(), *asg.right, quote!(#name = #v)));
                }
                other => values.push((v.clone(), other, quote!(#v))),
            }
        }
        let mut captures = Vec::new();
        if let Some(f) = &format {
            for name in captured_names(f)? {
                if named.contains(&name) {
                    continue;
                }
                let ident = syn::Ident::new(&name, f.span());
                captures.push((ident.clone(), syn::parse_quote!(#ident)));
            }
        }
        let mut lets = Vec::new();
        let mut words = Vec::new();
        let mut readers = Vec::new();
        let mut reads = Vec::new();
        let mut format_args = Vec::new();
        let bound = values
            .into_iter()
            .map(|(v, e, f)| (v, e, Some(f)))
            .chain(captures.into_iter().map(|(v, e)| (v, e, None)));
        for (i, (v, e, f)) in bound.enumerate() {
            let value = self.rv(&e)?;
            let es = e.span();
            let w = format_ident!("__cohort_read_{i}");
            lets.push(quote_spanned! {es=> let #v = ::cohort::ir::print::arg(#value); });
            words.push(quote! { __cohort_words.extend_from_slice(#v.words()); });
            readers.push(quote! { let #w = #v.reader(); });
            reads.push(quote! { let #v = __cohort_reader.read(#w); });
            format_args.extend(f);
        }
        let text = match &format {
            Some(f) => quote_spanned! {f.span()=> ::std::format!(#f #(, #format_args)*) },
            None => quote!(::std::string::String::new()),
        };
        let newline = which
            .ends_with("ln")
            .then(|| quote!(__cohort_text.push('\n');));
        Ok(quote_spanned! {span=> {
            #(#lets)*
            let mut __cohort_words = ::std::vec::Vec::new();
            #(#words)*
            ::cohort::ir::print::record(
                ::cohort::ir::print::PrintStream::#stream,
                __cohort_words,
                {
                    #(#readers)*
                    ::cohort::ir::print::format(move |__cohort_record: &[u32]| {
                        let mut __cohort_reader = ::cohort::ir::print::Reader::new(__cohort_record);
                        #(#reads)*
                        #[allow(unused_mut)]
                        let mut __cohort_text = #text;
                        #newline
                        __cohort_text
                    })
                },
                ::core::concat!(::core::file!(), ":", ::core::line!(), ":", ::core::column!()),
            );
        }})
    }
}
