//! `#[derive(GpuType)]` for `#[repr(C)]` structs: registers the naga struct with the
//! host's field offsets and checks, at compile time, that those offsets and the size
//! follow the GPU's layout rules (so a buffer of the struct means the same bytes on the
//! host and in the shader). The member index of a field is found from its offset.

use proc_macro2::TokenStream;
use quote::{quote, quote_spanned};
use syn::spanned::Spanned;
use syn::DeriveInput;

use crate::rewrite::{err, err_at};

pub fn expand(input: DeriveInput) -> syn::Result<TokenStream> {
    let name = &input.ident;
    if !input.generics.params.is_empty() {
        return err_at(
            &input.generics,
            "`#[derive(GpuType)]` does not support generic structs",
        );
    }
    let repr_c = input.attrs.iter().any(|a| {
        a.path().is_ident("repr")
            && a.parse_args_with(
                syn::punctuated::Punctuated::<syn::Ident, syn::Token![,]>::parse_terminated,
            )
            .map(|l| l.iter().any(|i| i == "C"))
            .unwrap_or(false)
    });
    if !repr_c {
        return err(
            name.span(),
            "`#[derive(GpuType)]` needs `#[repr(C)]` so that the host layout is fixed",
        );
    }
    let syn::Data::Struct(s) = &input.data else {
        return err(name.span(), "`#[derive(GpuType)]` supports structs only");
    };
    let fields = match &s.fields {
        syn::Fields::Named(f) => f,
        syn::Fields::Unnamed(f) => return err_at(f, "`#[derive(GpuType)]` needs named fields"),
        syn::Fields::Unit => return err(name.span(), "`#[derive(GpuType)]` needs named fields"),
    };
    let name_lit = name.to_string();
    let mut members = Vec::new();
    let mut aligns = Vec::new();
    let mut shareable = Vec::new();
    let mut checks = Vec::new();
    let mut index_arms = Vec::new();
    let mut uniform_checks = Vec::new();
    let mut prev: Option<(&syn::Ident, &syn::Type)> = None;
    for (i, f) in fields.named.iter().enumerate() {
        let fname = f.ident.as_ref().unwrap();
        let flit = fname.to_string();
        let ty = &f.ty;
        let i = i as u32;
        members.push(quote! {
            ::cohort::ir::MemberDesc {
                name: #flit,
                ty: <#ty as ::cohort::ir::GpuType>::naga_type(m),
                host_offset: ::core::mem::offset_of!(#name, #fname),
                gpu_align: <#ty as ::cohort::ir::GpuType>::GPU_ALIGN,
            }
        });
        aligns.push(quote! { <#ty as ::cohort::ir::GpuType>::GPU_ALIGN });
        shareable.push(quote! { <#ty as ::cohort::ir::GpuType>::HOST_SHAREABLE });
        let msg = format!(
            "GpuType `{name_lit}`: field `{flit}` is not at a multiple of its GPU alignment (WGSL: vec3/vec4/mat need 16 bytes, vec2 8); reorder the fields or add padding"
        );
        let size_msg = format!("GpuType `{name_lit}`: field `{flit}` has a different size on the host and the GPU (e.g. glam::Mat3); use a type with the same layout");
        // The const-evaluation error points at the `assert!`: give it the field's name
        // (offset) or type (size) as its span, not the field's first token (`pub`).
        let name_span = fname.span();
        let ty_span = match ty {
            syn::Type::Path(p) => p
                .path
                .segments
                .last()
                .map_or_else(|| ty.span(), |s| s.ident.span()),
            _ => ty.span(),
        };
        checks.push(quote_spanned! {name_span=>
            ::core::assert!(!SHAREABLE_FIELDS || ::core::mem::offset_of!(#name, #fname) % <#ty as ::cohort::ir::GpuType>::GPU_ALIGN == 0, #msg);
        });
        checks.push(quote_spanned! {ty_span=>
            ::core::assert!(!<#ty as ::cohort::ir::GpuType>::HOST_SHAREABLE || ::core::mem::size_of::<#ty>() == <#ty as ::cohort::ir::GpuType>::GPU_SIZE, #size_msg);
        });
        index_arms.push(quote! { if offset == ::core::mem::offset_of!(#name, #fname) { return ::core::option::Option::Some(#i); } });
        // WGSL's uniform layout, checked where a kernel takes the struct as `&T`.
        let inner_msg = format!("GpuType `{name_lit}`: field `{flit}` cannot be in a uniform: it holds an array whose elements are not 16 bytes apart (WGSL's uniform layout); use [Vec4; N] / [UVec4; N], or pass the data in a storage buffer (&[{name_lit}])");
        let struct_msg = format!("GpuType `{name_lit}`: field `{flit}` is a struct, which in a uniform must start at a multiple of 16 bytes (WGSL's uniform layout); add padding before it");
        uniform_checks.push(quote! {
            if <#ty as ::cohort::ir::GpuType>::UNIFORM_PROBLEM.is_some() { return ::core::option::Option::Some(#inner_msg); }
            if <#ty as ::cohort::ir::GpuType>::IS_STRUCT && ::core::mem::offset_of!(#name, #fname) % 16 != 0 { return ::core::option::Option::Some(#struct_msg); }
        });
        if let Some((pname, pty)) = prev {
            let after_msg = format!("GpuType `{name_lit}`: field `{flit}` follows the struct field `{pname}` too closely for a uniform (WGSL rounds a struct member's size up to 16 bytes there); add padding before it");
            uniform_checks.push(quote! {
                if <#pty as ::cohort::ir::GpuType>::IS_STRUCT
                    && ::core::mem::offset_of!(#name, #fname) < ::core::mem::offset_of!(#name, #pname) + ::core::mem::size_of::<#pty>().div_ceil(16) * 16
                {
                    return ::core::option::Option::Some(#after_msg);
                }
            });
        }
        prev = Some((fname, ty));
    }
    let size_msg = format!(
        "GpuType `{name_lit}`: its size is not a multiple of its GPU alignment (the largest field alignment); add padding fields at the end"
    );
    Ok(quote! {
        const _: () = {
            const SHAREABLE_FIELDS: bool = true #(&& #shareable)*;
            const ALIGN: usize = { let mut a = 1usize; #( if #aligns > a { a = #aligns; } )* a };
            #(#checks)*
            ::core::assert!(!SHAREABLE_FIELDS || ::core::mem::size_of::<#name>() % ALIGN == 0, #size_msg);
        };
        unsafe impl ::cohort::ir::GpuType for #name {
            fn naga_type(m: &mut ::cohort::naga::Module) -> ::cohort::naga::Handle<::cohort::naga::Type> {
                let members = ::std::vec![#(#members),*];
                ::cohort::ir::struct_type(m, #name_lit, members, ::core::mem::size_of::<#name>(), <Self as ::cohort::ir::GpuType>::GPU_ALIGN, <Self as ::cohort::ir::GpuType>::HOST_SHAREABLE)
            }
            const GPU_ALIGN: usize = { let mut a = 1usize; #( if #aligns > a { a = #aligns; } )* a };
            const GPU_SIZE: usize = ::core::mem::size_of::<#name>();
            const HOST_SHAREABLE: bool = true #(&& #shareable)*;
            const IS_STRUCT: bool = true;
            const UNIFORM_PROBLEM: ::core::option::Option<&'static str> = {
                const fn problem() -> ::core::option::Option<&'static str> {
                    #(#uniform_checks)*
                    ::core::option::Option::None
                }
                problem()
            };
            fn member_index(offset: usize) -> ::core::option::Option<u32> {
                #(#index_arms)*
                ::core::option::Option::None
            }
        }
        impl ::cohort::ir::HostRepr for #name {
            type Pod = #name;
        }
    })
}
