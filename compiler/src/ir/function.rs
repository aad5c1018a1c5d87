//! Helper functions (`#[kernel_fn]`) become naga functions, built once per module and
//! per monomorphised instance, and called with `Statement::Call`.
//!
//! The generated `ir` function of a helper calls [`function`] with a key type unique to
//! the helper and its generic arguments; the body closure runs only the first time the
//! helper is used in a module, inside a fresh naga function.

use naga::{
    AddressSpace, Expression, FunctionArgument, FunctionResult, Handle, Span, Statement, TypeInner,
};
use std::any::TypeId;

use super::builder::{with, FnState};
use super::types::GpuType;
use super::val::{Place, Val};

/// One parameter of a helper: a value or a `&mut` place.
pub trait Param: Copy {
    fn arg_type(m: &mut naga::Module) -> Handle<naga::Type>;
    fn handle(self) -> Handle<Expression>;
    fn from_handle(h: Handle<Expression>) -> Self;
}
impl<T: GpuType> Param for Val<T> {
    fn arg_type(m: &mut naga::Module) -> Handle<naga::Type> {
        T::naga_type(m)
    }
    fn handle(self) -> Handle<Expression> {
        self.h
    }
    fn from_handle(h: Handle<Expression>) -> Self {
        Val::from_handle(h)
    }
}
impl<T: GpuType> Param for Place<T> {
    fn arg_type(m: &mut naga::Module) -> Handle<naga::Type> {
        let base = T::naga_type(m);
        m.types.insert(
            naga::Type {
                name: None,
                inner: TypeInner::Pointer {
                    base,
                    space: AddressSpace::Function,
                },
            },
            Span::UNDEFINED,
        )
    }
    fn handle(self) -> Handle<Expression> {
        self.ptr
    }
    fn from_handle(h: Handle<Expression>) -> Self {
        Place::from_handle(h)
    }
}

/// A helper's parameter list, as a tuple.
pub trait Params: Copy {
    fn types(m: &mut naga::Module) -> Vec<Handle<naga::Type>>;
    fn handles(self) -> Vec<Handle<Expression>>;
    fn from_handles(h: &[Handle<Expression>]) -> Self;
}
macro_rules! params_tuple {
    ($($p:ident $i:tt),*) => {
        impl<$($p: Param),*> Params for ($($p,)*) {
            #[allow(unused_variables)]
            fn types(m: &mut naga::Module) -> Vec<Handle<naga::Type>> { vec![$($p::arg_type(m)),*] }
            fn handles(self) -> Vec<Handle<Expression>> { vec![$(self.$i.handle()),*] }
            #[allow(unused_variables, clippy::unused_unit)]
            fn from_handles(h: &[Handle<Expression>]) -> Self { ($($p::from_handle(h[$i]),)*) }
        }
    };
}
params_tuple!();
params_tuple!(A 0);
params_tuple!(A 0, B 1);
params_tuple!(A 0, B 1, C 2);
params_tuple!(A 0, B 1, C 2, D 3);
params_tuple!(A 0, B 1, C 2, D 3, E 4);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10);
params_tuple!(A 0, B 1, C 2, D 3, E 4, F 5, G 6, H 7, I 8, J 9, K 10, L 11);

/// What a helper returns: nothing or a value.
pub trait Return {
    fn result(m: &mut naga::Module) -> Option<FunctionResult>;
    /// Records the `return` of the tail value at the end of the body.
    fn finish(self);
    fn from_call(h: Option<Handle<Expression>>) -> Self;
    /// A stand-in value for a call that is not made (it would recurse: an error is
    /// already recorded).
    fn placeholder() -> Self;
}
impl Return for () {
    fn result(_: &mut naga::Module) -> Option<FunctionResult> {
        None
    }
    fn finish(self) {}
    fn from_call(_: Option<Handle<Expression>>) -> Self {}
    fn placeholder() -> Self {}
}
impl<T: GpuType> Return for Val<T> {
    fn result(m: &mut naga::Module) -> Option<FunctionResult> {
        Some(FunctionResult {
            ty: T::naga_type(m),
            binding: None,
        })
    }
    fn finish(self) {
        with(|c| {
            c.stmt(Statement::Return {
                value: Some(self.h),
            })
        });
    }
    fn from_call(h: Option<Handle<Expression>>) -> Self {
        Val::from_handle(h.expect("call result"))
    }
    fn placeholder() -> Self {
        Val::from_handle(with(|c| {
            let ty = T::naga_type(&mut c.module);
            c.expr(Expression::ZeroValue(ty))
        }))
    }
}

/// Calls helper `name` (identified by `K`, a type unique to the helper instance), building
/// it first if this module does not have it yet.
pub fn function<K: 'static + ?Sized, P: Params, R: Return>(
    name: &'static str,
    param_names: &[&str],
    args: P,
    body: impl FnOnce(P) -> R,
) -> R {
    let key = (TypeId::of::<K>(), name);
    enter(key, name, || {
        call_helper::<K, P, R>(key, name, param_names, args, body)
    })
}

/// Records the body of helper `name`, which takes a buffer or a reference, in the caller
/// (WGSL functions cannot take such pointers), tracking it on the call stack as
/// [`function`] does.
#[doc(hidden)]
pub fn inlined<K: 'static + ?Sized, R: Return>(name: &'static str, body: impl FnOnce() -> R) -> R {
    enter((TypeId::of::<K>(), name), name, body)
}

/// Runs `build` with `key` on the call stack, unless the call recurses.
fn enter<R: Return>(
    key: (TypeId, &'static str),
    name: &'static str,
    build: impl FnOnce() -> R,
) -> R {
    // Recursion through other helpers (a helper calling itself directly is refused by
    // `#[kernel_fn]` at compile time): reported as the kernel's build error with the
    // chain of calls, and the call replaced by a zero value so that building can finish.
    let cycle = with(|c| {
        c.call_stack.iter().position(|k| *k == key).map(|at| {
            let chain: Vec<&str> = c.call_stack[at..]
                .iter()
                .map(|k| k.1)
                .chain([name])
                .collect();
            c.unsupported.push(format!(
                "helper `{name}` calls itself through {}: kernel code cannot recurse (GPUs have no \
                 call stack); write it as a loop, with a local array as the stack if it needs one",
                chain.join(" -> ")
            ));
        })
    });
    if cycle.is_some() {
        return R::placeholder();
    }
    with(|c| c.call_stack.push(key));
    let r = build();
    with(|c| c.call_stack.pop());
    r
}

fn call_helper<K: 'static + ?Sized, P: Params, R: Return>(
    key: (TypeId, &'static str),
    name: &'static str,
    param_names: &[&str],
    args: P,
    body: impl FnOnce(P) -> R,
) -> R {
    // WGSL functions cannot take pointers into workgroup or storage memory, so a call
    // that passes one is inlined: the body is recorded in the caller.
    if args.handles().iter().any(|h| points_outside_function(*h)) {
        with(|c| c.inline_depth += 1);
        let r = body(args);
        with(|c| c.inline_depth -= 1);
        return r;
    }
    let cached = with(|c| c.fn_cache.get(&key).copied());
    let fh = match cached {
        Some(h) => h,
        None => {
            let fresh = with(|c| {
                let types = P::types(&mut c.module);
                let result = R::result(&mut c.module);
                let mut st = FnState::new(&fn_name::<K>(name));
                st.func.result = result;
                for (i, ty) in types.iter().enumerate() {
                    st.func.arguments.push(FunctionArgument {
                        name: param_names.get(i).map(|s| s.to_string()),
                        ty: *ty,
                        binding: None,
                    });
                }
                c.fns.push(st);
                let handles: Vec<_> = (0..types.len())
                    .map(|i| c.expr(Expression::FunctionArgument(i as u32)))
                    .collect();
                P::from_handles(&handles)
            });
            let ret = body(fresh);
            ret.finish();
            with(|c| {
                let func = c.fns.pop().expect("helper function").finish();
                let h = c.module.functions.append(func, Span::UNDEFINED);
                c.fn_cache.insert(key, h);
                h
            })
        }
    };
    let arguments = args.handles();
    with(|c| {
        let has_result = c.module.functions[fh].result.is_some();
        let result = has_result.then(|| c.expr(Expression::CallResult(fh)));
        c.stmt(Statement::Call {
            function: fh,
            arguments,
            result,
        });
        R::from_call(result)
    })
}

/// Generic instances of one helper get distinct, stable names (`sample_Cosine`).
fn fn_name<K: ?Sized>(name: &str) -> String {
    let full = std::any::type_name::<K>();
    // The key type is `path::__Key<A, B>`; keep the generic arguments' last segments.
    match full.find('<') {
        Some(i) => {
            let args = &full[i + 1..full.len() - 1];
            let parts: Vec<String> = args
                .split(',')
                .map(|a| {
                    let a = a.trim();
                    let last = a.rsplit("::").next().unwrap_or(a);
                    last.chars()
                        .map(|ch| if ch.is_ascii_alphanumeric() { ch } else { '_' })
                        .collect()
                })
                .collect();
            format!("{name}_{}", parts.join("_"))
        }
        // Trait methods are keyed by the implementing type itself.
        None if !full.ends_with("__Key") => {
            let last = full.rsplit("::").next().unwrap_or(full);
            format!("{name}_{last}")
        }
        None => name.to_string(),
    }
}

fn points_outside_function(h: Handle<Expression>) -> bool {
    with(|c| {
        let exprs = &c.f().func.expressions;
        let mut cur = h;
        loop {
            match exprs[cur] {
                Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => {
                    cur = base
                }
                Expression::GlobalVariable(_) => return true,
                _ => return false,
            }
        }
    })
}
