//! Front end of the Cohort kernel language.
//!
//! `#[kernel]` and the helper attributes parse a function with syn, check that it stays in
//! the supported subset (each rejection is a `syn::Error` at the offending span, with the
//! alternative), check uniformity, and rewrite the body into Rust that builds IR through
//! `::cohort::ir` when it runs. The original function is kept for the host, with integer
//! arithmetic routed through `::cohort::host::ops` (`host.rs`) so that it wraps and divides
//! as the GPU does in every build profile. This
//! crate never builds naga IR or shader text itself: a proc macro runs in the compiler, where
//! the kernel's types and the device are unknown, so the IR is built when `build` runs.

use proc_macro::TokenStream;

mod derive;
mod helper;
mod host;
mod kernel;
mod print;
mod rewrite;
mod types_check;
mod uniformity;

fn out(r: syn::Result<proc_macro2::TokenStream>) -> TokenStream {
    r.unwrap_or_else(syn::Error::into_compile_error).into()
}

/// A compute kernel: `#[kernel(workgroup = 256, group = Warp)] fn k(...) { ... }`.
#[proc_macro_attribute]
pub fn kernel(attr: TokenStream, item: TokenStream) -> TokenStream {
    let attr = match syn::parse::<kernel::KernelAttr>(attr) {
        Ok(a) => a,
        Err(e) => return e.into_compile_error().into(),
    };
    let f = match syn::parse::<syn::ItemFn>(item) {
        Ok(f) => f,
        Err(e) => return e.into_compile_error().into(),
    };
    out(kernel::expand(attr, f))
}

/// A helper function callable from kernels (and from host code).
#[proc_macro_attribute]
pub fn kernel_fn(attr: TokenStream, item: TokenStream) -> TokenStream {
    if !attr.is_empty() {
        return syn::Error::new(
            proc_macro2::Span::call_site(),
            "`#[kernel_fn]` takes no arguments",
        )
        .into_compile_error()
        .into();
    }
    match syn::parse::<syn::ItemFn>(item) {
        Ok(f) => out(helper::expand_fn(f)),
        Err(e) => e.into_compile_error().into(),
    }
}

/// A trait whose associated functions kernels call through a generic parameter
/// (`S::sample(..)`): each implementation is one strategy.
#[proc_macro_attribute]
pub fn kernel_trait(_attr: TokenStream, item: TokenStream) -> TokenStream {
    match syn::parse::<syn::ItemTrait>(item) {
        Ok(t) => out(helper::expand_trait(t)),
        Err(e) => e.into_compile_error().into(),
    }
}

/// An implementation of a `#[kernel_trait]`.
#[proc_macro_attribute]
pub fn kernel_impl(_attr: TokenStream, item: TokenStream) -> TokenStream {
    match syn::parse::<syn::ItemImpl>(item) {
        Ok(i) => out(helper::expand_impl(i)),
        Err(e) => e.into_compile_error().into(),
    }
}

/// A struct kernels can use in buffers, uniforms and values.
#[proc_macro_derive(GpuType)]
pub fn derive_gpu_type(item: TokenStream) -> TokenStream {
    match syn::parse::<syn::DeriveInput>(item) {
        Ok(i) => out(derive::expand(i)),
        Err(e) => e.into_compile_error().into(),
    }
}
