//! Types and values a kernel cannot have, refused at their span with what to write instead
//! (without this, rustc reports them through the DSL's internal traits: `CastTo<u64>`,
//! `HostRepr`, `GpuType`, or E0223 for `Vec::new()`).

use syn::visit::{self, Visit};

/// Why a type or value named `name` is not available in kernels, if it is not.
fn refusal(name: &str) -> Option<String> {
    Some(match name {
        "u64" | "i64" | "u128" | "i128" | "isize" => format!(
            "`{name}` is not a kernel type (kernels compute in 32 bits): use u32 or i32, or two u32 words"
        ),
        "u8" | "i8" | "u16" | "i16" => format!(
            "`{name}` is not a kernel type: use u32 or i32 (pack narrow values with shifts and masks)"
        ),
        "f64" | "f16" => format!("`{name}` is not a kernel type: use f32"),
        "char" | "str" | "String" => format!("`{name}`: text is not available in kernels"),
        "Vec" | "Box" | "HashMap" | "BTreeMap" | "VecDeque" => format!(
            "`{name}`: heap allocation is not available in kernels; use a fixed-size array `[T; N]` or a storage buffer parameter (`&[T]` / `&mut [T]`)"
        ),
        _ => return None,
    })
}

struct Check {
    error: Option<syn::Error>,
}

impl Check {
    fn path(&mut self, p: &syn::Path) {
        if self.error.is_some() {
            return;
        }
        // A type or a type's function: `u64`, `Vec<u32>`, `Vec::new`, `f64::sqrt`.
        for seg in p.segments.iter().take(2) {
            if let Some(msg) = refusal(&seg.ident.to_string()) {
                self.error = Some(syn::Error::new(seg.ident.span(), msg));
                return;
            }
        }
    }
}

impl<'ast> Visit<'ast> for Check {
    fn visit_type_path(&mut self, t: &'ast syn::TypePath) {
        self.path(&t.path);
        visit::visit_type_path(self, t);
    }
    fn visit_expr_path(&mut self, e: &'ast syn::ExprPath) {
        if e.path.segments.len() >= 2 {
            self.path(&e.path);
        }
        visit::visit_expr_path(self, e);
    }
    fn visit_lit(&mut self, l: &'ast syn::Lit) {
        if self.error.is_none() {
            let suffix = match l {
                syn::Lit::Int(i) => i.suffix(),
                syn::Lit::Float(f) => f.suffix(),
                _ => "",
            };
            if let Some(msg) = refusal(suffix) {
                self.error = Some(syn::Error::new(l.span(), msg));
            }
        }
    }
    // A nested item is not kernel code.
    fn visit_item(&mut self, _: &'ast syn::Item) {}
}

/// Checks a kernel's or helper's signature and body; also refuses const generic
/// parameters, which kernels cannot be specialised by.
pub fn check(f: &syn::ItemFn) -> syn::Result<()> {
    if let Some(c) = f.sig.generics.const_params().next() {
        return Err(syn::Error::new_spanned(
            c,
            "const generic parameters are not supported on kernels and helpers: use a `const` item, or a type parameter whose trait has an associated constant",
        ));
    }
    let mut v = Check { error: None };
    v.visit_signature(&f.sig);
    v.visit_block(&f.block);
    match v.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
