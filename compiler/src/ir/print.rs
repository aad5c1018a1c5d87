//! `print!`, `println!`, `eprint!` and `eprintln!` in kernels (docs/LANGUAGE.md, section 14).
//!
//! `#[kernel]` rewrites a print into [`record`]: the arguments' values as `u32` words, a
//! site number, and a closure that formats the words back into host values with the
//! kernel's own format string. The kernel appends the record to the print buffer
//! (`crate::abi` describes its layout); the runtime decodes it after the
//! dispatch. The format string is applied on the host by `format!`, so a kernel prints
//! exactly what the same `println!` prints when the function runs on the host.

use std::sync::atomic::{AtomicU32, Ordering};

use naga::{AddressSpace, ArraySize, Expression, Handle, ScalarKind, StorageAccess, TypeInner};

use super::builder::with;
use super::control::{and, if_};
use super::kernel::add_global;
use super::ops::{ge, le};
use super::types::GpuType;
use super::val::{lit, place_index, Place, RtArray, Val};
use crate::abi::{BindingKind, PrintFormat, PrintSite, HEADER_WORDS};

pub use crate::abi::{PrintStream, PRINT_BINDING};

/// A value a kernel can print: `f32`, `u32`, `i32`, `usize`, `bool` and glam's vectors of
/// them, formatted as on the host.
#[diagnostic::on_unimplemented(
    message = "`{Self}` cannot be printed from a kernel",
    label = "not printable in a kernel",
    note = "kernels print f32, u32, i32, usize, bool and the vectors Vec2..4, UVec2..4, IVec2..4; print a struct's fields one by one"
)]
pub trait Printable: Sized + 'static {
    /// `u32` words a value takes in a print record.
    const WORDS: usize;
    /// The value's words, as IR expressions of type `u32`.
    #[doc(hidden)]
    fn words(v: Val<Self>) -> Vec<Handle<Expression>>;
    /// The host value back from its words.
    #[doc(hidden)]
    fn from_words(w: &[u32]) -> Self;
}

/// A scalar expression as one `u32` word: bits kept for floats and signed integers.
fn scalar_word(h: Handle<Expression>, kind: ScalarKind) -> Handle<Expression> {
    with(|c| match kind {
        ScalarKind::Uint => h,
        ScalarKind::Bool => {
            let one = c.expr(Expression::Literal(naga::Literal::U32(1)));
            let zero = c.expr(Expression::Literal(naga::Literal::U32(0)));
            c.expr(Expression::Select {
                condition: h,
                accept: one,
                reject: zero,
            })
        }
        _ => c.expr(Expression::As {
            expr: h,
            kind: ScalarKind::Uint,
            convert: None,
        }),
    })
}

macro_rules! printable_scalar {
    ($($t:ty: $kind:expr, |$w:ident| $back:expr;)*) => {$(
        impl Printable for $t {
            const WORDS: usize = 1;
            fn words(v: Val<Self>) -> Vec<Handle<Expression>> {
                vec![scalar_word(v.h, $kind)]
            }
            fn from_words($w: &[u32]) -> Self {
                $back
            }
        }
    )*};
}
printable_scalar! {
    f32: ScalarKind::Float, |w| f32::from_bits(w[0]);
    u32: ScalarKind::Uint, |w| w[0];
    i32: ScalarKind::Sint, |w| w[0] as i32;
    usize: ScalarKind::Uint, |w| w[0] as usize;
    bool: ScalarKind::Bool, |w| w[0] != 0;
}

macro_rules! printable_vector {
    ($($t:ty: $n:expr, $elem:ty, $kind:expr;)*) => {$(
        impl Printable for $t {
            const WORDS: usize = $n;
            fn words(v: Val<Self>) -> Vec<Handle<Expression>> {
                (0..$n)
                    .map(|i| {
                        let c = with(|c| c.expr(Expression::AccessIndex { base: v.h, index: i }));
                        scalar_word(c, $kind)
                    })
                    .collect()
            }
            fn from_words(w: &[u32]) -> Self {
                let mut a = [<$elem>::default(); $n];
                for (x, w) in a.iter_mut().zip(w) {
                    *x = <$elem as Printable>::from_words(std::slice::from_ref(w));
                }
                <$t>::from_array(a)
            }
        }
    )*};
}
printable_vector! {
    glam::Vec2: 2, f32, ScalarKind::Float;
    glam::Vec3: 3, f32, ScalarKind::Float;
    glam::Vec4: 4, f32, ScalarKind::Float;
    glam::UVec2: 2, u32, ScalarKind::Uint;
    glam::UVec3: 3, u32, ScalarKind::Uint;
    glam::UVec4: 4, u32, ScalarKind::Uint;
    glam::IVec2: 2, i32, ScalarKind::Sint;
    glam::IVec3: 3, i32, ScalarKind::Sint;
    glam::IVec4: 4, i32, ScalarKind::Sint;
}

/// A print argument: its words in the IR and how to read them back on the host. Only
/// making one needs `Printable`, so a value that is not printable is reported once, at
/// the argument.
#[doc(hidden)]
pub struct PrintArg<T> {
    words: Vec<Handle<Expression>>,
    read: fn(&[u32]) -> T,
}

#[doc(hidden)]
pub fn arg<T: Printable>(v: Val<T>) -> PrintArg<T> {
    PrintArg {
        words: T::words(v),
        read: T::from_words,
    }
}

impl<T> PrintArg<T> {
    /// The argument's words, in the IR.
    pub fn words(&self) -> &[Handle<Expression>] {
        &self.words
    }
    /// How the formatting closure reads the argument back.
    pub fn reader(&self) -> (usize, fn(&[u32]) -> T) {
        (self.words.len(), self.read)
    }
}

/// Reads a record's words back as host values, one argument after another.
#[doc(hidden)]
pub struct Reader<'a>(&'a [u32]);

impl<'a> Reader<'a> {
    pub fn new(words: &'a [u32]) -> Self {
        Reader(words)
    }
    pub fn read<T>(&mut self, (n, read): (usize, fn(&[u32]) -> T)) -> T {
        let (now, rest) = self.0.split_at(n);
        self.0 = rest;
        read(now)
    }
}

/// The print binding, declared on the first print.
fn print_global() -> Handle<naga::GlobalVariable> {
    if let Some(g) = with(|c| c.print) {
        return g;
    }
    let ty = with(|c| {
        let base = <AtomicU32 as GpuType>::naga_type(&mut c.module);
        c.ty(TypeInner::Array {
            base,
            size: ArraySize::Dynamic,
            stride: 4,
        })
    });
    let g = add_global(
        PRINT_BINDING,
        AddressSpace::Storage {
            access: StorageAccess::LOAD | StorageAccess::STORE,
        },
        ty,
        Some(BindingKind::StorageReadWrite),
    );
    with(|c| c.print = Some(g));
    g
}

/// One print: appends a record of `words` for a new site to the print buffer, or counts
/// it as dropped when the buffer is full.
#[doc(hidden)]
pub fn record(
    stream: PrintStream,
    words: Vec<Handle<Expression>>,
    format: PrintFormat,
    location: &str,
) {
    let n = words.len() as u32;
    let site = with(|c| {
        c.prints.push(PrintSite {
            words: n,
            stream,
            format,
            location: location.to_string(),
        });
        c.prints.len() as u32 - 1
    });
    let g = print_global();
    let (buffer, length) = with(|c| {
        let p = c.expr(Expression::GlobalVariable(g));
        (p, c.expr(Expression::ArrayLength(p)))
    });
    let buffer = Place::<RtArray<AtomicU32>>::from_handle(buffer);
    let record_words = lit(n + 1);
    let at = place_index(buffer, lit(0u32)).fetch_add(record_words, Ordering::Relaxed);
    let capacity = Val::<u32>::from_handle(length) - lit(HEADER_WORDS as u32);
    let fits = and(le(at, capacity), || ge(capacity - at, record_words));
    if_(
        fits,
        || {
            let start = at + lit(HEADER_WORDS as u32);
            place_index(buffer, start).store(lit(site), Ordering::Relaxed);
            for (i, w) in words.into_iter().enumerate() {
                place_index(buffer, start + lit(i as u32 + 1))
                    .store(Val::from_handle(w), Ordering::Relaxed);
            }
        },
        || {
            place_index(buffer, lit(1u32)).fetch_add(lit(1u32), Ordering::Relaxed);
        },
    );
}

/// The formatting closure as the runtime stores it.
#[doc(hidden)]
pub fn format(f: impl Fn(&[u32]) -> String + Send + Sync + 'static) -> PrintFormat {
    std::sync::Arc::new(f)
}
