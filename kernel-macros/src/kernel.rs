//! `#[kernel]`: keeps the function for the host and generates, in a module of the same
//! name, `build` (the rewritten body that builds IR), `artifact` (cached compile) and
//! the typed `launch` functions.

use proc_macro2::TokenStream;
use quote::{format_ident, quote, quote_spanned, ToTokens};
use std::collections::HashSet;
use syn::parse::{Parse, ParseStream};
use syn::spanned::Spanned;
use syn::{FnArg, ItemFn, Pat, Type};

use crate::rewrite::{err_at, Bind, Rewriter};
use crate::uniformity;

pub struct KernelAttr {
    workgroup: u32,
    group: TokenStream,
    finite_loops: bool,
    /// `cpu_dispatch = path`: a function that runs a whole dispatch on the CPU backend.
    cpu_dispatch: Option<syn::Path>,
}

impl Parse for KernelAttr {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let mut attr = KernelAttr {
            workgroup: 64,
            group: quote!(::cohort::Group::Thread),
            finite_loops: false,
            cpu_dispatch: None,
        };
        let mut group_block: Option<u32> = None;
        while !input.is_empty() {
            let key: syn::Ident = input.parse()?;
            input.parse::<syn::Token![=]>()?;
            match key.to_string().as_str() {
                "workgroup" => {
                    let n: syn::LitInt = input.parse()?;
                    let v: u32 = n.base10_parse()?;
                    if v == 0 || v > 1024 {
                        return Err(syn::Error::new(n.span(), "workgroup size must be in 1..=1024"));
                    }
                    attr.workgroup = v;
                }
                "group" => {
                    let g: syn::Ident = input.parse()?;
                    attr.group = match g.to_string().as_str() {
                        "Thread" => quote!(::cohort::Group::Thread),
                        "Warp" => quote!(::cohort::Group::Warp),
                        "Grid" => quote!(::cohort::Group::Grid),
                        "Block" => {
                            let content;
                            syn::parenthesized!(content in input);
                            let n: syn::LitInt = content.parse()?;
                            let v: u32 = n.base10_parse()?;
                            if v == 0 || v > 1024 {
                                return Err(syn::Error::new(n.span(), "Block(n) needs n in 1..=1024"));
                            }
                            group_block = Some(v);
                            quote!(::cohort::Group::Block(#v))
                        }
                        _ => {
                            return Err(syn::Error::new(
                                g.span(),
                                "unknown group level; expected `Thread`, `Warp`, `Block(n)` or `Grid`",
                            ))
                        }
                    };
                }
                "loops" => {
                    let v: syn::Ident = input.parse()?;
                    if v != "finite" {
                        return Err(syn::Error::new(
                            v.span(),
                            "`loops = finite` is the only loop option: it promises that every loop of the kernel ends (docs/LANGUAGE.md, \"Loops\")",
                        ));
                    }
                    attr.finite_loops = true;
                }
                "cpu_dispatch" => {
                    attr.cpu_dispatch = Some(input.parse()?);
                }
                other => {
                    return Err(syn::Error::new(
                        key.span(),
                        format!("unknown kernel option `{other}`; expected `workgroup = N`, `group = Thread | Warp | Block(n) | Grid`, `loops = finite` or `cpu_dispatch = path`"),
                    ))
                }
            }
            if !input.is_empty() {
                input.parse::<syn::Token![,]>()?;
            }
        }
        if let Some(n) = group_block {
            attr.workgroup = n;
        }
        Ok(attr)
    }
}

enum ParamKind {
    Builtin(syn::Ident),
    Storage {
        elem: Type,
        writable: bool,
    },
    Uniform(Type),
    Workgroup(Type),
    /// `#[specialize]`: a value fixed when the kernel is built (its `k`-th constant).
    Constant(Type, usize),
}

struct Param {
    name: syn::Ident,
    kind: ParamKind,
}

const BUILTINS: &[&str] = &[
    "global_index",
    "local_index",
    "workgroup_index",
    "global_id",
    "local_id",
    "workgroup_id",
    "num_workgroups",
    "workgroup_size",
    "subgroup_size",
    "subgroup_lane",
    "subgroup_invocation_id",
    "subgroup_id",
    "num_subgroups",
];

/// The builtins whose value is a `glam::UVec3`; the others are `u32`.
const UVEC3_BUILTINS: &[&str] = &["global_id", "local_id", "workgroup_id", "num_workgroups"];

/// Checks the declared type of a `#[builtin(..)]` parameter syntactically (`u32`, or
/// `UVec3` under any path), so that a wrong type is reported as such rather than as a
/// mismatch inside the generated code.
fn check_builtin_type(builtin: &str, ty: &Type) -> syn::Result<()> {
    let want = if UVEC3_BUILTINS.contains(&builtin) {
        "UVec3"
    } else {
        "u32"
    };
    let ok = match ty {
        Type::Path(p) if p.qself.is_none() => p
            .path
            .segments
            .last()
            .is_some_and(|s| s.arguments.is_empty() && s.ident == want),
        Type::Paren(p) => return check_builtin_type(builtin, &p.elem),
        Type::Group(g) => return check_builtin_type(builtin, &g.elem),
        _ => false,
    };
    if ok {
        return Ok(());
    }
    let full = if want == "UVec3" {
        "UVec3` (`glam::UVec3`)"
    } else {
        "u32`"
    };
    let found = ty
        .to_token_stream()
        .to_string()
        .replace(" :: ", "::")
        .replace(":: ", "::")
        .replace("& ", "&")
        .replace(" <", "<")
        .replace("< ", "<")
        .replace(" >", ">");
    err_at(ty, format!("builtin `{builtin}` is `{full}, not `{found}`"))
}

fn is_atomic(t: &Type) -> bool {
    if let Type::Path(p) = t {
        if let Some(s) = p.path.segments.last() {
            return s.ident == "AtomicU32" || s.ident == "AtomicI32";
        }
    }
    false
}

fn classify(arg: &mut FnArg, constants: &mut usize) -> syn::Result<Param> {
    let FnArg::Typed(pt) = arg else {
        return err_at(arg, "kernels take no `self`");
    };
    let name = match &*pt.pat {
        Pat::Ident(i) => i.ident.clone(),
        other => return err_at(other, "kernel parameters bind one name each"),
    };
    let mut builtin = None;
    let mut workgroup = false;
    let mut specialize = false;
    let mut kept = Vec::new();
    for a in pt.attrs.drain(..) {
        if a.path().is_ident("builtin") {
            let id: syn::Ident = a.parse_args()?;
            let s = id.to_string();
            if !BUILTINS.contains(&s.as_str()) {
                return err_at(
                    &id,
                    format!(
                        "unknown builtin `{s}`; expected one of: {}",
                        BUILTINS.join(", ")
                    ),
                );
            }
            check_builtin_type(&s, &pt.ty)?;
            builtin = Some(if s == "subgroup_invocation_id" {
                format_ident!("subgroup_lane", span = id.span())
            } else {
                id
            });
        } else if a.path().is_ident("workgroup") {
            workgroup = true;
        } else if a.path().is_ident("specialize") {
            if let syn::Meta::List(l) = &a.meta {
                return err_at(l, "`#[specialize]` takes no arguments");
            }
            specialize = true;
        } else {
            kept.push(a);
        }
    }
    pt.attrs = kept;
    let kind = if let Some(b) = builtin {
        ParamKind::Builtin(b)
    } else if specialize {
        let ok = matches!(&*pt.ty, Type::Path(p) if p.qself.is_none() && (p.path.is_ident("u32") || p.path.is_ident("bool")));
        if !ok {
            return err_at(
                &pt.ty,
                "a `#[specialize]` parameter is a `u32` or a `bool` (a value fixed when the kernel is built)",
            );
        }
        ParamKind::Constant((*pt.ty).clone(), *constants)
    } else {
        match &*pt.ty {
            Type::Reference(r) => {
                if workgroup {
                    if r.mutability.is_none() {
                        return err_at(r, "workgroup memory parameters are `&mut T`");
                    }
                    ParamKind::Workgroup((*r.elem).clone())
                } else if let Type::Slice(s) = &*r.elem {
                    let elem = (*s.elem).clone();
                    let writable = r.mutability.is_some() || is_atomic(&elem);
                    ParamKind::Storage { elem, writable }
                } else if r.mutability.is_some() {
                    return err_at(r, "`&mut T` kernel parameters must be `#[workgroup]` memory; storage buffers are `&mut [T]`");
                } else {
                    ParamKind::Uniform((*r.elem).clone())
                }
            }
            other => {
                return err_at(
                    other,
                    "kernel parameters are storage buffers (`&[T]`, `&mut [T]`), uniforms (`&T`), `#[builtin(..)]` values or `#[workgroup]` memory",
                )
            }
        }
    };
    if let ParamKind::Constant(..) = kind {
        *constants += 1;
        if *constants > MAX_CONSTANTS {
            return err_at(
                &pt.pat,
                format!("a kernel has at most {MAX_CONSTANTS} `#[specialize]` parameters; pack flags into one `u32`"),
            );
        }
    }
    Ok(Param { name, kind })
}

/// `cohort_compiler::spec::MAX_CONSTANTS` (the macro crate cannot depend on the compiler).
const MAX_CONSTANTS: usize = 4;

pub fn expand(attr: KernelAttr, mut f: ItemFn) -> syn::Result<TokenStream> {
    crate::types_check::check(&f)?;
    let span = f.sig.ident.span();
    if let Some(r) = match &f.sig.output {
        syn::ReturnType::Type(_, t) => Some(t),
        _ => None,
    } {
        return err_at(r, "kernels return nothing; write results to a buffer");
    }
    if let Some(a) = &f.sig.asyncness {
        return err_at(a, "kernels are plain `fn`s (not async or unsafe)");
    }
    if let Some(u) = &f.sig.unsafety {
        return err_at(u, "kernels are plain `fn`s (not async or unsafe)");
    }
    let mut params = Vec::new();
    let mut constants = 0usize;
    for arg in f.sig.inputs.iter_mut() {
        params.push(classify(arg, &mut constants)?);
    }

    // Front-end checks: uniformity, and what host-run group closures may read.
    let mut up = uniformity::Params::default();
    let mut all_names = HashSet::new();
    for p in &params {
        let n = p.name.to_string();
        all_names.insert(n.clone());
        match &p.kind {
            ParamKind::Builtin(b) if uniformity::uniform_builtin(&b.to_string()) => {
                up.uniform.insert(n);
            }
            ParamKind::Builtin(_) => {
                up.nonuniform.insert(n);
            }
            ParamKind::Uniform(_) => {
                up.uniform_buffers.insert(n);
            }
            // The same value for every invocation, and a host value the launch has.
            ParamKind::Constant(..) => {
                up.uniform.insert(n.clone());
                up.uniform_buffers.insert(n);
            }
            ParamKind::Storage { .. } | ParamKind::Workgroup(_) => {
                up.memory.insert(n);
            }
        }
    }
    up.generics = f
        .sig
        .generics
        .type_params()
        .map(|t| t.ident.to_string())
        .collect();
    let calls = uniformity::check(&f.block, &up)?;
    let (uniform_call_checks, _) = uniformity::call_checks(&calls, None);
    uniformity::check_grid_closures(&f.block, &up, &all_names)?;

    let mut rw = Rewriter::new();
    rw.allow_group_share = true;
    for g in f.sig.generics.type_params() {
        rw.generics.insert(g.ident.to_string());
    }
    let mut decls = Vec::new();
    let mut launch_params = Vec::new();
    let mut launch_names = Vec::new();
    let mut launch_args = Vec::new();
    let mut uniform_uploads = Vec::new();
    let mut layout_checks = Vec::new();
    let mut storage_names = Vec::new();
    let mut constant_names = Vec::new();
    let mut constant_params = Vec::new();
    for (i, p) in params.iter().enumerate() {
        let name = &p.name;
        let lit = name.to_string();
        let pspan = name.span();
        match &p.kind {
            ParamKind::Builtin(b) => {
                let FnArg::Typed(pt) = &f.sig.inputs[i] else {
                    unreachable!()
                };
                let ty = &pt.ty;
                decls.push(quote_spanned! {pspan=> let #name: ::cohort::ir::Val<#ty> = ::cohort::ir::builtin::#b(); });
                rw.bind(&lit, Bind::Val);
            }
            ParamKind::Storage { elem, writable } => {
                // An element whose host size is not its GPU array stride (Vec3: 12 bytes on
                // the host, 16 apart in a WGSL array) would be misread: refused at compile
                // time where the type names no generic parameter, else when the kernel is built.
                if !mentions_any(elem, &rw.generics) {
                    let espan = elem.span();
                    layout_checks.push(quote_spanned! {espan=>
                        const _: () = ::core::assert!(
                            ::cohort::ir::storage_element_ok::<#elem>(),
                            "this storage buffer's element type has another size on the host than its stride in a GPU array (e.g. Vec3: 12 bytes on the host, 16 apart on the GPU), so the buffer would be misread: use Vec4, [f32; 3] or a #[derive(GpuType)] struct of the same size on both"
                        );
                    });
                }
                decls.push(quote_spanned! {pspan=> let #name = ::cohort::ir::Buffer::<#elem>::declare(#lit, #writable); });
                rw.bind(&lit, Bind::Root);
                launch_names.push(name.clone());
                storage_names.push(name.clone());
                launch_params.push(quote_spanned! {pspan=> #name: &::cohort::runtime::GpuBuffer<<#elem as ::cohort::ir::HostRepr>::Pod> });
                launch_args.push(quote! { #name.arg() });
            }
            ParamKind::Uniform(t) => {
                if !mentions_any(t, &rw.generics) {
                    let tspan = t.span();
                    layout_checks.push(quote_spanned! {tspan=> const _: () = ::cohort::ir::assert_uniform::<#t>(); });
                }
                decls.push(quote_spanned! {pspan=> let #name = ::cohort::ir::Uniform::<#t>::declare(#lit); });
                rw.bind(&lit, Bind::Root);
                launch_names.push(name.clone());
                launch_params.push(quote_spanned! {pspan=> #name: &#t });
                let buf = format_ident!("__uniform_{}", name);
                uniform_uploads.push(quote! { let #buf = __cohort_device.upload_uniform(#name)?; });
                launch_args.push(quote! { #buf.arg() });
            }
            ParamKind::Workgroup(t) => {
                decls.push(quote_spanned! {pspan=> let #name = ::cohort::ir::Workgroup::<#t>::declare(#lit); });
                rw.bind(&lit, Bind::Root);
            }
            ParamKind::Constant(t, k) => {
                decls.push(quote_spanned! {pspan=> let #name: ::cohort::ir::Val<#t> = ::cohort::ir::spec_constant::<#t>(__cohort_constants[#k]); });
                rw.bind(&lit, Bind::Val);
                launch_names.push(name.clone());
                launch_params.push(quote_spanned! {pspan=> #name: #t });
                constant_names.push(name.clone());
                constant_params.push(quote_spanned! {pspan=> #name: #t });
            }
        }
    }
    // The launch functions build the specialisation of their constants' values.
    let specialize_spec = quote! {
        let __cohort_spec = &self::specialized(__cohort_spec #(, #constant_names)*);
    };
    let body = rw.block(&f.block)?;
    crate::host::host_block(&mut f.block);
    let (cpu_copy, cpu_invoke, cpu_workgroup_vars) = cpu_form(&f, &params);

    // `len()` reads the element counts the launch passes (a binding the kernel has only when
    // it calls `len()`): an empty buffer is bound to a stand-in whose size the GPU would see.
    let lengths_upload = quote! {
        let __lengths_at = __cohort_art.bindings.iter().position(|b| b.name == ::cohort::ir::LENGTHS_BINDING);
        let __lengths = match __lengths_at {
            Some(_) => Some(__cohort_device.upload(&[#(#storage_names.len() as u32),*])?),
            None => None,
        };
    };
    let lengths_arg = quote! {
        if let (Some(at), Some(b)) = (__lengths_at, &__lengths) { __args.insert(at, b.arg()); }
    };
    let fn_name = &f.sig.ident;
    let vis = &f.vis;
    let name_lit = fn_name.to_string();
    let wg = attr.workgroup;
    let group = attr.group;
    let finite_loops = attr.finite_loops;
    let cpu_dispatch = match &attr.cpu_dispatch {
        Some(p) => quote!(::core::option::Option::Some(#p as ::cohort::runtime::cpu::DispatchForm)),
        None => quote!(::core::option::Option::None),
    };
    let generics = &f.sig.generics;
    let type_params: Vec<_> = generics.type_params().map(|t| t.ident.clone()).collect();
    let (impl_g, _, where_clause) = generics.split_for_impl();
    let static_bounds = type_params.iter().map(|t| quote!(#t: 'static));
    let where_static = match where_clause {
        Some(w) => {
            let preds = &w.predicates;
            quote!(where #preds, #(#static_bounds),*)
        }
        None if type_params.is_empty() => quote!(),
        None => quote!(where #(#static_bounds),*),
    };
    let turbofish = if type_params.is_empty() {
        quote!()
    } else {
        quote!(::<#(#type_params),*>)
    };
    let key_params = if type_params.is_empty() {
        quote!()
    } else {
        quote!(<#(#type_params),*>)
    };
    let line_col = quote_spanned! {span=> (line!(), column!()) };

    // Split off `<...>` to add a lifetime to launch functions.
    let gparams = &generics.params;
    let launch_generics = if gparams.is_empty() {
        quote!(<'__grid>)
    } else {
        quote!(<'__grid, #gparams>)
    };
    let _ = impl_g;

    Ok(quote! {
        #f

        #cpu_copy

        #[allow(non_snake_case, unused_imports, unused_variables, unused_mut, unused_braces, unused_parens, clippy::all)]
        #vis mod #fn_name {
            use super::*;

            /// Static facts about the kernel (name, definition site, attribute defaults).
            pub static INFO: ::cohort::KernelInfo = ::cohort::KernelInfo {
                name: #name_lit,
                file: file!(),
                line: #line_col.0,
                column: #line_col.1,
                workgroup_size: #wg,
                group: #group,
                finite_loops: #finite_loops,
            };

            #(#layout_checks)*
            #(#uniform_call_checks)*

            #[doc(hidden)]
            pub struct __Key #generics (::core::marker::PhantomData<fn() -> (#(#type_params,)*)>);

            /// Builds the kernel's naga module for one specialisation.
            pub fn build #generics (spec: &::cohort::Spec) -> ::cohort::ir::BuiltKernel #where_static {
                let __cohort_constants = spec.constants;
                ::cohort::ir::build_kernel(&INFO, *spec, || {
                    #(#decls)*
                    ::cohort::ir::discard(#body);
                })
            }

            /// Runs the invocations `lanes` names on the CPU backend, with the buffers
            /// bound once.
            #[doc(hidden)]
            pub fn __cpu_invoke #generics (a: &::cohort::runtime::cpu::LaneArgs<'_>, lanes: &::cohort::runtime::cpu::Lanes<'_>) #where_static {
                #cpu_invoke
            }

            /// Size and alignment of each `#[workgroup]` parameter, for the CPU backend.
            #[doc(hidden)]
            pub fn __cpu_workgroup_vars #generics () -> ::std::vec::Vec<(usize, usize)> #where_static {
                #cpu_workgroup_vars
            }

            /// The compiled kernel (WGSL + SPIR-V + host form) for `spec`, cached after the
            /// first call.
            pub fn artifact #generics (spec: &::cohort::Spec) -> ::core::result::Result<::std::sync::Arc<::cohort::runtime::KernelArtifact>, ::cohort::emit::CompileError> #where_static {
                ::cohort::launch::artifact::<__Key #key_params>(
                    &INFO,
                    *spec,
                    |s| build #turbofish (s),
                    ::cohort::emit::HostEntry {
                        invoke: __cpu_invoke #turbofish,
                        workgroup_vars: __cpu_workgroup_vars #turbofish,
                        dispatch: #cpu_dispatch,
                    },
                )
            }

            /// The best specialisation of this kernel for `device` at `group` level
            /// (the attribute's level when `None`).
            pub fn spec(device: &::cohort::runtime::Device, group: ::core::option::Option<::cohort::Group>) -> ::cohort::Spec {
                ::cohort::Spec::for_device(&INFO, &device.info().target(), group.unwrap_or(INFO.group))
            }

            /// `spec` with the kernel's `#[specialize]` parameters set to these values
            /// (the specialisation `artifact` builds; the launch functions make it).
            pub fn specialized(spec: &::cohort::Spec #(, #constant_params)*) -> ::cohort::Spec {
                spec.with_constants(&[#(::cohort::ir::SpecConstant::raw(#constant_names)),*])
            }

            /// Runs the kernel with the attribute's group level.
            // The launch functions' own parameters and locals are `__cohort_*`, and they
            // call this module's functions through `self::`, so that a kernel parameter
            // of any name (`device`, `grid`, `spec`, ...) can sit beside them.
            pub fn launch #launch_generics (
                __cohort_device: &::cohort::runtime::Device,
                __cohort_grid: impl ::core::convert::Into<::cohort::Grid<'__grid>>,
                #(#launch_params),*
            ) -> ::cohort::Result<::cohort::runtime::DispatchStats> #where_static {
                let __cohort_spec = self::spec(__cohort_device, ::core::option::Option::None);
                self::launch_spec #turbofish (__cohort_device, &__cohort_spec, __cohort_grid, #(#launch_names),*)
            }

            /// Records one specialisation of the kernel into `batch` (submitted later
            /// with the batch's other dispatches, in order).
            pub fn record #launch_generics (
                __cohort_batch: &mut ::cohort::runtime::Batch<'_>,
                __cohort_spec: &::cohort::Spec,
                __cohort_grid: impl ::core::convert::Into<::cohort::Grid<'__grid>>,
                #(#launch_params),*
            ) -> ::cohort::Result<()> #where_static {
                #specialize_spec
                let __cohort_device = __cohort_batch.device();
                let __cohort_art = self::artifact #turbofish (__cohort_spec)?;
                #(#uniform_uploads)*
                #lengths_upload
                let mut __args: ::std::vec::Vec<::cohort::runtime::BufferArg<'_>> = ::std::vec![#(#launch_args),*];
                #lengths_arg
                let __cohort_dispatch = ::cohort::launch::dispatch_of(__cohort_grid.into(), __cohort_spec, __cohort_device.info().max_workgroups_per_dim);
                ::core::result::Result::Ok(__cohort_batch.dispatch(&__cohort_art, &__args, __cohort_dispatch)?)
            }

            /// Runs one specialisation of the kernel.
            pub fn launch_spec #launch_generics (
                __cohort_device: &::cohort::runtime::Device,
                __cohort_spec: &::cohort::Spec,
                __cohort_grid: impl ::core::convert::Into<::cohort::Grid<'__grid>>,
                #(#launch_params),*
            ) -> ::cohort::Result<::cohort::runtime::DispatchStats> #where_static {
                #specialize_spec
                let __cohort_art = self::artifact #turbofish (__cohort_spec)?;
                #(#uniform_uploads)*
                #lengths_upload
                let mut __args: ::std::vec::Vec<::cohort::runtime::BufferArg<'_>> = ::std::vec![#(#launch_args),*];
                #lengths_arg
                let __cohort_dispatch = ::cohort::launch::dispatch_of(__cohort_grid.into(), __cohort_spec, __cohort_device.info().max_workgroups_per_dim);
                ::core::result::Result::Ok(__cohort_device.dispatch(&__cohort_art, &__args, __cohort_dispatch)?)
            }
        }
    })
}

/// The CPU backend's form of a kernel: a copy of its host function, next to it, that takes
/// writable storage and workgroup memory as raw pointers (the invocations of a workgroup
/// share them across sync points, where no `&mut` parameter may be assumed unaliased) and
/// rebinds them as the references the body expects; the body of `__cpu_invoke`, which
/// calls the copy with one invocation's builtins and buffers; and the body of
/// `__cpu_workgroup_vars`.
fn cpu_form(f: &ItemFn, params: &[Param]) -> (TokenStream, TokenStream, TokenStream) {
    let mut copy = f.clone();
    let copy_name = format_ident!("__cohort_cpu_{}", f.sig.ident);
    copy.sig.ident = copy_name.clone();
    copy.vis = syn::Visibility::Inherited;
    // The kernel's own `allow`s and `cfg`s apply to the copy too (its lints are the
    // kernel's, already reported there).
    copy.attrs
        .retain(|a| a.path().is_ident("allow") || a.path().is_ident("cfg"));
    copy.attrs.push(syn::parse_quote!(#[doc(hidden)]));
    copy.attrs
        .push(syn::parse_quote!(#[allow(unused, non_snake_case, clippy::all)]));
    let mut prologue = Vec::new();
    let mut call_args = Vec::new();
    let mut vars = Vec::new();
    let (mut buffer, mut workgroup) = (0usize, 0usize);
    // Buffers and workgroup memory are bound once per call (`binds`), before the loop
    // over the invocations it runs; builtins are read per invocation.
    let mut binds = Vec::new();
    fn bind(binds: &mut Vec<TokenStream>, value: TokenStream) -> TokenStream {
        let local = format_ident!("__cohort_p{}", binds.len());
        binds.push(quote!(let #local = #value;));
        quote!(#local)
    }
    for (arg, p) in copy.sig.inputs.iter_mut().zip(params) {
        let FnArg::Typed(pt) = arg else { continue };
        let name = &p.name;
        let mutable_ref = matches!(&*pt.ty, Type::Reference(r) if r.mutability.is_some());
        match &p.kind {
            ParamKind::Builtin(b) => {
                if UVEC3_BUILTINS.contains(&b.to_string().as_str()) {
                    call_args.push(quote!(::cohort::glam::UVec3::from_array(__cohort_b.#b)));
                } else {
                    call_args.push(quote!(__cohort_b.#b));
                }
            }
            ParamKind::Storage { elem, .. } => {
                if mutable_ref {
                    call_args.push(bind(&mut binds, quote!(a.storage_mut::<#elem>(#buffer))));
                } else {
                    call_args.push(bind(&mut binds, quote!(a.storage::<#elem>(#buffer))));
                }
                buffer += 1;
            }
            ParamKind::Uniform(t) => {
                call_args.push(bind(&mut binds, quote!(a.uniform::<#t>(#buffer))));
                buffer += 1;
            }
            ParamKind::Constant(t, k) => {
                call_args.push(bind(
                    &mut binds,
                    quote!(<#t as ::cohort::ir::SpecConstant>::from_raw(a.constant(#k))),
                ));
            }
            ParamKind::Workgroup(t) => {
                call_args.push(bind(&mut binds, quote!(a.workgroup::<#t>(#workgroup))));
                vars.push(quote!((::core::mem::size_of::<#t>(), ::core::mem::align_of::<#t>())));
                workgroup += 1;
            }
        }
        if mutable_ref {
            let Type::Reference(r) = &*pt.ty else {
                unreachable!()
            };
            let elem = &r.elem;
            let ty = pt.ty.clone();
            prologue.push(quote! {
                // SAFETY: the CPU backend passes memory of this type that outlives the call.
                let #name: #ty = unsafe { &mut *#name };
            });
            *pt.ty = syn::parse_quote!(*mut #elem);
            *pt.pat = syn::parse_quote!(#name);
        }
    }
    let stmts = &copy.block.stmts;
    copy.block = Box::new(syn::parse_quote!({ #(#prologue)* #(#stmts)* }));
    let type_params: Vec<_> = f.sig.generics.type_params().map(|t| &t.ident).collect();
    let turbofish = if type_params.is_empty() {
        quote!()
    } else {
        quote!(::<#(#type_params),*>)
    };
    let invoke = quote! {
        // SAFETY: the CPU backend binds the buffers the launch functions passed, in
        // parameter order, and workgroup memory laid out by `__cpu_workgroup_vars`.
        unsafe {
            #(#binds)*
            for __cohort_local in lanes.range() {
                let __cohort_b = lanes.enter(__cohort_local);
                super::#copy_name #turbofish (#(#call_args),*)
            }
        }
    };
    let vars = quote!(::std::vec![#(#vars),*]);
    (copy.into_token_stream(), invoke, vars)
}

/// Whether `ty` names any of `names` (the kernel's generic type parameters).
fn mentions_any(ty: &syn::Type, names: &std::collections::HashSet<String>) -> bool {
    fn walk(ts: proc_macro2::TokenStream, names: &std::collections::HashSet<String>) -> bool {
        ts.into_iter().any(|t| match t {
            proc_macro2::TokenTree::Ident(i) => names.contains(&i.to_string()),
            proc_macro2::TokenTree::Group(g) => walk(g.stream(), names),
            _ => false,
        })
    }
    walk(quote::ToTokens::to_token_stream(ty), names)
}
